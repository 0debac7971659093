"""ctypes mirror of include/plumage.h: the structs, the entry points and loading.

The struct layouts follow the header field for field (tests/test_layout.py
compares sizes and offsets with a C compiler's). Nothing here is an
algorithm: it only declares what the C ABI offers.
"""

from __future__ import annotations

import ctypes
import os
import sys
from ctypes import POINTER, c_char_p, c_float, c_int16, c_int32, c_size_t, c_uint8, c_uint16, c_uint32, c_uint64, c_void_p
from pathlib import Path

ABI_VERSION = 1

STATUS_OK = 0
STATUS_INVALID_ARGUMENT = 2
STATUS_INVALID_MESH = 3
STATUS_BUFFER_TOO_SMALL = 5
STATUS_INDEX_OUT_OF_RANGE = 11
STATUS_NOT_AVAILABLE = 16

SAMPLERS = {"guided": 0, "random": 1}
PRESETS = {"feathers": 0, "scales": 1, "sleek": 2, "kite": 3}
MODES = {"incremental": 0, "legacy": 1, "rebuild": 2}
PHASES = {0: "preparing", 1: "sampling", 2: "ordering", 3: "adjusting", 4: "validating"}

ProgressFn = ctypes.CFUNCTYPE(c_int32, c_void_p, c_uint32, c_float)
TaskFn = ctypes.CFUNCTYPE(None, c_void_p, c_uint32)
ParallelForFn = ctypes.CFUNCTYPE(None, c_void_p, c_uint32, TaskFn, c_void_p)


class Config(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("sampler", c_uint32),
        ("seed", c_uint64),
        ("threads", c_uint32),
        ("mode", c_uint32),
        ("target_feathers", c_uint32),
        ("k_neighbours", c_uint32),
        ("spacing", c_float),
        ("theta", c_float),
        ("randomness", c_float),
        ("pool_factor", c_float),
        ("feather_length", c_float),
        ("feather_width", c_float),
        ("feather_thickness", c_float),
        ("gamma", c_float),
        ("lambda", c_float),
        ("height_field_u", c_uint32),
        ("height_field_v", c_uint32),
        ("fluffiness", c_float),
        ("collision_allowance", c_float),
        ("theta_s", c_float),
        ("flow_axis", c_float * 3),
        ("recompute_neighbourhoods", c_uint32),
        ("progress", ProgressFn),
        ("progress_user_data", c_void_p),
        ("flow_source_enabled", c_uint32),
        ("flow_source", c_float * 3),
        ("drift_tolerance", c_float),
        ("curvature_min_scale", c_float),
        ("shaft_segments", c_uint32),
        ("bend_limit", c_float),
        ("length_per_spacing", c_float),
        ("width_per_spacing", c_float),
        ("pop_threshold", c_float),
        ("parallel_for", ParallelForFn),
        ("parallel_for_context", c_void_p),
        ("settle_rate", c_float),
        ("checkpoint_interval", c_uint32),
        ("checkpoint_cap", c_uint32),
        ("reserved", c_uint32),
        ("memory_limit", c_uint64),
    ]


# PlumageConfig fields that are no keywords of `System`: the struct's size,
# the callbacks and their contexts, and the flag behind `flow_source=None`.
NON_KEYWORD_FIELDS = (
    "struct_size",
    "progress",
    "progress_user_data",
    "flow_source_enabled",
    "parallel_for",
    "parallel_for_context",
    "reserved",
)


class Skeleton(ctypes.Structure):
    _fields_ = [
        ("joint_count", c_uint32),
        ("influences", c_uint32),
        ("joint_positions", POINTER(c_float)),
        ("joint_parents", POINTER(c_int32)),
        ("vertex_joints", POINTER(c_uint32)),
        ("vertex_weights", POINTER(c_float)),
        ("head_joint", c_int32),
    ]


class FeatherType(ctypes.Structure):
    _fields_ = [
        ("length_per_spacing", c_float),
        ("width_per_spacing", c_float),
        ("thickness_scale", c_float),
    ]


class MeshDesc(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("positions", POINTER(c_float)),
        ("vertex_count", c_size_t),
        ("indices", POINTER(c_uint32)),
        ("triangle_count", c_size_t),
        ("orientations", POINTER(c_float)),
        ("spacing_scale", POINTER(c_float)),
        ("length_scale", POINTER(c_float)),
        ("width_scale", POINTER(c_float)),
        ("skeleton", POINTER(Skeleton)),
        ("layer", POINTER(c_float)),
        ("feather_type", POINTER(c_uint32)),
        ("feather_types", POINTER(FeatherType)),
        ("feather_type_count", c_uint32),
    ]


