"""The `System` class: a Plumage system driven with numpy arrays."""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, fields
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Type, TypeVar, Union

import numpy as np
import numpy.typing as npt

from . import _ffi
from ._ffi import lib

FloatArray = npt.NDArray[np.float32]
UIntArray = npt.NDArray[np.uint32]
ArrayLike = npt.ArrayLike

# progress(phase_name, fraction) -> truthy to stop the running call
ProgressCallback = Callable[[str, float], Any]


class PlumageError(Exception):
    """A refusal: by the library (its status and message) or by the binding's
    own checks of what the C ABI cannot see (array shapes, dtypes), which use
    the status the library gives for the same fault."""

    def __init__(self, status: int, message: str, call: str = "") -> None:
        self.status = int(status)
        self.status_name = _ffi.status_name(self.status)
        self.message = message
        self.call = call
        where = f"{call}: " if call else ""
        super().__init__(f"{where}{self.status_name}: {message}")


def _check(status: int, handle: Optional[int], call: str) -> None:
    if status != _ffi.STATUS_OK:
        raise PlumageError(status, _ffi.last_error(handle) or "(no message)", call)


def _float_array(value: ArrayLike, name: str, columns: int) -> FloatArray:
    """C-contiguous float32 copy (or view) with `columns` values per row."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"{name}: not a numeric array ({e})") from None
    if arr.dtype.kind not in "fiub":
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"{name}: expected real numbers, got dtype {arr.dtype}")
    if columns > 1:
        if arr.ndim == 1 and arr.size % columns == 0:
            arr = arr.reshape(-1, columns)
        if arr.ndim != 2 or arr.shape[1] != columns:
            raise PlumageError(
                _ffi.STATUS_INVALID_ARGUMENT, f"{name}: expected shape (n, {columns}) or a flat array of n*{columns}, got {arr.shape}"
            )
    elif arr.ndim != 1:
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"{name}: expected a flat array, got shape {arr.shape}")
    with np.errstate(over="ignore", invalid="ignore"):  # overflow becomes inf: the library names it NON_FINITE
        return np.ascontiguousarray(arr, dtype=np.float32)


def _integers(value: ArrayLike, name: str, what: str) -> np.ndarray:
    """`value` as a numpy integer array (an empty one as int64), else INVALID_ARGUMENT naming `what` was expected."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"{name}: not an integer array ({e})") from None
    if arr.size == 0:
        arr = arr.astype(np.int64)
    if arr.dtype.kind not in "iu":
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"{name}: expected {what}, got dtype {arr.dtype}")
    return arr


