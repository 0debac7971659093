"""`python -m plumage dress` without the C++ host: the package's glTF reader
(plumage.gltf) against the host's evaluator, and the USD it writes against
the host's .glb of the same run.

The host writes what it hands the library with --poses (rest pose, triangles,
configuration, maps, every frame's positions): the reader must give the same
bytes. Its .glb stores the body and the feathers as a rest pose plus one morph
target per frame, each target the float32 difference frame - rest: those
differences must be the same bytes too.
"""

from __future__ import annotations

import base64
import json
import subprocess
import sys
from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest

from plumage.poses import read_poses

from conftest import REPO, glb_node_arrays, run_host, uv_sphere

pytest.importorskip("pygltflib", reason="pygltflib is not installed")
from plumage import gltf  # noqa: E402
from plumage.builtin import ProceduralBody  # noqa: E402

MODELS = ["Flamingo", "Fox", "bird"]
DATA = REPO.parent / "shared" / "data"


def shared_model(name: str) -> Path:
    path = DATA / f"{name}.glb"
    if not path.is_file():
        pytest.skip(f"{path} is absent (the shared models live at ../shared/data from the repository root)")
    return path


def host_poses(host: str, tmp: Path, *args: str, glb: bool = True):
    count = [] if "--spacing" in args else ["--feathers", "60"]
    cmd = [*args, *count, "--threads", "1", "--validate", "none", "--poses", str(tmp / "run.poses")]
    run_host(host, *cmd, *(["--out", str(tmp / "run.glb")] if glb else []))
    return read_poses(tmp / "run.poses")


def assert_reader_is_host(subject, poses, fps: float = 30.0, start: float = 0.0) -> None:
    assert subject.rest_positions.dtype == np.float32
    assert subject.rest_positions.tobytes() == poses.rest.tobytes()
    assert np.array_equal(subject.triangles, poses.triangles)
    times = gltf.frame_times(subject.clip, fps, start, len(poses.times))
    assert times.tobytes() == poses.times.tobytes()
    for k, t in enumerate(times):
        ours = subject.pose_at(float(t))
        assert ours.tobytes() == poses.frames[k].tobytes(), f"frame {k} (t = {t}): max difference {np.abs(ours - poses.frames[k]).max()}"


@pytest.mark.parametrize("name", MODELS)
def test_rest_and_frames_are_the_hosts(host, tmp_path, name) -> None:
    model = shared_model(name)
    poses = host_poses(host, tmp_path, str(model), "--frames", "12", "--fps", "24", "--start", "0.1")
    scene = gltf.Scene(model)
    assert_reader_is_host(scene, poses, fps=24, start=0.1)
    # the same bytes as the host's .glb: its rest pose, and each frame as its morph target (frame - rest)
    base, indices, targets = glb_node_arrays(tmp_path / "run.glb", "body")
    assert base.tobytes() == scene.rest_positions.tobytes()
    assert np.array_equal(indices, scene.triangles)
    assert len(targets) == 12
    for k, t in enumerate(poses.times):
        assert targets[k].tobytes() == (scene.pose_at(float(t)) - scene.rest_positions).tobytes(), f"frame {k}"


@pytest.mark.parametrize("name", ["Flamingo", "bird"])
def test_whole_clip_by_default(host, tmp_path, name) -> None:
    model = shared_model(name)
    poses = host_poses(host, tmp_path, str(model), "--fps", "48", glb=False)
    scene = gltf.Scene(model)
    assert len(gltf.frame_times(scene.clip, 48.0)) == len(poses.times) > 20
    assert_reader_is_host(scene, poses, fps=48)


def test_every_clip_and_every_mesh(host, tmp_path) -> None:
    bird = shared_model("bird")
    for clip in ("1", "Armature.004|Scene"):
        poses = host_poses(host, tmp_path, str(bird), "--animation", clip, "--frames", "9", glb=False)
        assert_reader_is_host(gltf.Scene(bird, clip=clip), poses)
    fox = shared_model("Fox")
    for meshes in (["all"], ["Circle.001"], ["3", "0"]):
        poses = host_poses(host, tmp_path, str(fox), *[a for m in meshes for a in ("--mesh", m)], "--frames", "5", glb=False)
        scene = gltf.Scene(fox, meshes)
        assert_reader_is_host(scene, poses)
    assert gltf.Scene(fox, ["all"]).mesh_indices == [0]  # the only skinned mesh
    assert gltf.Scene(fox, ["3", "0"]).mesh_indices == [3, 0]


