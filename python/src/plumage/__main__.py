"""Command line: `python -m plumage dress INPUT.glb --out OUT.usd [options]`.

The package reads the glTF itself (plumage.gltf: node hierarchy, skins,
morph targets, samplers, evaluated exactly as the C++ host plumage_gltf
evaluates them), drives the library frame by frame and writes USD. No C++
host is needed; `--host PROGRAM` hands the evaluation to plumage_gltf
instead (its `--poses` file), which also accepts the host's other options.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

import numpy as np

EXIT_OUTPUT, EXIT_USAGE, EXIT_INPUT, EXIT_LIBRARY = 1, 2, 3, 4


def find_host(explicit: Optional[str]) -> Optional[str]:
    for candidate in (explicit, os.environ.get("PLUMAGE_GLTF_HOST"), shutil.which("plumage_gltf")):
        if candidate and Path(candidate).is_file() and os.access(candidate, os.X_OK):
            return candidate
    return None


# ---------------------------------------------------------------- options


def _vector(text: str) -> Tuple[float, float, float]:
    fields = text.split(",")
    try:
        xyz = tuple(float(f) for f in fields)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text}: expected X,Y,Z") from None
    if len(xyz) != 3 or not all(np.isfinite(xyz)) or any(abs(v) > float(np.finfo(np.float32).max) for v in xyz):
        raise argparse.ArgumentTypeError(f"{text}: expected X,Y,Z (finite, in float range)")
    return xyz


@dataclass(frozen=True)
class MapSpec:
    attribute: str
    first: int = 0


def _map(text: str) -> MapSpec:
    """NAME or NAME:C (C = 0..3: the component of a vector attribute), as plumage_gltf."""
    name, first = text, 0
    if ":" in text:
        name, c = text.rsplit(":", 1)
        if len(c) != 1 or c not in "0123":
            raise argparse.ArgumentTypeError(f"{text}: expected NAME or NAME:C with C from 0 to 3")
        first = int(c)
    if not name:
        raise argparse.ArgumentTypeError(f"{text}: expected a vertex attribute name")
    return MapSpec(name, first)


def _nonnegative(limit: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        if not text.isdigit() or int(text) > limit:
            raise argparse.ArgumentTypeError(f"{text}: expected an integer from 0 to {limit}")
        return int(text)

    return parse


def _fps(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not (0 < v <= 1e4):
        raise argparse.ArgumentTypeError(f"{text}: expected a rate above 0 and at most 10000")
    return v


def _start(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not (0 <= v <= 1e7):
        raise argparse.ArgumentTypeError(f"{text}: expected seconds from 0 to 10000000")
    return v


def _finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not np.isfinite(v) or abs(v) > float(np.finfo(np.float32).max):
        raise argparse.ArgumentTypeError(f"{text}: expected a finite number in float range")
    return v


def _float32(text: str) -> float:
    """A number as the host's parse_float keeps it: the nearest float32."""
    return float(np.float32(_finite(text)))


def _feather_types(text: str) -> Tuple[str, ...]:
    names = tuple(text.split(","))
    for name in names:
        if name not in ("feathers", "sleek", "kite", "scales"):
            raise argparse.ArgumentTypeError(f"{text}: expected P,P,... with each P one of feathers|sleek|kite|scales")
    return names


def _resolution(text: str) -> Tuple[int, int]:
    fields = text.split(",")
    if len(fields) != 2 or not all(f.isdigit() and 3 <= int(f) <= 4096 for f in fields):
        raise argparse.ArgumentTypeError(f"{text}: expected RINGS,SEGMENTS, each from 3 to 4096")
    return int(fields[0]), int(fields[1])


