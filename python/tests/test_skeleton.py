"""System(skeleton=..., layer=...): the skeleton's flow, painted layers, the
new figures (discord_percent, field_singularities) and the refusals of bad
skeletons and layer maps."""

from __future__ import annotations

import numpy as np
import pytest

import plumage
from plumage import PlumageError

from conftest import uv_sphere


def capsule() -> tuple:
    """An upright body (a sphere stretched to z in [-1.5, 1.5]) and its spine: joints at z = 1.5, 0, -1.5."""
    v, t = uv_sphere(32, 48)
    v = v * np.array([0.5, 0.5, 1.5], np.float32)
    joints = np.array([[0, 0, 1.5], [0, 0, 0], [0, 0, -1.5]], np.float32)
    # each vertex weighted to its two nearest joints along z
    z = v[:, 2].astype(np.float64)
    upper = z >= 0
    u = np.where(upper, 1 - z / 1.5, -z / 1.5)  # 0 at the upper joint of the pair, 1 at the lower one
    vertex_joints = np.stack([np.where(upper, 0, 1), np.where(upper, 1, 2)], 1)
    vertex_weights = np.stack([1 - u, u], 1).astype(np.float32)
    skeleton = plumage.Skeleton(joints, np.array([-1, 0, 1]), vertex_joints, vertex_weights)
    return v, t, skeleton


def headings(s: plumage.System) -> tuple:
    f = s.feathers()
    return f["root"], f["direction"]


def test_feathers_follow_the_skeleton_from_the_head_down() -> None:
    v, t, skeleton = capsule()
    with plumage.System(v, t, skeleton=skeleton, target_feathers=800, seed=3, threads=1) as s:
        roots, dirs = headings(s)
        side = np.abs(roots[:, 2]) < 1.0
        assert side.sum() > 200
        assert np.median(-dirs[side, 2]) > 0.9  # down the body, away from the head at the top
        v_ = s.validate()
        assert v_.intersecting_pairs == 0 and v_.body_penetrations == 0
        assert 0.0 <= v_.discord_percent <= 100.0
        # a closed surface's field must turn somewhere (the hairy ball)
        assert s.sampling_stats().field_singularities >= 1
        state = s.save_state()
    # a dict is the same skeleton; the head given explicitly at the bottom turns the flow round
    as_dict = {k: getattr(skeleton, k) for k in ("joint_positions", "joint_parents", "vertex_joints", "vertex_weights")}
    with plumage.System(v, t, skeleton=as_dict, target_feathers=800, seed=3, threads=1) as s:
        assert s.save_state() == state
    with plumage.System(v, t, skeleton={**as_dict, "head_joint": 2}, target_feathers=800, seed=3, threads=1) as s:
        roots, dirs = headings(s)
        assert np.median(dirs[np.abs(roots[:, 2]) < 1.0, 2]) > 0.9
    # a flow source overrides the skeleton (the library's precedence)
    with plumage.System(v, t, skeleton=skeleton, flow_source=(0, 0, -1.5), target_feathers=800, seed=3, threads=1) as s:
        roots, dirs = headings(s)
        assert np.median(dirs[np.abs(roots[:, 2]) < 1.0, 2]) > 0.9


def test_layers() -> None:
    v, t = uv_sphere()
    with plumage.System(v, t, target_feathers=600, seed=4, threads=1) as s:
        plain = s.feathers().tobytes()
    # one layer everywhere orders nothing (the saved state differs: it names its input)
    for value in (0.0, 1.0, 0.5):
        with plumage.System(v, t, layer=np.full(len(v), value), target_feathers=600, seed=4, threads=1) as s:
            assert s.feathers().tobytes() == plain, value
    with plumage.System(v, t, layer=(v[:, 2] > 0).astype(np.float32), target_feathers=600, seed=4, threads=1) as s:
        r = s.validate()
        assert r.intersecting_pairs == 0 and r.body_penetrations == 0


def test_any_uniform_layer_orders_nothing() -> None:
    v, t = uv_sphere()
    with plumage.System(v, t, target_feathers=600, seed=4, threads=1) as s:
        plain = s.feathers().tobytes()
    with plumage.System(v, t, layer=np.full(len(v), 3.0), target_feathers=600, seed=4, threads=1) as s:
        assert s.feathers().tobytes() == plain


def refused(status_name: str, **kwargs) -> str:
    v, t, _ = capsule()
    with pytest.raises(PlumageError) as info:
        plumage.System(v, t, target_feathers=100, **kwargs)
    assert info.value.status_name == status_name, str(info.value)
    return str(info.value)