def test_builtin_model_is_the_hosts(host, tmp_path) -> None:
    poses = host_poses(host, tmp_path, "--frames", "20", glb=False)
    assert_reader_is_host(ProceduralBody(), poses)
    poses = host_poses(host, tmp_path, "--model-resolution", "12,7", "--frames", "40", glb=False)
    assert_reader_is_host(ProceduralBody(12, 7), poses)


def test_vertex_maps_are_the_hosts(host, tmp_path) -> None:
    """Scalar maps from vertex attributes, and a flow map carried to the rest pose through the skin."""
    bird = shared_model("bird")
    maps = ("--spacing-map", "TEXCOORD_0:1", "--length-map", "WEIGHTS_0:0", "--width-map", "TEXCOORD_0", "--flow-map", "NORMAL")
    poses = host_poses(host, tmp_path, str(bird), *maps, "--frames", "1", glb=False)
    from plumage.__main__ import dress_parser, prepare

    run = prepare(dress_parser().parse_args([str(bird), "--out", "x.usda", *maps, "--frames", "1"]))
    assert sorted(run.maps) == sorted(poses.maps) == ["length_scale", "orientations", "spacing_scale", "width_scale"]
    for key, values in poses.maps.items():
        assert run.maps[key].dtype == np.float32 and run.maps[key].tobytes() == values.tobytes(), key


def test_dress_configures_the_library_as_the_host(host, tmp_path) -> None:
    from plumage.__main__ import dress_parser, prepare
    from plumage.poses import config_from_struct
    from plumage.system import _build_config

    fox = shared_model("Fox")
    for extra in ([], ["--preset", "kite", "--seed", "7", "--mode", "rebuild"], ["--spacing", "2.5", "--flow", "0,1,0.5"],
                  ["--preset", "scales", "--flow-source", "1,2,3", "--mode", "legacy"]):
        poses = host_poses(host, tmp_path, str(fox), "--frames", "2", *extra, glb=False)
        count = [] if "--spacing" in extra else ["--feathers", "60"]
        run = prepare(dress_parser().parse_args([str(fox), "--out", "x.usda", "--frames", "2", *count, "--threads", "1", *extra]))
        assert config_from_struct(_build_config(run.config, run.preset)) == poses.config, extra


def dress(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "plumage", "dress", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          cwd=tmp_path)


@pytest.mark.parametrize("name,preset", [("Fox", "kite"), ("Flamingo", "feathers"), ("bird", "scales"), ("builtin", "feathers"),
                                         ("Fox", "feathers"), ("bird", "feathers")])