def _index_array(value: ArrayLike, name: str) -> UIntArray:
    arr = _integers(value, name, "integer indices")
    if arr.ndim == 1 and arr.size % 3 == 0:
        arr = arr.reshape(-1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise PlumageError(_ffi.STATUS_INVALID_MESH, f"{name}: expected shape (m, 3) or a flat array of 3*m, got {arr.shape}")
    if arr.size and (arr.min() < 0 or arr.max() > np.iinfo(np.uint32).max):
        bad = int(arr.min()) if arr.min() < 0 else int(arr.max())
        raise PlumageError(_ffi.STATUS_INDEX_OUT_OF_RANGE, f"{name}: index {bad} is not a vertex index")
    return np.ascontiguousarray(arr, dtype=np.uint32)


def _integer_array(value: ArrayLike, name: str, low: int, high: int) -> np.ndarray:
    """An integer array with every value in [low, high] (else INDEX_OUT_OF_RANGE)."""
    arr = _integers(value, name, "integers")
    if arr.size and (int(arr.min()) < low or int(arr.max()) > high):
        bad = int(arr.min()) if int(arr.min()) < low else int(arr.max())
        raise PlumageError(_ffi.STATUS_INDEX_OUT_OF_RANGE, f"{name}: {bad} is out of range [{low}, {high}]")
    return arr


@dataclass(eq=False)
class Skeleton:
    """The skeleton a mesh is skinned to (PlumageSkeleton), for `System(skeleton=...)`.

    joint_positions: (J, 3) joint positions at the rest pose, in the space of
    the mesh's vertices; joint_parents: (J,) each joint's parent, -1 for a
    root; vertex_joints: (n, k) the joints each vertex is weighted to (k = 1
    to 16 influences); vertex_weights: (n, k) their weights (finite, >= 0;
    unused slots weight 0); head_joint: the joint the flow starts from (the
    tip of the head or the beak), or -1: the end joint farthest against
    `flow_axis` when that is set, else farthest up and forward (+Y plus +Z).
    Without `orientations` or `flow_source`, feathers then run from the head
    down the trunk and out along every limb. A dict with these keys (or any
    object with these attributes, such as plumage.gltf.SkinSkeleton) is
    taken too.
    """

    joint_positions: ArrayLike
    joint_parents: ArrayLike
    vertex_joints: ArrayLike
    vertex_weights: ArrayLike
    head_joint: int = -1


SKELETON_FIELDS = ("joint_positions", "joint_parents", "vertex_joints", "vertex_weights", "head_joint")
MAX_INFLUENCES = 16


def _skeleton_struct(value: Union[Skeleton, Mapping[str, Any]], n: int) -> Tuple[_ffi.Skeleton, List[np.ndarray]]:
    """The PlumageSkeleton of `value` for a mesh of `n` vertices, and the arrays it points into (kept alive by the caller)."""
    if isinstance(value, Skeleton) or (not isinstance(value, Mapping) and all(hasattr(value, k) for k in SKELETON_FIELDS[:4])):
        parts = {name: getattr(value, name, -1) for name in SKELETON_FIELDS}  # also plumage.gltf.SkinSkeleton
    elif isinstance(value, Mapping):
        unknown = sorted(set(value) - set(SKELETON_FIELDS))
        missing = [k for k in SKELETON_FIELDS[:4] if k not in value]
        if unknown or missing:
            what = f"unknown key {unknown[0]!r}" if unknown else f"no {missing[0]!r}"
            raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"skeleton: {what} (keys: {', '.join(SKELETON_FIELDS)}; head_joint optional)")
        parts = {"head_joint": -1, **value}
    else:
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"skeleton: expected a plumage.Skeleton or a dict, got {type(value).__name__}")
    positions = _float_array(parts["joint_positions"], "skeleton.joint_positions", 3)
    joints = positions.shape[0]
    if not 1 <= joints <= 1 << 16:
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"skeleton.joint_positions: {joints} joints; it must have 1 to {1 << 16}")
    parents = _integer_array(parts["joint_parents"], "skeleton.joint_parents", -1, joints - 1)
    if parents.shape != (joints,):
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"skeleton.joint_parents: expected shape ({joints},) (one per joint), got {parents.shape}")
    vj = _integer_array(parts["vertex_joints"], "skeleton.vertex_joints", 0, joints - 1)
    if vj.ndim == 1:
        vj = vj.reshape(-1, 1)
    if vj.ndim != 2 or vj.shape[0] != n:
        raise PlumageError(_ffi.STATUS_INVALID_MESH, f"skeleton.vertex_joints: expected shape ({n}, k) (k joints per vertex), got {vj.shape}")
    k = vj.shape[1]
    if not 1 <= k <= MAX_INFLUENCES:
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"skeleton.vertex_joints: {k} influences per vertex; it must be 1 to {MAX_INFLUENCES}")
    weights = parts["vertex_weights"]
    if k == 1 and np.ndim(weights) == 2 and np.shape(weights)[1] == 1:
        weights = np.reshape(weights, -1)
    vw = _float_array(weights, "skeleton.vertex_weights", k).reshape(-1, k)
    if vw.shape != vj.shape:
        raise PlumageError(_ffi.STATUS_INVALID_MESH, f"skeleton.vertex_weights: expected shape {vj.shape} (as vertex_joints), got {vw.shape}")
    head = parts["head_joint"]
    if isinstance(head, bool) or not isinstance(head, (int, np.integer)) or not -1 <= int(head) < joints:
        raise PlumageError(_ffi.STATUS_INDEX_OUT_OF_RANGE, f"skeleton.head_joint: expected -1 or a joint index below {joints}, got {head!r}")
    weights_c: FloatArray = np.ascontiguousarray(vw, dtype=np.float32)
    parents_c, joints_c = np.ascontiguousarray(parents, dtype=np.int32), np.ascontiguousarray(vj, dtype=np.uint32)
    arrays: List[np.ndarray] = [positions, parents_c, joints_c, weights_c]
    raw = _ffi.Skeleton()
    raw.joint_count = joints
    raw.influences = k
    raw.joint_positions = _fptr(positions)
    raw.joint_parents = parents_c.ctypes.data_as(ctypes.POINTER(ctypes.c_int32))
    raw.vertex_joints = joints_c.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32))
    raw.vertex_weights = _fptr(weights_c)
    raw.head_joint = int(head)
    return raw, arrays


