"""Bad input from Python gives a PlumageError naming the status, never a crash,
and a refused call leaves the system as it was."""

from __future__ import annotations

import numpy as np
import pytest

import plumage
from plumage import PlumageError

from conftest import wobble


def refused(status_name: str, fn, *args, **kwargs) -> PlumageError:
    with pytest.raises(PlumageError) as info:
        fn(*args, **kwargs)
    assert info.value.status_name == status_name, str(info.value)
    assert info.value.message, "a refusal carries a message"
    assert status_name in str(info.value)
    return info.value


@pytest.fixture
def system(sphere):
    with plumage.System(*sphere, target_feathers=300, seed=5, threads=1) as s:
        yield s


def snapshot(s: plumage.System) -> bytes:
    return s.feathers().tobytes() + s.save_state()


# -- create -----------------------------------------------------------------
def test_nan_vertex_is_refused_by_name(sphere) -> None:
    v, t = sphere
    v = v.copy()
    v[7, 1] = np.nan
    e = refused("NON_FINITE", plumage.System, v, t)
    assert e.call == "plumage_system_create"


def test_huge_float64_becomes_non_finite_not_garbage(sphere) -> None:
    v, t = sphere
    v = v.astype(np.float64)
    v[3, 0] = 1e300
    refused("NON_FINITE", plumage.System, v, t)


def test_index_out_of_range(sphere) -> None:
    v, t = sphere
    t = t.copy()
    t[4, 2] = len(v)
    refused("INDEX_OUT_OF_RANGE", plumage.System, v, t)


def test_negative_index_is_not_wrapped(sphere) -> None:
    v, t = sphere
    t = t.copy()
    t[0, 0] = -1
    refused("INDEX_OUT_OF_RANGE", plumage.System, v, t)


def test_float_indices_and_string_positions_are_refused(sphere) -> None:
    v, t = sphere
    refused("INVALID_ARGUMENT", plumage.System, v, t.astype(np.float64))
    refused("INVALID_ARGUMENT", plumage.System, v.astype(str), t)
    refused("INVALID_ARGUMENT", plumage.System, v.astype(np.complex64), t)
    refused("INVALID_ARGUMENT", plumage.System, "not an array", t)


def test_wrong_shapes(sphere) -> None:
    v, t = sphere
    refused("INVALID_ARGUMENT", plumage.System, v[:, :2], t)
    refused("INVALID_ARGUMENT", plumage.System, v.reshape(-1)[:-1], t)
    refused("INVALID_MESH", plumage.System, v, t.reshape(-1)[:-1])


def test_empty_mesh(sphere) -> None:
    refused("EMPTY_MESH", plumage.System, np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))


def test_map_with_wrong_count_or_bad_values(sphere) -> None:
    v, t = sphere
    refused("INVALID_MESH", plumage.System, v, t, spacing_scale=np.ones(len(v) - 1))
    refused("INVALID_MESH", plumage.System, v, t, orientations=np.ones((len(v) + 1, 3)))
    bad = np.ones(len(v))
    bad[10] = np.nan
    refused("NON_FINITE", plumage.System, v, t, length_scale=bad)


def test_bad_configuration(sphere) -> None:
    v, t = sphere
    with pytest.raises(TypeError, match="unknown configuration field"):
        plumage.System(v, t, feathers=100)
    refused("INVALID_ARGUMENT", plumage.System, v, t, mode="fast")
    refused("INVALID_ARGUMENT", plumage.System, v, t, threads=-1)
    refused("INVALID_ARGUMENT", plumage.System, v, t, target_feathers=2.5)
    refused("INVALID_ARGUMENT", plumage.System, v, t, flow_axis=(1, 0))
    e = pytest.raises(PlumageError, plumage.System, v, t, gamma=float("nan")).value
    assert e.status_name in ("NON_FINITE", "INVALID_ARGUMENT")


# -- frames -----------------------------------------------------------------
def test_step_with_wrong_vertex_count_leaves_the_system_as_it_was(system, sphere) -> None:
    v, _ = sphere
    before = snapshot(system)
    refused("VERTEX_COUNT_MISMATCH", system.step, v[:-1])
    refused("VERTEX_COUNT_MISMATCH", system.evaluate, np.concatenate([v, v[:1]]))
    assert snapshot(system) == before


def test_step_with_nan_leaves_the_system_as_it_was(system, sphere) -> None:
    v, _ = sphere
    frame = wobble(v, 1)
    frame[5] = np.nan
    before = snapshot(system)
    refused("NON_FINITE", system.step, frame)
    refused("NON_FINITE", system.evaluate, frame)
    assert snapshot(system) == before
    system.step(wobble(v, 1))  # still usable
    assert system.frame_stats().frame_index == 1


def test_step_with_too_small_or_misshapen_array(system) -> None:
    before = snapshot(system)
    refused("INVALID_ARGUMENT", system.step, np.zeros(7, dtype=np.float32))
    refused("INVALID_ARGUMENT", system.step, np.zeros((10, 4), dtype=np.float32))
    refused("VERTEX_COUNT_MISMATCH", system.step, np.zeros((0, 3), dtype=np.float32))
    refused("INVALID_ARGUMENT", system.step, None)
    assert snapshot(system) == before


def test_non_contiguous_and_float64_positions_are_converted(system, sphere) -> None:
    v, _ = sphere
    frame = wobble(v, 1)
    wide = np.zeros((len(v), 6), dtype=np.float64)
    wide[:, ::2] = frame  # a strided float64 view holding the same numbers
    with plumage.System(*sphere, target_feathers=300, seed=5, threads=1) as twin:
        twin.step(frame)
        system.step(wide[:, ::2])
        assert system.feather_triangles().tobytes() == twin.feather_triangles().tobytes()


def test_corrupt_and_foreign_state(system, sphere) -> None:
    v, t = sphere
    before = snapshot(system)
    blob = system.save_state()
    refused("INVALID_STATE", system.load_state, b"")
    refused("INVALID_STATE", system.load_state, blob[: len(blob) // 2])
    damaged = bytearray(blob)
    damaged[len(damaged) // 2] ^= 0xFF
    refused("INVALID_STATE", system.load_state, bytes(damaged))
    refused("INVALID_ARGUMENT", system.load_state, 12345)
    with plumage.System(v, t, target_feathers=300, seed=6, threads=1) as other:
        refused("INVALID_STATE", other.load_state, blob)
    assert snapshot(system) == before


def test_closed_system_refuses(sphere) -> None:
    s = plumage.System(*sphere, target_feathers=200, seed=1, threads=1)
    s.close()
    s.close()
    refused("NULL_POINTER", s.step, sphere[0])
    refused("NULL_POINTER", lambda: s.feather_count)


def test_progress_callback_can_stop_and_exceptions_stop_too(system, sphere) -> None:
    v, t = sphere
    refused("INTERRUPTED", plumage.System, v, t, target_feathers=300, progress=lambda phase, f: True)

    def broken(phase: str, fraction: float) -> bool:
        raise RuntimeError("callback bug")

    refused("INTERRUPTED", plumage.System, v, t, target_feathers=300, progress=broken)
    phases = []
    with plumage.System(v, t, target_feathers=300, progress=lambda p, f: phases.append(p)) as s:
        assert s.feather_count > 0
    assert {"preparing", "sampling", "adjusting"} <= set(phases)
