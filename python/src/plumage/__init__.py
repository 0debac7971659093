"""Plumage: collision-free feathers and scales on animated surfaces.

A thin binding of the library's C ABI (include/plumage.h) with numpy arrays
in and out::

    import numpy as np, plumage
    sys = plumage.System(vertices, triangles, target_feathers=2000, seed=7)
    sys.step(frame_positions)
    geo = sys.feather_geometry()      # positions, normals, triangles, ids
"""

from ._ffi import ABI_VERSION, library_path
from .system import (
    CONFIG_FIELDS,
    FEATHER_DTYPE,
    INSTANCE_DTYPE,
    FeatherGeometry,
    FeatherTemplate,
    FrameStats,
    Memory,
    OrderingStats,
    PlumageError,
    SamplingStats,
    Skeleton,
    System,
    Validation,
    default_config,
    version,
    vertex_normals,
)

__all__ = [
    "ABI_VERSION",
    "CONFIG_FIELDS",
    "FEATHER_DTYPE",
    "INSTANCE_DTYPE",
    "FeatherGeometry",
    "FeatherTemplate",
    "FrameStats",
    "Memory",
    "OrderingStats",
    "PlumageError",
    "SamplingStats",
    "Skeleton",
    "System",
    "Validation",
    "default_config",
    "library_path",
    "version",
    "vertex_normals",
]
__version__ = "0.1.0"