class Feather(ctypes.Structure):
    _fields_ = [
        ("id", c_uint64),
        ("order_index", c_uint32),
        ("triangle", c_uint32),
        ("barycentric", c_float * 3),
        ("root", c_float * 3),
        ("normal", c_float * 3),
        ("direction", c_float * 3),
        ("pitch", c_float),
        ("roll", c_float),
        ("length", c_float),
        ("width", c_float),
        ("thickness", c_float),
        ("reserved", c_uint32),
    ]


class SamplingStats(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("roots", c_uint32),
        ("spacing", c_float),
        ("relative_radius", c_float),
        ("coverage_gap", c_float),
        ("alignment", c_float),
        ("seconds", ctypes.c_double),
        ("field_singularities", c_uint32),
        ("reserved", c_uint32),
    ]


class OrderingStats(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("pairs", c_uint32),
        ("edges", c_uint32),
        ("dropped_edges", c_uint32),
        ("violations", c_uint32),
        ("reserved", c_uint32),
        ("seconds", ctypes.c_double),
    ]


class Memory(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("reserved", c_uint32),
        ("total", c_uint64),
        ("mesh", c_uint64),
        ("coat", c_uint64),
        ("neighbourhoods", c_uint64),
        ("history", c_uint64),
        ("scratch", c_uint64),
    ]


class FrameStats(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("clamped", c_uint32),
        ("frame_index", c_uint64),
        ("adjusted", c_uint64),
        ("collision_tests", c_uint64),
        ("collision_tests_per_feather", ctypes.c_double),
        ("priority_changes", c_uint64),
        ("priority_change_percent", ctypes.c_double),
        ("reversals", c_uint64),
        ("reversals_refused", c_uint64),
        ("cycles_broken", c_uint64),
        ("reorder_seconds", ctypes.c_double),
        ("adjust_seconds", ctypes.c_double),
        ("step_seconds", ctypes.c_double),
        ("deformed", c_uint64),
        ("seeds", c_uint64),
        ("verified", c_uint64),
        ("neighbourhood_seconds", ctypes.c_double),
        ("levels", c_uint64),
        ("pops", c_uint64),
        ("largest_pose_change_deg", ctypes.c_double),
        ("draped", c_uint64),
        ("drape_descents", c_uint64),
        ("kept_in_place", c_uint64),
    ]


class Validation(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("reserved", c_uint32),
        ("intersecting_pairs", c_uint64),
        ("body_penetrations", c_uint64),
        ("coverage", ctypes.c_double),
        ("mean_pitch_deg", ctypes.c_double),
        ("probes", c_uint64),
        ("buried_probes", c_uint64),
        ("tip_height_median", ctypes.c_double),
        ("tip_height_p90", ctypes.c_double),
        ("bristle_percent", ctypes.c_double),
        ("stack_efficiency", ctypes.c_double),
        ("stack_depth_median", ctypes.c_double),
        ("discord_percent", ctypes.c_double),
    ]


class FeatherGeometry(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("reserved", c_uint32),
        ("feather_count", c_uint64),
        ("vertex_count", c_uint64),
        ("triangle_count", c_uint64),
        ("positions", POINTER(c_float)),
        ("positions_capacity", c_size_t),
        ("normals", POINTER(c_float)),
        ("normals_capacity", c_size_t),
        ("uvs", POINTER(c_float)),
        ("uvs_capacity", c_size_t),
        ("indices", POINTER(c_uint32)),
        ("indices_capacity", c_size_t),
        ("vertex_feathers", POINTER(c_uint32)),
        ("vertex_feathers_capacity", c_size_t),
        ("vertex_counts", POINTER(c_uint32)),
        ("vertex_counts_capacity", c_size_t),
        ("triangle_counts", POINTER(c_uint32)),
        ("triangle_counts_capacity", c_size_t),
        ("placed", POINTER(c_uint8)),
        ("placed_capacity", c_size_t),
    ]


class FeatherInstance(ctypes.Structure):
    _fields_ = [
        ("root", c_float * 3),
        ("rotation", c_int16 * 4),
        ("length", c_float),
        ("width", c_float),
        ("bends", c_int16 * 3),
        ("reserved", c_uint16),
    ]


# PLUMAGE_INSTANCE_BEND_RANGE: a bends value of 32767 is this many radians.
INSTANCE_BEND_RANGE = 3.1415927


class FeatherTemplate(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("segments", c_uint32),
        ("vertex_count", c_uint32),
        ("triangle_count", c_uint32),
        ("vane_split", c_float),
        ("reserved", c_uint32),
        ("positions", POINTER(c_float)),
        ("positions_capacity", c_size_t),
        ("uvs", POINTER(c_float)),
        ("uvs_capacity", c_size_t),
        ("indices", POINTER(c_uint32)),
        ("indices_capacity", c_size_t),
        ("vertex_segments", POINTER(c_uint32)),
        ("vertex_segments_capacity", c_size_t),
    ]


