"""Scrubbing from Python (issue 35): seek, then replay, gives the playback bytes."""

from __future__ import annotations

import numpy as np
import pytest

import plumage


def _clip(vertices: np.ndarray, frames: int) -> list:
    return [vertices * (1.0 + 0.02 * np.sin(0.4 * k)) for k in range(frames)]


def test_seek_and_replay_give_the_playback_bytes(sphere) -> None:
    positions, triangles = sphere
    clip = _clip(np.asarray(positions, dtype=np.float32).reshape(-1, 3), 16)
    s = plumage.System(positions, triangles, target_feathers=200, seed=3, threads=1, checkpoint_interval=5)
    playback = [s.save_state()]
    for frame in clip:
        s.step(frame)
        playback.append(s.save_state())
    for target in (12, 3, 16, 7, 0, 11):
        start = s.seek(target)
        assert 0 <= start <= target
        for k in range(start, target):
            s.step(clip[k])
        assert s.save_state() == playback[target], f"seek to {target} from {start}"


def test_seek_is_refused_without_checkpoints(sphere) -> None:
    s = plumage.System(*sphere, target_feathers=100, seed=3, threads=1)
    with pytest.raises(plumage.PlumageError):
        s.seek(3)
    with pytest.raises(plumage.PlumageError):
        s.seek(-1)
