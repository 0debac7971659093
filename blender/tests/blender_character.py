"""Run inside Blender (headless) by python/tests/test_blender.py, in three
processes on the same files:

    blender -b --factory-startup --python-exit-code 1 --python blender_character.py -- build ADDON_ZIP OUT_DIR
    blender -b --factory-startup --python-exit-code 1 OUT_DIR/character.blend --python blender_character.py -- play OUT_DIR
    blender -b --factory-startup --python-exit-code 1 --python blender_character.py -- rebuild ADDON_ZIP OUT_DIR

build: makes a character (an armature with three bones, three meshes
skinned to it, one of them a limb on the third bone, a fourth parented
rigidly to the second bone, a painted layer group, an action over frames
1..20 that also moves the armature object), dresses the armature as one coat
(the flow from its skeleton: the limb's feathers run along its bone),
plays 1..20 checking the library's validation at each frame, scrubs 12, 3,
20, 12 comparing with playback, checks the shader attributes, bakes to
OUT_DIR/character.pc2 and saves OUT_DIR/character.blend.
play (without the plumage package): the saved file plays the cache.
rebuild: reopens the file, rebuilds the live system from the state beside
the cache and scrubs it.
Each prints one line `PLUMAGE_RESULT {json}`.
"""

import json
import math
import struct
import sys

import bmesh
import bpy
import numpy as np
from mathutils import Matrix

args = sys.argv[sys.argv.index("--") + 1 :]
mode = args[0]
result = {"mode": mode}


def read_pc2(path):
    """The cache as the test reads it, without the add-on."""
    with open(path, "rb") as f:
        magic, version, points, start, rate, samples = struct.unpack("<12siiffi", f.read(32))
        data = np.frombuffer(f.read(), dtype="<f4")
    assert magic == b"POINTCACHE2\0" and version == 1
    return data.reshape(samples, points, 3), start


def evaluated_points(obj):
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = ev.to_mesh()
    co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    return co.reshape(-1, 3)


def mesh_points(obj):
    co = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


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


def skin(obj, arm, weight_b2):
    """Vertex groups B1/B2 with B2's weight given per vertex, and an Armature modifier."""
    g1, g2 = obj.vertex_groups.new(name="B1"), obj.vertex_groups.new(name="B2")
    for v in obj.data.vertices:
        w = float(weight_b2(v.co))
        if w < 1.0:
            g1.add([v.index], 1.0 - w, "REPLACE")
        if w > 0.0:
            g2.add([v.index], w, "REPLACE")
    mod = obj.modifiers.new("Armature", "ARMATURE")
    mod.object = arm


