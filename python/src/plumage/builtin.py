"""The C++ host's built-in model (cpp_examples/gltf_host/procedural_model.cpp):
an elongated body, head at x = 0 and tail at x = 4, y up, bending sideways
with a travelling wave that grows toward the tail and fades in over the first
half second (clip "swim", 2 s). Computed with the host's operations in the
host's order (libm's sin, cos and hypot), so its positions are the host's bit
for bit. Like a UV-mapped glTF mesh it is a soup with a duplicated seam.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import math
from typing import List, Optional

import numpy as np
import numpy.typing as npt

from .gltf import Clip, GltfUsageError

_PI = 3.14159265358979323846
_LENGTH, _RADIUS, _WAVELENGTH, _PERIOD = 4.0, 0.45, 0.8, 1.0
RINGS, SEGMENTS = 96, 32
DURATION = 2.0

# C's hypot (Python's math.hypot is its own algorithm, not libm's)
_libm = ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6")
_libm.hypot.restype = ctypes.c_double
_libm.hypot.argtypes = [ctypes.c_double, ctypes.c_double]


def _radius(u: float) -> float:
    return _RADIUS * math.sqrt(math.sin(_PI * u)) * (1.0 - 0.5 * u)


def _amplitude(u: float) -> float:
    return 0.05 + 0.35 * u * u


def _envelope(t: float) -> float:
    s = min(max(t / 0.5, 0.0), 1.0)
    return s * s * (3 - 2 * s)


class ProceduralBody:
    """The built-in model with `rings` cross-sections of `segments` vertices."""

    mesh_name = "procedural_body"
    facing = (-1.0, 0.0, 0.0)  # the head is at x = 0 and the body runs along +x

    def __init__(self, rings: int = RINGS, segments: int = SEGMENTS) -> None:
        self.rings, self.segments = max(rings, 3), max(segments, 3)
        ring_size = self.segments + 1
        head = (self.rings - 1) * ring_size
        tail = head + 1
        tris: List[int] = []
        for i in range(1, self.rings - 1):
            for j in range(self.segments):
                a, b = (i - 1) * ring_size + j, (i - 1) * ring_size + j + 1
                if i == 1:
                    tris += [head, a, b]
                if i + 2 < self.rings:
                    c, d = i * ring_size + j, i * ring_size + j + 1
                    tris += [a, c, d, a, d, b]
                else:
                    tris += [a, tail, b]
        self.triangles = np.array(tris, np.uint32).reshape(-1, 3)
        self.clip: Optional[Clip] = Clip("swim", 0, [], [], 0.0, DURATION)
        self.rest_positions = self.pose_at(0.0)
        self.first_vertex = [0]
        self.parts = [self]

    def pose_at(self, t: float) -> npt.NDArray[np.float32]:
        env = _envelope(t)
        rings, segments = self.rings, self.segments
        ring_size = segments + 1
        xyz = np.zeros(((rings - 1) * ring_size + 2, 3), np.float64)

        def centre(u: float) -> "tuple[float, float, float, float]":
            phase = 2 * _PI * (u / _WAVELENGTH - t / _PERIOD)
            x = _LENGTH * u
            w = env * _amplitude(u) * math.sin(phase)
            dw = env * (0.7 * u * math.sin(phase) + _amplitude(u) * math.cos(phase) * 2 * _PI / _WAVELENGTH)
            n = _libm.hypot(_LENGTH, dw)
            return x, w, _LENGTH / n, dw / n

        cos_sin = [(math.cos(phi), math.sin(phi)) for phi in (2 * _PI * (j % segments) / segments for j in range(ring_size))]
        for i in range(1, rings - 1):
            u = i / rings
            x, w, tx, tz = centre(u)
            r = _radius(u)
            row = (i - 1) * ring_size
            for j, (c, s) in enumerate(cos_sin):
                side, up = r * c, 0.8 * r * s
                xyz[row + j] = (x - side * tz, up, w + side * tx)
        poles = (rings - 1) * ring_size
        for end in (0, 1):
            x, w, _, _ = centre(float(end))
            xyz[poles + end] = (x, 0.0, w)
        return xyz.astype(np.float32)

    def check_requests(self, meshes: List[str], animation: str) -> None:
        """The host's checks of --mesh and --animation for the built-in model."""
        for m in meshes:
            if m not in (self.mesh_name, "0", "all"):
                raise GltfUsageError(f"--mesh {m}: the built-in model has one mesh, procedural_body")
        if len(meshes) > 1:
            raise GltfUsageError("--mesh: the built-in model has one mesh, procedural_body; give --mesh once")
        if animation not in ("", "swim", "0"):
            raise GltfUsageError(f"--animation {animation}: the built-in model has one clip, swim")
