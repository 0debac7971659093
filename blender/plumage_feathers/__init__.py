"""Plumage for Blender: dresses the active mesh object with collision-free
feathers or scales, follows the animation while scrubbing, and bakes a frame
range to a cache for rendering.

Needs the `plumage` Python package in Blender's Python (for instance
`pip install ./python --no-deps --target ~/.config/blender/<version>/scripts/modules`,
which builds the library with cargo). The panel is in the Properties editor,
Object tab, "Plumage".
"""

from __future__ import annotations

bl_info = {
    "name": "Plumage feathers",
    "author": "Plumage",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Object > Plumage",
    "description": "Collision-free feathers and scales on animated meshes",
    "category": "Object",
}

import os
from typing import Any, Dict, Optional

import bpy
import numpy as np
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, PointerProperty, StringProperty

try:
    import plumage
except ImportError as e:  # the panel and the operators say so
    plumage = None
    IMPORT_ERROR = (
        f"the plumage Python package cannot be imported in Blender's Python ({e}): install it into "
        f"{bpy.utils.user_resource('SCRIPTS', path='modules')} (pip install ./python --no-deps --target DIR); "
        "Blender started with --factory-startup does not look there unless BLENDER_USER_SCRIPTS points at its parent"
    )
else:
    IMPORT_ERROR = ""


def _package_missing(cls: Any) -> bool:
    """Whether `plumage` failed to import; then the operator's poll says why."""
    if plumage is None:
        cls.poll_message_set(IMPORT_ERROR)
        return True
    return False

# object name -> live state (the System, its last frame, the cache)
_RUNS: Dict[str, Dict[str, Any]] = {}

# Frames between two kept states of a dressed object: a jump replays at
# most this many frames.
CHECKPOINT_INTERVAL = 8

# Set while a jump replays frames (the frame changes it makes are not
# followed again).
_REPLAYING = False


