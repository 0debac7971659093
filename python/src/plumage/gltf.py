"""glTF input for `python -m plumage dress`: one or more meshes of a .glb or
.gltf file evaluated at any time of one animation clip (node hierarchy with
TRS or matrix, morph targets, linear blend skins), read with `pygltflib`.

This is a port of the C++ host's evaluator (cpp_examples/gltf_host:
gltf_scene.cpp, animation.cpp, accessor.cpp, math3d.h) that keeps its
choices and its arithmetic: the same mesh is chosen, vertices are numbered
the same way (the triangle primitives one after the other, no welding), and
every position is computed in float64 with the same operations in the same
order before being rounded to float32, so the rest pose and every frame are
bit for bit what the host hands the library. Per-vertex work is done with
numpy element-wise operations (never matmul or dot, whose summation order
and fused multiply-adds differ); the few node matrices in plain Python floats.
"""

from __future__ import annotations

import base64
import bisect
import json
import math
import struct
import urllib.parse
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

try:
    import pygltflib  # type: ignore[import-untyped]
except ImportError as e:  # pragma: no cover - exercised only without pygltflib
    raise ImportError("plumage.gltf needs the pygltflib package: pip install pygltflib") from e

# glTF constants
_BYTE, _UBYTE, _SHORT, _USHORT, _UINT, _FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
_COMPONENT: Dict[int, Tuple["np.dtype[Any]", float]] = {
    _BYTE: (np.dtype("<i1"), 127.0),
    _UBYTE: (np.dtype("<u1"), 255.0),
    _SHORT: (np.dtype("<i2"), 32767.0),
    _USHORT: (np.dtype("<u2"), 65535.0),
    _UINT: (np.dtype("<u4"), 4294967295.0),
    _FLOAT: (np.dtype("<f4"), 0.0),
}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_TRIANGLES, _STRIP, _FAN = 4, 5, 6
_MAX_VALUES = 1 << 26  # as the host: no accessor may ask for more
_FLOAT_MAX = float(np.finfo(np.float32).max)

Mat4 = List[float]  # column-major, element (row r, column c) at [c * 4 + r]
_IDENTITY: Mat4 = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]


class GltfError(ValueError):
    """Content the reader cannot read (the host's InputError, exit 3)."""


class GltfUsageError(ValueError):
    """A request that names something the file does not hold (the host's UsageError, exit 2)."""


# ---------------------------------------------------------------- math3d.h


def mat_mul(a: Mat4, b: Mat4) -> Mat4:
    r = [0.0] * 16
    for c in range(4):
        for row in range(4):
            s = 0.0
            for k in range(4):
                s += a[k * 4 + row] * b[c * 4 + k]
            r[c * 4 + row] = s
    return r


def normalized(q: Sequence[float]) -> Tuple[float, float, float, float]:
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not (n > 0) or not math.isfinite(n):
        return (0.0, 0.0, 0.0, 1.0)
    return (x / n, y / n, z / n, w / n)


def slerp(a: Sequence[float], b: Sequence[float], u: float) -> Tuple[float, float, float, float]:
    d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
    if d < 0:
        b = (-b[0], -b[1], -b[2], -b[3])
        d = -d
    wa, wb = 1 - u, u
    if d < 0.9995:
        theta = math.acos(d)
        s = math.sin(theta)
        wa = math.sin((1 - u) * theta) / s
        wb = math.sin(u * theta) / s
    return normalized((wa * a[0] + wb * b[0], wa * a[1] + wb * b[1], wa * a[2] + wb * b[2], wa * a[3] + wb * b[3]))


def compose_trs(t: Sequence[float], q_in: Sequence[float], s: Sequence[float]) -> Mat4:
    qx, qy, qz, qw = normalized(q_in)
    xx, yy, zz = qx * qx, qy * qy, qz * qz
    xy, xz, yz = qx * qy, qx * qz, qy * qz
    wx, wy, wz = qw * qx, qw * qy, qw * qz
    r = list(_IDENTITY)
    r[0] = (1 - 2 * (yy + zz)) * s[0]
    r[1] = 2 * (xy + wz) * s[0]
    r[2] = 2 * (xz - wy) * s[0]
    r[4] = 2 * (xy - wz) * s[1]
    r[5] = (1 - 2 * (xx + zz)) * s[1]
    r[6] = 2 * (yz + wx) * s[1]
    r[8] = 2 * (xz + wy) * s[2]
    r[9] = 2 * (yz - wx) * s[2]
    r[10] = (1 - 2 * (xx + yy)) * s[2]
    r[12], r[13], r[14] = t[0], t[1], t[2]
    return r