def _fptr(arr: Optional[FloatArray]) -> Any:
    return None if arr is None else arr.ctypes.data_as(ctypes.POINTER(ctypes.c_float))


@dataclass(frozen=True)
class FrameStats:
    """What the last create, step or evaluate did (PlumageFrameStats)."""

    clamped: int
    frame_index: int
    adjusted: int
    collision_tests: int
    collision_tests_per_feather: float
    priority_changes: int
    priority_change_percent: float
    reversals: int
    reversals_refused: int
    cycles_broken: int
    reorder_seconds: float
    adjust_seconds: float
    step_seconds: float
    deformed: int
    seeds: int
    verified: int
    neighbourhood_seconds: float
    levels: int
    pops: int
    largest_pose_change_deg: float
    draped: int
    drape_descents: int
    kept_in_place: int


@dataclass(frozen=True)
class Validation:
    """Exact validation of the current feathers (PlumageValidation)."""

    intersecting_pairs: int
    body_penetrations: int
    coverage: float
    mean_pitch_deg: float
    probes: int
    buried_probes: int
    tip_height_median: float
    tip_height_p90: float
    bristle_percent: float
    stack_efficiency: float
    stack_depth_median: float
    discord_percent: float  # feathers turned > 45 degrees from their 8 nearest neighbours' mean heading


@dataclass(frozen=True)
class SamplingStats:
    roots: int
    spacing: float
    relative_radius: float
    coverage_gap: float
    alignment: float
    seconds: float
    field_singularities: int  # faces the rest orientation field turns round (sources, sinks, whorls, saddles)


@dataclass(frozen=True)
class Memory:
    """Heap bytes the system holds, by part (PlumageMemory)."""

    total: int
    mesh: int
    coat: int
    neighbourhoods: int
    history: int
    scratch: int


@dataclass(frozen=True)
class OrderingStats:
    pairs: int
    edges: int
    dropped_edges: int
    violations: int
    seconds: float


@dataclass(frozen=True)
class FeatherGeometry:
    """Every feather as a triangle mesh (plumage_system_feather_geometry).

    positions, normals: (V, 3) float32 (unit normals facing away from the
    skin); uvs: (V, 2) float32, u 0 at the root to 1 at the tip, v 0 to 1
    across the vanes (0.5 on the shaft); triangles: (T, 3) uint32 into the
    whole vertex array; feather_index: (V,) uint32, the feather (row of
    `ids`) each vertex belongs to; ids: (F,) uint64, the feathers' stable
    ids; vertex_counts, triangle_counts: (F,) uint32; placed: (F,) bool,
    False for a feather left out (all its vertices at its root). Feathers
    come one after the other in the order of `System.feathers()`; all but
    positions and normals stay the same from frame to frame.
    """

    positions: FloatArray
    normals: FloatArray
    uvs: FloatArray
    triangles: UIntArray
    feather_index: UIntArray
    ids: npt.NDArray[np.uint64]
    vertex_counts: UIntArray
    triangle_counts: UIntArray
    placed: npt.NDArray[np.bool_]


@dataclass(frozen=True)
class FeatherTemplate:
    """The card every feather is instanced from (plumage_system_feather_template).

    positions: (V, 3) float32 in the feather's own frame for unit length and
    width (x along the unbent shaft 0..1, y across, z 0); uvs: (V, 2)
    float32; triangles: (T, 3) uint32; vertex_segments: (V,) uint32, the
    shaft segment carrying each vertex; segments: S; vane_split: where the
    vane corners sit. `System.feather_instances()` places it (see
    PlumageFeatherInstance in plumage.h for the convention).
    """

    segments: int
    vane_split: float
    positions: FloatArray
    uvs: FloatArray
    triangles: UIntArray
    vertex_segments: UIntArray


S = TypeVar("S")


def _from_struct(cls: Type[S], raw: ctypes.Structure) -> S:
    return cls(**{f.name: getattr(raw, f.name) for f in fields(cls)})  # type: ignore[arg-type]


# dtype of one PlumageFeather as numpy sees it (same bytes)
FEATHER_DTYPE = np.dtype(
    {
        "names": [f[0] for f in _ffi.Feather._fields_],
        "formats": [
            "<u8",
            "<u4",
            "<u4",
            ("<f4", 3),
            ("<f4", 3),
            ("<f4", 3),
            ("<f4", 3),
            "<f4",
            "<f4",
            "<f4",
            "<f4",
            "<f4",
            "<u4",
        ],
        "offsets": [getattr(_ffi.Feather, f[0]).offset for f in _ffi.Feather._fields_],
        "itemsize": ctypes.sizeof(_ffi.Feather),
    }
)