def body_arrays(obj: bpy.types.Object, depsgraph: bpy.types.Depsgraph) -> tuple:
    """(positions (n, 3), triangles (m, 3)) of the evaluated mesh, object space."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        n = len(mesh.vertices)
        co = np.empty(3 * n, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        mesh.calc_loop_triangles()
        tris = np.empty(3 * len(mesh.loop_triangles), dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", tris)
    finally:
        evaluated.to_mesh_clear()
    return co.reshape(-1, 3), tris.reshape(-1, 3)


def vertex_map(mesh: bpy.types.Mesh, spec: str, components: int) -> Optional[np.ndarray]:
    """A per-vertex map from attribute NAME or NAME:C (as the C++ host reads them)."""
    if not spec:
        return None
    name, _, comp = spec.partition(":")
    first = int(comp) if comp else 0
    attr = mesh.attributes.get(name)
    if attr is None:
        raise ValueError(f"the mesh has no attribute {name!r}")
    if attr.domain != "POINT":
        raise ValueError(f"attribute {name!r} is not per vertex (domain {attr.domain})")
    width = {"FLOAT": 1, "INT": 1, "FLOAT_VECTOR": 3, "FLOAT_COLOR": 4, "BYTE_COLOR": 4, "FLOAT2": 2}.get(attr.data_type)
    if width is None or first + components > width:
        raise ValueError(f"attribute {name!r} ({attr.data_type}) has no components {first}..{first + components - 1}")
    key = {"FLOAT": "value", "INT": "value", "FLOAT_VECTOR": "vector", "FLOAT2": "vector"}.get(attr.data_type, "color")
    values = np.empty(len(mesh.vertices) * width, dtype=np.float32)
    attr.data.foreach_get(key, values)
    out = values.reshape(-1, width)[:, first : first + components]
    return np.ascontiguousarray(out[:, 0] if components == 1 else out)


def system_config(props: "PlumageSettings") -> Dict[str, Any]:
    cfg: Dict[str, Any] = {"seed": props.seed, "threads": props.threads, "mode": props.mode.lower(), "preset": props.preset.lower()}
    # Checkpoints every few frames: a jump seeks and replays, so scrubbing
    # shows what playback shows.
    cfg["checkpoint_interval"] = CHECKPOINT_INTERVAL
    if props.shaft_segments > 0:
        cfg["shaft_segments"] = props.shaft_segments
    if props.density == "COUNT":
        cfg["target_feathers"] = props.target_feathers
    else:
        cfg["spacing"] = props.spacing
    cfg["feather_length"] = props.feather_length
    cfg["feather_width"] = props.feather_width
    if props.flow == "AXIS":
        cfg["flow_axis"] = {"X": (1, 0, 0), "Y": (0, 1, 0), "Z": (0, 0, 1), "-X": (-1, 0, 0), "-Y": (0, -1, 0), "-Z": (0, 0, -1)}[props.flow_axis]
    return cfg


def feathers_object(body: bpy.types.Object) -> bpy.types.Object:
    name = body.name + "_feathers"
    obj = bpy.data.objects.get(name)
    if obj is None:
        obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
        for coll in body.users_collection:
            coll.objects.link(obj)
        obj.parent = body
    return obj


def write_feather_mesh(obj: bpy.types.Object, geo: Any, topology: bool) -> None:
    mesh = obj.data
    if topology:
        mesh.clear_geometry()
        mesh.vertices.add(len(geo.positions))
        mesh.loops.add(3 * len(geo.triangles))
        mesh.polygons.add(len(geo.triangles))
        mesh.loops.foreach_set("vertex_index", geo.triangles.astype(np.int32).ravel())
        mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(geo.triangles), 3, dtype=np.int32))
        mesh.polygons.foreach_set("loop_total", np.full(len(geo.triangles), 3, dtype=np.int32))
        uv = mesh.uv_layers.new(name="UVMap")
        uv.data.foreach_set("uv", geo.uvs[geo.triangles.ravel()].astype(np.float32).ravel())
        ids = mesh.attributes.new("feather_index", "INT", "POINT")
        ids.data.foreach_set("value", geo.feather_index.astype(np.int32))
    mesh.vertices.foreach_set("co", geo.positions.astype(np.float32).ravel())
    mesh.update()


class PlumageSettings(bpy.types.PropertyGroup):
    density: EnumProperty(name="Density", items=[("COUNT", "Count", "A target feather count"), ("SPACING", "Spacing", "Root spacing")])
    target_feathers: IntProperty(name="Feathers", default=2000, min=1, max=10_000_000)
    spacing: FloatProperty(name="Spacing", default=0.05, min=1e-6, subtype="DISTANCE")
    feather_length: FloatProperty(name="Length", default=0.0, min=0.0, subtype="DISTANCE", description="0 = derived from the spacing")
    feather_width: FloatProperty(name="Width", default=0.0, min=0.0, subtype="DISTANCE", description="0 = derived from the spacing")
    flow: EnumProperty(
        name="Flow",
        items=[
            ("AUTO", "From the mesh", "The library derives the flow from the mesh's principal axis"),
            ("AXIS", "Object axis", "Feathers point along this axis of the object"),
            ("ATTRIBUTE", "Vertex attribute", "A per-vertex direction attribute"),
        ],
    )
    flow_axis: EnumProperty(name="Axis", items=[(a, a, "") for a in ("X", "Y", "Z", "-X", "-Y", "-Z")], default="-Y")
    flow_attribute: StringProperty(name="Flow attribute", description="Vector attribute NAME or NAME:C")
    spacing_map: StringProperty(name="Spacing map", description="Attribute NAME or NAME:C (0 = bare skin)")
    length_map: StringProperty(name="Length map")
    width_map: StringProperty(name="Width map")
    mode: EnumProperty(name="Mode", items=[("INCREMENTAL", "Incremental", ""), ("LEGACY", "Legacy", ""), ("REBUILD", "Rebuild", "")])
    preset: EnumProperty(
        name="Preset",
        items=[
            ("FEATHERS", "Feathers", "Contour feathers with bent shafts that lie down over what is beneath them"),
            ("KITE", "Kite", "The paper's rigid feather: cheaper, but the coat stands off the body"),
            ("SCALES", "Scales", "Fish scales, short, wide and nearly rigid"),
        ],
    )
    shaft_segments: IntProperty(
        name="Segments", default=0, min=0, max=4, description="Shaft segments (0 = the preset's): more lets a feather bend over what lies beneath it"
    )
    seed: IntProperty(name="Seed", default=1, min=0)
    threads: IntProperty(name="Threads", default=0, min=0, max=256, description="0 = all cores")
    cache_path: StringProperty(name="Cache", subtype="FILE_PATH", default="//plumage_cache.npz")
    use_cache: BoolProperty(name="Play from cache", default=False)


def create_run(context: bpy.types.Context, obj: bpy.types.Object) -> Dict[str, Any]:
    props = obj.plumage
    depsgraph = context.evaluated_depsgraph_get()
    positions, triangles = body_arrays(obj, depsgraph)
    mesh = obj.data
    if len(mesh.vertices) != len(positions):
        raise ValueError(f"the modifiers change the vertex count ({len(mesh.vertices)} -> {len(positions)}): maps cannot be read")
    maps = {
        "spacing_scale": vertex_map(mesh, props.spacing_map, 1),
        "length_scale": vertex_map(mesh, props.length_map, 1),
        "width_scale": vertex_map(mesh, props.width_map, 1),
        "orientations": vertex_map(mesh, props.flow_attribute, 3) if props.flow == "ATTRIBUTE" else None,
    }
    system = plumage.System(positions, triangles, **maps, **system_config(props))
    target = feathers_object(obj)
    write_feather_mesh(target, system.feather_geometry(), topology=True)
    frame = context.scene.frame_current
    run = {"system": system, "frame": frame, "start": frame, "target": target.name}
    old = _RUNS.pop(obj.name, None)
    if old:
        old["system"].close()
    _RUNS[obj.name] = run
    return run


def follow(scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph) -> None:
    """Updates every dressed object to the scene's frame."""
    for name, run in list(_RUNS.items()):
        obj = bpy.data.objects.get(name)
        target = bpy.data.objects.get(run["target"])
        if obj is None or target is None:
            _RUNS.pop(name)["system"].close()
            continue
        frame = scene.frame_current
        cache = run.get("cache")
        if obj.plumage.use_cache and cache is not None and frame in cache["frames"]:
            target.data.vertices.foreach_set("co", cache["positions"][cache["frames"].index(frame)].ravel())
            target.data.update()
            continue
        system = run["system"]
        if frame == run["frame"] + 1:
            system.step(body_arrays(obj, depsgraph)[0])  # playing forward: the incremental path
        elif frame != run["frame"]:
            if frame >= run["start"]:
                replay_to(scene, obj, run, frame)  # a jump: what playback shows at this frame
            else:
                system.evaluate(body_arrays(obj, depsgraph)[0])  # before the dressed frame: solve this pose
        run["frame"] = frame
        write_feather_mesh(target, system.feather_geometry(), topology=False)