def dress_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m plumage dress",
        description="Dress an animated glTF mesh with feathers and write USD: /Plumage/Body and /Plumage/Feathers, "
        "one time sample per frame at the clip's rate. The glTF is read and evaluated by this package "
        "(no C++ host needed); the rest pose and frames are those plumage_gltf hands the library, bit for bit.",
    )
    p.add_argument("input", help="INPUT.glb or .gltf ('builtin' for plumage_gltf's built-in swimming body)")
    p.add_argument("--out", required=True, help="OUT.usd / .usda / .usdc")
    g = p.add_argument_group("what to dress")
    g.add_argument("--mesh", action="append", default=[], metavar="NAME|I|all",
                   help="mesh to dress (default: the largest skinned or morphed mesh, else the largest); repeat it "
                   "to dress several as one, or `all` for every skinned or morphed mesh")
    g.add_argument("--animation", default="", metavar="NAME|I", help="clip to play (default: clip 0)")
    g.add_argument("--fps", type=_fps, default=30.0, help="sampling rate of the clip (default 30)")
    g.add_argument("--start", type=_start, default=0.0, metavar="S", help="seconds into the clip of the first frame (default 0)")
    g.add_argument("--frames", type=_nonnegative(10_000_000), metavar="N",
                   help="frames to step (default: the rest of the clip; 0 = rest pose only)")
    g.add_argument("--model-resolution", type=_resolution, metavar="RINGS,SEGMENTS",
                   help="the built-in model's resolution (default 96,32)")
    c = p.add_argument_group("feathers (unset ones keep the preset's defaults)")
    c.add_argument("--preset", choices=["feathers", "sleek", "kite", "scales"], default="feathers",
                   help="the library's defaults: contour feathers (default; `sleek` is the same), the rigid kite, or fish scales")
    count = c.add_mutually_exclusive_group()
    count.add_argument("--feathers", type=_nonnegative(2**32 - 1), metavar="N", help="target feather count")
    count.add_argument("--spacing", type=_finite, metavar="D", help="root spacing in model units (instead of --feathers)")
    c.add_argument("--seed", type=_nonnegative(2**64 - 1), help="random seed")
    c.add_argument("--sampler", choices=["guided", "random"], help="how roots are placed (default guided)")
    c.add_argument("--theta", type=_float32, metavar="DEG", help="the feathers' pitch above the surface, in degrees")
    c.add_argument("--mode", choices=["incremental", "legacy", "rebuild"], help="how frames are solved (default incremental)")
    c.add_argument("--threads", type=_nonnegative(2**32 - 1), help="worker threads (0 = all cores)")
    c.add_argument("--memory-limit", type=_nonnegative(2**44 - 1), metavar="MIB",
                   help="most heap the library's system may hold (default: no limit); a create or step that would pass it is refused")
    c.add_argument("--drift-tolerance", type=_float32, metavar="DEG",
                   help="incremental: how far a feather may drift before it is readjusted (default 17.2)")
    c.add_argument("--settle-rate", type=_float32, metavar="DEG",
                   help="incremental: most a readjusted feather settles toward its solved pose in a frame (default 2; 0 = at once)")
    c.add_argument("--curvature-min-scale", type=_float32, metavar="S",
                   help="smallest spacing factor where the surface bends tighter than a feather (default 0.4; 1 = uniform)")
    c.add_argument("--fluffiness", type=_float32, metavar="DEG", help="extra pitch added to every feather (default 0)")
    c.add_argument("--shaft-segments", type=_nonnegative(2**32 - 1), metavar="S",
                   help="shaft segments of a feather, 1 to 4 (default 4; 1 = the rigid kite)")
    c.add_argument("--bend-limit", type=_float32, metavar="DEG", help="largest bend at each shaft joint (default 22.9)")
    c.add_argument("--flow", type=_vector, metavar="X,Y,Z", help="flow axis")
    c.add_argument("--flow-source", type=_vector, metavar="X,Y,Z",
                   help="feathers flow away from this point along the surface; with no --flow, --flow-source or "
                   "--flow-map, a skinned mesh's feathers follow its bones from the head down the trunk and each limb, "
                   "other meshes flow from the front-most rest vertex (glTF models face +Z)")
    c.add_argument("--skeleton-flow", choices=["on", "off"], default="on",
                   help="off: a skinned mesh flows from its front-most rest vertex too (default on)")
    m = p.add_argument_group("per-vertex maps from vertex attributes of the glTF mesh (NAME or NAME:C, C = component 0-3)")
    m.add_argument("--spacing-map", type=_map, metavar="NAME[:C]", help="spacing multiplier: 2 = half as dense, 0 = bare skin")
    m.add_argument("--length-map", type=_map, metavar="NAME[:C]", help="feather length multiplier")
    m.add_argument("--width-map", type=_map, metavar="NAME[:C]", help="feather width multiplier")
    m.add_argument("--flow-map", type=_map, metavar="NAME[:C]",
                   help="flow direction from components C..C+2, in the mesh's own space (overrides --flow and --flow-source)")
    m.add_argument("--layer-map", type=_map, metavar="NAME[:C]",
                   help="per-vertex layer: where neighbouring feathers' layers differ, the higher lies on top")
    m.add_argument("--type-map", type=_map, metavar="NAME[:C]", help="per-vertex feather type (rounded), an index into --feather-types")
    m.add_argument("--feather-types", type=_feather_types, metavar="P,P,...",
                   help="the types' proportions from presets feathers|sleek|kite|scales (default feathers,scales)")
    o = p.add_argument_group("output")
    o.add_argument("--validate", choices=["every", "last", "none"], default="last",
                   help="exact validation (pairs, penetrations, coverage, discord) of every frame, the last, or none (default last)")
    o.add_argument("--up-axis", choices=["Y", "Z"], default="Y", help="stage up axis (glTF is Y-up)")
    o.add_argument("--quiet", action="store_true", help="no progress on stderr")
    h = p.add_argument_group("through the C++ host instead (plumage_gltf evaluates the glTF; other options go to it)")
    h.add_argument("--host", metavar="PROGRAM", help="use plumage_gltf (PROGRAM, else $PLUMAGE_GLTF_HOST, else PATH)")
    h.add_argument("--glb", help="with --host: also keep the host's own .glb of the same run")
    h.add_argument("--poses", help="with --host: keep the host's pose file here (default: a temporary file)")
    return p