def test_bad_skeletons_and_layers_are_refused() -> None:
    v, t, sk = capsule()
    n = len(v)
    good = {"joint_positions": sk.joint_positions, "joint_parents": sk.joint_parents, "vertex_joints": sk.vertex_joints,
            "vertex_weights": sk.vertex_weights}
    assert "expected a plumage.Skeleton" in refused("INVALID_ARGUMENT", skeleton=[1, 2, 3])
    assert "no 'vertex_weights'" in refused("INVALID_ARGUMENT", skeleton={k: good[k] for k in list(good)[:3]})
    assert "unknown key 'bones'" in refused("INVALID_ARGUMENT", skeleton={**good, "bones": 1})
    assert "joint_positions" in refused("INVALID_ARGUMENT", skeleton={**good, "joint_positions": np.zeros((3, 2))})
    assert "joint_parents" in refused("INVALID_ARGUMENT", skeleton={**good, "joint_parents": [-1, 0]})
    assert "joint_parents" in refused("INDEX_OUT_OF_RANGE", skeleton={**good, "joint_parents": [-2, 0, 1]})
    assert "joint_parents" in refused("INVALID_ARGUMENT", skeleton={**good, "joint_parents": [-1.0, 0.0, 1.0]})
    assert "vertex_joints" in refused("INVALID_MESH", skeleton={**good, "vertex_joints": good["vertex_joints"][:-1]})
    assert "vertex_joints" in refused("INDEX_OUT_OF_RANGE", skeleton={**good, "vertex_joints": -good["vertex_joints"] - 1})
    assert "vertex_joints" in refused("INDEX_OUT_OF_RANGE", skeleton={**good, "vertex_joints": good["vertex_joints"] + 3})
    wide = np.zeros((n, 17), np.int64)
    assert "17 influences" in refused("INVALID_ARGUMENT", skeleton={**good, "vertex_joints": wide, "vertex_weights": wide.astype(np.float32)})
    assert "vertex_weights" in refused("INVALID_MESH", skeleton={**good, "vertex_weights": good["vertex_weights"][:-1]})
    nan = good["vertex_weights"].copy()
    nan[5, 1] = np.nan
    assert "weight" in refused("NON_FINITE", skeleton={**good, "vertex_weights": nan})
    assert "weights must be finite and >= 0" in refused("INVALID_ARGUMENT", skeleton={**good, "vertex_weights": -good["vertex_weights"]})
    assert "head_joint" in refused("INDEX_OUT_OF_RANGE", skeleton={**good, "head_joint": 3})
    assert "head_joint" in refused("INDEX_OUT_OF_RANGE", skeleton={**good, "head_joint": True})
    assert "cycle" in refused("INVALID_ARGUMENT", skeleton={**good, "joint_parents": [2, 0, 1]})
    assert "layer" in refused("INVALID_MESH", layer=np.zeros(n - 1))
    bad = np.zeros(n, np.float32)
    bad[3] = np.inf
    assert "layer" in refused("NON_FINITE", layer=bad)
    # one influence per vertex may be given flat
    with plumage.System(v, t, target_feathers=100, skeleton={**good, "vertex_joints": np.zeros(n, int), "vertex_weights": np.ones(n)}) as s:
        assert s.feather_count > 50


def test_a_type_map_gives_scales_where_it_says() -> None:
    v, t = uv_sphere()
    kinds = (np.asarray(v)[:, 2] < 0).astype(np.uint32)  # scales on the lower half
    with plumage.System(v, t, feather_type=kinds, target_feathers=600, seed=4, threads=1) as s:
        f = s.feathers()
        placed = f["length"] > 0
        ratio = f["width"][placed] / f["length"][placed]
        lower = f["root"][placed][:, 2] < -0.2
        upper = f["root"][placed][:, 2] > 0.2
        assert abs(np.median(ratio[lower]) - 1.0) < 0.1 and abs(np.median(ratio[upper]) - 1.75 / 4) < 0.05
        v_ = s.validate()
        assert v_.intersecting_pairs == 0 and v_.body_penetrations == 0
    with pytest.raises(PlumageError) as info:
        plumage.System(v, t, feather_type=kinds, feather_types=("feathers", "gills"))
    assert info.value.status_name == "INVALID_ARGUMENT"
    with pytest.raises(PlumageError) as info:
        plumage.System(v, t, feather_type=kinds + 5)
    assert info.value.status_name == "INDEX_OUT_OF_RANGE"