def replay_to(scene: bpy.types.Scene, obj: bpy.types.Object, run: Dict[str, Any], frame: int) -> None:
    """Brings the system to what playing from the dressed frame to `frame`
    gives: back to the nearest kept state (seek), then the frames between
    stepped one by one (at most CHECKPOINT_INTERVAL of them, or from the
    frame played last when jumping forward)."""
    global _REPLAYING
    system, first = run["system"], run["start"]
    begin = system.seek(frame - first)
    if begin == frame - first:
        return
    _REPLAYING = True
    try:
        for k in range(begin, frame - first):
            scene.frame_set(first + k + 1)  # step k takes the frame after the k-th
            system.step(body_arrays(obj, bpy.context.evaluated_depsgraph_get())[0])
    finally:
        _REPLAYING = False


@persistent
def on_frame_change(scene: bpy.types.Scene, depsgraph: Optional[bpy.types.Depsgraph] = None) -> None:
    if plumage is None or not _RUNS or _REPLAYING:
        return
    follow(scene, depsgraph or bpy.context.evaluated_depsgraph_get())


class PLUMAGE_OT_dress(bpy.types.Operator):
    bl_idname = "plumage.dress"
    bl_label = "Dress"
    bl_description = "Create feathers on the active mesh at the current frame"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return not _package_missing(cls) and context.object is not None and context.object.type == "MESH"

    def execute(self, context: bpy.types.Context) -> set:
        try:
            run = create_run(context, context.object)
        except (plumage.PlumageError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"{run['system'].feather_count} feathers")
        return {"FINISHED"}


