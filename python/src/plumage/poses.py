"""Reads the file `plumage_gltf --poses FILE` writes: what the C++ glTF host
handed the library (rest mesh, configuration, per-vertex maps, and every
stepped frame's positions; from version 2 also the layer map and the
skeleton, from version 3 the per-vertex feather types), so that Python drives the library with exactly the same input. The layout is documented in cpp_examples/gltf_host/pose_writer.h.
"""

from __future__ import annotations

import ctypes
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Union

import numpy as np
import numpy.typing as npt

from . import _ffi
from .system import Skeleton

MAGIC = b"PLMPOSE\0"
_HEAD = struct.Struct("<8sII3QdII")
_SKELETON_HEAD = struct.Struct("<IIiI")  # joint_count, influences, head_joint, reserved (version 2)
_SKELETON_BIT = 1 << 5
_TYPES_HEAD = struct.Struct("<II")  # type_count, reserved (version 3)
_TYPES_BIT = 1 << 6
_PRESET_NAMES = {v: k for k, v in _ffi.PRESETS.items()}


class PosesFormatError(ValueError):
    """The file is not a pose file of a version this package reads."""


@dataclass(frozen=True)
class Poses:
    rest: npt.NDArray[np.float32]  # (n, 3)
    triangles: npt.NDArray[np.uint32]  # (m, 3)
    times: npt.NDArray[np.float64]  # (frames,) clip seconds
    frames: npt.NDArray[np.float32]  # (frames, n, 3)
    fps: float
    config: Dict[str, Any]  # keyword arguments of plumage.System
    maps: Dict[str, Any]  # keyword arguments of plumage.System (those present): float32 arrays, `skeleton` a plumage.Skeleton,
    # `feather_type` a uint32 array with `feather_types` the preset names


def config_from_struct(raw: _ffi.Config) -> Dict[str, Any]:
    out: Dict[str, Any] = {}
    for name in (f[0] for f in _ffi.Config._fields_):
        if name in _ffi.NON_KEYWORD_FIELDS:
            continue
        v = getattr(raw, name)
        out[name] = tuple(v) if isinstance(v, ctypes.Array) else v
    if not raw.flow_source_enabled:
        out["flow_source"] = None
    return out


def read_poses(path: Union[str, Path]) -> Poses:
    data = Path(path).read_bytes()
    if len(data) < _HEAD.size:
        raise PosesFormatError(f"{path}: too short for a pose file")
    magic, version, config_size, nv, nt, nf, fps, mask, _ = _HEAD.unpack_from(data, 0)
    if magic != MAGIC:
        raise PosesFormatError(f"{path}: not a pose file (written by plumage_gltf --poses)")
    if version not in (1, 2, 3):
        raise PosesFormatError(f"{path}: pose file version {version}; this package reads versions 1 to 3")
    if version == 1 and mask >> 4:
        raise PosesFormatError(f"{path}: version 1 with map bits {mask:#x} (layer and skeleton came with version 2)")
    if version < 3 and mask >> 6:
        raise PosesFormatError(f"{path}: version {version} with map bits {mask:#x} (feather types came with version 3)")
    if mask >> 7:
        raise PosesFormatError(f"{path}: unknown map bits {mask:#x}")
    if config_size != ctypes.sizeof(_ffi.Config):
        raise PosesFormatError(f"{path}: PlumageConfig of {config_size} bytes; this package's has {ctypes.sizeof(_ffi.Config)}")
    map_sizes = [("spacing_scale", nv), ("length_scale", nv), ("width_scale", nv), ("orientations", 3 * nv), ("layer", nv)]
    expected = _HEAD.size + config_size + 12 * nv + 12 * nt + 8 * nf + 12 * nv * nf
    expected += sum(4 * size for bit, (_, size) in enumerate(map_sizes) if mask >> bit & 1)
    joints = influences = head_joint = 0
    if mask & _SKELETON_BIT:
        at = expected - 12 * nv * nf  # the skeleton block sits before the frames
        if len(data) < at + _SKELETON_HEAD.size:
            raise PosesFormatError(f"{path}: too short for its skeleton")
        joints, influences, head_joint, _ = _SKELETON_HEAD.unpack_from(data, at)
        expected += _SKELETON_HEAD.size + 16 * joints + 8 * influences * nv
    type_count = 0
    if mask & _TYPES_BIT:
        at = expected - 12 * nv * nf  # the types block sits before the frames, after the skeleton
        if len(data) < at + _TYPES_HEAD.size:
            raise PosesFormatError(f"{path}: too short for its feather types")
        type_count, _ = _TYPES_HEAD.unpack_from(data, at)
        expected += _TYPES_HEAD.size + 4 * type_count + 4 * nv
    if len(data) != expected:
        raise PosesFormatError(f"{path}: {len(data)} bytes where its header announces {expected}")
    offset = _HEAD.size
    raw = _ffi.Config.from_buffer_copy(data[offset : offset + config_size])
    offset += config_size

    def take(dtype: Any, count: int) -> np.ndarray:
        nonlocal offset
        arr = np.frombuffer(data, dtype=dtype, count=count, offset=offset).copy()
        offset += arr.nbytes
        return arr

    rest = take("<f4", 3 * nv).reshape(-1, 3)
    triangles = take("<u4", 3 * nt).reshape(-1, 3)
    times = take("<f8", nf)
    maps: Dict[str, Any] = {}
    for bit, (name, size) in enumerate(map_sizes):
        if mask >> bit & 1:
            values = take("<f4", size)
            maps[name] = values.reshape(-1, 3) if name == "orientations" else values
    if mask & _SKELETON_BIT:
        offset += _SKELETON_HEAD.size
        positions = take("<f4", 3 * joints).reshape(-1, 3)
        parents = take("<i4", joints)
        vertex_joints = take("<u4", influences * nv).reshape(nv, influences)
        vertex_weights = take("<f4", influences * nv).reshape(nv, influences)
        maps["skeleton"] = Skeleton(positions, parents, vertex_joints, vertex_weights, head_joint)
    if mask & _TYPES_BIT:
        offset += _TYPES_HEAD.size
        presets = take("<u4", type_count)
        unknown = [int(p) for p in presets if int(p) not in _PRESET_NAMES]
        if unknown:
            raise PosesFormatError(f"{path}: feather type preset {unknown[0]} is none this package knows")
        maps["feather_types"] = tuple(_PRESET_NAMES[int(p)] for p in presets)
        maps["feather_type"] = take("<u4", nv)
    frames = take("<f4", 3 * nv * nf).reshape(nf, nv, 3)
    return Poses(rest=rest, triangles=triangles, times=times, frames=frames, fps=fps, config=config_from_struct(raw), maps=maps)