# ---------------------------------------------------------------- what the library gets


@dataclass
class DressInput:
    """Everything the library is handed: the same as plumage_gltf's --poses file."""

    subject: Any  # plumage.gltf.Scene or plumage.builtin.ProceduralBody
    rest: np.ndarray  # (n, 3) float32
    triangles: np.ndarray  # (m, 3) uint32
    times: np.ndarray  # (frames,) clip seconds
    fps: float
    preset: str
    config: Dict[str, Any]  # keyword arguments of plumage.System
    maps: Dict[str, Any]  # keyword arguments of plumage.System (those present): float32 arrays, `skeleton` a gltf.SkinSkeleton
    warnings: List[str]

    @property
    def flow_from(self) -> str:
        """Where the orientation field comes from, as the host's report `config.flow_from` (the library's precedence)."""
        return flow_from(self.config, self.maps)

    def frames(self) -> Iterator[np.ndarray]:
        for t in self.times:
            yield self.subject.pose_at(float(t))


def flow_from(config: Dict[str, Any], maps: Dict[str, Any]) -> str:
    if maps.get("orientations") is not None:
        return "flow_map"
    if config.get("flow_source") is not None:
        return "flow_source"
    return "skeleton" if maps.get("skeleton") is not None else "flow_axis"


def flow_line(config: Dict[str, Any], maps: Dict[str, Any]) -> str:
    source = flow_from(config, maps)
    if source == "skeleton":
        return f"flow from the skeleton ({len(maps['skeleton'].joint_parents)} joints)"
    if source == "flow_source":
        return "flow from the flow source ({:g}, {:g}, {:g})".format(*config["flow_source"])
    if source == "flow_map":
        return "flow from the flow map"
    axis = config.get("flow_axis")
    return "flow along the axis" + (" ({:g}, {:g}, {:g})".format(*axis) if axis is not None else " (the preset's)")


def sampling_line(system: Any) -> str:
    s = system.sampling_stats()
    if s is None:
        return "sampling: none"
    return f"sampling: {s.roots} roots, spacing {s.spacing:.4g}, field_singularities {s.field_singularities}"


