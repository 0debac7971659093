"""Plumage for Blender: dresses a whole character (every mesh an armature
deforms, the objects parented to its bones, or the selected meshes) with one
coat of collision-free feathers or scales, follows the animation while
scrubbing, and bakes a frame range to a point cache that Blender's Mesh Cache
modifier plays without the library.

Needs the `plumage` Python package in Blender's Python:
`python -m plumage.blender_install` (from the environment where
`pip install ./python` put it) copies it, with the library, into Blender's
user modules folder. The panel is in the Properties editor, Object tab,
"Plumage".
"""

from __future__ import annotations

bl_info = {
    "name": "Plumage feathers",
    "author": "Plumage",
    "version": (0, 2, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Object > Plumage",
    "description": "Collision-free feathers and scales on animated meshes",
    "category": "Object",
}

import json
import os
import uuid
from typing import Any, Dict, List, Optional, Tuple

import bpy
import numpy as np
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, PointerProperty, StringProperty

from . import jobs, pointcache

try:
    import plumage
except Exception as e:  # ImportError, or OSError when the library inside it does not load: the panel and the operators say so
    plumage = None
    IMPORT_ERROR = (
        f"the plumage Python package cannot be imported in Blender's Python ({type(e).__name__}: {e}): "
        "run `python -m plumage.blender_install [--blender PATH]` where `pip install ./python` installed it; "
        f"or install it into {bpy.utils.user_resource('SCRIPTS', path='modules')} (pip install ./python --no-deps --target DIR); "
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


# dressed object (an armature or a mesh) name -> live state: the System,
# its last frame, the dressed frame, the feathers object, the source meshes,
# and the token of the Dress that made it (also kept on the object as
# RUN_PROPERTY, so that an undo that takes the object back to before that
# Dress shows: the object's token is no longer the run's)
_RUNS: Dict[str, Dict[str, Any]] = {}

# runs an undo (or redo) took out of the file, by token: a redo (or undo)
# that brings their token back makes them live again; at most PARKED_MAX
# are kept (the oldest closed first)
_PARKED: Dict[str, Dict[str, Any]] = {}
PARKED_MAX = 2
RUN_PROPERTY = "plumage_run"
VALIDATION_PROPERTY = "plumage_validation"

# Frames between two kept states of a dressed object: a jump replays at
# most this many frames.
CHECKPOINT_INTERVAL = 8

# Set while a jump replays frames or a bake steps them (the frame changes
# they make are not followed again).
_REPLAYING = False

CACHE_MODIFIER = "Plumage cache"
MATERIAL_NAME = "Plumage feathers"


def is_feathers(obj: bpy.types.Object) -> bool:
    return bool(obj.get("plumage_feathers_of"))


def is_hidden(obj: bpy.types.Object) -> bool:
    """Hidden in the viewport (the object's own switch, or hidden in the view
    layer, or not in the view layer at all)."""
    if obj.hide_viewport:
        return True
    try:
        return bool(obj.hide_get())
    except RuntimeError:  # not in the view layer: not shown either
        return True


def dress_sources(context: bpy.types.Context, obj: bpy.types.Object) -> List[bpy.types.Object]:
    """The meshes one coat covers, in name order: for an armature every mesh
    its Armature modifiers name and every mesh below it in the hierarchy
    (parented to a bone or not); for a mesh the selected meshes and it.
    Hidden meshes (hide_viewport, or hidden in the view layer) are left out,
    except the active mesh itself."""
    if obj.type == "ARMATURE":
        found = {o for o in obj.children_recursive if o.type == "MESH"}
        for o in context.scene.objects:
            if o.type == "MESH" and any(m.type == "ARMATURE" and m.object == obj for m in o.modifiers):
                found.add(o)
    else:
        found = {o for o in context.selected_objects if o.type == "MESH"} | {obj}
    return sorted((o for o in found if not is_feathers(o) and (o is obj or not is_hidden(o))), key=lambda o: o.name)


def world_arrays(
    objects: List[bpy.types.Object], depsgraph: bpy.types.Depsgraph, triangles: bool = True
) -> Tuple[np.ndarray, Optional[np.ndarray], List[int]]:
    """(positions (n, 3) in world space, triangles (m, 3) or None, vertex
    count of each object) of the evaluated meshes, one after the other: what
    the library sees as one body. An object parented to a bone moves with it
    (its evaluated world matrix)."""
    positions, tris, counts = [], [], []
    offset = 0
    for obj in objects:
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        try:
            n = len(mesh.vertices)
            co = np.empty(3 * n, dtype=np.float32)
            mesh.vertices.foreach_get("co", co)
            if triangles:
                mesh.calc_loop_triangles()
                t = np.empty(3 * len(mesh.loop_triangles), dtype=np.int64)
                mesh.loop_triangles.foreach_get("vertices", t)
                tris.append(t.reshape(-1, 3) + offset)
            m = np.array(evaluated.matrix_world, dtype=np.float64)
        finally:
            evaluated.to_mesh_clear()
        positions.append(co.reshape(-1, 3).astype(np.float64) @ m[:3, :3].T + m[:3, 3])
        counts.append(n)
        offset += n
    pos = np.concatenate(positions).astype(np.float32) if positions else np.zeros((0, 3), np.float32)
    return pos, (np.concatenate(tris) if tris else np.zeros((0, 3), np.int64)) if triangles else None, counts


def body_arrays(obj: bpy.types.Object, depsgraph: bpy.types.Depsgraph) -> tuple:
    """(positions (n, 3), triangles (m, 3)) of one evaluated mesh in world space."""
    pos, tris, _ = world_arrays([obj], depsgraph)
    return pos, tris


def vertex_map(mesh: bpy.types.Mesh, spec: str, components: int) -> Optional[np.ndarray]:
    """A per-vertex map from attribute NAME or NAME:C (as the C++ host reads them)."""
    if not spec:
        return None
    name, _, comp = spec.partition(":")
    first = int(comp) if comp else 0
    attr = mesh.attributes.get(name)
    if attr is None:
        raise ValueError(f"the mesh {mesh.name!r} has no attribute {name!r}")
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


def dress_armature(obj: bpy.types.Object, sources: List[bpy.types.Object]) -> Optional[bpy.types.Object]:
    """The armature whose skeleton the coat follows: the dressed armature, or
    the one a dressed mesh's Armature modifier (else its parent) names."""
    if obj.type == "ARMATURE":
        return obj
    for o in [obj] + [s for s in sources if s is not obj]:
        for m in o.modifiers:
            if m.type == "ARMATURE" and m.object is not None and m.object.type == "ARMATURE":
                return m.object
        if o.parent is not None and o.parent.type == "ARMATURE":
            return o.parent
    return None


SKELETON_UP_FORWARD = np.array([0.0, -1.0, 1.0])  # Blender's up (+Z) and forward (-Y): where the head is looked for
MAX_INFLUENCES = 16


def armature_skeleton(arm: bpy.types.Object, sources: List[bpy.types.Object], counts: List[int]) -> Optional[Dict[str, Any]]:
    """`plumage.System(skeleton=...)` for the meshes `sources` bound to `arm`,
    or None when no vertex is bound to a bone (or a modifier changes a
    mesh's vertex count, so that vertex groups no longer name its vertices).

    Joints: every bone's head, in world space, as posed at the current frame
    (the frame the coat is dressed at, so in the space of the dressed
    positions; the rest pose when the armature stands in it), parents the
    parent bones; plus the tail of each bone no connected child continues
    from (its parent that bone), so that a limb's or the neck's last bone
    still has a direction. Weights:
    per vertex, the vertex groups named after deforming bones, normalised
    (the 16 largest at most); a mesh parented to a bone without such groups
    rides that bone (weight 1). The head is the end joint farthest up and
    forward (Blender: +Z, -Y)."""
    bones = list(arm.data.bones)
    if not bones:
        return None
    index = {b.name: k for k, b in enumerate(bones)}
    world = np.array(arm.matrix_world, dtype=np.float64)
    pose = arm.pose.bones

    def to_world(v: Any) -> List[float]:
        return list(world[:3, :3] @ np.array(v, dtype=np.float64) + world[:3, 3])

    positions = [to_world(pose[b.name].head) for b in bones]
    parents = [index[b.parent.name] if b.parent is not None else -1 for b in bones]
    for k, b in enumerate(bones):
        if not any(c.use_connect for c in b.children):  # no child continues from its tail
            positions.append(to_world(pose[b.name].tail))
            parents.append(k)
    per_vertex: List[List[Tuple[int, float]]] = []
    for src, n in zip(sources, counts):
        if len(src.data.vertices) != n:
            return None
        group_joint = {g.index: index[g.name] for g in src.vertex_groups if g.name in index and bones[index[g.name]].use_deform}
        rider = index.get(src.parent_bone) if src.parent is arm and src.parent_type == "BONE" else None
        for v in src.data.vertices:
            inf = [(group_joint[g.group], float(g.weight)) for g in v.groups if g.group in group_joint and g.weight > 0]
            if not inf and rider is not None:
                inf = [(rider, 1.0)]
            inf.sort(key=lambda jw: -jw[1])
            per_vertex.append(inf[:MAX_INFLUENCES])
    if not any(per_vertex):
        return None
    width = max(1, max(len(inf) for inf in per_vertex))
    joints = np.zeros((len(per_vertex), width), np.uint32)
    weights = np.zeros((len(per_vertex), width), np.float32)
    for v, inf in enumerate(per_vertex):
        total = sum(w for _, w in inf)
        for k, (j, w) in enumerate(inf):
            joints[v, k], weights[v, k] = j, w / total
    positions_arr = np.array(positions, np.float32)
    parents_arr = np.array(parents, np.int32)
    return {"joint_positions": positions_arr, "joint_parents": parents_arr, "vertex_joints": joints, "vertex_weights": weights,
            "head_joint": skeleton_head(positions_arr, parents_arr, joints, weights)}


def skeleton_head(positions: np.ndarray, parents: np.ndarray, joints: np.ndarray, weights: np.ndarray) -> int:
    """The end joint (one bone attached) farthest up and forward among the
    joints the library keeps (weighted, or below a weighted joint)."""
    n = len(parents)
    weighted = np.zeros(n, bool)
    weighted[joints[weights > 0]] = True
    kept = weighted.copy()
    for _ in range(n):  # down the trees: a joint below a kept one is kept
        below = ~kept & (parents >= 0)
        grow = below.copy()
        grow[below] = kept[parents[below]]
        if not grow.any():
            break
        kept |= grow
    degree = np.zeros(n, int)
    for j in range(n):
        if kept[j] and parents[j] >= 0 and kept[parents[j]]:
            degree[j] += 1
            degree[parents[j]] += 1
    ends = [j for j in range(n) if kept[j] and degree[j] <= 1]
    if not ends:
        return -1
    return int(max(ends, key=lambda j: (float(positions[j].astype(np.float64) @ SKELETON_UP_FORWARD), -j)))


def front_source(positions: np.ndarray) -> Tuple[float, float, float]:
    """The front-most vertex (Blender models face -Y; the first of equals): feathers flow away from it."""
    return tuple(float(x) for x in positions[int(np.argmax(-positions[:, 1]))])  # type: ignore[return-value]


def layer_map(sources: List[bpy.types.Object], counts: List[int], group: str, field: str = "Layer group") -> Optional[np.ndarray]:
    """Per vertex its weight in the vertex group `group` (0 outside it or on a mesh without it): the painted layer."""
    if not group:
        return None
    if not any(group in src.vertex_groups for src in sources):
        raise ValueError(f"no dressed mesh has a vertex group {group!r} ({field})")
    parts = []
    for src, n in zip(sources, counts):
        if len(src.data.vertices) != n:
            raise ValueError(f"{src.name!r}: the modifiers change the vertex count ({len(src.data.vertices)} -> {n}): the {field.lower()} cannot be read")
        values = np.zeros(n, np.float32)
        g = src.vertex_groups.get(group)
        if g is not None:
            for v in src.data.vertices:
                for e in v.groups:
                    if e.group == g.index:
                        values[v.index] = e.weight
        parts.append(values)
    return np.concatenate(parts)


# the types a Type group chooses between: weight < 0.5 feathers, >= 0.5 scales
TYPE_GROUP_TYPES = ("feathers", "scales")


def type_map(sources: List[bpy.types.Object], counts: List[int], group: str) -> Optional[np.ndarray]:
    """Per vertex the feather type the vertex group `group` paints: 0
    (feathers) where its weight is below 0.5 (or outside it), 1 (scales) where
    it is 0.5 or more; an index into TYPE_GROUP_TYPES."""
    weights = layer_map(sources, counts, group, "Type group")
    return None if weights is None else (weights >= 0.5).astype(np.uint32)


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


def dress_inputs(context: bpy.types.Context, obj: bpy.types.Object) -> Dict[str, Any]:
    """Everything `plumage.System` takes for the coat of `obj`, read at the
    current frame: the world-space concatenation of its source meshes, the
    maps of each (attributes of the same name on every mesh) and the
    configuration from its panel."""
    props = obj.plumage
    sources = dress_sources(context, obj)
    if not sources:
        raise ValueError(f"{obj.name!r}: no mesh to dress (an armature dresses the meshes it deforms or that are parented to it)")
    depsgraph = context.evaluated_depsgraph_get()
    positions, triangles, counts = world_arrays(sources, depsgraph)
    maps: Dict[str, Any] = {}
    for key, spec, width in (("spacing_scale", props.spacing_map, 1), ("length_scale", props.length_map, 1), ("width_scale", props.width_map, 1),
                             ("orientations", props.flow_attribute if props.flow == "ATTRIBUTE" else "", 3)):
        if not spec:
            maps[key] = None
            continue
        parts = []
        for src, n in zip(sources, counts):
            if len(src.data.vertices) != n:
                raise ValueError(f"{src.name!r}: the modifiers change the vertex count ({len(src.data.vertices)} -> {n}): maps cannot be read")
            part = vertex_map(src.data, spec, width)
            if width == 3:  # directions into world space, as the positions
                part = part @ np.array(src.matrix_world, dtype=np.float32)[:3, :3].T
            parts.append(part)
        maps[key] = np.ascontiguousarray(np.concatenate(parts), dtype=np.float32)
    maps["layer"] = layer_map(sources, counts, props.layer_group)
    maps["feather_type"] = type_map(sources, counts, props.type_group)
    config = system_config(props)
    # the flow: the armature's bones unless another is chosen; without a
    # bound armature, away from the front-most vertex
    flow_from = {"AXIS": "axis", "ATTRIBUTE": "attribute", "AUTO": "mesh"}.get(props.flow, "front")
    skeleton = None
    if props.flow == "SKELETON":
        arm = dress_armature(obj, sources)
        skeleton = armature_skeleton(arm, sources, counts) if arm is not None else None
        flow_from = "skeleton" if skeleton is not None else "front"
    if flow_from == "front" and len(positions):
        config["flow_source"] = front_source(positions)
    return {"positions": positions, "triangles": triangles, "counts": counts, "sources": [o.name for o in sources],
            "maps": maps, "skeleton": skeleton, "flow_from": flow_from, "config": config, "frame": context.scene.frame_current}


def make_system(inputs: Dict[str, Any], progress: Any = None) -> Any:
    maps = {k: v for k, v in inputs["maps"].items() if v is not None}
    if inputs.get("skeleton") is not None:
        maps["skeleton"] = inputs["skeleton"]
    if "feather_type" in maps:
        maps["feather_types"] = TYPE_GROUP_TYPES
    return plumage.System(inputs["positions"], inputs["triangles"], progress=progress, **maps, **inputs["config"])


def feathers_object(key_obj: bpy.types.Object, collections: Any = None) -> bpy.types.Object:
    """`<name>_feathers`: one mesh in world space (identity transform, no
    parent) holding the whole coat."""
    name = key_obj.name + "_feathers"
    obj = bpy.data.objects.get(name)
    if obj is None:
        obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
        for coll in collections or key_obj.users_collection:
            coll.objects.link(obj)
    obj["plumage_feathers_of"] = key_obj.name
    key_obj.plumage.feathers_object = obj.name
    return obj


def feather_random(ids: np.ndarray) -> np.ndarray:
    """A value in [0, 1) per feather id (splitmix64 of the id): the same
    feather gets the same value on every frame, in every run."""
    with np.errstate(over="ignore"):
        z = ids.astype(np.uint64) + np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = z ^ (z >> np.uint64(31))
    return ((z >> np.uint64(40)).astype(np.float64) / float(1 << 24)).astype(np.float32)


def _point_attribute(mesh: bpy.types.Mesh, name: str, kind: str, values: np.ndarray) -> None:
    attr = mesh.attributes.get(name) or mesh.attributes.new(name, kind, "POINT")
    attr.data.foreach_set("vector" if kind == "FLOAT_VECTOR" else "value", values.ravel())


def write_feather_mesh(obj: bpy.types.Object, geo: Any, topology: bool, roots: Optional[np.ndarray] = None) -> None:
    """Writes the coat's vertices; with `topology` also its triangles, the
    vane UVs and the per-vertex attributes shaders read: `feather_index`,
    the feather's 64-bit id as `feather_id_lo`/`feather_id_hi` (its two
    32-bit halves as signed ints), `feather_random` in [0, 1),
    `feather_root` (the root at the dressed frame), `feather_u` (0 at the
    root to 1 at the tip) and `feather_v` (0 to 1 across the vanes)."""
    mesh = obj.data
    if topology:
        mesh.clear_geometry()
        for attr in [a.name for a in mesh.attributes if a.name.startswith("feather_")]:
            mesh.attributes.remove(mesh.attributes[attr])
        mesh.vertices.add(len(geo.positions))
        mesh.loops.add(3 * len(geo.triangles))
        mesh.polygons.add(len(geo.triangles))
        mesh.loops.foreach_set("vertex_index", geo.triangles.astype(np.int32).ravel())
        mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(geo.triangles), 3, dtype=np.int32))
        mesh.polygons.foreach_set("loop_total", np.full(len(geo.triangles), 3, dtype=np.int32))
        uv = mesh.uv_layers.get("UVMap") or mesh.uv_layers.new(name="UVMap")
        uv.data.foreach_set("uv", geo.uvs[geo.triangles.ravel()].astype(np.float32).ravel())
        fi = geo.feather_index.astype(np.intp)
        ids = geo.ids.astype(np.uint64)[fi]
        _point_attribute(mesh, "feather_index", "INT", geo.feather_index.astype(np.int32))
        _point_attribute(mesh, "feather_id_lo", "INT", (ids & np.uint64(0xFFFFFFFF)).astype(np.uint32).view(np.int32))
        _point_attribute(mesh, "feather_id_hi", "INT", (ids >> np.uint64(32)).astype(np.uint32).view(np.int32))
        _point_attribute(mesh, "feather_random", "FLOAT", feather_random(geo.ids)[fi])
        if roots is not None:
            _point_attribute(mesh, "feather_root", "FLOAT_VECTOR", np.ascontiguousarray(roots, dtype=np.float32)[fi])
        _point_attribute(mesh, "feather_u", "FLOAT", np.ascontiguousarray(geo.uvs[:, 0], dtype=np.float32))
        _point_attribute(mesh, "feather_v", "FLOAT", np.ascontiguousarray(geo.uvs[:, 1], dtype=np.float32))
        if not mesh.materials:
            mesh.materials.append(default_material())
    mesh.vertices.foreach_set("co", geo.positions.astype(np.float32).ravel())
    mesh.update()