def _transform(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    """transform_point for every row: m is (16,) or (n, 16) column-major, p (n, 3) float64."""
    m = m.reshape(-1, 16)
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    out = np.empty_like(p)
    for row in range(3):
        out[:, row] = m[:, row] * x + m[:, 4 + row] * y + m[:, 8 + row] * z + m[:, 12 + row]
    return out


def to_float32(x: np.ndarray) -> npt.NDArray[np.float32]:
    """Doubles to floats as the host stores them: beyond float's range, an infinity."""
    with np.errstate(over="ignore", invalid="ignore"):
        out = x.astype(np.float32)
    out[x > _FLOAT_MAX] = np.inf
    out[x < -_FLOAT_MAX] = -np.inf
    return out


# ---------------------------------------------------------------- the file


def _raw_json(path: Path, data: bytes) -> Dict[str, Any]:
    """The file's JSON (pygltflib drops a few fields the host reads, e.g. a node's morph weights)."""
    if data[:4] == b"glTF":
        if len(data) < 20:
            raise GltfError(f"{path}: truncated GLB header")
        length, kind = struct.unpack_from("<II", data, 12)
        if kind != 0x4E4F534A:
            raise GltfError(f"{path}: the first GLB chunk is not JSON")
        raw: Dict[str, Any] = json.loads(data[20 : 20 + length])
        return raw
    doc: Dict[str, Any] = json.loads(data)
    return doc


class GltfFile:
    """A glTF file: pygltflib's model, its buffers and accessors read as the host reads them."""

    def __init__(self, path: Union[str, Path]) -> None:
        self.path = Path(path)
        if self.path.is_dir():
            raise GltfError(f"{path}: is a directory")
        try:
            data = self.path.read_bytes()
        except OSError as e:
            raise GltfError(f"{path}: cannot open: {e.strerror or e}") from None
        if not data:
            raise GltfError(f"{path}: empty file")
        if data[:4] != b"glTF" and not data.lstrip(b" \t\r\n").startswith(b"{"):
            raise GltfError(f"{path}: not a glTF file (neither a GLB container nor JSON)")
        try:
            self.raw = _raw_json(self.path, data)
            self.gltf = pygltflib.GLTF2.load_from_bytes(data) if data[:4] == b"glTF" else pygltflib.GLTF2.from_json(data.decode("utf-8"))
        except Exception as e:  # noqa: BLE001 - any parse failure is an unreadable input
            raise GltfError(f"{path}: invalid glTF: {e}") from None
        for ext in self.gltf.extensionsRequired or []:
            if not (ext in ("KHR_mesh_quantization", "KHR_lights_punctual") or ext.startswith(("KHR_materials_", "KHR_texture_", "EXT_texture_"))):
                raise GltfError(f"{path}: requires the unsupported extension {ext}")
        self._buffers: Dict[int, bytes] = {}

    @property
    def meshes(self) -> List[Any]:
        return self.gltf.meshes or []

    @property
    def nodes(self) -> List[Any]:
        return self.gltf.nodes or []

    def node_weights(self, node: int) -> List[float]:
        nodes = self.raw.get("nodes") or []
        return [float(w) for w in (nodes[node].get("weights") or [])] if node < len(nodes) else []

    def buffer(self, index: int) -> bytes:
        if index in self._buffers:
            return self._buffers[index]
        buffers = self.gltf.buffers or []
        if index is None or not 0 <= index < len(buffers):
            raise GltfError(f"buffer {index} does not exist")
        uri = buffers[index].uri
        if uri is None:
            blob = self.gltf.binary_blob() if index == 0 else None
            if blob is None:
                raise GltfError(f"buffer {index} has no data")
            data = bytes(blob)
        elif uri.startswith("data:"):
            data = base64.b64decode(uri.split(",", 1)[1])
        else:
            try:
                data = (self.path.parent / urllib.parse.unquote(uri)).read_bytes()
            except OSError as e:
                raise GltfError(f"buffer {index}: cannot read {uri}: {e.strerror or e}") from None
        self._buffers[index] = data
        return data

    def _view(self, index: Optional[int], what: str) -> Tuple[bytes, int, int, Optional[int]]:
        views = self.gltf.bufferViews or []
        if index is None or not 0 <= index < len(views):
            raise GltfError(f"{what}: buffer view {index} does not exist")
        v = views[index]
        data = self.buffer(v.buffer)
        off, length = v.byteOffset or 0, v.byteLength or 0
        if off > len(data) or length > len(data) - off:
            raise GltfError(f"{what}: buffer view {index} runs past the end of its buffer")
        return data, off, length, v.byteStride

    def accessor_count(self, index: Optional[int]) -> int:
        accessors = self.gltf.accessors or []
        return accessors[index].count if index is not None and 0 <= index < len(accessors) else 0

    def accessor(self, index: Optional[int], what: str, components: Optional[int] = None) -> npt.NDArray[np.float64]:
        """Accessor `index` as float64 (count, width): normalized integers as
        the glTF spec maps them, other integers by value; no buffer view = zeros;
        sparse substitution applied (accessor.cpp's read_accessor)."""
        accessors = self.gltf.accessors or []
        if index is None or not 0 <= index < len(accessors):
            raise GltfError(f"{what}: accessor {index} does not exist")
        acc = accessors[index]
        if acc.componentType not in _COMPONENT or acc.type not in _WIDTH:
            raise GltfError(f"{what}: unsupported accessor component type or element type")
        dtype, scale = _COMPONENT[acc.componentType]
        width = _WIDTH[acc.type]
        if acc.type in ("MAT2", "MAT3") and dtype.itemsize < 4:
            raise GltfError(f"{what}: padded small-component matrices are not supported")
        count = acc.count or 0
        if count > _MAX_VALUES // width:
            raise GltfError(f"{what}: accessor count {count} is too large")
        element = dtype.itemsize * width
        out = np.zeros((count, width), np.float64)

        def convert(raw: np.ndarray) -> np.ndarray:
            values = raw.astype(np.float64)
            if acc.normalized and acc.componentType != _FLOAT:
                values = values / scale
                if acc.componentType in (_BYTE, _SHORT):
                    values = np.maximum(values, -1.0)
            return values

        if acc.bufferView is not None:
            data, off, length, declared = self._view(acc.bufferView, what)
            stride = declared or element
            if stride < element or stride % dtype.itemsize != 0:
                raise GltfError(f"{what}: byte stride {stride} does not fit its elements")
            start = acc.byteOffset or 0
            if count:
                if start > length or stride * (count - 1) + element > length - start:
                    raise GltfError(f"{what}: accessor runs past the end of its buffer view")
                raw = np.ndarray((count, width), dtype, buffer=data, offset=off + start, strides=(stride, dtype.itemsize))
                out[:] = convert(raw)
        sparse = acc.sparse
        if sparse is not None and sparse.count is not None:
            n = sparse.count
            if n < 1 or n > count:
                raise GltfError(f"{what}: sparse count out of range")
            itype = sparse.indices.componentType
            if itype not in (_UBYTE, _USHORT, _UINT):
                raise GltfError(f"{what}: sparse indices must be unsigned integers")
            idata, ioff0, ilen, _ = self._view(sparse.indices.bufferView, what)
            vdata, voff0, vlen, _ = self._view(sparse.values.bufferView, what)
            ioff, voff = sparse.indices.byteOffset or 0, sparse.values.byteOffset or 0
            isize = _COMPONENT[itype][0].itemsize
            if ioff > ilen or isize * n > ilen - ioff:
                raise GltfError(f"{what}: sparse indices run past their buffer view")
            if voff > vlen or element * n > vlen - voff:
                raise GltfError(f"{what}: sparse values run past their buffer view")
            targets = np.frombuffer(idata, _COMPONENT[itype][0], n, ioff0 + ioff).astype(np.int64)
            if (targets >= count).any():
                raise GltfError(f"{what}: sparse index past the accessor's count")
            values = np.frombuffer(vdata, dtype, n * width, voff0 + voff).reshape(n, width)
            for i in range(n):  # in order: a repeated index keeps the last value, as the host
                out[targets[i]] = convert(values[i])
        if components is not None and width != components:
            raise GltfError(f"{what}: expected {components} components per element, got {width}")
        return out

    def indices(self, index: int, what: str) -> npt.NDArray[np.uint32]:
        values = self.accessor(index, what, 1)[:, 0]
        acc = self.gltf.accessors[index]
        if acc.normalized or acc.componentType in (_FLOAT, _BYTE, _SHORT):
            raise GltfError(f"{what}: indices must be unsigned integers")
        return values.astype(np.uint32)


# ---------------------------------------------------------------- mesh choice


def _attribute(attributes: Any, name: str) -> Optional[int]:
    if attributes is None:
        return None
    value = attributes.get(name) if isinstance(attributes, dict) else getattr(attributes, name, None)
    return value if isinstance(value, int) else None


def _mode(p: Any) -> int:
    return _TRIANGLES if p.mode is None else p.mode


def _is_triangles(p: Any) -> bool:
    return _mode(p) in (_TRIANGLES, _STRIP, _FAN)


def _primitive_triangles(f: GltfFile, p: Any) -> int:
    if not _is_triangles(p):
        return 0
    n = f.accessor_count(p.indices) if p.indices is not None else f.accessor_count(_attribute(p.attributes, "POSITION"))
    if _mode(p) in (_STRIP, _FAN):
        return n - 2 if n >= 3 else 0
    return n // 3


def _mesh_triangles(f: GltfFile, mesh: int) -> int:
    return sum(_primitive_triangles(f, p) for p in f.meshes[mesh].primitives or [])


def _mesh_is_animated(f: GltfFile, mesh: int) -> bool:
    if any(p.targets for p in f.meshes[mesh].primitives or []):
        return True
    return any(n.mesh == mesh and n.skin is not None for n in f.nodes)


def _list_names(names: Sequence[str]) -> str:
    return ", ".join(f'{i}:"{n}"' for i, n in enumerate(names)) or "none"


def _find(names: Sequence[str], request: str) -> int:
    """`request` among `names` by exact name, then as a number."""
    for i, n in enumerate(names):
        if n == request:
            return i
    if request and len(request) < 10 and all("0" <= c <= "9" for c in request) and int(request) < len(names):
        return int(request)
    return -1


def _mesh_names(f: GltfFile) -> List[str]:
    return [m.name or "" for m in f.meshes]


def choose_mesh(f: GltfFile, request: str = "") -> int:
    """The mesh `request` names (name or index), else the largest skinned or morphed mesh, else the largest."""
    names = _mesh_names(f)
    if request:
        found = _find(names, request)
        if found < 0:
            raise GltfUsageError(f"--mesh {request}: no such mesh (meshes: {_list_names(names)})")
        if _mesh_triangles(f, found) == 0:
            raise GltfError(f"mesh {request} has no triangles")
        return found
    best = best_animated = -1
    most = most_animated = 0
    for i in range(len(names)):
        n = _mesh_triangles(f, i)
        if n > most:
            most, best = n, i
        if n > most_animated and _mesh_is_animated(f, i):
            most_animated, best_animated = n, i
    if best < 0:
        raise GltfError("the file holds no triangle mesh")
    return best_animated if best_animated >= 0 else best


def choose_meshes(f: GltfFile, requests: Sequence[str] = ()) -> List[int]:
    """The meshes `--mesh` options name, in their order (gltf_scene.h's choose_meshes)."""
    if not requests:
        return [choose_mesh(f, "")]
    if list(requests) == ["all"]:
        chosen = [i for i in range(len(f.meshes)) if _mesh_triangles(f, i) > 0 and _mesh_is_animated(f, i)]
        if not chosen:
            raise GltfUsageError(f"--mesh all: no skinned or morphed triangle mesh (meshes: {_list_names(_mesh_names(f))})")
        return chosen
    chosen = []
    for r in requests:
        if r == "all":
            raise GltfUsageError("--mesh all dresses every skinned or morphed mesh: give it alone, not with other --mesh options")
        m = choose_mesh(f, r)
        if m in chosen:
            raise GltfUsageError(f"--mesh {r}: mesh {m} is already chosen")
        chosen.append(m)
    return chosen


# ---------------------------------------------------------------- animation


class Sampler:
    """One animation sampler (animation.cpp): key times and `width` values per key."""

    def __init__(self, times: List[float], values: List[float], width: int, interpolation: str) -> None:
        self.times, self.values, self.width, self.interpolation = times, values, width, interpolation

    def _value(self, key: int) -> List[float]:
        w = self.width
        at = (3 * key + 1) * w if self.interpolation == "CUBICSPLINE" else key * w
        return self.values[at : at + w]

    def sample(self, t: float, rotation: bool) -> List[float]:
        times, w = self.times, self.width
        n = len(times)
        if n == 1 or t <= times[0] or t >= times[-1]:
            return self._value(0 if n == 1 or t <= times[0] else n - 1)
        k = bisect.bisect_right(times, t) - 1
        td = times[k + 1] - times[k]
        s = (t - times[k]) / td
        a, b = self._value(k), self._value(k + 1)
        if self.interpolation == "STEP":
            return a
        if self.interpolation == "LINEAR":
            if rotation and w == 4:
                return list(slerp(a, b, s))
            return [a[i] + s * (b[i] - a[i]) for i in range(w)]
        s2 = s * s
        s3 = s2 * s
        h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
        out_a = self.values[(3 * k + 2) * w : (3 * k + 3) * w]
        in_b = self.values[3 * (k + 1) * w : (3 * (k + 1) + 1) * w]
        out = [h00 * a[i] + h10 * td * out_a[i] + h01 * b[i] + h11 * td * in_b[i] for i in range(w)]
        if rotation and w == 4:
            out = list(normalized(out))
        return out


@dataclass(frozen=True)
class Channel:
    node: int
    path: str  # translation | rotation | scale | weights
    sampler: int


@dataclass(frozen=True)
class Clip:
    name: str
    index: int
    samplers: List[Sampler]
    channels: List[Channel]
    start: float
    end: float

    @property
    def duration(self) -> float:
        return self.end - self.start


def load_clip(f: GltfFile, index: int) -> Clip:
    anim = f.gltf.animations[index]
    what = f"animation {index}"
    samplers = []
    for i, s in enumerate(anim.samplers or []):
        sw = f"{what} sampler {i}"
        times = f.accessor(s.input, sw + " input", 1)[:, 0]
        if len(times) == 0:
            raise GltfError(f"{sw}: no keys")
        if not np.isfinite(times).all():
            raise GltfError(f"{sw}: non-finite key time")
        if (np.diff(times) < 0).any():
            raise GltfError(f"{sw}: key times decrease")
        interpolation = s.interpolation or "LINEAR"
        if interpolation not in ("LINEAR", "STEP", "CUBICSPLINE"):
            raise GltfError(f'{sw}: unsupported interpolation "{interpolation}"')
        values = f.accessor(s.output, sw + " output").reshape(-1)
        groups = len(times) * (3 if interpolation == "CUBICSPLINE" else 1)
        if len(values) == 0 or len(values) % groups != 0:
            raise GltfError(f"{sw}: output count does not match the key count")
        if not np.isfinite(values).all():
            raise GltfError(f"{sw}: non-finite output value")
        samplers.append(Sampler(times.tolist(), values.tolist(), len(values) // groups, interpolation))
    start, end = math.inf, -math.inf
    channels = []
    for c in anim.channels or []:
        target = c.target
        if target is None or target.node is None or target.path not in ("translation", "rotation", "scale", "weights"):
            continue
        if not 0 <= target.node < len(f.nodes):
            raise GltfError(f"{what}: channel targets a missing node")
        if c.sampler is None or not 0 <= c.sampler < len(samplers):
            raise GltfError(f"{what}: channel names a missing sampler")
        s = samplers[c.sampler]
        want = {"rotation": 4, "weights": 0}.get(target.path, 3)
        if want and s.width != want:
            raise GltfError(f"{what}: {target.path} channel with {s.width} values per key")
        start, end = min(start, s.times[0]), max(end, s.times[-1])
        channels.append(Channel(target.node, target.path, c.sampler))
    if not channels:
        start = end = 0.0
    return Clip(anim.name or "", index, samplers, channels, start, end)


# ---------------------------------------------------------------- one mesh


@dataclass
class _Node:
    translation: Tuple[float, ...] = (0.0, 0.0, 0.0)
    rotation: Tuple[float, ...] = (0.0, 0.0, 0.0, 1.0)
    scale: Tuple[float, ...] = (1.0, 1.0, 1.0)
    matrix: Optional[Mat4] = None


@dataclass(frozen=True)
class Skeleton:
    """The skin of a skinned mesh, for a skeleton-driven flow.

    joint_nodes: (J,) node index of each joint, in the skin's order
    parents: (J,) index within the skin of each joint's nearest ancestor
        joint, -1 for a root of the skeleton
    rest_positions: (J, 3) float64 world position of each joint at rest
        (the translation of its global transform, no animation applied)
    joints, weights: (n, 4) JOINTS_0 (into the skin's joints) and WEIGHTS_0
        of each vertex, in the mesh's vertex order (normalized integer
        weights as floats; the evaluator itself renormalizes every set)
    """

    joint_nodes: npt.NDArray[np.int64]
    parents: npt.NDArray[np.int64]
    rest_positions: npt.NDArray[np.float64]
    joints: npt.NDArray[np.int64]
    weights: npt.NDArray[np.float64]


@dataclass(eq=False)
class SkinSkeleton:
    """The skeleton as plumage_gltf hands it to the library (animated_mesh.h
    SkinSkeleton, PlumageSkeleton), usable as `plumage.System(skeleton=...)`.

    joint_positions: (J, 3) float32, each joint's rest world position (the
        float cast of its global transform's translation)
    joint_parents: (J,) int32, the nearest ancestor joint, -1 for a root
    vertex_joints, vertex_weights: (n, k) uint32 and float32: per vertex its
        influences of weight > 0 from every JOINTS_n/WEIGHTS_n set in order,
        each weight / their sum (in double, then cast), packed first and
        padded with (joint 0, weight 0) up to the widest vertex's count
        (at most 16)
    head_joint: -1 (the library picks the head)
    """

    joint_positions: npt.NDArray[np.float32]
    joint_parents: npt.NDArray[np.int32]
    vertex_joints: npt.NDArray[np.uint32]
    vertex_weights: npt.NDArray[np.float32]
    head_joint: int = -1

    @property
    def influences(self) -> int:
        return int(self.vertex_joints.shape[1])

    def append(self, other: "SkinSkeleton") -> "SkinSkeleton":
        """`other`'s joints after these and its vertices after these (SkinSkeleton::append)."""
        width = max(self.influences, other.influences)
        offset = len(self.joint_parents)

        def widen(s: SkinSkeleton, shift: int) -> Tuple[np.ndarray, np.ndarray]:
            pad = ((0, 0), (0, width - s.influences))
            return np.pad(s.vertex_joints + np.uint32(shift), pad), np.pad(s.vertex_weights, pad)

        (j0, w0), (j1, w1) = widen(self, 0), widen(other, offset)
        parents = np.where(other.joint_parents < 0, -1, other.joint_parents + offset).astype(np.int32)
        return SkinSkeleton(np.concatenate([self.joint_positions, other.joint_positions]), np.concatenate([self.joint_parents, parents]),
                            np.concatenate([j0, j1]), np.concatenate([w0, w1]))


MAX_INFLUENCES = 16


class MeshScene:
    """Mesh `mesh_index` of `f`, evaluated at any time of the clip named or
    numbered `clip_request` (else clip 0 when there is one): gltf_scene.cpp's
    GltfScene."""

    def __init__(self, f: GltfFile, mesh_index: int, clip_request: str = "") -> None:
        if not 0 <= mesh_index < len(f.meshes):
            raise GltfUsageError(f"mesh {mesh_index} does not exist")
        self.file = f
        self.mesh_index = mesh_index
        self._load_hierarchy()
        self.mesh_name = f.meshes[mesh_index].name or f"mesh {mesh_index}"
        self.instance_node = self._find_instance_node()
        self._load_mesh()
        self._select_clip(clip_request)
        self.rest_positions = self._evaluate(None, 0.0)
        if not np.isfinite(self.rest_positions).all():
            v = int(np.flatnonzero(~np.isfinite(self.rest_positions).all(axis=1))[0])
            raise GltfError(f"mesh {self.mesh_name}: the rest pose of vertex {v} is not finite (node transforms or morph weights overflow)")

    # -- loading

    def _load_hierarchy(self) -> None:
        nodes = self.file.nodes
        n = len(nodes)
        self.parent = [-1] * n
        self.nodes: List[_Node] = []
        for i, node in enumerate(nodes):
            for c in node.children or []:
                if not 0 <= c < n or c == i:
                    raise GltfError(f"node {i}: invalid child {c}")
                if self.parent[c] >= 0:
                    raise GltfError(f"node {c} has two parents")
                self.parent[c] = i
            t = _Node()
            if node.matrix:
                if len(node.matrix) != 16:
                    raise GltfError(f"node {i}: matrix must have 16 values")
                t.matrix = [float(v) for v in node.matrix]
            for name, size in (("translation", 3), ("rotation", 4), ("scale", 3)):
                value = getattr(node, name)
                if value:
                    if len(value) != size:
                        raise GltfError(f"node {i}: malformed translation, rotation or scale")
                    setattr(t, name, tuple(float(v) for v in value))
            values = list(t.translation) + list(t.rotation) + list(t.scale) + (t.matrix or [])
            if not all(math.isfinite(v) for v in values):
                raise GltfError(f"node {i}: non-finite value")
            self.nodes.append(t)
        self.order: List[int] = []  # parents before children
        stack = [i for i in range(n - 1, -1, -1) if self.parent[i] < 0]
        while stack:
            i = stack.pop()
            self.order.append(i)
            stack.extend(reversed(nodes[i].children or []))
        if len(self.order) != n:
            raise GltfError("the node hierarchy has a cycle")

    def _find_instance_node(self) -> int:
        """The node that shows the mesh: the first in the default scene, else any."""
        g, nodes = self.file.gltf, self.file.nodes
        scenes = g.scenes or []
        scene = g.scene if g.scene is not None else (0 if scenes else -1)
        if 0 <= scene < len(scenes):
            stack = list(reversed(scenes[scene].nodes or []))
            while stack:
                n = stack.pop()
                if not 0 <= n < len(nodes):
                    continue
                if nodes[n].mesh == self.mesh_index:
                    return int(n)
                stack.extend(reversed(nodes[n].children or []))
        for n in self.order:
            if nodes[n].mesh == self.mesh_index:
                return n
        return -1

    def _load_mesh(self) -> None:
        f = self.file
        mesh = f.meshes[self.mesh_index]
        prims = mesh.primitives or []
        target_count = max([len(p.targets or []) for p in prims] + [0])
        skin = f.nodes[self.instance_node].skin if self.instance_node >= 0 else None
        self.joints: List[int] = []
        self.inverse_bind: List[Mat4] = []
        self.skin_index = skin
        if skin is not None:
            self._load_skin(skin)
        positions: List[np.ndarray] = []
        indices: List[np.ndarray] = []
        deltas: List[List[np.ndarray]] = [[] for _ in range(target_count)]
        influences: List[Tuple[np.ndarray, np.ndarray]] = []
        offset = 0
        for i, p in enumerate(prims):
            if not _is_triangles(p):
                continue
            what = f"mesh {self.mesh_name} primitive {i}"
            pos = f.accessor(_attribute(p.attributes, "POSITION"), what + " POSITION", 3)
            if not np.isfinite(pos).all():
                raise GltfError(f"{what} POSITION: non-finite value")
            nv = len(pos)
            if (offset + nv) * 3 * max(target_count, 1) > (1 << 26):
                raise GltfError(f"{what}: too many vertices or morph targets")
            local = f.indices(p.indices, what + " indices") if p.indices is not None else np.arange(nv, dtype=np.uint32)
            tris = _triangle_list(_mode(p), local, what)
            if len(tris) and int(tris.max()) >= nv:
                raise GltfError(f"{what}: index {int(tris.max())} past the vertex count")
            indices.append(tris.astype(np.uint32) + np.uint32(offset))
            positions.append(pos)
            for t in range(target_count):
                targets = p.targets or []
                acc = _attribute(targets[t], "POSITION") if t < len(targets) else None
                if acc is None:
                    deltas[t].append(np.zeros((nv, 3)))
                    continue
                if f.accessor_count(acc) != nv:
                    raise GltfError(f"{what} target {t}: count differs from POSITION")
                d = f.accessor(acc, f"{what} target {t}", 3)
                if not np.isfinite(d).all():
                    raise GltfError(f"{what} target: non-finite value")
                deltas[t].append(d)
            if self.skinned:
                influences.append(self._load_skin_weights(i, p, nv))
            offset += nv
        if not indices or sum(len(x) for x in indices) == 0:
            raise GltfError(f"mesh {self.mesh_name} has no triangles")
        self.base_positions = np.concatenate(positions)
        self.triangles = np.concatenate(indices).reshape(-1, 3)
        self.target_deltas = [np.concatenate(d) for d in deltas]
        if self.skinned:
            width = max(j.shape[1] for j, _ in influences)
            self.influence_joint = np.concatenate([np.pad(j, ((0, 0), (0, width - j.shape[1])), constant_values=-1) for j, _ in influences])
            self.influence_weight = np.concatenate([np.pad(w, ((0, 0), (0, width - w.shape[1]))) for _, w in influences])
        # default weights: the node's, else the mesh's
        weights = [float(w) for w in (mesh.weights or [])]
        if self.instance_node >= 0 and self.file.node_weights(self.instance_node):
            weights = self.file.node_weights(self.instance_node)
        if not all(math.isfinite(w) for w in weights):
            raise GltfError("morph weights: non-finite value")
        self.base_weights = (weights + [0.0] * target_count)[:target_count]

    @property
    def skinned(self) -> bool:
        return bool(self.joints)

    def _load_skin(self, skin: int) -> None:
        f = self.file
        skins = f.gltf.skins or []
        if not 0 <= skin < len(skins):
            raise GltfError(f"node {self.instance_node} names a missing skin")
        s = skins[skin]
        what = f"skin {skin}"
        if not s.joints:
            raise GltfError(f"{what}: no joints")
        for j in s.joints:
            if not 0 <= j < len(f.nodes):
                raise GltfError(f"{what}: joint {j} is not a node")
        self.joints = list(s.joints)
        self.inverse_bind = [list(_IDENTITY) for _ in self.joints]
        if s.inverseBindMatrices is not None:
            m = f.accessor(s.inverseBindMatrices, what + " inverseBindMatrices", 16)
            if not np.isfinite(m).all():
                raise GltfError(f"{what}: non-finite value")
            if len(m) < len(self.joints):
                raise GltfError(f"{what}: fewer inverse bind matrices than joints")
            self.inverse_bind = [m[j].tolist() for j in range(len(self.joints))]

    def _load_skin_weights(self, index: int, p: Any, nv: int) -> Tuple[np.ndarray, np.ndarray]:
        """Every JOINTS_n / WEIGHTS_n slot of each vertex, in order, as (joint, normalized weight);
        unused slots (weight not above 0) get weight 0 and joint -1."""
        f = self.file
        what = f"mesh {self.mesh_name} primitive {index}"
        joints_sets, weight_sets = [], []
        for n in range(1 << 16):
            ja_i, wa_i = _attribute(p.attributes, f"JOINTS_{n}"), _attribute(p.attributes, f"WEIGHTS_{n}")
            if ja_i is None or wa_i is None:
                if n == 0:
                    raise GltfError(f"{what}: skinned but has no JOINTS_0 and WEIGHTS_0")
                break
            accessors = f.gltf.accessors or []
            for a in (ja_i, wa_i):
                if not 0 <= a < len(accessors):
                    raise GltfError(f"{what} JOINTS_{n}: accessor {a} does not exist")
            ja, wa = accessors[ja_i], accessors[wa_i]
            if ja.normalized or ja.componentType not in (_UBYTE, _USHORT):
                raise GltfError(f"{what} JOINTS_{n}: must be unsigned bytes or shorts")
            if wa.componentType != _FLOAT and not wa.normalized:
                raise GltfError(f"{what} WEIGHTS_{n}: integer weights must be normalized")
            j = f.accessor(ja_i, f"{what} JOINTS_{n}", 4)
            w = f.accessor(wa_i, f"{what} WEIGHTS_{n}", 4)
            if len(j) != nv or len(w) != nv:
                raise GltfError(f"{what}: JOINTS_{n}/WEIGHTS_{n} count differs from POSITION")
            used = w > 0
            if (used & (j >= len(self.joints))).any():
                raise GltfError(f"{what}: joint index past the skin's joints")
            joints_sets.append(np.where(used, j, -1).astype(np.int64))
            weight_sets.append(np.where(used, w, 0.0))
        joints = np.concatenate(joints_sets, axis=1)
        weights = np.concatenate(weight_sets, axis=1)
        total = np.zeros(nv)
        for k in range(weights.shape[1]):  # summed in slot order, as the host
            total = np.where(joints[:, k] >= 0, total + weights[:, k], total)
        with np.errstate(divide="ignore", invalid="ignore"):
            weights = np.where(joints >= 0, weights / total[:, None], 0.0)
        return joints, weights

    def _select_clip(self, request: str) -> None:
        anims = self.file.gltf.animations or []
        names = [a.name or "" for a in anims]
        if not request:
            index = 0 if names else -1
        else:
            index = _find(names, request)
            if index < 0:
                raise GltfUsageError(f"--animation {request}: no such clip (clips: {_list_names(names)})")
        self.clip: Optional[Clip] = None
        if index < 0:
            return
        self.clip = load_clip(self.file, index)
        for c in self.clip.channels:
            if c.path != "weights" and self.nodes[c.node].matrix is not None:
                raise GltfError(f"animation {index} animates node {c.node}, which has a matrix")
            if c.path == "weights" and c.node == self.instance_node and self.clip.samplers[c.sampler].width != len(self.target_deltas):
                raise GltfError(f"animation {index}: weights channel does not match the morph target count")

    # -- evaluation

    def _global_transforms(self, local: List[_Node]) -> List[Mat4]:
        out: List[Mat4] = [list(_IDENTITY)] * len(local)
        for i in self.order:
            t = local[i]
            m = t.matrix if t.matrix is not None else compose_trs(t.translation, t.rotation, t.scale)
            out[i] = m if self.parent[i] < 0 else mat_mul(out[self.parent[i]], m)
        return out

    def _vertex_maps(self, glob: List[Mat4]) -> np.ndarray:
        if not self.skinned:
            return np.array([glob[self.instance_node] if self.instance_node >= 0 else _IDENTITY], np.float64)
        return np.array([mat_mul(glob[j], self.inverse_bind[k]) for k, j in enumerate(self.joints)], np.float64)

    def _morphed(self, weights: Sequence[float]) -> np.ndarray:
        p = self.base_positions.copy()
        for t, w in enumerate(weights):
            if w == 0:
                continue
            p += w * self.target_deltas[t]
        return p

    def _posed(self, p: np.ndarray, maps: np.ndarray) -> np.ndarray:
        if not self.skinned:
            return _transform(maps[0], p)
        joint, weight = self.influence_joint, self.influence_weight
        used: np.ndarray = joint >= 0
        out = np.where(np.any(used, axis=1)[:, None], 0.0, p)  # no influence: left in place
        for k in range(joint.shape[1]):
            q = _transform(maps[np.maximum(joint[:, k], 0)], p)
            out = np.where(used[:, k : k + 1], out + weight[:, k : k + 1] * q, out)
        return out

    def _evaluate(self, clip: Optional[Clip], seconds: float) -> npt.NDArray[np.float32]:
        local = [_Node(n.translation, n.rotation, n.scale, n.matrix) for n in self.nodes]
        weights = list(self.base_weights)
        if clip is not None:
            for c in clip.channels:
                s = clip.samplers[c.sampler]
                if c.path == "weights":
                    if c.node == self.instance_node:
                        weights = s.sample(seconds, False)
                else:
                    setattr(local[c.node], c.path, tuple(s.sample(seconds, c.path == "rotation")))
        maps = self._vertex_maps(self._global_transforms(local))
        return to_float32(self._posed(self._morphed(weights), maps))

    def pose_at(self, seconds: float) -> npt.NDArray[np.float32]:
        """(n, 3) float32 positions at clip time `seconds` (the rest pose without a clip)."""
        return self._evaluate(self.clip, seconds)

    @property
    def vertex_count(self) -> int:
        return len(self.base_positions)

    def vertex_attribute(self, name: str, first: int = 0, components: int = 1) -> npt.NDArray[np.float32]:
        """Vertex attribute `name` in the order of rest_positions: `components` values per vertex from `first`."""
        f = self.file
        out = []
        for i, p in enumerate(f.meshes[self.mesh_index].primitives or []):
            if not _is_triangles(p):
                continue
            what = f"mesh {self.mesh_name} primitive {i}"
            acc = _attribute(p.attributes, name)
            if acc is None:
                raise GltfUsageError(f"{what} has no vertex attribute {name}")
            data = f.accessor(acc, f"{what} {name}")
            if data.shape[1] < first + components:
                raise GltfUsageError(f"{what} {name} has {data.shape[1]} components per vertex, {first + components} needed")
            if len(data) != f.accessor_count(_attribute(p.attributes, "POSITION")):
                raise GltfError(f"{what} {name}: count differs from POSITION")
            with np.errstate(over="ignore", invalid="ignore"):
                out.append(data[:, first : first + components].astype(np.float32))
        values = np.concatenate(out) if out else np.zeros((0, components), np.float32)
        if len(values) != self.vertex_count:
            raise GltfError(f"vertex attribute {name}: not one value per vertex")
        if not np.isfinite(values).all():
            raise GltfError(f"vertex attribute {name} holds a value that is not finite")
        return values[:, 0] if components == 1 else values

    def rest_directions(self, name: str, first: int = 0) -> npt.NDArray[np.float32]:
        """Directions from components first..first+2 of attribute `name` carried to the rest pose."""
        d = self.vertex_attribute(name, first, 3).astype(np.float64)
        maps = self._vertex_maps(self._global_transforms(self.nodes))
        at = self._morphed(self.base_weights)
        return to_float32(self._posed(at + d, maps) - self._posed(at, maps))

    def _skin_joints(self) -> Tuple[List[int], npt.NDArray[np.float64]]:
        """Each joint's parent within the skin (its nearest ancestor that is a joint, -1 for none) and its world
        position at rest (the translation of its global transform), as GltfScene::skeleton() takes them."""
        glob = self._global_transforms(self.nodes)
        index = {node: k for k, node in enumerate(self.joints)}
        parents = []
        for node in self.joints:
            up = self.parent[node]
            while up >= 0 and up not in index:
                up = self.parent[up]
            parents.append(index[up] if up >= 0 else -1)
        return parents, np.array([[glob[j][12], glob[j][13], glob[j][14]] for j in self.joints], np.float64)

    def skeleton(self) -> Optional[Skeleton]:
        """The skin's joints at rest and each vertex's JOINTS_0/WEIGHTS_0 (None for a mesh without a skin)."""
        if not self.skinned:
            return None
        parents, rest = self._skin_joints()
        joints, weights = [], []
        f = self.file
        for i, p in enumerate(f.meshes[self.mesh_index].primitives or []):
            if _is_triangles(p):
                joints.append(f.accessor(_attribute(p.attributes, "JOINTS_0"), f"primitive {i} JOINTS_0", 4).astype(np.int64))
                weights.append(f.accessor(_attribute(p.attributes, "WEIGHTS_0"), f"primitive {i} WEIGHTS_0", 4))
        return Skeleton(np.array(self.joints, np.int64), np.array(parents, np.int64), rest, np.concatenate(joints), np.concatenate(weights))


    def skin_skeleton(self) -> Optional[SkinSkeleton]:
        """The skeleton plumage_gltf hands the library for this mesh (GltfScene::skeleton()), None without a skin."""
        if not self.skinned:
            return None
        parents, rest = self._skin_joints()
        positions = rest.astype(np.float32)
        used = self.influence_joint >= 0
        order = np.argsort(~used, axis=1, kind="stable")  # the used slots first, in slot order
        joints = np.take_along_axis(self.influence_joint, order, axis=1)
        weights = np.take_along_axis(self.influence_weight, order, axis=1)
        width = min(max(1, int(used.sum(axis=1).max()) if len(used) else 1), MAX_INFLUENCES)
        joints, weights = joints[:, :width], weights[:, :width]
        keep = joints >= 0
        return SkinSkeleton(positions, np.array(parents, np.int32), np.where(keep, joints, 0).astype(np.uint32),
                            np.where(keep, weights, 0.0).astype(np.float32))


def _triangle_list(mode: int, v: np.ndarray, what: str) -> np.ndarray:
    """Strips and fans as plain triangle lists (glTF 2.0, 3.7.2.1)."""
    if mode not in (_STRIP, _FAN):
        if len(v) % 3 != 0:
            raise GltfError(f"{what}: index count is not a multiple of 3")
        return v
    out = []
    for i in range(len(v) - 2):
        if mode == _FAN:
            out += [v[i + 1], v[i + 2], v[0]]
        elif i % 2 == 0:
            out += [v[i], v[i + 1], v[i + 2]]
        else:
            out += [v[i + 1], v[i], v[i + 2]]
    return np.array(out, np.uint32)


# ---------------------------------------------------------------- what is dressed


class Scene:
    """The meshes a run dresses, handed to the library as one triangle soup
    (the host's MeshUnion): their vertices and triangles one after the other."""

    def __init__(self, path: Union[str, Path], meshes: Sequence[str] = (), clip: str = "") -> None:
        self.file = GltfFile(path)
        self.mesh_indices = choose_meshes(self.file, meshes)
        self.parts = [MeshScene(self.file, m, clip) for m in self.mesh_indices]
        firsts = np.cumsum([0] + [p.vertex_count for p in self.parts])
        self.first_vertex = [int(x) for x in firsts[:-1]]
        self.rest_positions = np.concatenate([p.rest_positions for p in self.parts])
        self.triangles = np.concatenate([p.triangles + np.uint32(first) for p, first in zip(self.parts, self.first_vertex)])
        self.mesh_name = ", ".join(p.mesh_name for p in self.parts)

    @property
    def clip(self) -> Optional[Clip]:
        return self.parts[0].clip

    def pose_at(self, seconds: float) -> npt.NDArray[np.float32]:
        return np.concatenate([p.pose_at(seconds) for p in self.parts])

    def vertex_attribute(self, name: str, first: int = 0, components: int = 1) -> npt.NDArray[np.float32]:
        return np.concatenate([p.vertex_attribute(name, first, components) for p in self.parts])

    def rest_directions(self, name: str, first: int = 0) -> npt.NDArray[np.float32]:
        return np.concatenate([p.rest_directions(name, first) for p in self.parts])

    def skin_skeleton(self) -> Optional[SkinSkeleton]:
        """Every mesh's skeleton one after the other (MeshUnion::skeleton); None unless every mesh is skinned."""
        out: Optional[SkinSkeleton] = None
        for part in self.parts:
            s = part.skin_skeleton()
            if s is None:
                return None
            out = s if out is None else out.append(s)
        return out

    def frame_times(self, fps: float = 30.0, start: float = 0.0, frames: Optional[int] = None) -> npt.NDArray[np.float64]:
        return frame_times(self.clip, fps, start, frames)


def frame_times(clip: Optional[Clip], fps: float = 30.0, start: float = 0.0, frames: Optional[int] = None) -> npt.NDArray[np.float64]:
    """Clip times of the frames to step: the clip's start + `start` + k / fps,
    up to the end of the clip by default; without a clip, `frames` frames
    from `start` (none by default) (main.cpp's frame_times)."""
    if clip is not None and start > clip.duration + 1e-9:
        raise GltfUsageError(f'--start {start:g} is past the end of clip "{clip.name}" ({clip.duration:g} s long)')
    n = 0
    if frames is not None:
        n = frames
    elif clip is not None:
        n = math.floor((clip.duration - start) * fps + 1e-6) + 1
    first = (clip.start if clip is not None else 0.0) + start
    return np.array([first + k / fps for k in range(n)], np.float64)
