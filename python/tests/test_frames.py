"""Frames, copy-out, figures, determinism and the save/load round trip."""

from __future__ import annotations

import numpy as np
import pytest

import plumage

from conftest import wobble


def run(sphere, threads: int, frames: int = 3, **config) -> plumage.System:
    v, t = sphere
    s = plumage.System(v, t, target_feathers=400, seed=11, threads=threads, **config)
    for k in range(1, frames + 1):
        s.step(wobble(v, k))
    return s


def test_same_bytes_at_one_and_two_threads(sphere) -> None:
    with run(sphere, 1) as a, run(sphere, 2) as b:
        assert a.feathers().tobytes() == b.feathers().tobytes()
        assert a.feather_triangles().tobytes() == b.feather_triangles().tobytes()


def test_save_load_round_trip_gives_identical_next_steps(sphere) -> None:
    v, t = sphere
    with run(sphere, 1, frames=2) as s:
        blob = s.save_state()
        s.step(wobble(v, 3))
        s.step(wobble(v, 4))
        after_save = (s.feathers().tobytes(), s.feather_triangles().tobytes(), s.frame_stats().frame_index)
        s.load_state(blob)
        assert s.frame_stats().frame_index == 2
        s.step(wobble(v, 3))
        s.step(wobble(v, 4))
        assert (s.feathers().tobytes(), s.feather_triangles().tobytes(), s.frame_stats().frame_index) == after_save
        # a fresh system of the same mesh and configuration resumes the same way
        with plumage.System(v, t, target_feathers=400, seed=11, threads=2) as fresh:
            fresh.load_state(blob)
            fresh.step(wobble(v, 3))
            fresh.step(wobble(v, 4))
            assert fresh.feather_triangles().tobytes() == after_save[1]


def test_feather_geometry_matches_the_feathers_and_their_triangles(sphere) -> None:
    v, _ = sphere
    with run(sphere, 1, frames=1) as s:
        geo = s.feather_geometry()
        feathers = s.feathers()
        posed = s.feather_triangles()
        f = s.feather_count
        nv, nt = len(geo.positions), len(geo.triangles)
        assert geo.positions.dtype == np.float32 and geo.triangles.dtype == np.uint32
        assert geo.normals.shape == (nv, 3) and geo.uvs.shape == (nv, 2) and geo.feather_index.shape == (nv,)
        assert geo.vertex_counts.sum() == nv and geo.triangle_counts.sum() == nt and len(geo.vertex_counts) == f
        assert np.array_equal(geo.ids, feathers["id"]) and len(np.unique(geo.ids)) == f
        assert np.array_equal(geo.feather_index, np.repeat(np.arange(f), geo.vertex_counts))
        assert np.array_equal(geo.placed, feathers["length"] > 0)
        assert geo.triangles.max() < nv
        # each triangle stays within its feather's vertices
        assert np.array_equal(geo.feather_index[geo.triangles[:, 0]], np.repeat(np.arange(f), geo.triangle_counts))
        assert (geo.feather_index[geo.triangles] == geo.feather_index[geo.triangles[:, :1]]).all()
        # the mesh's triangles are plumage_system_feather_triangles, bit for bit
        assert nt * 3 == posed.shape[0] * posed.shape[1]
        assert geo.positions[geo.triangles].reshape(posed.shape).tobytes() == posed.tobytes()
        assert ((geo.uvs >= 0) & (geo.uvs <= 1)).all()
        first = np.concatenate([[0], np.cumsum(geo.vertex_counts)[:-1]]).astype(np.intp)
        # the first vertex of a placed feather is its root (u 0, on the shaft)
        assert np.allclose(geo.positions[first], feathers["root"], atol=1e-5)
        assert np.allclose(geo.uvs[first], [0.0, 0.5])
        assert np.allclose(np.linalg.norm(geo.normals, axis=1), 1.0, atol=1e-4)
        facing = np.einsum("ij,ij->i", geo.normals[first][geo.placed], feathers["normal"][geo.placed])
        assert (facing > 0).mean() > 0.95
        # only positions and normals move from frame to frame
        s.step(wobble(v, 2))
        later = s.feather_geometry()
        for name in ("uvs", "triangles", "feather_index", "vertex_counts", "triangle_counts", "ids"):
            assert np.array_equal(getattr(later, name), getattr(geo, name)), name
        assert not np.array_equal(later.positions, geo.positions)