class PLUMAGE_OT_bake(bpy.types.Operator):
    bl_idname = "plumage.bake"
    bl_label = "Bake frame range"
    bl_description = "Step the scene's frame range and store every frame's feathers in the cache file"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return not _package_missing(cls) and context.object is not None and context.object.name in _RUNS

    def execute(self, context: bpy.types.Context) -> set:
        obj, scene = context.object, context.scene
        run = _RUNS[obj.name]
        frames, positions = [], []
        scene.frame_set(scene.frame_start)
        if scene.frame_start >= run["start"]:
            replay_to(scene, obj, run, scene.frame_start)
        else:
            run["system"].evaluate(body_arrays(obj, context.evaluated_depsgraph_get())[0])
        run["frame"] = scene.frame_start
        for frame in range(scene.frame_start, scene.frame_end + 1):
            scene.frame_set(frame)  # the handler steps the system
            frames.append(frame)
            positions.append(run["system"].feather_geometry().positions.copy())
        geo = run["system"].feather_geometry()
        path = bpy.path.abspath(obj.plumage.cache_path)
        os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
        np.savez(path, frames=np.array(frames), positions=np.stack(positions), triangles=geo.triangles, uvs=geo.uvs, ids=geo.ids)
        run["cache"] = {"frames": frames, "positions": positions}
        obj.plumage.use_cache = True
        self.report({"INFO"}, f"baked {len(frames)} frames to {path}")
        return {"FINISHED"}


class PLUMAGE_PT_panel(bpy.types.Panel):
    bl_label = "Plumage"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return context.object is not None and context.object.type == "MESH"

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        if plumage is None:
            layout.label(text="The plumage package is missing:", icon="ERROR")
            for part in IMPORT_ERROR.split("; "):
                layout.label(text=part)
            return
        props = context.object.plumage
        layout.prop(props, "preset", expand=True)
        layout.prop(props, "shaft_segments")
        layout.prop(props, "density", expand=True)
        layout.prop(props, "target_feathers" if props.density == "COUNT" else "spacing")
        row = layout.row()
        row.prop(props, "feather_length")
        row.prop(props, "feather_width")
        layout.prop(props, "flow")
        if props.flow != "AUTO":
            layout.prop(props, "flow_axis" if props.flow == "AXIS" else "flow_attribute")
        layout.prop(props, "spacing_map")
        layout.prop(props, "length_map")
        layout.prop(props, "width_map")
        layout.prop(props, "mode")
        row = layout.row()
        row.prop(props, "seed")
        row.prop(props, "threads")
        layout.operator("plumage.dress")
        layout.prop(props, "cache_path")
        layout.prop(props, "use_cache")
        layout.operator("plumage.bake")


CLASSES = (PlumageSettings, PLUMAGE_OT_dress, PLUMAGE_OT_bake, PLUMAGE_PT_panel)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.plumage = PointerProperty(type=PlumageSettings)
    bpy.app.handlers.frame_change_post.append(on_frame_change)


def unregister() -> None:
    if on_frame_change in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.remove(on_frame_change)
    for run in _RUNS.values():
        run["system"].close()
    _RUNS.clear()
    del bpy.types.Object.plumage
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
