"""The memory figure and limit (issue 36) from Python."""

from __future__ import annotations

import pytest

import plumage


def test_memory_figure_by_part(sphere) -> None:
    s = plumage.System(*sphere, target_feathers=300, seed=2, threads=1)
    m = s.memory()
    assert m.total == m.mesh + m.coat + m.neighbourhoods + m.history + m.scratch
    assert min(m.mesh, m.coat, m.neighbourhoods, m.scratch) > 0


def test_memory_limit_refuses_create(sphere) -> None:
    with pytest.raises(plumage.PlumageError) as e:
        plumage.System(*sphere, target_feathers=300, seed=2, threads=1, memory_limit=1000)
    assert "memory_limit" in str(e.value)
    s = plumage.System(*sphere, target_feathers=300, seed=2, threads=1, memory_limit=1 << 30)
    assert s.memory().total < 1 << 30