def test_usd_feathers_are_the_hosts_glb(host, tmp_path, name, preset) -> None:
    """The USD of `dress` (no host) against the host's .glb of the same run, frame by frame."""
    pytest.importorskip("pxr", reason="usd-core is not installed")
    from pxr import Usd, UsdGeom

    model = "builtin" if name == "builtin" else str(shared_model(name))
    options = ["--feathers", "300", "--frames", "3", "--fps", "10", "--seed", "5", "--threads", "1", "--preset", preset]
    run = dress(tmp_path, model, "--out", str(tmp_path / "run.usda"), *options)
    assert run.returncode == 0, run.stderr
    assert "feathers" in run.stdout and run.stderr == ""
    run_host(host, *([] if model == "builtin" else [model]), *options, "--validate", "none", "--out", str(tmp_path / "host.glb"), "--poses", str(tmp_path / "host.poses"))
    poses = read_poses(tmp_path / "host.poses")

    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    body = UsdGeom.Mesh(stage.GetPrimAtPath("/Plumage/Body"))
    feathers = UsdGeom.Mesh(stage.GetPrimAtPath("/Plumage/Feathers"))
    codes = list(poses.times * poses.fps)
    assert feathers.GetPointsAttr().GetTimeSamples() == codes and stage.GetTimeCodesPerSecond() == 10
    assert np.array(body.GetPointsAttr().Get(), np.float32).tobytes() == poses.rest.tobytes()
    for k, code in enumerate(codes):
        assert np.array(body.GetPointsAttr().Get(code), np.float32).tobytes() == poses.frames[k].tobytes(), f"body, frame {k}"

    f_base, f_idx, f_targets = glb_node_arrays(tmp_path / "host.glb", "feathers")
    usd_idx = np.array(feathers.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
    assert usd_idx.shape == f_idx.shape and len(f_targets) == 3
    rest = np.array(feathers.GetPointsAttr().Get(), np.float32)
    assert rest[usd_idx].tobytes() == f_base[f_idx].tobytes()  # the rest pose, bit for bit
    for k, code in enumerate(codes):
        points = np.array(feathers.GetPointsAttr().Get(code), np.float32)
        assert (points - rest)[usd_idx].tobytes() == f_targets[k][f_idx].tobytes(), f"feathers, frame {k}"


# ---------------------------------------------------------------- a synthetic model


def synthetic_gltf(path: Path, animated: bool = True, external: bool = False) -> Path:
    """A sphere under a matrix node and an animated TRS node, with two morph
    targets (one sparse) and custom attributes, plus a non-indexed triangle
    strip (a ribbon, no targets) in the same mesh; the clip samples
    translation by STEP, rotation and morph weights by CUBICSPLINE, scale by
    LINEAR. `external`: the buffer in a .bin file beside the .gltf, else a data URI."""
    verts, tris = uv_sphere(10, 16, 0.5)
    n = len(verts)
    chunks: List[bytes] = []
    views: List[Dict] = []
    accessors: List[Dict] = []

    def add(array: np.ndarray, component: int, kind: str, **extra) -> int:
        data = np.ascontiguousarray(array).tobytes()
        offset = sum(len(c) for c in chunks)
        chunks.append(data + b"\0" * (-len(data) % 4))
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(data)})
        count = len(array) if kind != "SCALAR" else array.size
        accessors.append({"bufferView": len(views) - 1, "componentType": component, "count": count, "type": kind, **extra})
        return len(accessors) - 1

    position = add(verts.astype(np.float32), 5126, "VEC3", min=[-0.5] * 3, max=[0.5] * 3)
    indices = add(tris.astype(np.uint16).reshape(-1), 5123, "SCALAR")
    density = add(np.stack([np.linspace(0.5, 2, n), np.linspace(2, 1, n)], 1).astype(np.float32), 5126, "VEC2")
    flow = add(np.tile(np.array([[0, 127, 20, 0]], np.int8), (n, 1)), 5120, "VEC4", normalized=True)
    bulge = add((verts * np.array([0.3, 0.0, 0.1])).astype(np.float32), 5126, "VEC3")
    # a sparse target: zeros, with a few vertices pulled outwards
    picked = np.arange(0, n, 7, dtype=np.uint16)
    sparse_idx = add(picked, 5123, "SCALAR")
    sparse_val = add((verts[picked] * 0.4).astype(np.float32), 5126, "VEC3")
    accessors.append({"componentType": 5126, "count": n, "type": "VEC3",
                      "sparse": {"count": len(picked), "indices": {"bufferView": accessors[sparse_idx]["bufferView"], "componentType": 5123},
                                 "values": {"bufferView": accessors[sparse_val]["bufferView"]}}})
    sparse = len(accessors) - 1
    ribbon = np.array([[x, 0.6 + 0.1 * (i % 2), 0.1 * x] for i, x in enumerate(np.linspace(-0.5, 0.5, 12))], np.float32)
    ribbon_position = add(ribbon, 5126, "VEC3", min=ribbon.min(0).tolist(), max=ribbon.max(0).tolist())
    ribbon_density = add(np.full((len(ribbon), 2), 1.5, np.float32), 5126, "VEC2")
    ribbon_flow = add(np.tile(np.array([[127, 0, 0, 0]], np.int8), (len(ribbon), 1)), 5120, "VEC4", normalized=True)
    nodes = [
        {"name": "root", "matrix": [0.9, 0.1, 0, 0, -0.1, 0.9, 0, 0, 0, 0, 1.2, 0, 0.3, -0.2, 0.1, 1], "children": [1]},
        {"name": "arm", "translation": [0, 1, 0], "rotation": [0, 0, 0.3826834, 0.9238795], "children": [2]},
        {"name": "ball", "mesh": 0, "weights": [0.25, 0.0], "scale": [1, 1.5, 1]},
    ]
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
        "meshes": [{"name": "ball", "weights": [0.9, 0.9], "primitives": [{
            "attributes": {"POSITION": position, "_DENSITY": density, "_FLOW": flow},
            "indices": indices, "targets": [{"POSITION": bulge}, {"POSITION": sparse}]},
            {"attributes": {"POSITION": ribbon_position, "_DENSITY": ribbon_density, "_FLOW": ribbon_flow}, "mode": 5}]}],
    }
    if animated:
        keys = np.array([0.0, 0.4, 1.1, 1.5], np.float32)
        t_in = add(keys, 5126, "SCALAR", min=[0.0], max=[1.5])
        step = add(np.array([[0, 1, 0], [0.2, 1, 0], [0.2, 1.3, -0.1], [0, 1, 0]], np.float32), 5126, "VEC3")
        rot = np.array([[0, 0, 0.3826834, 0.9238795], [0.2, 0, 0.2, 0.96], [-0.3, 0.5, 0, 0.8], [0, 0, 0.3826834, 0.9238795]], np.float32)
        tangents = np.array([[0.1, 0.3, -0.2, 0.0]] * 4, np.float32)
        rot_cubic = add(np.stack([tangents, rot, -tangents], 1).reshape(-1, 4), 5126, "VEC4")
        scale = add(np.array([[1, 1.5, 1], [1.2, 1.2, 0.8], [0.9, 1.5, 1.1], [1, 1.5, 1]], np.float32), 5126, "VEC3")
        w = np.array([[0.25, 0], [1, 0.5], [0, 1], [0.25, 0]], np.float32)
        w_cubic = add(np.stack([np.full_like(w, 0.5), w, np.full_like(w, -1.0)], 1).reshape(-1), 5126, "SCALAR")
        doc["animations"] = [{"name": "wiggle", "samplers": [
            {"input": t_in, "output": step, "interpolation": "STEP"},
            {"input": t_in, "output": rot_cubic, "interpolation": "CUBICSPLINE"},
            {"input": t_in, "output": scale, "interpolation": "LINEAR"},
            {"input": t_in, "output": w_cubic, "interpolation": "CUBICSPLINE"},
        ], "channels": [
            {"sampler": 0, "target": {"node": 1, "path": "translation"}},
            {"sampler": 1, "target": {"node": 1, "path": "rotation"}},
            {"sampler": 2, "target": {"node": 2, "path": "scale"}},
            {"sampler": 3, "target": {"node": 2, "path": "weights"}},
        ]}]
    blob = b"".join(chunks)
    if external:
        (path.parent / "ball data.bin").write_bytes(blob)
        uri = "ball%20data.bin"
    else:
        uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    doc["buffers"] = [{"byteLength": len(blob), "uri": uri}]
    doc["bufferViews"] = views
    doc["accessors"] = accessors
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("external", [False, True])
def test_synthetic_samplers_sparse_and_matrix_are_the_hosts(host, tmp_path, external) -> None:
    model = synthetic_gltf(tmp_path / "ball.gltf", external=external)
    maps = ("--spacing-map", "_DENSITY:1", "--flow-map", "_FLOW")
    poses = host_poses(host, tmp_path, str(model), "--fps", "20", *maps, glb=False)
    scene = gltf.Scene(model)
    assert scene.clip is not None and scene.clip.duration == 1.5 and len(poses.times) == 31
    assert len(scene.triangles) == len(uv_sphere(10, 16)[1]) + 10  # the strip's 12 vertices make 10 triangles
    assert_reader_is_host(scene, poses, fps=20)
    assert scene.vertex_attribute("_DENSITY", 1).tobytes() == poses.maps["spacing_scale"].tobytes()
    assert scene.rest_directions("_FLOW").tobytes() == poses.maps["orientations"].tobytes()


