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


def test_feather_geometry_is_the_kites_as_an_indexed_mesh(sphere) -> None:
    with run(sphere, 1, frames=1) as s:
        geo = s.feather_geometry()
        kites = s.feather_triangles()
        f = s.feather_count
        assert kites.shape == (f, 6, 3)
        assert geo.positions.shape == (4 * f, 3) and geo.positions.dtype == np.float32
        assert geo.triangles.shape == (2 * f, 3) and geo.triangles.dtype == np.uint32
        # the indexed triangles give back the library's 18 floats per feather, bit for bit
        assert geo.positions[geo.triangles].reshape(f, 6, 3).tobytes() == kites.tobytes()
        assert np.array_equal(geo.feather_index, np.repeat(np.arange(f), 4))
        assert np.array_equal(geo.ids, s.feathers()["id"])
        assert len(np.unique(geo.ids)) == f
        assert geo.vertex_counts.sum() == len(geo.positions) and geo.triangle_counts.sum() == len(geo.triangles)
        # normals are unit length and face away from the skin like the feathers' own normals
        lengths = np.linalg.norm(geo.normals, axis=1)
        placed = s.feathers()["length"] > 0
        per_vertex_placed = np.repeat(placed, 4)
        assert np.allclose(lengths[per_vertex_placed], 1.0, atol=1e-5)
        facing = np.einsum("ij,ij->i", geo.normals[::4][placed], s.feathers()["normal"][placed])
        assert (facing > 0).mean() > 0.95


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