def build(addon_zip, out_dir):
    bpy.ops.preferences.addon_install(filepath=addon_zip, overwrite=True)
    bpy.ops.preferences.addon_enable(module="plumage_feathers")
    import plumage_feathers

    assert plumage_feathers.plumage is not None, plumage_feathers.IMPORT_ERROR
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 20
    scene.frame_set(1)

    # the rig: B1 from the origin up to z = 1, B2 on to z = 2
    arm = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    b1 = arm.data.edit_bones.new("B1")
    b1.head, b1.tail = (0, 0, 0), (0, 0, 1)
    b2 = arm.data.edit_bones.new("B2")
    b2.head, b2.tail = (0, 0, 1), (0, 0, 2)
    b2.parent, b2.use_connect = b1, True
    b3 = arm.data.edit_bones.new("B3")  # a limb off B2 (a shoulder), out along +x
    b3.head, b3.tail = (0.6, 0, 0.9), (1.5, 0, 0.9)
    b3.parent, b3.use_connect = b2, False
    bpy.ops.object.mode_set(mode="OBJECT")

    # a torso bending with B2 above z = 0.9, a head on B2, a crest parented to B2's tail
    torso = sphere_object("Torso", (0, 0, 0.8), (0.45, 0.35, 0.6))
    skin(torso, arm, lambda co: min(max((co.z - 0.9) / 0.5, 0.0), 1.0) ** 2 * (3 - 2 * min(max((co.z - 0.9) / 0.5, 0.0), 1.0)))
    head = sphere_object("Head", (0, 0, 1.95), (0.3, 0.3, 0.3), 24, 12)
    skin(head, arm, lambda co: 1.0)
    head.parent = arm  # parented and skinned: found once
    crest = sphere_object("Crest", (0, 0, 2.55), (0.13, 0.13, 0.13), 16, 8)
    crest.parent, crest.parent_type, crest.parent_bone = arm, "BONE", "B2"
    bpy.context.view_layer.update()
    crest.matrix_world = Matrix.Identity(4)  # stays where it was built, then follows the bone
    bpy.context.view_layer.update()
    # a limb skinned wholly to B3, beside the torso
    limb = sphere_object("Wing", (1.05, 0, 0.9), (0.42, 0.12, 0.12), 32, 12)
    limb.vertex_groups.new(name="B3").add([v.index for v in limb.data.vertices], 1.0, "REPLACE")
    limb.modifiers.new("Armature", "ARMATURE").object = arm
    # a painted layer: the torso's upper half on top
    layer = torso.vertex_groups.new(name="Layer")
    layer.add([v.index for v in torso.data.vertices if v.co.z > 0.8], 1.0, "REPLACE")

    # the action: B2 bends forward, B1 twists, the rig walks along x
    for pb in arm.pose.bones:
        pb.rotation_mode = "XYZ"
    for frame, bend, twist, x in ((1, 0.0, 0.0, 0.0), (20, 0.5, 0.6, 0.4)):
        arm.pose.bones["B2"].rotation_euler = (bend, 0, 0)
        arm.pose.bones["B2"].keyframe_insert("rotation_euler", frame=frame)
        arm.pose.bones["B1"].rotation_euler = (0, twist, 0)
        arm.pose.bones["B1"].keyframe_insert("rotation_euler", frame=frame)
        arm.location = (x, 0, 0)
        arm.keyframe_insert("location", frame=frame)
    scene.frame_set(1)

    props = arm.plumage
    props.target_feathers = 700
    props.threads = 2
    props.layer_group = "Layer"
    # the flow: the default (the armature's skeleton); an explicit axis or the front instead
    inputs = plumage_feathers.dress_inputs(bpy.context, arm)
    result["flow"] = {"default": props.flow, "flow_from": inputs["flow_from"], "no_source": "flow_source" not in inputs["config"],
                      "joints": len(inputs["skeleton"]["joint_parents"]), "head": inputs["skeleton"]["head_joint"],
                      "head_at": [float(x) for x in inputs["skeleton"]["joint_positions"][inputs["skeleton"]["head_joint"]]],
                      "weights_sum_1": bool(np.allclose(inputs["skeleton"]["vertex_weights"].sum(axis=1), 1, atol=1e-6)),
                      "layer_on": int((inputs["maps"]["layer"] > 0).sum()),
                      "layer_expected": sum(1 for v in torso.data.vertices if v.co.z > 0.8)}
    props.flow, props.flow_axis = "AXIS", "-Z"
    other = plumage_feathers.dress_inputs(bpy.context, arm)
    result["flow"]["axis"] = [other["flow_from"], other["skeleton"] is None, other["config"].get("flow_axis")]
    props.flow = "FRONT"
    other = plumage_feathers.dress_inputs(bpy.context, arm)
    result["flow"]["front"] = [other["flow_from"], other["skeleton"] is None, other["config"].get("flow_source")]
    props.flow = "SKELETON"
    for o in bpy.context.selected_objects:
        o.select_set(False)
    bpy.context.view_layer.objects.active = arm
    # the modal Dress's own methods (_start, then modal() on timer events and
    # Esc) with a stand-in for the operator instance: headless Blender has no
    # window to run it modal; the events are what the window manager sends
    import time
    from types import SimpleNamespace

    Op = plumage_feathers.PLUMAGE_OT_dress

    def modal_dress(esc_at_once):
        reports = []
        op = SimpleNamespace(_timer=None, report=lambda kind, text: reports.append(text))
        op._end = lambda context: Op._end(op, context)
        Op._start(op, bpy.context, arm)
        events, status = 0, {"RUNNING_MODAL"}
        while status == {"RUNNING_MODAL"} and events < 600:
            kind = "ESC" if esc_at_once and events == 0 else "TIMER"
            status = Op.modal(op, bpy.context, SimpleNamespace(type=kind))
            events += 1
            time.sleep(0.02)
        return status, reports

    status, told = modal_dress(esc_at_once=True)
    result["modal_cancel"] = {"status": sorted(status), "told": told, "no_run": "Rig" not in plumage_feathers._RUNS,
                              "no_feathers": "Rig_feathers" not in bpy.data.objects}
    status, told = modal_dress(esc_at_once=False)
    modal_state = plumage_feathers._RUNS["Rig"]["system"].save_state()
    result["modal_finish"] = {"status": sorted(status), "told": told}
    assert bpy.ops.plumage.dress() == {"FINISHED"}
    run = plumage_feathers._RUNS["Rig"]
    system = run["system"]
    feathers_obj = bpy.data.objects["Rig_feathers"]
    result["sources"] = run["sources"]
    result["counts"] = run["counts"]
    result["feathers"] = system.feather_count
    result["modal_finish"]["is_dress"] = modal_state == system.save_state()
    result["feathers_object_identity"] = feathers_obj.parent is None and np.allclose(np.array(feathers_obj.matrix_world), np.eye(4))
    # the limb's feathers run along its bone (+x), away from the body: the angle between each
    # feather's direction and the bone's direction in the skin's tangent plane, mid-limb
    f = system.feathers()
    mid = (f["root"][:, 0] > 0.8) & (f["root"][:, 0] < 1.3)
    bone = np.array([1.0, 0.0, 0.0])
    n = f["normal"][mid].astype(np.float64)
    along = bone - (n @ bone)[:, None] * n
    along /= np.linalg.norm(along, axis=1, keepdims=True)
    d = f["direction"][mid].astype(np.float64)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    angles = np.degrees(np.arccos(np.clip((d * along).sum(axis=1), -1, 1)))
    result["limb"] = {"feathers": int(mid.sum()), "median_deg": float(np.median(angles)), "p90_deg": float(np.percentile(angles, 90)),
                      "max_deg": float(angles.max())}
    # the torso's side below the limb runs down the body (from the head at the top)
    side = (np.abs(f["root"][:, 2] - 0.5) < 0.3) & (np.hypot(f["root"][:, 0], f["root"][:, 1]) > 0.3)
    result["torso_down"] = float(np.median(-f["direction"][side, 2]))

    # shader attributes
    geo = system.feather_geometry()
    mesh = feathers_obj.data

    def attr(name, width=1, kind=np.float32):
        a = mesh.attributes[name]
        out = np.empty(len(mesh.vertices) * width, dtype=kind)
        a.data.foreach_get("vector" if width == 3 else "value", out)
        return out.reshape(-1, width) if width > 1 else out

    fi = attr("feather_index", kind=np.int32).astype(np.intp)
    lo, hi = attr("feather_id_lo", kind=np.int32), attr("feather_id_hi", kind=np.int32)
    ids = (hi.view(np.uint32).astype(np.uint64) << np.uint64(32)) | lo.view(np.uint32).astype(np.uint64)
    rnd = attr("feather_random")
    roots = attr("feather_root", 3)
    mat = mesh.materials[0] if mesh.materials else None
    result["attributes"] = {
        "ids_match": bool(np.array_equal(ids, geo.ids[fi])),
        "random_in_range": bool(rnd.min() >= 0.0 and rnd.max() < 1.0 and rnd.std() > 0.1),
        "random_per_feather": bool(np.all(rnd == rnd[np.searchsorted(fi, fi)])),
        "roots_match": bool(np.array_equal(roots, system.feathers()["root"][fi])),
        "u_matches": bool(np.array_equal(attr("feather_u"), geo.uvs[:, 0])),
        "v_matches": bool(np.array_equal(attr("feather_v"), geo.uvs[:, 1])),
        "material": mat.name if mat else None,
        "material_reads_uv": bool(mat and any(n.bl_idname == "ShaderNodeUVMap" for n in mat.node_tree.nodes)),
        "material_principled": bool(mat and any(n.bl_idname == "ShaderNodeBsdfPrincipled" for n in mat.node_tree.nodes)),
    }

    # the modal Dress's loop (the operator's timer ticks) inside Blender: the
    # same system as Dress; cancelled at once, nothing
    jobs = plumage_feathers.jobs
    inputs = plumage_feathers.dress_inputs(bpy.context, arm)
    job = jobs.DressJob(lambda progress: plumage_feathers.make_system(inputs, progress))
    status = jobs.drive(job, interval=0.02)
    result["job_status"] = status
    result["job_is_dress"] = status == jobs.FINISHED and job.system.save_state() == system.save_state()
    if job.system is not None:
        job.system.close()
    job = jobs.DressJob(lambda progress: plumage_feathers.make_system(inputs, progress))
    result["job_cancelled"] = jobs.drive(job, cancel_requested=lambda now: True, interval=0.02)

    # play 1..20: the library's validation at every frame
    crest_rows = slice(sum(run["counts"][:0]), run["counts"][0])  # "Crest" comes first in name order
    playback, frames = {}, []
    rest_crest = plumage_feathers.run_positions(run, bpy.context.evaluated_depsgraph_get())[crest_rows].copy()
    for frame in range(1, 21):
        scene.frame_set(frame)
        playback[frame] = (system.save_state(), system.feather_geometry().positions.copy())
        v = system.validate()
        frames.append({"frame": frame, "frame_index": system.frame_stats().frame_index, "intersecting_pairs": v.intersecting_pairs,
                       "body_penetrations": v.body_penetrations, "coverage": v.coverage,
                       "mesh_matches": bool(np.array_equal(mesh_points(feathers_obj), playback[frame][1]))})
    result["frames"] = frames
    # the crest is rigid and follows the bone: its world-space points are its matrix times its rest points
    world = plumage_feathers.run_positions(run, bpy.context.evaluated_depsgraph_get())[crest_rows]
    m = np.array(crest.matrix_world)
    result["crest_moved"] = float(np.abs(world - rest_crest).max())
    result["crest_rigid_error"] = float(np.abs(rest_crest.astype(np.float64) @ m[:3, :3].T + m[:3, 3] - world).max())

    # scrubbing 12, 3, 20, 12: what playback showed, byte for byte
    scrub = []
    for frame in (12, 3, 20, 12):
        scene.frame_set(frame)
        v = system.validate()
        scrub.append({"frame": frame, "state_is_playback": system.save_state() == playback[frame][0],
                      "mesh_is_playback": bool(np.array_equal(mesh_points(feathers_obj), playback[frame][1])),
                      "intersecting_pairs": v.intersecting_pairs, "body_penetrations": v.body_penetrations})
    result["scrub"] = scrub

    # bake next to the saved file (refused before the file has a place), then save it with the cache attached
    props.cache_path = "//character.pc2"
    try:
        bpy.ops.plumage.bake()
        result["unsaved_bake_refused"] = ""
    except RuntimeError as e:
        result["unsaved_bake_refused"] = str(e)
    blend = out_dir + "/character.blend"
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    props.cache_path = "//character.pc2"
    assert bpy.ops.plumage.bake() == {"FINISHED"}
    samples, first = read_pc2(out_dir + "/character.pc2")
    result["cache_shape"] = list(samples.shape)
    result["cache_first"] = first
    result["cache_is_playback"] = all(np.array_equal(samples[f - 1], playback[f][1]) for f in range(1, 21))
    played = {}
    for frame in (20, 7, 1, 12):
        scene.frame_set(frame)
        played[frame] = bool(np.array_equal(evaluated_points(feathers_obj), samples[frame - 1]))
    result["cache_plays"] = played
    scene.frame_set(1)
    bpy.ops.wm.save_mainfile()
    result["blend"] = blend


