"""Point caches Blender's Mesh Cache modifier plays (no bpy here, so tests
can import it without Blender).

PC2 layout (little-endian): the 12 bytes ``POINTCACHE2\\0``, int32 version
(1), int32 point count, float32 start frame, float32 sample rate, int32
sample count, then every sample's points as float32 x, y, z.
"""

from __future__ import annotations

import os
import struct
from typing import Sequence, Tuple

import numpy as np

PC2_MAGIC = b"POINTCACHE2\0"
_HEADER = struct.Struct("<12siiffi")


def write_pc2(path: str, frames: Sequence[np.ndarray], start_frame: float = 0.0, sample_rate: float = 1.0) -> None:
    """Writes one (n, 3) array per frame (every frame the same n) to `path`,
    through a temporary file so a reader never sees half a cache."""
    arrays = [np.ascontiguousarray(f, dtype="<f4").reshape(-1, 3) for f in frames]
    points = arrays[0].shape[0] if arrays else 0
    if any(a.shape[0] != points for a in arrays):
        raise ValueError("every frame of a point cache has the same point count")
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(_HEADER.pack(PC2_MAGIC, 1, points, float(start_frame), float(sample_rate), len(arrays)))
        for a in arrays:
            f.write(a.tobytes())
    os.replace(tmp, path)


def read_pc2(path: str) -> Tuple[np.ndarray, float, float]:
    """(samples (s, n, 3) float32, start frame, sample rate) of a .pc2 file."""
    with open(path, "rb") as f:
        head = f.read(_HEADER.size)
        if len(head) != _HEADER.size:
            raise ValueError(f"{path}: too short for a PC2 header")
        magic, version, points, start, rate, samples = _HEADER.unpack(head)
        if magic != PC2_MAGIC or version != 1:
            raise ValueError(f"{path}: not a PC2 version 1 file")
        data = np.frombuffer(f.read(), dtype="<f4")
    if data.size != samples * points * 3:
        raise ValueError(f"{path}: {data.size} floats for {samples} samples of {points} points")
    return data.reshape(samples, points, 3).astype(np.float32), start, rate


def sidecar_path(cache_path: str) -> str:
    """Where the state that rebuilds the live system is kept beside a cache."""
    return os.path.splitext(cache_path)[0] + ".plumage.npz"