def test_static_model_warns_and_writes_the_rest_pose(host, tmp_path) -> None:
    pytest.importorskip("pxr", reason="usd-core is not installed")
    from pxr import Usd, UsdGeom

    model = synthetic_gltf(tmp_path / "still.gltf", animated=False)
    run = dress(tmp_path, str(model), "--out", "still.usda", "--feathers", "200")
    assert run.returncode == 0, run.stderr
    assert "has no animation" in run.stderr and "rest pose only" in run.stderr
    stage = Usd.Stage.Open(str(tmp_path / "still.usda"))
    body = UsdGeom.Mesh(stage.GetPrimAtPath("/Plumage/Body"))
    assert body.GetPointsAttr().GetTimeSamples() == []
    poses = host_poses(host, tmp_path, str(model), glb=False)  # the host steps no frame either
    assert len(poses.times) == 0
    assert np.array(body.GetPointsAttr().Get(), np.float32).tobytes() == poses.rest.tobytes()
    run = dress(tmp_path, str(model), "--out", "still.usda", "--feathers", "200", "--frames", "2")
    assert run.returncode == 0 and "2 frames of the rest pose" in run.stderr


def test_skeleton_of_a_skinned_mesh() -> None:
    fox = gltf.Scene(shared_model("Fox"))
    skeleton = fox.parts[0].skeleton()
    assert skeleton is not None
    joints = len(skeleton.joint_nodes)
    assert skeleton.rest_positions.shape == (joints, 3) and skeleton.parents.shape == (joints,)
    assert (skeleton.parents == -1).sum() == 1 and (skeleton.parents < np.arange(joints)).all()
    assert skeleton.joints.shape == skeleton.weights.shape == (fox.parts[0].vertex_count, 4)
    assert skeleton.joints.max() < joints and np.allclose(skeleton.weights.sum(axis=1), 1, atol=1e-3)
    # at rest the Fox stands in its bind pose: each joint sits where its inverse bind matrix undoes
    inverse_bind = np.array(fox.parts[0].inverse_bind).reshape(-1, 4, 4).transpose(0, 2, 1)
    bind = np.array([np.linalg.inv(m)[:3, 3] for m in inverse_bind])
    assert np.abs(bind - skeleton.rest_positions).max() <= 1e-3 * np.abs(bind).max()  # float32 matrices
    assert gltf.Scene(shared_model("Flamingo")).parts[0].skeleton() is None