def default_material() -> bpy.types.Material:
    """A Principled BSDF shaded from the vane UVs: darker at the root, lighter
    at the tip (a ramp over u), a darker shaft (v near 0.5), and a little
    variation per feather (`feather_random`)."""
    mat = bpy.data.materials.get(MATERIAL_NAME)
    if mat is not None:
        return mat
    mat = bpy.data.materials.new(MATERIAL_NAME)
    mat.use_nodes = True
    mat.diffuse_color = (0.45, 0.3, 0.18, 1.0)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = "UVMap"
    split = nodes.new("ShaderNodeSeparateXYZ")
    links.new(uv.outputs["UV"], split.inputs["Vector"])
    along = nodes.new("ShaderNodeValToRGB")  # root to tip
    along.color_ramp.elements[0].color = (0.12, 0.07, 0.04, 1.0)
    along.color_ramp.elements[1].color = (0.62, 0.42, 0.24, 1.0)
    links.new(split.outputs["X"], along.inputs["Fac"])
    shaft = nodes.new("ShaderNodeMath")  # |v - 0.5|: 0 on the shaft, 0.5 at the vane's edges
    shaft.operation = "SUBTRACT"
    shaft.inputs[1].default_value = 0.5
    links.new(split.outputs["Y"], shaft.inputs[0])
    edge = nodes.new("ShaderNodeMath")
    edge.operation = "ABSOLUTE"
    links.new(shaft.outputs[0], edge.inputs[0])
    across = nodes.new("ShaderNodeMapRange")
    across.inputs["From Min"].default_value = 0.0
    across.inputs["From Max"].default_value = 0.06
    links.new(edge.outputs[0], across.inputs["Value"])
    vane = nodes.new("ShaderNodeMixRGB")
    vane.blend_type = "MULTIPLY"
    links.new(across.outputs["Result"], vane.inputs["Fac"])
    links.new(along.outputs["Color"], vane.inputs["Color1"])
    links.new(along.outputs["Color"], vane.inputs["Color2"])
    vary = nodes.new("ShaderNodeAttribute")
    vary.attribute_name = "feather_random"
    tint = nodes.new("ShaderNodeMixRGB")
    tint.blend_type = "MIX"
    tint.inputs["Color2"].default_value = (0.3, 0.2, 0.12, 1.0)
    scale = nodes.new("ShaderNodeMath")
    scale.operation = "MULTIPLY"
    scale.inputs[1].default_value = 0.35
    links.new(vary.outputs["Fac"], scale.inputs[0])
    links.new(scale.outputs[0], tint.inputs["Fac"])
    links.new(vane.outputs["Color"], tint.inputs["Color1"])
    links.new(tint.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.55
    return mat


def install_run(context: bpy.types.Context, obj: bpy.types.Object, system: Any, inputs: Dict[str, Any]) -> Dict[str, Any]:
    """Makes `system` (created from `inputs`) the live coat of `obj`: writes
    the feathers object and follows the frames from now on."""
    target = feathers_object(obj)
    remove_cache_modifier(target)
    obj.plumage.use_cache = False
    write_feather_mesh(target, system.feather_geometry(), topology=True, roots=system.feathers()["root"])
    obj.plumage.sources = "\n".join(inputs["sources"])
    token = uuid.uuid4().hex
    obj[RUN_PROPERTY] = token
    run = {"system": system, "frame": inputs["frame"], "start": inputs["frame"], "target": target.name, "sources": list(inputs["sources"]),
           "counts": list(inputs["counts"]), "inputs": inputs, "token": token, "object": obj.name}
    old = _RUNS.pop(obj.name, None)
    if old and old["system"] is not system:
        park(old)  # an undo of this Dress brings it back
    _RUNS[obj.name] = run
    record_validation(obj, run)
    return run


def record_validation(obj: bpy.types.Object, run: Dict[str, Any]) -> Optional[Dict[str, Any]]:
    """Validates the live system at its frame and keeps the figures the panel
    shows on the object (saved with the file)."""
    v = run["system"].validate()
    if v is None:
        return None
    figures = {"frame": int(run["frame"]), "pairs": int(v.intersecting_pairs), "penetrations": int(v.body_penetrations),
               "coverage": float(v.coverage), "discord_percent": float(v.discord_percent)}
    obj[VALIDATION_PROPERTY] = figures
    return figures


def validation_text(obj: bpy.types.Object) -> List[str]:
    """The panel's lines for the last validation of `obj`'s coat (none yet: no lines)."""
    v = obj.get(VALIDATION_PROPERTY)
    if v is None:
        return []
    return [f"Validated at frame {v['frame']}: {v['pairs']} pairs, {v['penetrations']} penetrations",
            f"coverage {v['coverage']:.3f}, discord {v['discord_percent']:.1f}%"]


def park(run: Dict[str, Any]) -> None:
    """Takes a run out of the live ones and keeps it (closed when more than PARKED_MAX are kept)."""
    _PARKED[run["token"]] = run
    while len(_PARKED) > PARKED_MAX:
        oldest = next(iter(_PARKED))
        _PARKED.pop(oldest)["system"].close()


def sync_runs() -> List[str]:
    """After an undo or redo: a live run whose object no longer carries its
    token (the Dress that made it was undone) is dropped from the live ones
    (parked for a redo); a parked run whose token the object carries again
    is live again, its feathers brought to the scene's frame. Returns what
    changed, for messages and tests."""
    changed = []
    names = set(_RUNS) | {r["object"] for r in _PARKED.values()}
    for name in sorted(names):
        obj = bpy.data.objects.get(name)
        token = obj.get(RUN_PROPERTY) if obj is not None else None
        live = _RUNS.get(name)
        if live is not None and live["token"] != token:
            park(_RUNS.pop(name))
            changed.append(f"dropped {name}")
        if name not in _RUNS and token is not None and token in _PARKED:
            run = _PARKED.pop(token)
            target = bpy.data.objects.get(run["target"])
            if target is None:
                run["system"].close()
                continue
            _RUNS[name] = run
            changed.append(f"restored {name}")
    return changed


def create_run(context: bpy.types.Context, obj: bpy.types.Object) -> Dict[str, Any]:
    inputs = dress_inputs(context, obj)
    return install_run(context, obj, make_system(inputs), inputs)


def run_positions(run: Dict[str, Any], depsgraph: bpy.types.Depsgraph) -> np.ndarray:
    objects = []
    for name in run["sources"]:
        o = bpy.data.objects.get(name)
        if o is None:
            raise ValueError(f"the dressed mesh {name!r} is gone: dress again")
        objects.append(o)
    positions, _, counts = world_arrays(objects, depsgraph, triangles=False)
    if counts != run["counts"]:
        raise ValueError(f"the dressed meshes' vertex counts changed ({run['counts']} -> {counts}): dress again")
    return positions


def advance(scene: bpy.types.Scene, run: Dict[str, Any], frame: int) -> None:
    """Brings the live system to `frame`: a step when it is the next frame, a
    seek and replay for a jump at or after the dressed frame (what playback
    shows), a solve from scratch before it."""
    system = run["system"]
    if frame == run["frame"] + 1:
        system.step(run_positions(run, bpy.context.evaluated_depsgraph_get()))  # playing forward: the incremental path
    elif frame != run["frame"]:
        if frame >= run["start"]:
            replay_to(scene, run, frame)
        else:
            system.evaluate(run_positions(run, bpy.context.evaluated_depsgraph_get()))
    run["frame"] = frame


def follow(scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph) -> None:
    """Updates every dressed object to the scene's frame (not those playing
    their cache: the Mesh Cache modifier does)."""
    for name, run in list(_RUNS.items()):
        obj = bpy.data.objects.get(name)
        target = bpy.data.objects.get(run["target"])
        if obj is None or target is None:
            _RUNS.pop(name)["system"].close()
            continue
        if obj.plumage.use_cache and target.modifiers.get(CACHE_MODIFIER) is not None:
            continue
        try:
            advance(scene, run, scene.frame_current)
        except (ValueError, plumage.PlumageError) as e:
            print(f"Plumage: {name}: {e}")
            _RUNS.pop(name)["system"].close()
            continue
        write_feather_mesh(target, run["system"].feather_geometry(), topology=False)


def replay_to(scene: bpy.types.Scene, run: Dict[str, Any], frame: int) -> None:
    """Brings the system to what playing from the dressed frame to `frame`
    gives: back to the nearest kept state (seek), then the frames between
    stepped one by one (at most CHECKPOINT_INTERVAL of them, or from the
    frame played last when jumping forward)."""
    global _REPLAYING
    system, first = run["system"], run["start"]
    begin = system.seek(frame - first)
    if begin == frame - first:
        return
    was, _REPLAYING = _REPLAYING, True
    try:
        for k in range(begin, frame - first):
            scene.frame_set(first + k + 1)  # step k takes the frame after the k-th
            system.step(run_positions(run, bpy.context.evaluated_depsgraph_get()))
    finally:
        _REPLAYING = was


@persistent
def on_frame_change(scene: bpy.types.Scene, depsgraph: Optional[bpy.types.Depsgraph] = None) -> None:
    if plumage is None or not _RUNS or _REPLAYING:
        return
    follow(scene, depsgraph or bpy.context.evaluated_depsgraph_get())


@persistent
def on_undo_redo(*_args: Any) -> None:
    """bpy.app.handlers.undo_post / redo_post: the live systems follow the file's state."""
    if plumage is None or not (_RUNS or _PARKED):
        return
    changed = sync_runs()
    restored = [c.split(" ", 1)[1] for c in changed if c.startswith("restored ")]
    if restored and not _REPLAYING:
        scene = bpy.context.scene
        for name in restored:
            run = _RUNS.get(name)
            target = bpy.data.objects.get(run["target"]) if run else None
            if run is None or target is None:
                continue
            try:
                advance(scene, run, scene.frame_current)
                write_feather_mesh(target, run["system"].feather_geometry(), topology=False)
            except (ValueError, plumage.PlumageError) as e:
                print(f"Plumage: {name}: {e}")
                _RUNS.pop(name)["system"].close()


@persistent
def on_load_pre(*_args: Any) -> None:
    """Another file: its objects are not these; the live systems go."""
    for run in list(_RUNS.values()) + list(_PARKED.values()):
        try:
            run["system"].close()
        except Exception:
            pass
    _RUNS.clear()
    _PARKED.clear()


# -- the point cache ---------------------------------------------------------


def remove_cache_modifier(target: bpy.types.Object) -> None:
    mod = target.modifiers.get(CACHE_MODIFIER)
    if mod is not None:
        target.modifiers.remove(mod)


def cache_modifier(target: bpy.types.Object, path: str, first_frame: int) -> bpy.types.Modifier:
    """The Mesh Cache modifier that plays the .pc2: sample k at scene frame
    `first_frame + k` (held before and after the range), replacing the
    vertices (the feathers object sits at the identity, the cache holds world
    space)."""
    mod = target.modifiers.get(CACHE_MODIFIER) or target.modifiers.new(CACHE_MODIFIER, "MESH_CACHE")
    mod.cache_format = "PC2"
    mod.filepath = path
    mod.time_mode = "FRAME"
    mod.play_mode = "SCENE"
    mod.frame_start = float(first_frame)
    mod.frame_scale = 1.0
    mod.interpolation = "NONE"
    mod.deform_mode = "OVERWRITE"
    mod.factor = 1.0
    mod.forward_axis, mod.up_axis = "POS_Y", "POS_Z"  # no axis conversion
    return mod


def _use_cache_changed(props: "PlumageSettings", context: bpy.types.Context) -> None:
    target = bpy.data.objects.get(props.feathers_object)
    mod = target.modifiers.get(CACHE_MODIFIER) if target is not None else None
    if mod is not None:
        mod.show_viewport = mod.show_render = props.use_cache


def bake(context: bpy.types.Context, obj: bpy.types.Object) -> Dict[str, Any]:
    """Steps the scene's frame range, writes every frame's feathers to the
    .pc2 at `cache_path` and, beside it (`<cache>.plumage.npz`), what
    rebuilds the live system: the dressed frame's inputs and the state
    bytes at the last baked frame. Attaches the Mesh Cache modifier and
    turns "Play from cache" on. Returns what was written."""
    global _REPLAYING
    scene, props = context.scene, obj.plumage
    if props.cache_path.startswith("//") and not bpy.data.filepath:
        raise ValueError(f"the cache {props.cache_path} is relative to the .blend: save the file first, or give an absolute path")
    run = _RUNS[obj.name]
    target = bpy.data.objects[run["target"]]
    frames, positions = [], []
    was, _REPLAYING = _REPLAYING, True  # this loop steps the system itself
    try:
        for frame in range(scene.frame_start, scene.frame_end + 1):
            scene.frame_set(frame)
            advance(scene, run, frame)
            frames.append(frame)
            positions.append(run["system"].feather_geometry().positions.copy())
        state = run["system"].save_state()
    finally:
        _REPLAYING = was
    path = bpy.path.abspath(props.cache_path)
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    pointcache.write_pc2(path, positions, start_frame=frames[0], sample_rate=1.0)
    inputs = run["inputs"]
    maps = {f"map_{k}": v for k, v in inputs["maps"].items() if v is not None}
    if inputs.get("skeleton") is not None:
        maps.update({f"skeleton_{k}": np.asarray(v) for k, v in inputs["skeleton"].items()})
    np.savez(pointcache.sidecar_path(path), positions=inputs["positions"], triangles=inputs["triangles"], counts=np.array(inputs["counts"]),
             sources=np.array(inputs["sources"]), config=np.array(json.dumps(inputs["config"])), dressed_frame=inputs["frame"],
             frames=np.array(frames), state=np.frombuffer(state, dtype=np.uint8), state_frame=frames[-1], **maps)
    record_validation(obj, run)
    cache_modifier(target, props.cache_path, frames[0])
    props.use_cache = True
    _use_cache_changed(props, context)
    write_feather_mesh(target, run["system"].feather_geometry(), topology=False)
    return {"path": path, "frames": frames}


def rebuild(context: bpy.types.Context, obj: bpy.types.Object) -> Dict[str, Any]:
    """The live system again, from the state kept beside the cache: created
    from the dressed frame's inputs (the same feathers, the library is
    deterministic) and resumed at the last baked frame (load_state). Scrubbing
    then seeks and replays from the dressed frame as before the save."""
    path = pointcache.sidecar_path(bpy.path.abspath(obj.plumage.cache_path))
    if not os.path.isfile(path):
        raise ValueError(f"no saved state at {path}: bake first")
    with np.load(path) as saved:
        maps = {k[len("map_"):]: saved[k] for k in saved.files if k.startswith("map_")}
        inputs = {"positions": saved["positions"], "triangles": saved["triangles"], "counts": [int(c) for c in saved["counts"]],
                  "sources": [str(s) for s in saved["sources"]], "config": json.loads(str(saved["config"])),
                  "maps": {k: maps.get(k) for k in ("spacing_scale", "length_scale", "width_scale", "orientations", "layer", "feather_type")},
                  "frame": int(saved["dressed_frame"])}
        skeleton = {k[len("skeleton_"):]: saved[k] for k in saved.files if k.startswith("skeleton_")}
        if skeleton:
            skeleton["head_joint"] = int(skeleton.get("head_joint", -1))
        inputs["skeleton"] = skeleton or None
        state, state_frame = saved["state"].tobytes(), int(saved["state_frame"])
    system = make_system(inputs)
    system.load_state(state)
    target = bpy.data.objects.get(obj.plumage.feathers_object) or feathers_object(obj)
    token = obj.get(RUN_PROPERTY) or uuid.uuid4().hex  # the saved Dress's: undoing later steps keeps it live
    obj[RUN_PROPERTY] = token
    run = {"system": system, "frame": state_frame, "start": inputs["frame"], "target": target.name, "sources": inputs["sources"],
           "counts": inputs["counts"], "inputs": inputs, "token": token, "object": obj.name}
    old = _RUNS.pop(obj.name, None)
    if old:
        old["system"].close()
    _RUNS[obj.name] = run
    return run


class PlumageSettings(bpy.types.PropertyGroup):
    density: EnumProperty(name="Density", items=[("COUNT", "Count", "A target feather count"), ("SPACING", "Spacing", "Root spacing")])
    target_feathers: IntProperty(name="Feathers", default=2000, min=1, max=10_000_000)
    spacing: FloatProperty(name="Spacing", default=0.05, min=1e-6, subtype="DISTANCE")
    feather_length: FloatProperty(name="Length", default=0.0, min=0.0, subtype="DISTANCE", description="0 = derived from the spacing")
    feather_width: FloatProperty(name="Width", default=0.0, min=0.0, subtype="DISTANCE", description="0 = derived from the spacing")
    flow: EnumProperty(
        name="Flow",
        items=[  # the numbers keep what files saved before Skeleton and Front meant
            ("SKELETON", "Skeleton", "Feathers follow the armature's bones from the head down the trunk and out along each limb "
             "(without an armature bound to the meshes: from the front)", 3),
            ("FRONT", "Front", "Feathers flow away from the front-most vertex (-Y) along the surface", 4),
            ("AXIS", "Axis", "Feathers point along this world axis (the coat is solved in world space)", 1),
            ("ATTRIBUTE", "Vertex attribute", "A per-vertex direction attribute", 2),
            ("AUTO", "Mesh axis", "The library derives the flow from the mesh's principal axis", 0),
        ],
        default="SKELETON",
    )
    flow_axis: EnumProperty(name="Axis", items=[(a, a, "") for a in ("X", "Y", "Z", "-X", "-Y", "-Z")], default="-Y")
    flow_attribute: StringProperty(name="Flow attribute", description="Vector attribute NAME or NAME:C")
    spacing_map: StringProperty(name="Spacing map", description="Attribute NAME or NAME:C (0 = bare skin)")
    length_map: StringProperty(name="Length map")
    width_map: StringProperty(name="Width map")
    layer_group: StringProperty(name="Layer group", description="Vertex group painting the layers: where neighbouring feathers' "
                                "weights differ, the higher lies on top (empty: no layers)")
    type_group: StringProperty(name="Type group", description="Vertex group choosing the feather type: feathers where its weight is "
                               "below 0.5 (or outside it), scales where it is 0.5 or more (empty: the preset everywhere)")
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
    cache_path: StringProperty(name="Cache", subtype="FILE_PATH", default="//plumage_cache.pc2",
                               description="The .pc2 point cache Bake writes (the state that rebuilds the live system goes beside it)")
    use_cache: BoolProperty(name="Play from cache", default=False, update=_use_cache_changed,
                            description="The Mesh Cache modifier plays the baked .pc2 (no library needed); off: the live system")
    feathers_object: StringProperty(name="Feathers object", description="The mesh that holds the coat")
    sources: StringProperty(name="Dressed meshes", description="The meshes of the coat, one name a line")


class PLUMAGE_OT_dress(bpy.types.Operator):
    bl_idname = "plumage.dress"
    bl_label = "Dress"
    bl_description = (
        "Create one coat of feathers at the current frame on the active armature's meshes (skinned to it or parented to it, "
        "bone-parented objects included) or on the selected meshes. From the panel it runs in the background "
        "with progress (Esc cancels)"
    )
    bl_options = {"REGISTER", "UNDO"}

    _job: Optional[jobs.DressJob] = None
    _timer: Any = None
    _inputs: Optional[Dict[str, Any]] = None

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return not _package_missing(cls) and context.object is not None and context.object.type in ("MESH", "ARMATURE")

    def execute(self, context: bpy.types.Context) -> set:
        try:
            run = create_run(context, context.object)
        except (plumage.PlumageError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"{run['system'].feather_count} feathers on {len(run['sources'])} meshes (flow: {run['inputs']['flow_from']})")
        return {"FINISHED"}

    def invoke(self, context: bpy.types.Context, event: Any) -> set:
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._start(context, context.object)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)  # progress and Esc seen within 0.1 s
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _start(self, context: bpy.types.Context, obj: bpy.types.Object) -> None:
        """Reads the inputs (here, on the main thread) and starts the create on a worker thread."""
        self._inputs = inputs = dress_inputs(context, obj)
        self._object = obj.name
        self._job = jobs.DressJob(lambda progress: make_system(inputs, progress))
        self._job.start()
        context.window_manager.progress_begin(0.0, 1.0)

    def _end(self, context: bpy.types.Context) -> None:
        wm = context.window_manager
        wm.progress_end()
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        if context.area is not None:
            context.area.header_text_set(None)

    def modal(self, context: bpy.types.Context, event: Any) -> set:
        job = self._job
        assert job is not None and self._inputs is not None
        if event.type not in ("TIMER", "ESC"):
            return {"PASS_THROUGH"}  # the interface stays responsive; the inputs are already copied
        status = job.tick(cancel_requested=event.type == "ESC")
        context.window_manager.progress_update(job.overall)
        if context.area is not None:
            context.area.header_text_set(f"Plumage: {job.phase} {100 * job.overall:.0f}% (Esc cancels)")
        if status == jobs.RUNNING:
            return {"RUNNING_MODAL"}
        self._end(context)
        if status == jobs.CANCELLED:
            self.report({"WARNING"}, "Dress cancelled: nothing changed")
            return {"CANCELLED"}
        if status == jobs.FAILED:
            self.report({"ERROR"}, str(job.error))
            return {"CANCELLED"}
        obj = bpy.data.objects.get(self._object)
        if obj is None:
            job.system.close()
            return {"CANCELLED"}
        run = install_run(context, obj, job.system, self._inputs)
        self.report({"INFO"}, f"{run['system'].feather_count} feathers on {len(run['sources'])} meshes (flow: {run['inputs']['flow_from']})")
        return {"FINISHED"}


