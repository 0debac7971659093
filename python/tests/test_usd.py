"""`python -m plumage dress` writes USD that pxr reads back with the run's data."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import plumage
from plumage.poses import read_poses

from conftest import REPO, glb_mesh_frames

pxr = pytest.importorskip("pxr", reason="usd-core is not installed")
from pxr import Usd, UsdGeom  # noqa: E402


def dress(host: str, tmp_path, *args: str):
    out = tmp_path / "run.usda"
    cmd = [sys.executable, "-m", "plumage", "dress", *args, "--out", str(out), "--host", host,
           "--glb", str(tmp_path / "run.glb"), "--poses", str(tmp_path / "run.poses")]
    run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert run.returncode == 0, run.stderr
    assert "feathers" in run.stdout
    return out, read_poses(tmp_path / "run.poses")


def check_stage(path, poses, glb) -> None:
    stage = Usd.Stage.Open(str(path))
    assert stage is not None
    assert stage.GetTimeCodesPerSecond() == poses.fps
    body = UsdGeom.Mesh(stage.GetPrimAtPath("/Plumage/Body"))
    feathers = UsdGeom.Mesh(stage.GetPrimAtPath("/Plumage/Feathers"))
    assert body and feathers
    codes = list(poses.times * poses.fps)
    for mesh in (body, feathers):
        assert np.allclose(mesh.GetPointsAttr().GetTimeSamples(), codes)  # one sample per frame
        assert len(mesh.GetNormalsAttr().GetTimeSamples()) == len(codes)
        assert mesh.GetNormalsInterpolation() == UsdGeom.Tokens.vertex
    assert stage.GetStartTimeCode() == codes[0] and stage.GetEndTimeCode() == codes[-1]

    # feather count and ids: those of the library for the same input
    with plumage.System(poses.rest, poses.triangles, **poses.maps, **poses.config) as s:
        ids = s.feathers()["id"]
        pv = UsdGeom.PrimvarsAPI(feathers.GetPrim())
        usd_ids = np.array(pv.GetPrimvar("id").Get(), dtype=np.int64).view(np.uint64)
        assert pv.GetPrimvar("id").GetInterpolation() == UsdGeom.Tokens.uniform
        geo = s.feather_geometry()
        counts = np.array(feathers.GetFaceVertexCountsAttr().Get())
        assert len(usd_ids) == len(counts) == len(geo.triangles)
        assert np.array_equal(usd_ids, np.repeat(ids, geo.triangle_counts))
        assert np.array_equal(np.array(pv.GetPrimvar("featherIndex").Get()), geo.feather_index)
        st = pv.GetPrimvar("st")
        assert st.GetInterpolation() == UsdGeom.Tokens.vertex
        assert np.array_equal(np.array(st.Get(), dtype=np.float32), geo.uvs)
        for frame in poses.frames:
            s.step(frame)
        last_frame_ours = s.feather_geometry()

    # points of each frame: those of the host's .glb of the same run
    body_base, body_idx, body_frames = glb_mesh_frames(glb, "body")
    f_base, f_idx, f_frames = glb_mesh_frames(glb, "feathers")
    usd_idx = np.array(feathers.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
    assert np.array_equal(np.array(body.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3), body_idx)
    scale = np.abs(body_base).max()
    for k, code in enumerate(codes):
        bp = np.array(body.GetPointsAttr().Get(code))
        assert bp.tobytes() == poses.frames[k].tobytes()  # what the library was handed
        assert np.abs(bp - body_frames[k]).max() <= 1e-6 * scale
        fp = np.array(feathers.GetPointsAttr().Get(code), dtype=np.float32)
        assert np.abs(fp[usd_idx] - f_frames[k][f_idx]).max() <= 1e-6 * scale
    assert fp.tobytes() == last_frame_ours.positions.tobytes()
    assert np.array(feathers.GetNormalsAttr().Get(codes[-1]), dtype=np.float32).tobytes() == last_frame_ours.normals.tobytes()
    # the default (untimed) value is the rest pose, bit for bit the host's
    rest_pts = np.array(feathers.GetPointsAttr().Get(), dtype=np.float32)
    assert rest_pts[usd_idx].tobytes() == f_base[f_idx].tobytes()


def test_dress_builtin_model(host, tmp_path) -> None:
    path, poses = dress(host, tmp_path, "builtin", "--frames", "3", "--feathers", "800", "--threads", "1")
    check_stage(path, poses, tmp_path / "run.glb")


def test_dress_flamingo(host, tmp_path) -> None:
    model = REPO.parent / "shared" / "data" / "Flamingo.glb"
    if not model.is_file():
        pytest.skip(f"{model} is absent")
    path, poses = dress(host, tmp_path, str(model), "--frames", "3", "--feathers", "2000", "--fps", "24")
    assert poses.fps == 24
    check_stage(path, poses, tmp_path / "run.glb")


def test_dress_reports_failures(host, tmp_path) -> None:
    missing = subprocess.run([sys.executable, "-m", "plumage", "dress", str(tmp_path / "nope.glb"), "--out", str(tmp_path / "x.usda"),
                              "--host", host], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert missing.returncode == 3 and "nope.glb" in missing.stderr
    nohost = subprocess.run([sys.executable, "-m", "plumage", "dress", "builtin", "--out", str(tmp_path / "x.usda"),
                             "--host", str(tmp_path / "no_host")], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={"PATH": "/usr/bin:/bin"})
    assert nohost.returncode == 2 and "plumage_gltf was not found" in nohost.stderr
    assert not (tmp_path / "x.usda").exists()


def test_frame_vertices_are_matched_to_the_rest_order_by_id() -> None:
    from plumage.usd import matching_vertices

    def geometry(ids, counts, base):
        counts = np.array(counts, dtype=np.uint32)
        n = int(counts.sum())
        pts = base + np.arange(n, dtype=np.float32)[:, None] * np.ones(3, np.float32)
        return plumage.FeatherGeometry(
            positions=pts, normals=pts, uvs=np.zeros((n, 2), np.float32), triangles=np.zeros((0, 3), np.uint32),
            feather_index=np.repeat(np.arange(len(ids)), counts).astype(np.uint32), ids=np.array(ids, dtype=np.uint64),
            vertex_counts=counts, triangle_counts=np.zeros(len(ids), np.uint32), placed=np.ones(len(ids), bool))

    rest = geometry([30, 10, 20], [4, 3, 4], 0.0)
    frame = geometry([20, 99, 30], [4, 2, 4], 100.0)  # 10 absent, 99 unknown at rest
    dest, src = matching_vertices(rest, frame)
    # rest rows: 30 -> 0..3, 10 -> 4..6, 20 -> 7..10; frame rows: 20 -> 0..3, 99 -> 4..5, 30 -> 6..9
    assert list(dest) == [7, 8, 9, 10, 0, 1, 2, 3]
    assert list(src) == [0, 1, 2, 3, 6, 7, 8, 9]
    with pytest.raises(ValueError, match="vertex count changed"):
        matching_vertices(rest, geometry([10], [5], 0.0))


@pytest.mark.parametrize("per", ["vertex", "corner", "none"])
def test_body_uvs_and_materials(tmp_path, sphere, per) -> None:
    """write_run without the host: the body gets `st` when UVs are given (per
    vertex or per triangle corner), both meshes a bound UsdPreviewSurface."""
    from pxr import UsdShade

    from conftest import wobble
    from plumage.usd import write_run

    verts, tris = sphere
    uvs = {"vertex": verts[:, :2] * 0.5 + 0.5, "corner": (verts[:, :2] * 0.5 + 0.5)[tris.ravel()], "none": None}[per]
    out = tmp_path / "run.usda"
    with plumage.System(verts, tris, target_feathers=300, seed=2) as s:
        write_run(out, s, verts, tris, [wobble(verts, k) for k in (1, 2)], [1 / 24, 2 / 24], 24.0, body_uvs=uvs)
    stage = Usd.Stage.Open(str(out))
    body, feathers = stage.GetPrimAtPath("/Plumage/Body"), stage.GetPrimAtPath("/Plumage/Feathers")
    st = UsdGeom.PrimvarsAPI(body).GetPrimvar("st")
    if uvs is None:
        assert not st.IsDefined()
    else:
        assert st.GetInterpolation() == (UsdGeom.Tokens.vertex if per == "vertex" else UsdGeom.Tokens.faceVarying)
        assert np.array_equal(np.array(st.Get(), dtype=np.float32), uvs.astype(np.float32))
    for prim, name in ((body, "Body"), (feathers, "Feathers")):
        material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        assert material and material.GetPath() == f"/Plumage/Materials/{name}"
        shader = material.ComputeSurfaceSource()[0]
        assert shader.GetIdAttr().Get() == "UsdPreviewSurface"
        assert material.GetInput("frame:stPrimvarName").Get() == "st"


def test_body_uvs_of_the_wrong_length_are_refused(tmp_path, sphere) -> None:
    from plumage.usd import write_run

    verts, tris = sphere
    with plumage.System(verts, tris, target_feathers=200) as s, pytest.raises(ValueError, match="body_uvs"):
        write_run(tmp_path / "x.usda", s, verts, tris, [verts], [0.0], 24.0, body_uvs=np.zeros((5, 2)))