def assert_same_skeleton(ours, hosts) -> None:
    for key in ("joint_positions", "joint_parents", "vertex_joints", "vertex_weights"):
        a, b = getattr(ours, key), getattr(hosts, key)
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), key
    assert ours.head_joint == hosts.head_joint == -1


def two_skinned_meshes(path: Path) -> Path:
    """The Fox with its skinned mesh shown twice (a second mesh on the same accessors, skinned to the same skin)."""
    import pygltflib

    g = pygltflib.GLTF2().load(str(shared_model("Fox")))
    first = next(i for i, n in enumerate(g.nodes) if n.mesh == 0)
    twin = pygltflib.Mesh(name="Twin", primitives=[pygltflib.Primitive(attributes=p.attributes, indices=p.indices, mode=p.mode)
                                                   for p in g.meshes[0].primitives])
    g.meshes.append(twin)
    g.nodes.append(pygltflib.Node(name="twin", mesh=len(g.meshes) - 1, skin=g.nodes[first].skin))
    g.scenes[g.scene or 0].nodes.append(len(g.nodes) - 1)
    g.save(str(path))
    return path


def test_skeleton_and_layers_are_the_hosts(host, tmp_path) -> None:
    """With no flow given, a skinned subject hands the library its skeleton (and no flow source), byte for byte the
    host's; --skeleton-flow off and an explicit flow give the front-most vertex or the flow instead, as the host."""
    from plumage.__main__ import dress_parser, prepare

    def both(model: Path, *extra: str):
        poses = host_poses(host, tmp_path, str(model), "--frames", "1", *extra, glb=False)
        run = prepare(dress_parser().parse_args([str(model), "--out", "x.usda", "--frames", "1", "--feathers", "60", "--threads", "1", *extra]))
        assert sorted(run.maps) == sorted(poses.maps), extra
        assert run.config.get("flow_source") == poses.config["flow_source"], extra
        return run, poses

    for name in ("Fox", "bird"):
        run, poses = both(shared_model(name))
        assert list(run.maps) == ["skeleton"] and run.config.get("flow_source") is None
        assert_same_skeleton(run.maps["skeleton"], poses.maps["skeleton"])
        assert run.maps["skeleton"].vertex_joints.shape[0] == len(run.rest)
        for extra in (["--skeleton-flow", "off"], ["--flow", "0,0,-1"], ["--flow-source", "0,1,2"], ["--flow-map", "NORMAL"]):
            run, poses = both(shared_model(name), *extra)
            assert "skeleton" not in run.maps, extra
    # influences packed first (weight > 0, renormalised), as many slots as the widest vertex needs
    bird = gltf.Scene(shared_model("bird")).skin_skeleton()
    assert bird is not None and bird.influences == 3 and (bird.vertex_weights[:, 0] > 0).all()
    assert np.allclose(bird.vertex_weights.sum(axis=1), 1, atol=1e-6)
    # a layer map from a vertex attribute, with the skeleton
    run, poses = both(shared_model("bird"), "--layer-map", "TEXCOORD_0:1")
    assert sorted(run.maps) == ["layer", "skeleton"] and run.maps["layer"].tobytes() == poses.maps["layer"].tobytes()
    # several skinned meshes: their skeletons one after the other, the joints offset
    twins = two_skinned_meshes(tmp_path / "twins.glb")
    run, poses = both(twins, "--mesh", "all")
    one = gltf.Scene(shared_model("Fox")).skin_skeleton()
    assert_same_skeleton(run.maps["skeleton"], poses.maps["skeleton"])
    joints = len(one.joint_parents)
    assert len(run.maps["skeleton"].joint_parents) == 2 * joints
    assert np.array_equal(run.maps["skeleton"].vertex_joints[len(one.vertex_joints):], one.vertex_joints + joints)
    # one skinned and one not: no skeleton, the front-most vertex
    run, poses = both(shared_model("Fox"), "--mesh", "3", "--mesh", "0")
    assert "skeleton" not in run.maps and run.config["flow_source"] is not None


