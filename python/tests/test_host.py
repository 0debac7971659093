"""The Python package against the C++ glTF host: same input, same coat."""

from __future__ import annotations

import numpy as np
import pytest

import plumage
from plumage.poses import PosesFormatError, read_poses

from conftest import glb_mesh_frames, run_host


@pytest.fixture(scope="module")
def host_run(host, tmp_path_factory):
    out = tmp_path_factory.mktemp("host")
    run_host(host, "--frames", "4", "--feathers", "1200", "--threads", "1", "--validate", "none", "--seed", "3",
             "--out", str(out / "run.glb"), "--poses", str(out / "run.poses"))
    return out / "run.glb", read_poses(out / "run.poses")


def test_pose_file_holds_what_the_glb_shows(host_run) -> None:
    glb, poses = host_run
    base, indices, frames = glb_mesh_frames(glb, "body")
    assert base.tobytes() == poses.rest.tobytes()
    assert np.array_equal(indices, poses.triangles)
    assert len(frames) == len(poses.frames) == len(poses.times) == 4
    assert poses.fps == 30 and np.allclose(np.diff(poses.times), 1 / 30)
    scale = np.abs(poses.rest).max()
    for k, frame in enumerate(frames):  # the .glb stores rest + (frame - rest)
        assert np.abs(frame - poses.frames[k]).max() <= 1e-6 * scale
    assert poses.config["seed"] == 3 and poses.config["target_feathers"] == 1200 and poses.config["threads"] == 1


def test_python_coat_is_the_hosts_coat(host_run) -> None:
    glb, poses = host_run
    base, indices, frames = glb_mesh_frames(glb, "feathers")
    for threads in (1, 2):
        config = {**poses.config, "threads": threads}
        with plumage.System(poses.rest, poses.triangles, **poses.maps, **config) as s:
            # the rest pose is stored unchanged in the .glb: identical bytes
            assert s.feather_triangles().tobytes() == base[indices].tobytes()
            scale = np.abs(base).max()
            for k, frame in enumerate(poses.frames):
                s.step(frame)
                ours = s.feather_triangles().reshape(-1, 3, 3)
                assert ours.shape == frames[k][indices].shape
                # frames are morph targets (rest + delta): equal up to that rounding
                assert np.abs(ours - frames[k][indices]).max() <= 1e-6 * scale, f"frame {k}"


def test_pose_file_errors_are_named(tmp_path, host_run) -> None:
    bad = tmp_path / "bad.poses"
    bad.write_bytes(b"not a pose file at all, just some bytes here to be long enough")
    with pytest.raises(PosesFormatError, match="not a pose file"):
        read_poses(bad)
    glb, _ = host_run
    truncated = tmp_path / "short.poses"
    truncated.write_bytes((glb.parent / "run.poses").read_bytes()[:-4])
    with pytest.raises(PosesFormatError, match="announces"):
        read_poses(truncated)
