"""Run inside Blender (headless) by python/tests/test_blender.py:
    blender -b --factory-startup --python-exit-code 1 --python blender_run.py -- ADDON_ZIP OUT_DIR
Installs and enables the add-on, dresses a UV sphere animated by a shape key,
steps through the frames checking the library's validation at each, bakes the
range and renders one frame to OUT_DIR/frame.png. Prints one line
`PLUMAGE_RESULT {json}` for the test to read."""

import json
import math
import sys

import bpy
import numpy as np

addon_zip, out_dir = sys.argv[sys.argv.index("--") + 1 :][:2]

bpy.ops.preferences.addon_install(filepath=addon_zip, overwrite=True)
bpy.ops.preferences.addon_enable(module="plumage_feathers")
import plumage_feathers  # noqa: E402

assert plumage_feathers.plumage is not None, plumage_feathers.IMPORT_ERROR

# an empty scene with a UV sphere whose shape key bulges it over frames 1..6
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=1.0)
body = bpy.context.object
body.name = "Body"
body.shape_key_add(name="Basis")
bulge = body.shape_key_add(name="Bulge")
co = np.empty(3 * len(bulge.data), dtype=np.float32)
bulge.data.foreach_get("co", co)
co = co.reshape(-1, 3)
co *= (1.0 + 0.25 * np.clip(co[:, 2:3], 0, None))  # the upper half swells
co[:, 0] += 0.15 * co[:, 2] ** 2  # and leans
bulge.data.foreach_set("co", co.ravel())
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 6
bulge.value = 0.0
bulge.keyframe_insert("value", frame=1)
bulge.value = 1.0
bulge.keyframe_insert("value", frame=6)
scene.frame_set(1)

props = body.plumage
props.target_feathers = 800
props.threads = 2
props.flow = "AXIS"
props.flow_axis = "-Z"
bpy.context.view_layer.objects.active = body
assert bpy.ops.plumage.dress() == {"FINISHED"}
run = plumage_feathers._RUNS["Body"]
system = run["system"]
feathers_obj = bpy.data.objects["Body_feathers"]

result = {"feathers": system.feather_count, "frames": []}
playback = {}
for frame in range(1, 7):
    scene.frame_set(frame)
    playback[frame] = system.save_state()
    v = system.validate()
    geo = system.feather_geometry()
    shown = np.empty(3 * len(feathers_obj.data.vertices), dtype=np.float32)
    feathers_obj.data.vertices.foreach_get("co", shown)
    result["frames"].append({
        "frame": frame,
        "frame_index": system.frame_stats().frame_index,
        "intersecting_pairs": v.intersecting_pairs,
        "body_penetrations": v.body_penetrations,
        "coverage": v.coverage,
        "mesh_matches": bool(np.array_equal(shown, geo.positions.ravel())),
    })

# scrubbing: a jump seeks back to a kept state and replays; it shows what
# playback showed, byte for byte
scene.frame_set(3)
result["scrub_back_frame_index"] = system.frame_stats().frame_index
result["scrub_back_valid"] = system.validate().intersecting_pairs == 0
result["scrub_back_is_playback"] = system.save_state() == playback[3]
scene.frame_set(5)
result["scrub_forward_is_playback"] = system.save_state() == playback[5]
shown = np.empty(3 * len(feathers_obj.data.vertices), dtype=np.float32)
feathers_obj.data.vertices.foreach_get("co", shown)
result["scrub_mesh_matches"] = bool(np.array_equal(shown, system.feather_geometry().positions.ravel()))
scene.frame_set(6)

props.cache_path = out_dir + "/cache.pc2"
assert bpy.ops.plumage.bake() == {"FINISHED"}
samples, first, _rate = plumage_feathers.pointcache.read_pc2(out_dir + "/cache.pc2")
result["cache_frames"] = list(range(int(first), int(first) + len(samples)))
result["cache_shape"] = list(samples.shape)

# playback from the cache: the Mesh Cache modifier shows the baked frame, the system is not touched
last_solved = run["frame"]
scene.frame_set(2)
evaluated = feathers_obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
shown = np.array([v.co[:] for v in evaluated.data.vertices], dtype=np.float32)
result["cache_playback_matches"] = bool(np.array_equal(shown, samples[1]))
result["cache_playback_untouched"] = run["frame"] == last_solved == scene.frame_end  # no step, no evaluate

# render frame 4 from the cache with Cycles on the CPU
scene.frame_set(4)
cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
scene.collection.objects.link(cam)
cam.location = (3.6, -3.6, 2.4)
cam.rotation_euler = (math.radians(65), 0, math.radians(45))
scene.camera = cam
sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
sun.data.energy = 4.0
sun.rotation_euler = (math.radians(40), 0, math.radians(30))
scene.collection.objects.link(sun)
mat = bpy.data.materials.new("Feathers")
mat.diffuse_color = (0.55, 0.35, 0.2, 1.0)
mat.use_nodes = True
mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.55, 0.33, 0.18, 1.0)
feathers_obj.data.materials.append(mat)
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.cycles.use_denoising = False  # Debian builds Blender without OpenImageDenoise
scene.render.resolution_x, scene.render.resolution_y = 480, 360
scene.render.resolution_percentage = 100
scene.render.filepath = out_dir + "/frame.png"
bpy.ops.render.render(write_still=True)
result["rendered"] = out_dir + "/frame.png"
# the Scales preset with bent shafts from the panel: the body dressed again
props.preset = "SCALES"
props.shaft_segments = 3
props.use_cache = False
scene.frame_set(1)
assert bpy.ops.plumage.dress() == {"FINISHED"}
scaly = plumage_feathers._RUNS["Body"]["system"]
v = scaly.validate()
geo = scaly.feather_geometry()
result["scales"] = {
    "feathers": scaly.feather_count,
    "intersecting_pairs": v.intersecting_pairs,
    "body_penetrations": v.body_penetrations,
    "vertices_per_feather": len(geo.positions) // max(scaly.feather_count, 1),
}
print("PLUMAGE_RESULT " + json.dumps(result))