def test_dress_through_the_host_passes_the_skeleton_and_layers(host, tmp_path) -> None:
    """`dress --host` drives the library from the host's pose file, skeleton and layer map included: the same USD."""
    pytest.importorskip("pxr", reason="usd-core is not installed")
    bird = str(shared_model("bird"))
    options = ["--feathers", "200", "--frames", "2", "--threads", "1", "--layer-map", "TEXCOORD_0:1", "--quiet"]
    native = dress(tmp_path, bird, "--out", "native.usda", *options)
    hosted = dress(tmp_path, bird, "--out", "hosted.usda", "--host", host, *options)
    assert native.returncode == 0 and hosted.returncode == 0, native.stderr + hosted.stderr
    assert (tmp_path / "native.usda").read_bytes() == (tmp_path / "hosted.usda").read_bytes()
    off = dress(tmp_path, bird, "--out", "off.usda", "--skeleton-flow", "off", *options)
    assert off.returncode == 0 and (tmp_path / "off.usda").read_bytes() != (tmp_path / "native.usda").read_bytes()


def test_pose_file_versions(host, tmp_path) -> None:
    """Version 2 only when a layer map or a skeleton is written; version 1 files read as before."""
    import struct

    poses = host_poses(host, tmp_path, str(shared_model("Flamingo")), "--frames", "1", glb=False)
    assert struct.unpack_from("<I", (tmp_path / "run.poses").read_bytes(), 8)[0] == 1 and poses.maps == {}
    poses = host_poses(host, tmp_path, str(shared_model("bird")), "--frames", "2", "--layer-map", "TEXCOORD_0", glb=False)
    data = (tmp_path / "run.poses").read_bytes()
    assert struct.unpack_from("<I", data, 8)[0] == 2 and sorted(poses.maps) == ["layer", "skeleton"]
    assert len(poses.frames) == 2 and poses.frames[1].shape == poses.rest.shape
    from plumage.poses import PosesFormatError

    (tmp_path / "cut.poses").write_bytes(data[:-4])
    with pytest.raises(PosesFormatError, match="header announces"):
        read_poses(tmp_path / "cut.poses")


def test_usage_and_input_errors(tmp_path) -> None:
    fox = shared_model("Fox")
    cases = [
        ([str(fox), "--mesh", "nope"], 2, "no such mesh"),
        ([str(fox), "--animation", "9"], 2, "no such clip"),
        ([str(fox), "--spacing-map", "_NOPE"], 2, "no vertex attribute _NOPE"),
        ([str(fox), "--spacing-map", "TEXCOORD_0:2"], 2, "components per vertex"),
        ([str(fox), "--glb", "x.glb"], 2, "give --host too"),
        ([str(fox), "--feathers", "10", "--spacing", "1"], 2, "not allowed with"),
        ([str(fox), "--bogus"], 2, "unrecognized arguments"),
        (["builtin", "--flow-map", "NORMAL"], 2, "the built-in model has none"),
        (["builtin", "--layer-map", "NORMAL"], 2, "the built-in model has none"),
        ([str(fox), "--layer-map", "_NOPE"], 2, "no vertex attribute _NOPE"),
        ([str(fox), "--skeleton-flow", "maybe"], 2, "invalid choice"),
        ([str(fox), "--type-map", "_NOPE"], 2, "no vertex attribute _NOPE"),
        (["builtin", "--type-map", "NORMAL"], 2, "the built-in model has none"),
        ([str(fox), "--feather-types", "feathers,fur"], 2, "feathers|sleek|kite|scales"),
        ([str(fox), "--validate", "sometimes"], 2, "invalid choice"),
        ([str(fox), "--theta", "nan"], 2, "finite number"),
        ([str(fox), "--memory-limit", "-1"], 2, "integer from 0"),
        ([str(fox), "--fluffiness", "-4", "--frames", "1"], 4, "fluffiness"),  # the library's refusal, as the host's
        ([str(tmp_path / "nope.glb")], 3, "nope.glb"),
    ]
    for args, code, message in cases:
        run = dress(tmp_path, *args, "--out", str(tmp_path / "x.usda"))
        assert run.returncode == code and message in run.stderr, (args, run.returncode, run.stderr)
    assert not (tmp_path / "x.usda").exists()


