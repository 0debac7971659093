"""The ctypes structs match include/plumage.h byte for byte."""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

import plumage
from plumage import _ffi

from conftest import REPO

STRUCTS = {
    "PlumageConfig": _ffi.Config,
    "PlumageMeshDesc": _ffi.MeshDesc,
    "PlumageSkeleton": _ffi.Skeleton,
    "PlumageFeatherType": _ffi.FeatherType,
    "PlumageFeather": _ffi.Feather,
    "PlumageSamplingStats": _ffi.SamplingStats,
    "PlumageOrderingStats": _ffi.OrderingStats,
    "PlumageFrameStats": _ffi.FrameStats,
    "PlumageMemory": _ffi.Memory,
    "PlumageValidation": _ffi.Validation,
    "PlumageFeatherGeometry": _ffi.FeatherGeometry,
    "PlumageFeatherInstance": _ffi.FeatherInstance,
    "PlumageFeatherTemplate": _ffi.FeatherTemplate,
}


def test_init_functions_report_the_size_of_the_mirrored_structs() -> None:
    cfg = _ffi.Config()
    _ffi.lib.plumage_config_init(ctypes.byref(cfg))
    assert cfg.struct_size == ctypes.sizeof(_ffi.Config)
    desc = _ffi.MeshDesc()
    _ffi.lib.plumage_mesh_desc_init(ctypes.byref(desc))
    assert desc.struct_size == ctypes.sizeof(_ffi.MeshDesc)
    geo = _ffi.FeatherGeometry()
    _ffi.lib.plumage_feather_geometry_init(ctypes.byref(geo))
    assert geo.struct_size == ctypes.sizeof(_ffi.FeatherGeometry)


def test_stats_structs_are_filled_whole(sphere) -> None:
    s = plumage.System(*sphere, target_feathers=300, seed=2, threads=1)
    for fn, raw_type in (
        (_ffi.lib.plumage_system_frame_stats, _ffi.FrameStats),
        (_ffi.lib.plumage_system_sampling_stats, _ffi.SamplingStats),
        (_ffi.lib.plumage_system_ordering_stats, _ffi.OrderingStats),
        (_ffi.lib.plumage_system_validate, _ffi.Validation),
        (_ffi.lib.plumage_system_memory, _ffi.Memory),
    ):
        raw = raw_type()
        raw.struct_size = ctypes.sizeof(raw_type)
        assert fn(s._handle, ctypes.byref(raw)) == 0
        assert raw.struct_size == ctypes.sizeof(raw_type), raw_type.__name__


def test_feather_dtype_matches_struct() -> None:
    assert plumage.FEATHER_DTYPE.itemsize == ctypes.sizeof(_ffi.Feather)
    for name, _ in _ffi.Feather._fields_:
        assert plumage.FEATHER_DTYPE.fields[name][1] == getattr(_ffi.Feather, name).offset


def test_offsets_match_a_c_compiler(tmp_path) -> None:
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        pytest.skip("no C compiler to compare the layout with")
    lines = ['#include <stdio.h>', '#include <stddef.h>', '#include "plumage.h"', "int main(void) {"]
    expected = []
    for c_name, py_type in STRUCTS.items():
        lines.append(f'  printf("%zu\\n", sizeof({c_name}));')
        expected.append(ctypes.sizeof(py_type))
        for field, _ in py_type._fields_:
            lines.append(f'  printf("%zu\\n", offsetof({c_name}, {field}));')
            expected.append(getattr(py_type, field).offset)
    lines += ["  return 0;", "}"]
    src = tmp_path / "layout.c"
    src.write_text("\n".join(lines))
    exe = tmp_path / "layout"
    subprocess.run([cc, "-std=c99", "-I", str(REPO / "include"), str(src), "-o", str(exe)], check=True)
    got = [int(x) for x in subprocess.run([str(exe)], check=True, stdout=subprocess.PIPE, text=True).stdout.split()]
    assert got == expected


def test_status_names_come_from_the_library() -> None:
    assert _ffi.status_name(0) == "OK"
    assert _ffi.status_name(9) == "NON_FINITE"
    assert _ffi.status_name(999) == "UNKNOWN_STATUS"
    assert plumage.version().count(".") == 2
    assert np.dtype(plumage.FEATHER_DTYPE).names[0] == "id"
