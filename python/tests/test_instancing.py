"""Feathers for instancing: the packed records placed on the template card give
the copied-out geometry, and the changed list names every feather that moved."""

from __future__ import annotations

import numpy as np
import pytest

import plumage
from plumage import _ffi

from conftest import wobble


def place(records: np.ndarray, card: plumage.FeatherTemplate) -> np.ndarray:
    """(F, V, 3): every record's card in world space, by the convention of
    PlumageFeatherInstance (the reference shader's steps, vectorised)."""
    q = records["rotation"].astype(np.float64) / 32767.0
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    bends = records["bends"].astype(np.float64) * _ffi.INSTANCE_BEND_RANGE / 32767.0
    s = card.segments
    angles = np.concatenate([np.zeros((len(records), 1)), np.cumsum(bends, axis=1)], axis=1)[:, :s]  # a_k
    length = records["length"].astype(np.float64)[:, None]
    steps = np.stack([np.cos(angles), np.sin(angles)], axis=-1) * (length / s)[..., None]  # (F, S, 2)
    starts = np.concatenate([np.zeros((len(records), 1, 2)), np.cumsum(steps, axis=1)[:, :-1]], axis=1)
    k = card.vertex_segments.astype(np.intp)
    along = (card.positions[:, 0] - k / s)[None, :] * length  # (F, V)
    a = angles[:, k]
    shaft = starts[:, k] + np.stack([np.cos(a), np.sin(a)], axis=-1) * along[..., None]
    local = np.stack([shaft[..., 0], card.positions[None, :, 1] * records["width"][:, None], shaft[..., 1]], axis=-1)
    u, w = q[:, None, :3], q[:, None, 3:]
    t = 2.0 * np.cross(u, local)
    return records["root"][:, None, :] + local + w * t + np.cross(u, t)


@pytest.mark.parametrize("segments", [1, 2, 3, 4])
def test_records_reconstruct_the_geometry(sphere, segments: int) -> None:
    v, t = sphere
    with plumage.System(v, t, target_feathers=400, seed=11, threads=1, shaft_segments=segments) as s:
        for k in range(1, 4):
            s.step(wobble(v, k))
        records = s.feather_instances()
        card = s.feather_template()
        geo = s.feather_geometry()
        assert records.dtype.itemsize == 36 and len(records) == s.feather_count
        assert card.segments == segments and np.array_equal(card.uvs, geo.uvs[: len(card.uvs)])
        placed = place(records, card)
        got = geo.positions.reshape(len(records), -1, 3)
        error = np.linalg.norm(placed - got, axis=2).max(axis=1)
        shown = records["length"] > 0
        assert (error[shown] / records["length"][shown]).max() < 1e-4
        assert (error[~shown] == 0).all()


def test_changed_feathers_name_every_feather_that_moved(sphere) -> None:
    v, t = sphere
    with plumage.System(v, t, target_feathers=400, seed=11, threads=1) as s:
        listed, every = s.changed_feathers()
        assert every and np.array_equal(listed, np.arange(s.feather_count))
        held = v[:, 2] < 0.0  # the lower half stays put, bit for bit
        before = (s.feather_instances(), s.feather_geometry().positions)
        for k in range(1, 4):
            frame = np.where(held[:, None], v, wobble(v, k)).astype(np.float32)
            s.step(frame)
            after = (s.feather_instances(), s.feather_geometry().positions)
            listed, every = s.changed_feathers()
            assert not every and 0 < len(listed) < s.feather_count
            nv = len(after[1]) // s.feather_count
            same = (before[0].view(np.uint8).reshape(-1, 36) == after[0].view(np.uint8).reshape(-1, 36)).all(axis=1)
            same &= (before[1].reshape(-1, nv * 3).view(np.uint32) == after[1].reshape(-1, nv * 3).view(np.uint32)).all(axis=1)
            mask = np.zeros(s.feather_count, dtype=bool)
            mask[listed] = True
            assert same[~mask].all() and not same[mask].any()
            before = after
