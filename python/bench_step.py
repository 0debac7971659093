"""How much the Python path adds to a step: System.step (numpy in, ctypes call)
against the C call alone (plumage_system_step through ctypes with a prepared
pointer, no conversion or checks), on the same system and frames.

    python python/bench_step.py [--feathers 10000] [--frames 20] [--threads 1] [--geometry]

The built-in-like test surface is a UV sphere with a travelling bulge. Both
paths step the same frames from the same saved state, alternating, so the
machine's load affects them alike; --geometry also times feather_geometry()
(a copy-out, not part of the step). Prints the mean times and the overhead.
"""

from __future__ import annotations

import argparse
import ctypes
import sys
import time
from pathlib import Path

import numpy as np

import plumage
from plumage._ffi import lib

sys.path.insert(0, str(Path(__file__).resolve().parent / "tests"))
from conftest import uv_sphere, wobble  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--feathers", type=int, default=10000)
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--rings", type=int, default=160)
    ap.add_argument("--geometry", action="store_true")
    args = ap.parse_args()

    v, t = uv_sphere(args.rings, 2 * args.rings)
    frames = [wobble(v, k) for k in range(1, args.frames + 1)]
    s = plumage.System(v, t, target_feathers=args.feathers, seed=1, threads=args.threads)
    start = s.save_state()
    handle = s._handle
    c_frames = [(f, f.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), len(f)) for f in frames]

    def run_c() -> list:
        out = []
        for _, ptr, n in c_frames:
            t0 = time.perf_counter()
            status = lib.plumage_system_step(handle, ptr, n)
            out.append(time.perf_counter() - t0)
            assert status == 0
            lib_times.append(s.frame_stats().step_seconds)
        return out

    def run_py() -> list:
        out = []
        for f in frames:
            t0 = time.perf_counter()
            s.step(f)
            out.append(time.perf_counter() - t0)
        return out

    c_times, py_times, geo_times, lib_times = [], [], [], []
    for _ in range(2):  # alternate: C, Python, C, Python
        s.load_state(start)
        c_times += run_c()
        c_result = s.feather_triangles().tobytes()
        s.load_state(start)
        py_times += run_py()
        assert s.feather_triangles().tobytes() == c_result, "both paths must give the same feathers"
    if args.geometry:
        for _ in range(5):
            t0 = time.perf_counter()
            s.feather_geometry()
            geo_times.append(time.perf_counter() - t0)

    # the binding's own work per step (conversion, checks, pointer), without the library
    from plumage.system import _float_array, _fptr

    reps = 200
    t0 = time.perf_counter()
    for _ in range(reps):
        for f in frames:
            _fptr(_float_array(f, "positions", 3))
    wrapper_ms = 1e3 * (time.perf_counter() - t0) / (reps * len(frames))

    c_ms, py_ms = 1e3 * np.mean(c_times), 1e3 * np.mean(py_times)
    print(f"vertices {len(v)}, triangles {len(t)}, feathers {s.feather_count}, frames {args.frames} x 2, threads {args.threads}")
    print(f"library's own step_seconds  {1e3 * np.mean(lib_times):8.3f} ms")
    print(f"C step (ctypes call only)   {c_ms:8.3f} ms")
    print(f"Python System.step          {py_ms:8.3f} ms")
    print(f"overhead                    {py_ms - c_ms:+8.3f} ms ({100 * (py_ms - c_ms) / c_ms:+.2f} %)")
    print(f"binding's own work per step {wrapper_ms:8.4f} ms ({100 * wrapper_ms / c_ms:.3f} % of the C step)")
    if geo_times:
        print(f"feather_geometry() copy-out {1e3 * np.mean(geo_times):8.3f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