class PLUMAGE_OT_bake(bpy.types.Operator):
    bl_idname = "plumage.bake"
    bl_label = "Bake frame range"
    bl_description = (
        "Step the scene's frame range, write every frame's feathers to the .pc2 point cache and play it with a Mesh Cache "
        "modifier (it plays after save and reopen without the library); the state that rebuilds the live system goes beside it"
    )

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return not _package_missing(cls) and context.object is not None and context.object.name in _RUNS

    def execute(self, context: bpy.types.Context) -> set:
        try:
            done = bake(context, context.object)
        except (plumage.PlumageError, ValueError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"baked {len(done['frames'])} frames to {done['path']}")
        return {"FINISHED"}


class PLUMAGE_OT_validate(bpy.types.Operator):
    bl_idname = "plumage.validate"
    bl_label = "Validate"
    bl_description = "Check the live coat at the current frame exactly: intersecting pairs, body penetrations, coverage and discord (shown in the panel)"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return not _package_missing(cls) and context.object is not None and context.object.name in _RUNS

    def execute(self, context: bpy.types.Context) -> set:
        figures = record_validation(context.object, _RUNS[context.object.name])
        if figures is None:
            self.report({"WARNING"}, "no feathers to validate")
            return {"CANCELLED"}
        self.report({"INFO"}, "; ".join(validation_text(context.object)))
        return {"FINISHED"}