def _library_name() -> str:
    if sys.platform == "darwin":
        return "libplumage.dylib"
    if sys.platform == "win32":
        return "plumage.dll"
    return "libplumage.so"


def _declare(lib: ctypes.CDLL) -> None:
    sys_p = c_void_p
    f_p = POINTER(c_float)
    size_p = POINTER(c_size_t)
    decls = {
        "plumage_version": (c_char_p, []),
        "plumage_abi_version": (c_uint32, []),
        "plumage_status_name": (c_char_p, [c_uint32]),
        "plumage_config_init": (None, [POINTER(Config)]),
        "plumage_config_init_preset": (c_uint32, [POINTER(Config), c_uint32]),
        "plumage_mesh_desc_init": (None, [POINTER(MeshDesc)]),
        "plumage_feather_type_init": (c_uint32, [POINTER(FeatherType), c_uint32]),
        "plumage_system_create": (c_uint32, [POINTER(Config), POINTER(MeshDesc), POINTER(c_void_p)]),
        "plumage_system_destroy": (c_uint32, [sys_p]),
        "plumage_system_step": (c_uint32, [sys_p, f_p, c_size_t]),
        "plumage_system_evaluate": (c_uint32, [sys_p, f_p, c_size_t]),
        "plumage_system_feather_count": (c_uint32, [sys_p, size_p]),
        "plumage_system_vertex_count": (c_uint32, [sys_p, size_p]),
        "plumage_system_feathers": (c_uint32, [sys_p, POINTER(Feather), c_size_t, size_p]),
        "plumage_system_feather_triangles": (c_uint32, [sys_p, f_p, c_size_t, size_p]),
        "plumage_feather_geometry_init": (None, [POINTER(FeatherGeometry)]),
        "plumage_system_feather_geometry": (c_uint32, [sys_p, POINTER(FeatherGeometry)]),
        "plumage_system_feather_instances": (c_uint32, [sys_p, POINTER(FeatherInstance), c_size_t, size_p]),
        "plumage_feather_template_init": (None, [POINTER(FeatherTemplate)]),
        "plumage_system_feather_template": (c_uint32, [sys_p, POINTER(FeatherTemplate)]),
        "plumage_system_changed_feathers": (c_uint32, [sys_p, POINTER(c_uint32), c_size_t, size_p, POINTER(c_uint32)]),
        "plumage_system_sampling_stats": (c_uint32, [sys_p, POINTER(SamplingStats)]),
        "plumage_system_ordering_stats": (c_uint32, [sys_p, POINTER(OrderingStats)]),
        "plumage_system_frame_stats": (c_uint32, [sys_p, POINTER(FrameStats)]),
        "plumage_system_memory": (c_uint32, [sys_p, POINTER(Memory)]),
        "plumage_system_seek": (c_uint32, [sys_p, c_uint64, POINTER(c_uint64)]),
        "plumage_system_validate": (c_uint32, [sys_p, POINTER(Validation)]),
        "plumage_system_save_state": (c_uint32, [sys_p, POINTER(c_uint8), c_size_t, size_p]),
        "plumage_system_load_state": (c_uint32, [sys_p, POINTER(c_uint8), c_size_t]),
        "plumage_system_last_error": (c_size_t, [sys_p, ctypes.c_char_p, c_size_t]),
    }
    for name, (restype, argtypes) in decls.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes


def library_path() -> Path:
    """The shared library used: $PLUMAGE_LIBRARY, else the one shipped in the package."""
    override = os.environ.get("PLUMAGE_LIBRARY")
    if override:
        return Path(override)
    return Path(__file__).resolve().parent / _library_name()


def _load() -> ctypes.CDLL:
    path = library_path()
    if not path.is_file():
        raise ImportError(
            f"the Plumage library is not at {path}: install the package with `pip install ./python` "
            "from the repository (it builds the library), or set PLUMAGE_LIBRARY"
        )
    lib = ctypes.CDLL(str(path))
    _declare(lib)
    abi = lib.plumage_abi_version()
    if abi != ABI_VERSION:
        raise ImportError(f"{path} speaks C ABI {abi}; this package expects {ABI_VERSION}")
    return lib


lib = _load()


def status_name(status: int) -> str:
    return str(lib.plumage_status_name(status).decode())


def last_error(sys_handle: int | None) -> str:
    needed = lib.plumage_system_last_error(sys_handle, None, 0)
    if needed == 0:
        return ""
    buf = ctypes.create_string_buffer(needed)
    lib.plumage_system_last_error(sys_handle, buf, needed)
    return str(buf.value.decode("utf-8", "replace"))