def validation_line(what: str, v: Any) -> str:
    return (f"{what}: pairs {v.intersecting_pairs}, penetrations {v.body_penetrations}, coverage {v.coverage:.4f}, "
            f"discord_percent {v.discord_percent:.2f}")


def validate_frame(when: str, k: int, n: int) -> bool:
    return when == "every" or (when == "last" and k + 1 == n)


def prepare(args: argparse.Namespace) -> DressInput:
    """Reads the input and builds the library's input as plumage_gltf does
    (main.cpp: open_subject, make_config, default_flow, frame_times)."""
    from .gltf import GltfUsageError, Scene, frame_times

    maps_asked = [(k, getattr(args, k)) for k in ("spacing_map", "length_map", "width_map", "flow_map", "layer_map", "type_map") if getattr(args, k)]
    if args.input == "builtin":
        from .builtin import ProceduralBody

        if maps_asked:
            raise GltfUsageError(f"--{maps_asked[0][0].replace('_', '-')} reads a vertex attribute of a glTF input; the built-in model has none")
        subject: Any = ProceduralBody(*(args.model_resolution or ()))
        subject.check_requests(args.mesh, args.animation)
        facing = subject.facing
    else:
        if args.model_resolution:
            raise GltfUsageError(f"--model-resolution applies to the built-in model only, not to {args.input}")
        subject = Scene(args.input, args.mesh, args.animation)
        facing = (0.0, 0.0, 1.0)
    maps: Dict[str, np.ndarray] = {}
    for key, name in (("spacing_map", "spacing_scale"), ("length_map", "length_scale"), ("width_map", "width_scale"), ("layer_map", "layer")):
        spec = getattr(args, key)
        if spec:
            maps[name] = subject.vertex_attribute(spec.attribute, spec.first, 1)
    if args.flow_map:
        maps["orientations"] = subject.rest_directions(args.flow_map.attribute, args.flow_map.first)
    if args.type_map:
        # whole numbers in the attribute, rounded half away from zero (std::lround); negative ones are 0
        values = np.maximum(subject.vertex_attribute(args.type_map.attribute, args.type_map.first, 1), np.float32(0)).astype(np.float64)
        maps["feather_type"] = np.floor(values + 0.5).astype(np.uint32)
        maps["feather_types"] = tuple(args.feather_types or ("feathers", "scales"))

    # the host's make_config: degrees to radians in double, then float
    config: Dict[str, Any] = {}
    for key, field in (("feathers", "target_feathers"), ("spacing", "spacing"), ("sampler", "sampler"), ("seed", "seed"), ("mode", "mode"),
                       ("threads", "threads"), ("flow", "flow_axis"), ("flow_source", "flow_source"),
                       ("curvature_min_scale", "curvature_min_scale"), ("shaft_segments", "shaft_segments")):
        if getattr(args, key) is not None:
            config[field] = getattr(args, key)
    for key, field in (("theta", "theta"), ("drift_tolerance", "drift_tolerance"), ("settle_rate", "settle_rate"),
                       ("bend_limit", "bend_limit"), ("fluffiness", "fluffiness")):
        if getattr(args, key) is not None:
            config[field] = getattr(args, key) * math.pi / 180.0
    if args.memory_limit is not None:
        config["memory_limit"] = args.memory_limit << 20
    rest = subject.rest_positions
    skeleton = None
    if args.flow is None and args.flow_source is None and args.flow_map is None and len(rest) and args.skeleton_flow == "on":
        # a skinned subject's feathers follow its bones (the library walks them from the head)
        skeleton = getattr(subject, "skin_skeleton", lambda: None)()
    if skeleton is not None:
        maps["skeleton"] = skeleton
    elif args.flow is None and args.flow_source is None and args.flow_map is None and len(rest):
        # feathers flow from the front of the model to its back (float arithmetic, first of equals)
        f = np.array(facing, np.float32)
        ahead = rest[:, 0] * f[0] + rest[:, 1] * f[1] + rest[:, 2] * f[2]
        config["flow_source"] = tuple(float(v) for v in rest[int(np.argmax(ahead))])

    warnings = []
    clip = subject.clip
    times = frame_times(clip, args.fps, args.start, args.frames)
    if clip is None or not (clip.channels or args.input == "builtin"):
        what = "has no animation" if clip is None else f'has an animation clip ("{clip.name}") that animates nothing'
        shown = "the rest pose only" if len(times) == 0 else f"{len(times)} frames of the rest pose"
        warnings.append(f"plumage dress: warning: {args.input} {what}: writing {shown}")
    return DressInput(subject, rest, subject.triangles, times, args.fps, args.preset, config, maps, warnings)