class PLUMAGE_OT_rebuild(bpy.types.Operator):
    bl_idname = "plumage.rebuild"
    bl_label = "Rebuild live system"
    bl_description = "Recreate the live system from the state saved beside the cache (after reopening a file), resumed at the last baked frame"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return not _package_missing(cls) and context.object is not None and context.object.name not in _RUNS

    def execute(self, context: bpy.types.Context) -> set:
        try:
            run = rebuild(context, context.object)
        except (plumage.PlumageError, ValueError, OSError, KeyError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"live again at frame {run['frame']}: {run['system'].feather_count} feathers")
        return {"FINISHED"}


class PLUMAGE_PT_panel(bpy.types.Panel):
    bl_label = "Plumage"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return context.object is not None and context.object.type in ("MESH", "ARMATURE") and not is_feathers(context.object)

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        if plumage is None:
            box = layout.box()
            box.label(text="The plumage package is missing:", icon="ERROR")
            for part in IMPORT_ERROR.split("; "):
                box.label(text=part)
            return
        obj = context.object
        props = obj.plumage
        layout.prop(props, "preset", expand=True)
        layout.prop(props, "shaft_segments")
        layout.prop(props, "density", expand=True)
        layout.prop(props, "target_feathers" if props.density == "COUNT" else "spacing")
        row = layout.row()
        row.prop(props, "feather_length")
        row.prop(props, "feather_width")
        layout.prop(props, "flow")
        if props.flow in ("AXIS", "ATTRIBUTE"):
            layout.prop(props, "flow_axis" if props.flow == "AXIS" else "flow_attribute")
        layout.prop(props, "layer_group")
        layout.prop(props, "type_group")
        layout.prop(props, "spacing_map")
        layout.prop(props, "length_map")
        layout.prop(props, "width_map")
        layout.prop(props, "mode")
        row = layout.row()
        row.prop(props, "seed")
        row.prop(props, "threads")
        sources = [o.name for o in dress_sources(context, obj)]
        layout.label(text=f"Dresses {len(sources)} mesh{'es' if len(sources) != 1 else ''}: {', '.join(sources)[:80]}")
        layout.operator("plumage.dress")
        lines = validation_text(obj)
        if lines:
            box = layout.box()
            v = obj[VALIDATION_PROPERTY]
            icon = "CHECKMARK" if v["pairs"] == 0 and v["penetrations"] == 0 else "ERROR"
            for k, line in enumerate(lines):
                box.label(text=line, icon=icon if k == 0 else "NONE")
        if obj.name in _RUNS:
            layout.operator("plumage.validate")
        layout.prop(props, "cache_path")
        layout.prop(props, "use_cache")
        row = layout.row()
        row.operator("plumage.bake")
        if obj.name not in _RUNS and os.path.isfile(pointcache.sidecar_path(bpy.path.abspath(props.cache_path))):
            row.operator("plumage.rebuild")


CLASSES = (PlumageSettings, PLUMAGE_OT_dress, PLUMAGE_OT_bake, PLUMAGE_OT_validate, PLUMAGE_OT_rebuild, PLUMAGE_PT_panel)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.plumage = PointerProperty(type=PlumageSettings)
    bpy.app.handlers.frame_change_post.append(on_frame_change)
    bpy.app.handlers.load_pre.append(on_load_pre)
    bpy.app.handlers.undo_post.append(on_undo_redo)
    bpy.app.handlers.redo_post.append(on_undo_redo)


def unregister() -> None:
    if on_frame_change in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.remove(on_frame_change)
    if on_load_pre in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(on_load_pre)
    for handlers in (bpy.app.handlers.undo_post, bpy.app.handlers.redo_post):
        if on_undo_redo in handlers:
            handlers.remove(on_undo_redo)
    on_load_pre()
    del bpy.types.Object.plumage
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