def test_progress_is_shown_on_long_runs(capsys) -> None:
    from plumage.__main__ import Progress

    progress = Progress(True)
    progress.frame_done(1, 10)  # within the first second: nothing
    assert capsys.readouterr().err == ""
    progress.start -= 30  # a long run
    assert progress.library("adjusting", 0.5) is False  # never interrupts
    progress.frame_done(3, 10)
    err = capsys.readouterr().err
    assert "rest pose: adjusting  50%" in err or "frame 3/10" in err
    quiet = Progress(False)
    quiet.start -= 30
    quiet.frame_done(3, 10)
    assert capsys.readouterr().err == ""


# ---------------------------------------------------------------- every option that changes the coat


def character(tmp: Path) -> Path:
    """scripts/make_character.py's walking figure: _FEATHER_TYPE 1 on the legs, _LAYER 1 on the arms."""
    out = tmp / "character.glb"
    if not out.is_file():
        subprocess.run([sys.executable, str(REPO / "scripts" / "make_character.py"), str(out)], check=True)
    return out


COAT_OPTIONS = [
    ["--theta", "37.5", "--sampler", "random", "--drift-tolerance", "5.3", "--settle-rate", "0.7"],
    ["--curvature-min-scale", "0.65", "--fluffiness", "12.25", "--shaft-segments", "2", "--bend-limit", "31.1"],
    ["--memory-limit", "512", "--preset", "kite", "--theta", "0.1", "--settle-rate", "0"],
    ["--preset", "scales", "--sampler", "guided", "--bend-limit", "1e-3", "--shaft-segments", "3", "--fluffiness", "4.0001"],
]


def both_inputs(host: str, tmp: Path, model: Path, *extra: str):
    """The host's pose file and `dress`'s prepared input for the same options."""
    from plumage.__main__ import dress_parser, prepare

    poses = host_poses(host, tmp, str(model), "--frames", "2", *extra, glb=False)
    count = [] if "--spacing" in extra else ["--feathers", "60"]
    run = prepare(dress_parser().parse_args([str(model), "--out", "x.usda", "--frames", "2", *count, "--threads", "1", *extra]))
    return run, poses


def assert_same_library_input(run, poses, extra) -> None:
    from plumage.poses import config_from_struct
    from plumage.system import _build_config

    assert config_from_struct(_build_config(run.config, run.preset)) == poses.config, extra
    assert sorted(run.maps) == sorted(poses.maps), extra
    for key, value in poses.maps.items():
        if key == "skeleton":
            assert_same_skeleton(run.maps[key], value)
        elif key == "feather_types":
            assert tuple(run.maps[key]) == value, extra
        else:
            assert run.maps[key].dtype == value.dtype and run.maps[key].tobytes() == value.tobytes(), (key, extra)
    assert run.rest.tobytes() == poses.rest.tobytes() and np.array_equal(run.triangles, poses.triangles)


@pytest.mark.parametrize("extra", COAT_OPTIONS)
def test_coat_options_configure_the_library_as_the_host(host, tmp_path, extra) -> None:
    """--theta, --sampler, --drift-tolerance, --settle-rate, --curvature-min-scale, --fluffiness, --shaft-segments,
    --bend-limit and --memory-limit give the library the host's configuration, byte for byte, on a shared model and
    on the test character."""
    for model in (shared_model("Fox"), character(tmp_path)):
        run, poses = both_inputs(host, tmp_path, model, *extra)
        assert_same_library_input(run, poses, extra)
    assert poses.config["memory_limit"] == (512 << 20 if "--memory-limit" in extra else 0)