def test_figures_after_create_and_steps(sphere) -> None:
    v, t = sphere
    with plumage.System(v, t, target_feathers=400, seed=11, threads=1) as s:
        fs = s.frame_stats()
        assert fs.frame_index == 0 and fs.adjusted == s.feather_count
        sampling = s.sampling_stats()
        assert abs(sampling.roots - 400) <= 60 and sampling.roots == s.feather_count
        assert s.ordering_stats().violations == 0
        s.step(wobble(v, 1))
        fs = s.frame_stats()
        assert fs.frame_index == 1 and fs.step_seconds > 0
        check = s.validate()
        assert check.intersecting_pairs == 0 and check.body_penetrations == 0
        assert 0.5 < check.coverage <= 1.0 and check.probes > 0
        assert check.stack_efficiency > 0 and check.stack_depth_median >= 0
        s.evaluate(wobble(v, 5))
        assert s.frame_stats().frame_index == 1  # evaluate keeps the frame count


def test_evaluate_is_independent_of_earlier_frames(sphere) -> None:
    v, t = sphere
    with run(sphere, 1, frames=3, mode="rebuild") as a, plumage.System(v, t, target_feathers=400, seed=11, threads=1, mode="rebuild") as b:
        a.evaluate(wobble(v, 6))
        b.evaluate(wobble(v, 6))
        assert a.feather_triangles().tobytes() == b.feather_triangles().tobytes()


def test_defaults_round_trip_through_the_keywords(sphere) -> None:
    d = plumage.default_config()
    assert d["mode"] == "incremental" and d["sampler"] == "guided"
    v, t = sphere
    with plumage.System(v, t, **{**d, "target_feathers": 300, "threads": 1}) as a, plumage.System(v, t, target_feathers=300, threads=1) as b:
        # (the state blob also holds wall times, so compare what the library made)
        assert a.feathers().tobytes() == b.feathers().tobytes()
        assert a.feather_triangles().tobytes() == b.feather_triangles().tobytes()


@pytest.mark.parametrize("mode", ["legacy", "rebuild"])
def test_modes_step_collision_free(sphere, mode: str) -> None:
    with run(sphere, 2, frames=2, mode=mode) as s:
        assert s.validate().intersecting_pairs == 0


def test_scales_preset_and_bent_feathers(sphere) -> None:
    v, t = sphere
    with plumage.System(v, t, target_feathers=300, threads=1) as feathers, plumage.System(
        v, t, target_feathers=300, threads=1, preset="scales"
    ) as scales, plumage.System(v, t, target_feathers=300, threads=1, shaft_segments=4) as bent:
        longest = [float(s.feathers()["length"].max()) / s.sampling_stats().spacing for s in (feathers, scales)]
        assert abs(longest[0] - 4.0) < 0.5 and abs(longest[1] - 2.0) < 0.3, longest
        for s in (scales, bent):
            v_ = s.validate()
            assert v_.intersecting_pairs == 0 and v_.body_penetrations == 0
        g = bent.feather_geometry()
        # A four-segment shaft: more than the kite's four vertices a feather, triangles to match.
        assert g.positions.shape[0] > 4 * bent.feather_count
        assert bent.feather_triangles().shape == (bent.feather_count, 3 * (g.triangles.shape[0] // bent.feather_count), 3)
        # The default feathers have four shaft segments (the sleek preset is
        # their older name); the kite preset is the rigid one.
        assert feathers.feather_geometry().positions.shape == g.positions.shape
    with plumage.System(v, t, target_feathers=300, threads=1, preset="sleek") as sleek:
        assert sleek.feather_geometry().positions.shape == g.positions.shape
    with plumage.System(v, t, target_feathers=300, threads=1, preset="kite") as kite:
        assert kite.feather_geometry().positions.shape[0] == 4 * kite.feather_count
        assert kite.feather_triangles().shape == (kite.feather_count, 6, 3)
    with pytest.raises(plumage.PlumageError) as e:
        plumage.System(v, t, preset="fur")
    assert e.value.status_name == "INVALID_ARGUMENT"