# dtype of one PlumageFeatherInstance (36 bytes, same bytes as the C struct)
INSTANCE_DTYPE = np.dtype(
    {
        "names": [f[0] for f in _ffi.FeatherInstance._fields_],
        "formats": [("<f4", 3), ("<i2", 4), "<f4", "<f4", ("<i2", 3), "<u2"],
        "offsets": [getattr(_ffi.FeatherInstance, f[0]).offset for f in _ffi.FeatherInstance._fields_],
        "itemsize": ctypes.sizeof(_ffi.FeatherInstance),
    }
)

CONFIG_FIELDS = tuple(
    f[0] for f in _ffi.Config._fields_ if f[0] not in _ffi.NON_KEYWORD_FIELDS
)


def default_config() -> Dict[str, Any]:
    """The library's defaults, as keyword arguments of `System`."""
    cfg = _ffi.Config()
    lib.plumage_config_init(ctypes.byref(cfg))
    out: Dict[str, Any] = {}
    for name in CONFIG_FIELDS:
        v = getattr(cfg, name)
        out[name] = tuple(v) if isinstance(v, ctypes.Array) else v
    out["mode"] = {v: k for k, v in _ffi.MODES.items()}.get(cfg.mode, cfg.mode)
    out["sampler"] = {v: k for k, v in _ffi.SAMPLERS.items()}.get(cfg.sampler, cfg.sampler)
    out["flow_source"] = None
    return out


def _build_config(config: Dict[str, Any], preset: str = "feathers") -> _ffi.Config:
    cfg = _ffi.Config()
    if preset not in _ffi.PRESETS:
        raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"preset {preset!r}: expected one of {', '.join(_ffi.PRESETS)}")
    status = lib.plumage_config_init_preset(ctypes.byref(cfg), _ffi.PRESETS[preset])
    if status != _ffi.STATUS_OK:
        raise PlumageError(status, f"preset {preset!r} refused", "plumage_config_init_preset")
    for key, value in config.items():
        if key not in CONFIG_FIELDS:
            raise TypeError(f"unknown configuration field {key!r}; known: {', '.join(CONFIG_FIELDS)}")
        if key == "flow_source":
            if value is None:
                cfg.flow_source_enabled = 0
                continue
            cfg.flow_source_enabled = 1
        if key in ("mode", "sampler") and isinstance(value, str):
            table = _ffi.MODES if key == "mode" else _ffi.SAMPLERS
            if value not in table:
                raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"{key} {value!r}: expected one of {', '.join(table)}")
            value = table[value]
        field_type = {f[0]: f[1] for f in _ffi.Config._fields_}[key]
        try:
            if isinstance(getattr(cfg, key), ctypes.Array):
                xyz = [float(v) for v in value]
                if len(xyz) != 3:
                    raise ValueError("expected three numbers")
                setattr(cfg, key, (ctypes.c_float * 3)(*xyz))
            elif field_type is ctypes.c_float:
                setattr(cfg, key, float(value))  # NaN stays NaN: the library refuses it by name
            else:
                as_int = int(value)
                if as_int != value:
                    raise ValueError("expected an integer")
                limit = 2 ** (8 * ctypes.sizeof(field_type))
                if not 0 <= as_int < limit:
                    raise ValueError(f"out of range [0, {limit})")
                setattr(cfg, key, as_int)
        except (TypeError, ValueError, OverflowError) as e:
            raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"{key}={value!r}: {e}") from None
    return cfg


