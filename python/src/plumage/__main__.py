"""Command line: `python -m plumage dress INPUT.glb --out OUT.usd [options]`.

The glTF animation (node hierarchy, skins, morph targets, samplers) is
evaluated by the C++ host `plumage_gltf`, which writes what it hands the
library (`--poses`); this package then drives the library itself with exactly
those positions and configuration and writes USD. Options it does not know
are passed to the host (`--feathers 8000`, `--fps 24`, `--frames 30`,
`--spacing-map COLOR_0:0`, ...; see `plumage_gltf --help`).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import List, Optional

EXIT_USAGE = 2


def find_host(explicit: Optional[str]) -> Optional[str]:
    for candidate in (explicit, os.environ.get("PLUMAGE_GLTF_HOST"), shutil.which("plumage_gltf")):
        if candidate and Path(candidate).is_file() and os.access(candidate, os.X_OK):
            return candidate
    return None


def dress(argv: List[str]) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m plumage dress",
        description="Dress an animated glTF mesh with feathers and write USD. Unknown options go to plumage_gltf.",
    )
    parser.add_argument("input", help="INPUT.glb or .gltf ('builtin' for the host's built-in model)")
    parser.add_argument("--out", required=True, help="OUT.usd / .usda / .usdc")
    parser.add_argument("--host", help="the plumage_gltf program (default: $PLUMAGE_GLTF_HOST, then PATH)")
    parser.add_argument("--glb", help="also keep the host's own .glb of the same run")
    parser.add_argument("--poses", help="keep the host's pose file here (default: a temporary file)")
    parser.add_argument("--up-axis", choices=["Y", "Z"], default="Y", help="stage up axis (glTF is Y-up)")
    args, host_args = parser.parse_known_args(argv)

    host = find_host(args.host)
    if host is None:
        print(
            "plumage dress: the C++ host plumage_gltf was not found: build it (cmake -S cpp_examples -B build && "
            "cmake --build build) and pass --host build/plumage_gltf or set PLUMAGE_GLTF_HOST",
            file=sys.stderr,
        )
        return EXIT_USAGE
    try:
        from . import usd
    except ImportError as e:
        print(f"plumage dress: {e}", file=sys.stderr)
        return EXIT_USAGE
    from .poses import read_poses
    from .system import PlumageError, System

    with tempfile.TemporaryDirectory(prefix="plumage-dress-") as tmp:
        poses_path = Path(args.poses) if args.poses else Path(tmp) / "poses.bin"
        cmd = [host] + ([] if args.input == "builtin" else [args.input]) + ["--poses", str(poses_path), "--validate", "none"]
        if args.glb:
            cmd += ["--out", args.glb]
        run = subprocess.run(cmd + host_args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if run.returncode != 0:
            sys.stderr.write(run.stderr)
            return run.returncode
        poses = read_poses(poses_path)
    try:
        with System(poses.rest, poses.triangles, **poses.maps, **poses.config) as system:
            usd.write_run(args.out, system, poses.rest, poses.triangles, poses.frames, poses.times, poses.fps)
            count = system.feather_count
    except PlumageError as e:
        print(f"plumage dress: {e}", file=sys.stderr)
        return 4
    print(f"plumage dress: {len(poses.rest)} vertices, {count} feathers, {len(poses.times)} frames at {poses.fps:g} fps -> {args.out}")
    return 0


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        print("\ncommands: dress (python -m plumage dress --help)")
        return 0 if argv else EXIT_USAGE
    if argv[0] == "dress":
        return dress(argv[1:])
    print(f"plumage: unknown command {argv[0]!r} (commands: dress)", file=sys.stderr)
    return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
