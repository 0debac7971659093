"""Run inside Blender (headless) by python/tests/test_blender.py:

    blender -b --factory-startup --python-exit-code 1 --python blender_gltf.py -- ADDON_ZIP CHARACTER.glb

Imports scripts/make_character.py's walking figure with Blender's own glTF
importer (with the numpy shim Debian's Blender 3.4 needs beside numpy 1.24:
`numpy.bool = bool`), dresses its armature, plays frames 1..8 checking the
library's validation and scrubs 6, 2, 8 against playback. Prints one line
`PLUMAGE_RESULT {json}`.
"""

import json
import sys

import bpy
import numpy

args = sys.argv[sys.argv.index("--") + 1 :]
result = {"shim": not hasattr(numpy, "bool")}
if result["shim"]:
    numpy.bool = bool  # what the importer of Blender 3.4 still uses; removed in numpy 1.24

bpy.ops.preferences.addon_install(filepath=args[0], overwrite=True)
bpy.ops.preferences.addon_enable(module="plumage_feathers")
import plumage_feathers as addon  # noqa: E402

for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
bpy.ops.import_scene.gltf(filepath=args[1])
scene = bpy.context.scene
arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
result["imported"] = sorted(o.name for o in bpy.data.objects)
action = arm.animation_data.action if arm.animation_data else None
result["action_frames"] = list(action.frame_range) if action else None
scene.frame_start, scene.frame_end = 1, 8
scene.frame_set(1)
for o in bpy.context.selected_objects:
    o.select_set(False)
bpy.context.view_layer.objects.active = arm
arm.plumage.target_feathers = 800
arm.plumage.threads = 2
assert bpy.ops.plumage.dress() == {"FINISHED"}
run = addon._RUNS[arm.name]
system = run["system"]
result["sources"] = run["sources"]
result["flow_from"] = run["inputs"]["flow_from"]
result["feathers"] = system.feather_count
playback, frames = {}, []
for frame in range(1, 9):
    scene.frame_set(frame)
    playback[frame] = system.save_state()
    v = system.validate()
    frames.append({"frame": frame, "pairs": v.intersecting_pairs, "penetrations": v.body_penetrations, "coverage": v.coverage})
result["frames"] = frames
result["moved"] = float(abs(addon.run_positions(run, bpy.context.evaluated_depsgraph_get()) - run["inputs"]["positions"]).max())
scrub = []
for frame in (6, 2, 8):
    scene.frame_set(frame)
    scrub.append({"frame": frame, "is_playback": system.save_state() == playback[frame]})
result["scrub"] = scrub
print("PLUMAGE_RESULT " + json.dumps(result))
