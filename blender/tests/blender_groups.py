"""Run inside Blender (headless) by python/tests/test_blender.py:

    blender -b --factory-startup --python-exit-code 1 --python blender_groups.py -- ADDON_ZIP

A rig with two bones and two skinned meshes (a torso and a leg) plus two
hidden meshes under it (one hide_viewport, one hidden in the view layer):
the hidden ones are not dressed; a Type group paints the leg (weight 1:
scales) and part of the torso below 0.5 (feathers); the panel's validation
figures; Dress undone and redone (bpy.ops.ed.undo / redo: the undo_post and
redo_post handlers drop the live system the undone Dress made, bring back
the one it replaced, and a redo brings it back). Prints one line
`PLUMAGE_RESULT {json}`.
"""

import json
import sys

import bmesh
import bpy
import numpy as np

args = sys.argv[sys.argv.index("--") + 1 :]
result = {}


def sphere_object(name, center, radii, segments=32, rings=16):
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=1.0)
    for v in bm.verts:
        v.co = (center[0] + radii[0] * v.co.x, center[1] + radii[1] * v.co.y, center[2] + radii[2] * v.co.z)
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def skin_to(obj, arm, bone):
    obj.vertex_groups.new(name=bone).add([v.index for v in obj.data.vertices], 1.0, "REPLACE")
    obj.modifiers.new("Armature", "ARMATURE").object = arm


def mesh_points(obj):
    co = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


bpy.ops.preferences.addon_install(filepath=args[0], overwrite=True)
bpy.ops.preferences.addon_enable(module="plumage_feathers")
import plumage_feathers as addon  # noqa: E402

assert addon.plumage is not None, addon.IMPORT_ERROR
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 6
scene.frame_set(1)

arm = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
scene.collection.objects.link(arm)
bpy.context.view_layer.objects.active = arm
bpy.ops.object.mode_set(mode="EDIT")
b1 = arm.data.edit_bones.new("B1")
b1.head, b1.tail = (0, 0, 0), (0, 0, 1)
b2 = arm.data.edit_bones.new("B2")
b2.head, b2.tail = (0, 0, 1), (0, 0, 2)
b2.parent, b2.use_connect = b1, True
bpy.ops.object.mode_set(mode="OBJECT")

torso = sphere_object("Torso", (0, 0, 1.0), (0.4, 0.35, 0.8))
skin_to(torso, arm, "B2")
leg = sphere_object("Leg", (0.95, 0, 0.6), (0.4, 0.15, 0.15), 32, 12)
skin_to(leg, arm, "B1")
shown_off = sphere_object("HiddenViewport", (0, 1.5, 1.0), (0.2, 0.2, 0.2), 16, 8)
shown_off.parent = arm
shown_off.hide_viewport = True
hidden = sphere_object("HiddenLayer", (0, -1.5, 1.0), (0.2, 0.2, 0.2), 16, 8)
skin_to(hidden, arm, "B1")
hidden.hide_set(True)
# the type group: the whole leg at 1 (scales); the torso's lower half at 0.3 (below 0.5: feathers)
leg.vertex_groups.new(name="Scales").add([v.index for v in leg.data.vertices], 1.0, "REPLACE")
torso.vertex_groups.new(name="Scales").add([v.index for v in torso.data.vertices if v.co.z < 1.0], 0.3, "REPLACE")

for pb in arm.pose.bones:
    pb.rotation_mode = "XYZ"
for frame, bend in ((1, 0.0), (6, 0.4)):
    arm.pose.bones["B2"].rotation_euler = (bend, 0, 0)
    arm.pose.bones["B2"].keyframe_insert("rotation_euler", frame=frame)
scene.frame_set(1)

props = arm.plumage
props.target_feathers = 600
props.threads = 2
props.type_group = "Scales"
for o in bpy.context.selected_objects:
    o.select_set(False)
bpy.context.view_layer.objects.active = arm

result["sources"] = [o.name for o in addon.dress_sources(bpy.context, arm)]
inputs = addon.dress_inputs(bpy.context, arm)
kinds = inputs["maps"]["feather_type"]
n_leg = len(leg.data.vertices)
result["types"] = {"dtype": str(kinds.dtype), "leg_all_scales": bool((kinds[:n_leg] == 1).all()),
                   "torso_all_feathers": bool((kinds[n_leg:] == 0).all())}