def play(out_dir):
    """The saved file without the package or the add-on: the Mesh Cache modifier plays the .pc2."""
    try:
        import plumage  # noqa: F401

        result["package_importable"] = True
    except ImportError:
        result["package_importable"] = False
    scene = bpy.context.scene
    feathers_obj = bpy.data.objects["Rig_feathers"]
    result["modifiers"] = [m.type for m in feathers_obj.modifiers]
    samples, _ = read_pc2(out_dir + "/character.pc2")
    matches = {}
    for frame in (12, 3, 20, 12, 1):
        scene.frame_set(frame)
        matches[str(frame)] = bool(np.array_equal(evaluated_points(feathers_obj), samples[frame - 1]))
    result["matches"] = matches


def rebuild(addon_zip, out_dir):
    """The live system back from the state beside the cache, then scrubbed."""
    bpy.ops.preferences.addon_install(filepath=addon_zip, overwrite=True)
    bpy.ops.preferences.addon_enable(module="plumage_feathers")
    bpy.ops.wm.open_mainfile(filepath=out_dir + "/character.blend")
    import plumage_feathers

    scene = bpy.context.scene
    arm = bpy.data.objects["Rig"]
    feathers_obj = bpy.data.objects["Rig_feathers"]
    bpy.context.view_layer.objects.active = arm
    samples, _ = read_pc2(out_dir + "/character.pc2")
    scene.frame_set(20)
    assert bpy.ops.plumage.rebuild() == {"FINISHED"}
    run = plumage_feathers._RUNS["Rig"]
    system = run["system"]
    result["resumed_frame"] = run["frame"]
    result["resumed_is_baked"] = bool(np.array_equal(system.feather_geometry().positions, samples[19]))
    arm.plumage.use_cache = False  # the live system shows again
    checks = []
    for frame in (12, 3, 20):
        scene.frame_set(frame)
        v = system.validate()
        checks.append({"frame": frame, "is_baked": bool(np.array_equal(mesh_points(feathers_obj), samples[frame - 1])),
                       "modifier_off": not feathers_obj.modifiers["Plumage cache"].show_viewport,
                       "intersecting_pairs": v.intersecting_pairs, "body_penetrations": v.body_penetrations})
    result["checks"] = checks


if mode == "build":
    build(args[1], args[2])
elif mode == "play":
    play(args[1])
else:
    rebuild(args[1], args[2])
print("PLUMAGE_RESULT " + json.dumps(result))