# ---------------------------------------------------------------- progress


class Progress:
    """Progress on stderr for long runs: on a terminal one line redrawn at
    most ten times a second once the run has lasted a second; otherwise a
    line every ten seconds."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.tty = sys.stderr.isatty()
        self.start = time.monotonic()
        self.last = 0.0
        self.drawn = False
        self.context = "rest pose"

    def library(self, phase: str, fraction: float) -> bool:
        self.draw(f"{self.context}: {phase} {fraction * 100:3.0f}%")
        return False  # never interrupts

    def frame_done(self, done: int, total: int) -> None:
        self.draw(f"frame {done}/{total}")

    def draw(self, text: str) -> None:
        now = time.monotonic() - self.start
        if not self.enabled or now < 1.0 or now - self.last < (0.1 if self.tty else 10.0):
            return
        self.last = now
        if self.tty:
            sys.stderr.write(f"\r\033[Kplumage dress: {text}")
            self.drawn = True
        else:
            sys.stderr.write(f"plumage dress: {text} ({now:.0f} s)\n")
        sys.stderr.flush()

    def clear(self) -> None:
        if self.drawn:
            sys.stderr.write("\r\033[K")
            sys.stderr.flush()
            self.drawn = False


# ---------------------------------------------------------------- the runs


def dress_native(args: argparse.Namespace) -> int:
    try:
        from . import usd
    except ImportError as e:
        print(f"plumage dress: {e}", file=sys.stderr)
        return EXIT_USAGE
    from .gltf import GltfError, GltfUsageError
    from .system import PlumageError, System

    try:
        run = prepare(args)
    except GltfUsageError as e:
        print(f"plumage dress: {e}", file=sys.stderr)
        return EXIT_USAGE
    except (GltfError, ImportError) as e:
        print(f"plumage dress: {e}", file=sys.stderr)
        return EXIT_INPUT
    for w in run.warnings:
        print(w, file=sys.stderr)
    progress = Progress(not args.quiet)
    n = len(run.times)
    checks: List[str] = []
    try:
        with System(run.rest, run.triangles, **run.maps, preset=run.preset, progress=progress.library, **run.config) as system:
            checks.append(sampling_line(system))
            if args.validate != "none":
                v = system.validate()
                if v is not None:
                    checks.append(validation_line("rest pose", v))
            try:
                writer = usd.UsdWriter(args.out, run.fps, run.rest, run.triangles, system.feather_geometry(), up_axis=args.up_axis)
                for k, (seconds, pose) in enumerate(zip(run.times, run.frames())):
                    progress.context = f"frame {k + 1}/{n}"
                    system.step(pose)
                    # validation after the step, as the host: not step time
                    if validate_frame(args.validate, k, n):
                        v = system.validate()
                        if v is not None:
                            checks.append(validation_line(f"frame {k + 1}/{n} (t = {float(seconds):g} s)", v))
                    writer.add_frame(float(seconds), pose, system.feather_geometry())
                    progress.frame_done(k + 1, n)
                writer.save()
            except Exception as e:  # noqa: BLE001 - pxr raises its own error types
                if isinstance(e, PlumageError):
                    raise
                progress.clear()
                print(f"plumage dress: cannot write {args.out}: {e}", file=sys.stderr)
                return EXIT_OUTPUT
            count = system.feather_count
    except PlumageError as e:
        progress.clear()
        print(f"plumage dress: {e}", file=sys.stderr)
        return EXIT_LIBRARY
    progress.clear()
    print(f"plumage dress: {args.input}, mesh \"{run.subject.mesh_name}\": {len(run.rest)} vertices, {count} feathers, "
          f"{n} frames at {run.fps:g} fps -> {args.out}")
    print(f"plumage dress: {flow_line(run.config, run.maps)} (flow_from {run.flow_from})")
    for line in checks:
        print(f"plumage dress: {line}")
    return 0


def _host_args(args: argparse.Namespace) -> List[str]:
    """The parsed options as plumage_gltf options."""
    out: List[str] = []
    for m in args.mesh:
        out += ["--mesh", m]
    defaults = dress_parser().parse_args(["x", "--out", "x"])
    for key in ("animation", "fps", "start", "frames", "model_resolution", "preset", "feathers", "spacing", "sampler", "theta", "seed", "mode",
                "threads", "memory_limit", "drift_tolerance", "settle_rate", "curvature_min_scale", "fluffiness", "shaft_segments", "bend_limit",
                "flow", "flow_source", "skeleton_flow", "spacing_map", "length_map", "width_map", "flow_map", "layer_map", "type_map",
                "feather_types"):
        value = getattr(args, key)
        if value is None or value == getattr(defaults, key):
            continue
        if isinstance(value, MapSpec):
            value = f"{value.attribute}:{value.first}"
        elif isinstance(value, tuple):
            value = ",".join(v if isinstance(v, str) else repr(v) for v in value)
        out += ["--" + key.replace("_", "-"), str(value)]
    return out


def dress_with_host(args: argparse.Namespace, host_extra: List[str]) -> int:
    host = find_host(args.host)
    if host is None:
        print(
            "plumage dress: the C++ host plumage_gltf was not found: build it (cmake -S cpp_examples -B build && "
            "cmake --build build) and pass --host build/plumage_gltf or set PLUMAGE_GLTF_HOST; "
            "without --host the package reads the glTF itself",
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
        run = subprocess.run(cmd + _host_args(args) + host_extra, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if run.returncode != 0:
            sys.stderr.write(run.stderr)
            return run.returncode
        poses = read_poses(poses_path)
    n = len(poses.times)
    checks: List[str] = []
    try:
        with System(poses.rest, poses.triangles, **poses.maps, **poses.config) as system:
            checks.append(sampling_line(system))
            if args.validate != "none" and (v := system.validate()) is not None:
                checks.append(validation_line("rest pose", v))
            writer = usd.UsdWriter(args.out, poses.fps, poses.rest, poses.triangles, system.feather_geometry(), up_axis=args.up_axis)
            for k, (seconds, frame) in enumerate(zip(poses.times, poses.frames)):
                system.step(frame)
                if validate_frame(args.validate, k, n) and (v := system.validate()) is not None:
                    checks.append(validation_line(f"frame {k + 1}/{n} (t = {float(seconds):g} s)", v))
                writer.add_frame(float(seconds), frame, system.feather_geometry())
            writer.save()
            count = system.feather_count
    except PlumageError as e:
        print(f"plumage dress: {e}", file=sys.stderr)
        return EXIT_LIBRARY
    print(f"plumage dress: {len(poses.rest)} vertices, {count} feathers, {n} frames at {poses.fps:g} fps -> {args.out}")
    print(f"plumage dress: {flow_line(poses.config, poses.maps)} (flow_from {flow_from(poses.config, poses.maps)})")
    for line in checks:
        print(f"plumage dress: {line}")
    return 0


def dress(argv: List[str]) -> int:
    parser = dress_parser()
    args, extra = parser.parse_known_args(argv)
    if args.host is None:
        if extra:
            parser.error(f"unrecognized arguments: {' '.join(extra)}")
        if args.glb or args.poses:
            parser.error("--glb and --poses are the C++ host's outputs: give --host too")
        return dress_native(args)
    return dress_with_host(args, extra)


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print((__doc__ or "").strip())
        print("\ncommands: dress (python -m plumage dress --help)")
        return 0 if argv else EXIT_USAGE
    if argv[0] == "dress":
        return dress(argv[1:])
    print(f"plumage: unknown command {argv[0]!r} (commands: dress)", file=sys.stderr)
    return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