bpy.ops.ed.undo_push(message="before Dress")
# ('EXEC_DEFAULT', True): with its undo step, as from the panel (a script's call has none by default)
assert bpy.ops.plumage.dress("EXEC_DEFAULT", True) == {"FINISHED"}
run = addon._RUNS["Rig"]
system = run["system"]
token_a = run["token"]
result["dressed_sources"] = run["sources"]
f = system.feathers()
tris = run["inputs"]["triangles"]
present = f["length"] > 0  # absent feathers (none drawn) have no size
result["absent"] = int((~present).sum())
f = f[present]
on_leg = (tris[f["triangle"]] < n_leg).all(axis=1)
ratio = f["width"] / f["length"]
result["leg"] = {"feathers": int(on_leg.sum()), "ratio_median": float(np.median(ratio[on_leg])),
                 "ratio_min": float(ratio[on_leg].min()), "ratio_max": float(ratio[on_leg].max())}
result["torso"] = {"feathers": int((~on_leg).sum()), "ratio_median": float(np.median(ratio[~on_leg]))}
frames = []
for frame in range(1, 7):
    scene.frame_set(frame)
    v = system.validate()
    frames.append({"frame": frame, "pairs": v.intersecting_pairs, "penetrations": v.body_penetrations})
result["frames"] = frames
# the panel's figures: those of the Dress, then of the Validate operator at frame 6
result["panel_after_dress"] = addon.validation_text(arm)
assert bpy.ops.plumage.validate() == {"FINISHED"}
result["panel_after_validate"] = addon.validation_text(arm)
result["panel_figures"] = dict(arm[addon.VALIDATION_PROPERTY])
state_a = system.save_state()
mesh_a = mesh_points(bpy.data.objects["Rig_feathers"]).copy()

# a second Dress (another seed) replaces the live system; undo brings the first back, undo again leaves none
scene.frame_set(1)
props.seed = 7
bpy.ops.ed.undo_push(message="seed")
assert bpy.ops.plumage.dress("EXEC_DEFAULT", True) == {"FINISHED"}
token_b = addon._RUNS["Rig"]["token"]
system_b = addon._RUNS["Rig"]["system"]
result["second_is_other"] = token_b != token_a and system_b is not system
undo = []


def snapshot(step):
    live = addon._RUNS.get("Rig")
    rig = bpy.data.objects.get("Rig")
    feathers = bpy.data.objects.get("Rig_feathers")
    undo.append({"step": step, "live": live["token"] if live else None, "object_token": rig.get(addon.RUN_PROPERTY) if rig else None,
                 "feathers_object": feathers is not None, "parked": sorted(addon._PARKED)})
    return live


bpy.ops.ed.undo()  # back to the seed change's step: the second Dress undone
live = snapshot("undo second Dress")
result["undo_restores_first"] = live is not None and live["token"] == token_a and live["system"] is system
if live is not None and live["system"] is system:
    result["restored_mesh_is_current"] = bool(np.array_equal(mesh_points(bpy.data.objects["Rig_feathers"]),
                                                             system.feather_geometry().positions))
    bpy.context.scene.frame_set(6)  # the restored system follows the frames again
    result["restored_follows_frames"] = system.save_state() == state_a and bool(
        np.array_equal(mesh_points(bpy.data.objects["Rig_feathers"]), mesh_a))
steps = 0
while steps < 8 and bpy.data.objects["Rig"].get(addon.RUN_PROPERTY) is not None:  # back to before the first Dress
    bpy.ops.ed.undo()
    steps += 1
live = snapshot("undo first Dress")
result["undo_steps_to_first"] = steps
result["undo_drops_first"] = live is None
bpy.context.scene.frame_set(3)  # no stale system follows the frames
result["no_stale_follow"] = "Rig" not in addon._RUNS
bpy.ops.ed.redo()
live = snapshot("redo first Dress")
result["redo_restores_first"] = live is not None and live["token"] == token_a
result["undo"] = undo
result["parked_at_most"] = addon.PARKED_MAX
print("PLUMAGE_RESULT " + json.dumps(result))