def test_type_map_and_types_are_the_hosts(host, tmp_path) -> None:
    """--type-map NAME[:C] with --feather-types: the per-vertex types (rounded) and the presets reach the library as
    the host hands them (pose file version 3), with the layer map and the skeleton; on the character and the bird."""
    import struct

    model = character(tmp_path)
    for extra in (["--type-map", "_FEATHER_TYPE"], ["--type-map", "_FEATHER_TYPE:0", "--feather-types", "sleek,kite", "--layer-map", "_LAYER"],
                  ["--type-map", "_LAYER", "--feather-types", "scales,feathers,kite", "--flow", "0,-1,0"]):
        run, poses = both_inputs(host, tmp_path, model, *extra)
        assert struct.unpack_from("<I", (tmp_path / "run.poses").read_bytes(), 8)[0] == 3
        assert_same_library_input(run, poses, extra)
        assert run.maps["feather_type"].dtype == np.uint32 and set(np.unique(run.maps["feather_type"])) == {0, 1}
    assert poses.maps["feather_types"] == ("scales", "feathers", "kite")
    # legs are type 1 in _FEATHER_TYPE: scales there by default
    run, poses = both_inputs(host, tmp_path, model, "--type-map", "_FEATHER_TYPE")
    assert poses.maps["feather_types"] == ("feathers", "scales") and 0 < poses.maps["feather_type"].mean() < 1
    # a float attribute rounded half away from zero, negative values 0: the bird's UVs scaled into 0..2
    bird = shared_model("bird")
    run, poses = both_inputs(host, tmp_path, bird, "--type-map", "TEXCOORD_0:1", "--feather-types", "feathers,scales,kite,sleek")
    assert_same_library_input(run, poses, "bird")
    # no type map: no types, whatever --feather-types says (as the host)
    run, poses = both_inputs(host, tmp_path, model, "--feather-types", "kite")
    assert "feather_type" not in run.maps and "feather_types" not in poses.maps
    assert struct.unpack_from("<I", (tmp_path / "run.poses").read_bytes(), 8)[0] == 2  # the skeleton only


def test_dress_reports_flow_validation_and_sampling(host, tmp_path) -> None:
    """dress prints where the flow came from (the host's config.flow_from), the sampling's field singularities and,
    with --validate, each validated frame's pairs, penetrations, coverage and discord; native and --host agree."""
    pytest.importorskip("pxr", reason="usd-core is not installed")
    import re

    model = str(character(tmp_path))
    options = ["--feathers", "300", "--frames", "3", "--threads", "1", "--type-map", "_FEATHER_TYPE", "--layer-map", "_LAYER",
               "--theta", "20", "--quiet"]
    native = dress(tmp_path, model, "--out", "native.usda", "--validate", "every", *options)
    assert native.returncode == 0, native.stderr
    hosted = dress(tmp_path, model, "--out", "hosted.usda", "--validate", "every", "--host", host, *options)
    assert hosted.returncode == 0, hosted.stderr
    assert (tmp_path / "native.usda").read_bytes() == (tmp_path / "hosted.usda").read_bytes()
    run_host(host, model, *options[:-1], "--validate", "every", "--report", str(tmp_path / "r.json"))
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["config"]["flow_from"] == "skeleton"
    for out in (native.stdout, hosted.stdout):
        assert "flow_from skeleton" in out and "flow from the skeleton (16 joints)" in out
        assert re.search(r"field_singularities \d+", out)
        frames = re.findall(r"frame (\d)/3 .*: pairs (\d+), penetrations (\d+), coverage ([\d.]+), discord_percent ([\d.]+)", out)
        assert [f[0] for f in frames] == ["1", "2", "3"] and "rest pose: pairs" in out
    assert native.stdout.split("->")[1].count("discord_percent") == hosted.stdout.split("->")[1].count("discord_percent") == 4
    # the same figures as the host's report, frame by frame
    host_frames = report["frames"]
    assert len(host_frames) == 3
    ours = re.findall(r"frame \d/3 .*: pairs (\d+), penetrations (\d+), coverage ([\d.]+), discord_percent ([\d.]+)", native.stdout)
    for v, (pairs, pen, cov, discord) in zip(host_frames, ours):
        assert (v["intersecting_pairs"], v["body_penetrations"]) == (int(pairs), int(pen))
        assert abs(v["coverage"] - float(cov)) < 1e-4 and abs(v["discord_percent"] - float(discord)) < 0.01
    assert int(re.search(r"field_singularities (\d+)", native.stdout).group(1)) == report["sampling"]["field_singularities"]
    # flow from a source, an axis, a map; last only; none
    bird = str(shared_model("bird"))
    for on, extra, source in ((model, ["--flow-source", "0,2,0"], "flow_source"), (model, ["--flow", "0,-1,0"], "flow_axis"),
                              (bird, ["--flow-map", "NORMAL"], "flow_map"), (bird, ["--skeleton-flow", "off"], "flow_source")):
        run = dress(tmp_path, on, "--out", "x.usda", "--feathers", "100", "--frames", "2", *extra)
        assert run.returncode == 0 and f"flow_from {source}" in run.stdout, run.stderr
        assert "frame 2/2" in run.stdout and "frame 1/2" not in run.stdout  # --validate last by default
    run = dress(tmp_path, model, "--out", "x.usda", "--feathers", "100", "--frames", "2", "--validate", "none")
    assert run.returncode == 0 and "discord_percent" not in run.stdout and "field_singularities" in run.stdout