class System:
    """A feathering system on a rest mesh.

    vertices: (n, 3) positions; triangles: (m, 3) vertex indices (a glTF
    triangle soup is fine). Optional per-vertex maps: `orientations` (n, 3)
    flow directions, `spacing_scale`, `length_scale`, `width_scale` (n,)
    multipliers, `layer` (n,) painted layers (where neighbouring feathers'
    layers differ, the higher lies on top), `feather_type` (n,) an index per
    vertex into `feather_types` (preset names, default ("feathers",
    "scales"): each feather takes its root's nearest corner's type), and
    `skeleton` (a `Skeleton` or
    a dict of its fields: joints at rest and skin weights; without
    `orientations` or `flow_source` the feathers then follow the bones from
    the head down the trunk and every limb). Keyword configuration: any `PlumageConfig` field
    (`target_feathers=`, `seed=`, `threads=`, `mode="incremental"|"legacy"|"rebuild"`,
    `sampler="guided"|"random"`, `flow_axis=(x, y, z)`, `flow_source=(x, y, z)`, ...),
    see `default_config()`. The default feathers have bent shafts that lie down over
    what is beneath them; `preset="kite"` starts from the paper's rigid feather and
    `preset="scales"` from the library's fish-scale defaults (the keywords then
    override them). `progress(phase, fraction)` is called while the
    library works; a truthy return stops the call (PlumageError INTERRUPTED).
    """

    def __init__(
        self,
        vertices: ArrayLike,
        triangles: ArrayLike,
        *,
        orientations: Optional[ArrayLike] = None,
        spacing_scale: Optional[ArrayLike] = None,
        length_scale: Optional[ArrayLike] = None,
        width_scale: Optional[ArrayLike] = None,
        layer: Optional[ArrayLike] = None,
        skeleton: Optional[Union[Skeleton, Mapping[str, Any]]] = None,
        feather_type: Optional[ArrayLike] = None,
        feather_types: Sequence[str] = ("feathers", "scales"),
        progress: Optional[ProgressCallback] = None,
        preset: str = "feathers",
        **config: Any,
    ) -> None:
        self._handle: Optional[int] = None
        cfg = _build_config(config, preset)
        pos = _float_array(vertices, "vertices", 3)
        tri = _index_array(triangles, "triangles")
        n = pos.shape[0]
        maps: Dict[str, Optional[FloatArray]] = {}
        for name, value, columns in (
            ("orientations", orientations, 3),
            ("spacing_scale", spacing_scale, 1),
            ("length_scale", length_scale, 1),
            ("width_scale", width_scale, 1),
            ("layer", layer, 1),
        ):
            if value is None:
                maps[name] = None
                continue
            arr = _float_array(value, name, columns)
            if arr.shape[0] != n:
                raise PlumageError(_ffi.STATUS_INVALID_MESH, f"{name}: {arr.shape[0]} values for {n} vertices")
            maps[name] = arr
        self._progress_fn = None
        if progress is not None:
            self._progress_fn = _ffi.ProgressFn(self._progress_trampoline(progress))
            cfg.progress = self._progress_fn
        desc = _ffi.MeshDesc()
        lib.plumage_mesh_desc_init(ctypes.byref(desc))
        desc.positions = _fptr(pos)
        desc.vertex_count = n
        desc.indices = tri.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32))
        desc.triangle_count = tri.shape[0]
        desc.orientations = _fptr(maps["orientations"])
        desc.spacing_scale = _fptr(maps["spacing_scale"])
        desc.length_scale = _fptr(maps["length_scale"])
        desc.width_scale = _fptr(maps["width_scale"])
        desc.layer = _fptr(maps["layer"])
        skeleton_raw = None
        if skeleton is not None:
            skeleton_raw, skeleton_arrays = _skeleton_struct(skeleton, n)
            desc.skeleton = ctypes.pointer(skeleton_raw)
        if feather_type is not None:
            table = (_ffi.FeatherType * max(len(feather_types), 1))()
            for k, name in enumerate(feather_types):
                if name not in _ffi.PRESETS:
                    raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"feather_types[{k}] {name!r}: expected one of {', '.join(_ffi.PRESETS)}")
                _check(lib.plumage_feather_type_init(ctypes.byref(table[k]), _ffi.PRESETS[name]), None, "plumage_feather_type_init")
            kinds = _integer_array(feather_type, "feather_type", 0, max(len(feather_types) - 1, 0)).astype(np.uint32).reshape(-1)
            if kinds.shape[0] != n:
                raise PlumageError(_ffi.STATUS_INVALID_MESH, f"feather_type: {kinds.shape[0]} values for {n} vertices")
            kinds = np.ascontiguousarray(kinds)
            desc.feather_type = kinds.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32))
            desc.feather_types = table
            desc.feather_type_count = len(feather_types)
        out = ctypes.c_void_p()
        status = lib.plumage_system_create(ctypes.byref(cfg), ctypes.byref(desc), ctypes.byref(out))
        _check(status, None, "plumage_system_create")
        self._handle = out.value
        self._config = cfg
        self._vertex_count = int(n)

    @staticmethod
    def _progress_trampoline(progress: ProgressCallback) -> Callable[[Any, int, float], int]:
        def call(_user: Any, phase: int, fraction: float) -> int:
            try:
                return 1 if progress(_ffi.PHASES.get(phase, str(phase)), fraction) else 0
            except BaseException:  # an exception cannot cross the C boundary: stop the call
                return 1

        return call

    # -- lifetime ---------------------------------------------------------
    def close(self) -> None:
        """Frees the system (later calls raise). Idempotent. Raises (and frees
        nothing) when another call is running on the system."""
        if self._handle is not None:
            _check(lib.plumage_system_destroy(self._handle), self._handle, "plumage_system_destroy")
            self._handle = None

    def __enter__(self) -> "System":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass

    def _h(self) -> int:
        if self._handle is None:
            raise PlumageError(1, "the system is closed")  # NULL_POINTER: what the C ABI says of a NULL system
        return self._handle

    # -- frames -----------------------------------------------------------
    @property
    def vertex_count(self) -> int:
        return self._vertex_count

    @property
    def feather_count(self) -> int:
        n = ctypes.c_size_t()
        _check(lib.plumage_system_feather_count(self._h(), ctypes.byref(n)), self._handle, "plumage_system_feather_count")
        return int(n.value)

    def _frame_positions(self, positions: ArrayLike) -> FloatArray:
        return _float_array(positions, "positions", 3)

    def step(self, positions: ArrayLike) -> None:
        """Advances by one frame: (n, 3) positions in the rest mesh's numbering."""
        pos = self._frame_positions(positions)
        h = self._h()
        _check(lib.plumage_system_step(h, _fptr(pos), pos.shape[0]), h, "plumage_system_step")

    def evaluate(self, positions: ArrayLike) -> None:
        """Solves this pose from scratch, independent of earlier frames."""
        pos = self._frame_positions(positions)
        h = self._h()
        _check(lib.plumage_system_evaluate(h, _fptr(pos), pos.shape[0]), h, "plumage_system_evaluate")

    # -- copy-out ---------------------------------------------------------
    def feathers(self) -> np.ndarray:
        """One record per feather (numpy structured array with the fields of PlumageFeather)."""
        h = self._h()
        n = ctypes.c_size_t()
        out = np.zeros(self.feather_count, dtype=FEATHER_DTYPE)
        _check(
            lib.plumage_system_feathers(h, out.ctypes.data_as(ctypes.POINTER(_ffi.Feather)), out.shape[0], ctypes.byref(n)),
            h,
            "plumage_system_feathers",
        )
        return out[: n.value]

    def feather_triangles(self) -> FloatArray:
        """(F, 3·T, 3) float32: each feather's T triangles as their corners (T = 2 for the
        one-segment kite), as plumage_system_feather_triangles."""
        h = self._h()
        n = ctypes.c_size_t()
        status = lib.plumage_system_feather_triangles(h, None, 0, ctypes.byref(n))
        if status != _ffi.STATUS_BUFFER_TOO_SMALL:
            _check(status, h, "plumage_system_feather_triangles")
        out = np.empty(n.value, dtype=np.float32)
        if n.value:
            _check(lib.plumage_system_feather_triangles(h, _fptr(out), out.size, ctypes.byref(n)), h, "plumage_system_feather_triangles")
        return out.reshape(self.feather_count, -1, 3) if self.feather_count else out.reshape(0, 6, 3)

    def feather_geometry(self) -> FeatherGeometry:
        """Every feather as an indexed triangle mesh with normals, UVs and feather ids."""
        h = self._h()
        ids = self.feathers()["id"].copy()
        g = _ffi.FeatherGeometry()
        lib.plumage_feather_geometry_init(ctypes.byref(g))
        _check(lib.plumage_system_feather_geometry(h, ctypes.byref(g)), h, "plumage_system_feather_geometry")
        nf, nv, nt = int(g.feather_count), int(g.vertex_count), int(g.triangle_count)
        positions = np.empty((nv, 3), dtype=np.float32)
        normals = np.empty((nv, 3), dtype=np.float32)
        uvs = np.empty((nv, 2), dtype=np.float32)
        triangles = np.empty((nt, 3), dtype=np.uint32)
        feather_index = np.empty(nv, dtype=np.uint32)
        vertex_counts = np.empty(nf, dtype=np.uint32)
        triangle_counts = np.empty(nf, dtype=np.uint32)
        placed = np.empty(nf, dtype=np.uint8)
        u32 = ctypes.POINTER(ctypes.c_uint32)
        for name, arr, ptr_type in (
            ("positions", positions, ctypes.POINTER(ctypes.c_float)),
            ("normals", normals, ctypes.POINTER(ctypes.c_float)),
            ("uvs", uvs, ctypes.POINTER(ctypes.c_float)),
            ("indices", triangles, u32),
            ("vertex_feathers", feather_index, u32),
            ("vertex_counts", vertex_counts, u32),
            ("triangle_counts", triangle_counts, u32),
            ("placed", placed, ctypes.POINTER(ctypes.c_uint8)),
        ):
            setattr(g, name, arr.ctypes.data_as(ptr_type))
            setattr(g, name + "_capacity", arr.size)
        _check(lib.plumage_system_feather_geometry(h, ctypes.byref(g)), h, "plumage_system_feather_geometry")
        if (int(g.feather_count), int(g.vertex_count), int(g.triangle_count)) != (nf, nv, nt) or nf != len(ids):
            raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, "the feather geometry changed between two reads")  # pragma: no cover
        return FeatherGeometry(
            positions=positions,
            normals=normals,
            uvs=uvs,
            triangles=triangles,
            feather_index=feather_index,
            ids=ids,
            vertex_counts=vertex_counts,
            triangle_counts=triangle_counts,
            placed=placed.astype(bool),
        )

    # -- instancing -------------------------------------------------------
    def feather_instances(self) -> np.ndarray:
        """One packed record per feather (structured array of INSTANCE_DTYPE: root,
        rotation as snorm16 (x, y, z, w), length, width, bends as snorm16 of
        INSTANCE_BEND_RANGE), in the order of `feathers()`."""
        h = self._h()
        n = ctypes.c_size_t()
        out = np.zeros(self.feather_count, dtype=INSTANCE_DTYPE)
        ptr = out.ctypes.data_as(ctypes.POINTER(_ffi.FeatherInstance))
        _check(lib.plumage_system_feather_instances(h, ptr, out.shape[0], ctypes.byref(n)), h, "plumage_system_feather_instances")
        return out[: n.value]

    def feather_template(self) -> FeatherTemplate:
        """The template card of the system's feathers."""
        h = self._h()
        t = _ffi.FeatherTemplate()
        lib.plumage_feather_template_init(ctypes.byref(t))
        _check(lib.plumage_system_feather_template(h, ctypes.byref(t)), h, "plumage_system_feather_template")
        nv, nt = int(t.vertex_count), int(t.triangle_count)
        positions = np.empty((nv, 3), dtype=np.float32)
        uvs = np.empty((nv, 2), dtype=np.float32)
        triangles = np.empty((nt, 3), dtype=np.uint32)
        vertex_segments = np.empty(nv, dtype=np.uint32)
        f_p, u_p = ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_uint32)
        for name, arr, ptr_type in (
            ("positions", positions, f_p),
            ("uvs", uvs, f_p),
            ("indices", triangles, u_p),
            ("vertex_segments", vertex_segments, u_p),
        ):
            setattr(t, name, arr.ctypes.data_as(ptr_type))
            setattr(t, name + "_capacity", arr.size)
        _check(lib.plumage_system_feather_template(h, ctypes.byref(t)), h, "plumage_system_feather_template")
        return FeatherTemplate(int(t.segments), float(t.vane_split), positions, uvs, triangles, vertex_segments)

    def changed_feathers(self) -> Tuple[UIntArray, bool]:
        """(indices, all): the feathers whose record and triangles the last create,
        step, evaluate, load or seek may have changed (every other one is as
        before, bit for bit), and whether that is every feather because there
        was nothing to compare with."""
        h = self._h()
        n = ctypes.c_size_t()
        every = ctypes.c_uint32()
        status = lib.plumage_system_changed_feathers(h, None, 0, ctypes.byref(n), ctypes.byref(every))
        if status == _ffi.STATUS_OK:
            return np.empty(0, dtype=np.uint32), bool(every.value)
        if status != _ffi.STATUS_BUFFER_TOO_SMALL:
            _check(status, h, "plumage_system_changed_feathers")
        out = np.empty(n.value, dtype=np.uint32)
        ptr = out.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32))
        _check(
            lib.plumage_system_changed_feathers(h, ptr, out.size, ctypes.byref(n), ctypes.byref(every)),
            h,
            "plumage_system_changed_feathers",
        )
        return out[: n.value], bool(every.value)

    # -- figures ----------------------------------------------------------
    def _stats(self, fn: Any, raw_type: Type[ctypes.Structure], call: str) -> Optional[ctypes.Structure]:
        h = self._h()
        raw = raw_type()
        raw.struct_size = ctypes.sizeof(raw_type)
        status = fn(h, ctypes.byref(raw))
        if status == _ffi.STATUS_NOT_AVAILABLE:
            return None
        _check(status, h, call)
        return raw

    def frame_stats(self) -> Optional[FrameStats]:
        raw = self._stats(lib.plumage_system_frame_stats, _ffi.FrameStats, "plumage_system_frame_stats")
        return None if raw is None else _from_struct(FrameStats, raw)

    def sampling_stats(self) -> Optional[SamplingStats]:
        raw = self._stats(lib.plumage_system_sampling_stats, _ffi.SamplingStats, "plumage_system_sampling_stats")
        return None if raw is None else _from_struct(SamplingStats, raw)

    def ordering_stats(self) -> Optional[OrderingStats]:
        raw = self._stats(lib.plumage_system_ordering_stats, _ffi.OrderingStats, "plumage_system_ordering_stats")
        return None if raw is None else _from_struct(OrderingStats, raw)

    def memory(self) -> Memory:
        """Heap bytes the system holds now, by part: what `memory_limit` is compared with."""
        raw = self._stats(lib.plumage_system_memory, _ffi.Memory, "plumage_system_memory")
        assert raw is not None, "plumage_system_memory is always available"
        return _from_struct(Memory, raw)

    def validate(self) -> Optional[Validation]:
        """Exact collision checks on the current feathers (None before feathers exist)."""
        raw = self._stats(lib.plumage_system_validate, _ffi.Validation, "plumage_system_validate")
        return None if raw is None else _from_struct(Validation, raw)

    # -- state ------------------------------------------------------------
    def save_state(self) -> bytes:
        h = self._h()
        n = ctypes.c_size_t()
        status = lib.plumage_system_save_state(h, None, 0, ctypes.byref(n))
        if status != _ffi.STATUS_BUFFER_TOO_SMALL:
            _check(status, h, "plumage_system_save_state")
        buf = (ctypes.c_uint8 * n.value)()
        _check(lib.plumage_system_save_state(h, buf, n.value, ctypes.byref(n)), h, "plumage_system_save_state")
        return bytes(buf)[: n.value]

    def seek(self, frame_index: int) -> int:
        """Scrubbing with checkpoints (needs ``checkpoint_interval`` > 0):
        prepares the system to reach the state after ``frame_index`` steps
        and returns the frame count it now stands at, ``start``. Step it
        with the clip's frames ``start .. frame_index - 1`` (step k takes
        frame k) and the result is byte for byte what playback gave."""
        h = self._h()
        if not isinstance(frame_index, (int, np.integer)) or isinstance(frame_index, bool) or frame_index < 0:
            raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"frame_index: expected an integer >= 0, got {frame_index!r}")
        start = ctypes.c_uint64()
        _check(lib.plumage_system_seek(h, int(frame_index), ctypes.byref(start)), h, "plumage_system_seek")
        return int(start.value)

    def load_state(self, blob: bytes) -> None:
        h = self._h()
        try:
            data = memoryview(blob).tobytes()  # bytes-like only: bytes(5) would be five zero bytes
        except TypeError:
            raise PlumageError(_ffi.STATUS_INVALID_ARGUMENT, f"state: expected bytes, got {type(blob).__name__}") from None
        buf = (ctypes.c_uint8 * len(data)).from_buffer_copy(data) if data else (ctypes.c_uint8 * 1)()
        _check(lib.plumage_system_load_state(h, buf, len(data)), h, "plumage_system_load_state")


def vertex_normals(positions: FloatArray, triangles: UIntArray) -> FloatArray:
    """Unit per-vertex normals: the area-weighted sum of the faces around each vertex."""
    p = positions.astype(np.float64)
    t = triangles.astype(np.intp)
    face = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
    acc = np.zeros_like(p)
    for c in range(3):
        np.add.at(acc, t[:, c], face)
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.where(length > 0, acc / np.where(length > 0, length, 1), 0.0)
    return np.ascontiguousarray(n, dtype=np.float32)


def version() -> str:
    return str(lib.plumage_version().decode())
