#!/usr/bin/env python3
"""Runs the glTF host (plumage_gltf) over the benchmark cases and prints
Markdown tables; scripts/bench.sh builds the host first and calls this.

Sections (table, scaling and threads by default, in this order; memory only
when named, as it takes about 6 to 10 minutes):
  table    the paper's Table 1: every model (the three shared models and the
           built-in one) at about --feathers feathers, modes legacy,
           incremental and rebuild side by side, on --table-threads threads
  scaling  the built-in model, incremental, at --scaling-feathers feathers:
           static setup and mean frame time, growth exponents (log-log fit)
  threads  the built-in model, incremental, at --threads-feathers feathers on
           1 and 2 threads: speed-up, and whether the .glb outputs are
           byte-identical (cmp)
  memory   the built-in model at --memory-resolution (about 200 000
           triangles) with about --memory-feathers feathers, incremental,
           --memory-frames steps on --memory-threads threads: resident set
           size and its peak after create and after the steps, and the
           growth of RSS and of the live heap from step --memory-early to
           the last (the host reads /proc/self/status and mallinfo2 after
           every step)

Every run has validation off (--validate none). Averages are over the
frames after the first: frame 0 goes from the rest (bind) pose to the
clip's first pose, which is not a frame-to-frame change (for the built-in
model it is the rest pose itself). Figures: the library's own seconds
(reorder_seconds, adjust_seconds, sampling/ordering/static seconds) where the
report has them, the host's wall time of plumage_system_step for frame time
(frames[].step_seconds) and of plumage_system_create for create time.
Nothing fails on speed: this prints figures.
"""

import argparse
import datetime
import json
import math
import os
import platform
import resource
import subprocess
import sys
import time

MODES = ("legacy", "incremental", "rebuild")
MODELS = ("Flamingo.glb", "Fox.glb", "bird.glb", None)  # None: the built-in model


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# ---- the machine ------------------------------------------------------------


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def load_average():
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return None


def git_revision():
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True, text=True).stdout.strip()
        return rev + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def machine():
    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "cores": os.cpu_count(),
        "cpu": cpu_model(),
        "kernel": platform.release(),
        "git": git_revision(),
        "load_average_at_start": load_average(),
    }


# ---- running the host -------------------------------------------------------


class Runner:
    def __init__(self, host, out_dir, fps):
        self.host = host
        self.fps = fps
        self.runs_dir = os.path.join(out_dir, "runs")
        os.makedirs(self.runs_dir, exist_ok=True)

    def run(self, name, model_path, args):
        """Runs the host; returns (report dict, command) or (None, command)."""
        report_path = os.path.join(self.runs_dir, name + ".json")
        if os.path.exists(report_path):
            os.remove(report_path)
        cmd = [self.host] + ([model_path] if model_path else []) + list(args) + ["--fps", f"{self.fps:g}", "--report", report_path]
        shown = " ".join(cmd)
        log(f"  $ {shown}")
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.monotonic()
        proc = subprocess.run(cmd, capture_output=True, text=True)
        took = time.monotonic() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        if proc.returncode != 0:
            log(f"    FAILED (exit {proc.returncode}) after {took:.1f} s: {proc.stderr.strip().splitlines()[-1:] or ''}")
            return None, shown
        log(f"    {took:.1f} s wall, {cpu:.1f} s CPU")
        with open(report_path) as f:
            report = json.load(f)
        # How much CPU the whole host process got: on a loaded machine a
        # one-thread run gets less than one core (cpu / wall < 1).
        report["bench_process"] = {"wall_seconds": took, "cpu_seconds": cpu}
        return report, shown


def clip_frames(runner, model_path, label, fps):
    """Frames in the model's default clip at `fps`, from a cheap rest-only run."""
    report, _ = runner.run(f"probe_{label}", model_path, ["--feathers", "100", "--frames", "0", "--validate", "none"])
    if report is None:
        return None
    clip = report["config"].get("animation")
    if not clip:
        return 1
    return int(math.floor(clip["duration"] * fps + 1e-6)) + 1


# ---- figures of one run -----------------------------------------------------


def summarise(report):
    """Per-run figures; averages over frames with index >= 1."""
    frames = [f for f in report["frames"] if f["index"] >= 1]
    n = len(frames)
    s = {
        "feathers": report["feathers"],
        "frames_stepped": len(report["frames"]),
        "frames_averaged": n,
        "sampling_seconds": report.get("sampling", {}).get("seconds"),
        "ordering_seconds": report.get("ordering", {}).get("seconds"),
        "static_adjust_seconds": report.get("static", {}).get("seconds"),
        "create_seconds": report["timing"].get("create_seconds"),
        "process_wall_seconds": report["bench_process"]["wall_seconds"],
        "process_cpu_seconds": report["bench_process"]["cpu_seconds"],
        "process_cpu_over_wall": report["bench_process"]["cpu_seconds"] / report["bench_process"]["wall_seconds"],
    }
    parts = [s["sampling_seconds"], s["ordering_seconds"], s["static_adjust_seconds"]]
    s["setup_seconds"] = sum(parts) if all(p is not None for p in parts) else None
    if n == 0:
        return s

    def total(key):
        vals = [f.get(key) for f in frames]
        return None if any(v is None for v in vals) else sum(vals)

    adjusted = total("adjusted")
    tests = sum(f.get("collision_tests_per_feather", 0.0) * f.get("adjusted", 0) for f in frames)
    changes = total("priority_changes")
    reorder = total("reorder_seconds")
    adjust = total("adjust_seconds")
    step = total("step_seconds")
    steps_sorted = sorted(f["step_seconds"] for f in frames)
    s.update(
        {
            "adjusted_per_frame": adjusted / n if adjusted is not None else None,
            "collision_tests_per_feather": tests / adjusted if adjusted else None,
            "priority_changes_per_frame": changes / n if changes is not None else None,
            # The paper's percentage is of the affected (adjusted) roots:
            # 4.8 of 1015.9 is its 0.47 %.
            "priority_changes_pct_of_adjusted": 100.0 * changes / adjusted if changes is not None and adjusted else None,
            "priority_changes_pct_of_feathers": 100.0 * changes / n / report["feathers"] if changes is not None and report["feathers"] else None,
            "reorder_ms": 1e3 * reorder / n if reorder is not None else None,
            "adjust_ms": 1e3 * adjust / n if adjust is not None else None,
            "frame_ms": 1e3 * step / n,
            "frame_ms_median": 1e3 * steps_sorted[n // 2] if n % 2 else 1e3 * 0.5 * (steps_sorted[n // 2 - 1] + steps_sorted[n // 2]),
            "frame_ms_max": 1e3 * steps_sorted[-1],
            "reorder_pct_of_frame": 100.0 * reorder / step if reorder is not None and step else None,
            "adjust_us_per_adjusted": 1e6 * adjust / adjusted if adjust is not None and adjusted else None,
            "frame_us_per_adjusted": 1e6 * step / adjusted if adjusted else None,
        }
    )
    return s


# ---- Markdown ---------------------------------------------------------------


def fmt(v, digits=1):
    if v is None:
        return "—"
    if isinstance(v, int):
        return f"{v:,}".replace(",", " ")
    if isinstance(v, float) and (math.isnan(v) or math.isinf(v)):
        return "—"
    return f"{v:.{digits}f}"


def md_table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---:" if i else "---" for i in range(len(header))) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def fit_slope(pts):
    """Least-squares slope of y on x over (x, y) points (None with fewer than 2)."""
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx == 0:
        return None
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def fit_exponent(xs, ys):
    """Least-squares slope of log y on log x (None with fewer than 2 points)."""
    return fit_slope([(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x and y and x > 0 and y > 0])


# ---- sections ---------------------------------------------------------------


def model_label(m):
    return m[: -len(".glb")] if m else "built-in"


def section_table(opt, runner, out):
    log(f"== table: {opt.feathers} feathers, modes {', '.join(MODES)}, {opt.table_threads} thread(s), at most {opt.frames} frames per clip")
    rows, missing = [], []
    for m in MODELS:
        label = model_label(m)
        path = None
        if m:
            path = os.path.join(opt.data, m)
            if not os.path.isfile(path):
                missing.append(m)
                log(f"  {m}: not found in {opt.data}, skipped")
                continue
        in_clip = clip_frames(runner, path, label, opt.fps)
        if in_clip is None:
            log(f"  {label}: the host could not open it, skipped")
            missing.append(m or "built-in")
            continue
        frames = min(opt.frames, in_clip)
        per_mode = {}
        for mode in MODES:
            args = ["--feathers", str(opt.feathers), "--frames", str(frames), "--mode", mode, "--threads", str(opt.table_threads), "--validate", "none"]
            report, cmd = runner.run(f"table_{label}_{mode}", path, args)
            if report is None:
                continue
            s = summarise(report)
            s.update({"model": label, "mode": mode, "threads": opt.table_threads, "clip_frames": in_clip, "command": cmd})
            per_mode[mode] = s
        inc = per_mode.get("incremental")
        for mode, s in per_mode.items():
            if mode == "incremental":
                for other in ("legacy", "rebuild"):
                    o = per_mode.get(other)
                    s[f"frame_ratio_incremental_over_{other}"] = inc["frame_ms"] / o["frame_ms"] if o and o.get("frame_ms") and inc.get("frame_ms") else None
            rows.append(s)

    header = [
        "model", "mode", "feathers", "frames", "adjusted / frame", "collision tests / feather", "priority changes / frame",
        "% of adjusted", "% of all", "reorder ms", "adjust ms", "frame ms", "reorder % of frame",
        "adjust µs / adjusted", "frame µs / adjusted", "inc / legacy", "inc / rebuild", "setup s", "CPU / wall",
    ]
    body = []
    for s in rows:
        body.append([
            s["model"], s["mode"], fmt(s["feathers"]), fmt(s["frames_averaged"]), fmt(s.get("adjusted_per_frame")),
            fmt(s.get("collision_tests_per_feather")), fmt(s.get("priority_changes_per_frame")),
            fmt(s.get("priority_changes_pct_of_adjusted"), 2), fmt(s.get("priority_changes_pct_of_feathers"), 2),
            fmt(s.get("reorder_ms")), fmt(s.get("adjust_ms")), fmt(s.get("frame_ms")), fmt(s.get("reorder_pct_of_frame")),
            fmt(s.get("adjust_us_per_adjusted")), fmt(s.get("frame_us_per_adjusted")),
            fmt(s.get("frame_ratio_incremental_over_legacy"), 2) if s["mode"] == "incremental" else "",
            fmt(s.get("frame_ratio_incremental_over_rebuild"), 2) if s["mode"] == "incremental" else "",
            fmt(s.get("setup_seconds"), 2), fmt(s.get("process_cpu_over_wall"), 2),
        ])
    text = [
        f"### Table 1: about {opt.feathers} feathers, {opt.table_threads} thread(s), validation off",
        "",
        md_table(header, body),
        "",
        f"Frames: each clip's first min({opt.frames}, clip length) frames at {opt.fps:g} fps are stepped; averages are over "
        "all of them but frame 0 (rest pose to the clip's first pose). reorder ms is the library's reorder_seconds (re-posing "
        "the roots, R_k, neighbourhoods and the order update); adjust ms its adjust_seconds; frame ms the host's wall time of "
        "plumage_system_step. Priority changes are neighbour pairs whose ΔP changed sign, as a percentage of the adjusted "
        "feathers (the paper's definition) and of all feathers. Ratios are of mean frame time, measured in this run. "
        "setup s: the library's sampling + ordering + static adjustment seconds of create. "
        "CPU / wall: CPU seconds over wall seconds of the whole host process; below 1 on one thread means the run "
        "waited for a core (the machine was busy) and its times are inflated.",
    ]
    if missing:
        text += ["", "Skipped (not found in " + opt.data + "): " + ", ".join(missing)]
    out["table1"] = {"feathers": opt.feathers, "threads": opt.table_threads, "max_frames": opt.frames, "fps": opt.fps, "missing": missing, "rows": rows}
    return "\n".join(text)


def section_scaling(opt, runner, out):
    log(f"== scaling: built-in model, incremental, {opt.table_threads} thread(s), {opt.scaling_frames} frames, feathers {opt.scaling_feathers}")
    rows = []
    for n in opt.scaling_feathers:
        args = ["--feathers", str(n), "--frames", str(opt.scaling_frames), "--mode", "incremental", "--threads", str(opt.table_threads), "--validate", "none"]
        report, cmd = runner.run(f"scaling_{n}", None, args)
        if report is None:
            continue
        s = summarise(report)
        s.update({"target_feathers": n, "threads": opt.table_threads, "command": cmd})
        rows.append(s)
    xs = [s["feathers"] for s in rows]
    exps = {
        "setup_seconds": fit_exponent(xs, [s.get("setup_seconds") for s in rows]),
        "create_seconds": fit_exponent(xs, [s.get("create_seconds") for s in rows]),
        "frame_ms": fit_exponent(xs, [s.get("frame_ms") for s in rows]),
        "adjusted_per_frame": fit_exponent(xs, [s.get("adjusted_per_frame") for s in rows]),
    }
    header = ["feathers", "sampling s", "ordering s", "static adjust s", "setup s", "create s (host)", "adjusted / frame", "frame ms", "adjust µs / adjusted", "CPU / wall"]
    body = [[
        fmt(s["feathers"]), fmt(s.get("sampling_seconds"), 3), fmt(s.get("ordering_seconds"), 3), fmt(s.get("static_adjust_seconds"), 3),
        fmt(s.get("setup_seconds"), 3), fmt(s.get("create_seconds"), 3), fmt(s.get("adjusted_per_frame")), fmt(s.get("frame_ms")),
        fmt(s.get("adjust_us_per_adjusted")), fmt(s.get("process_cpu_over_wall"), 2),
    ] for s in rows]
    body.append(["**exponent**", "", "", "", fmt(exps["setup_seconds"], 2), fmt(exps["create_seconds"], 2), fmt(exps["adjusted_per_frame"], 2), fmt(exps["frame_ms"], 2), "", ""])
    text = [
        f"### Scaling: built-in model, incremental, {opt.table_threads} thread(s), {opt.scaling_frames} frames, validation off",
        "",
        md_table(header, body),
        "",
        "setup s = the library's sampling + ordering + static adjustment seconds; create s = the host's wall time of "
        "plumage_system_create. Exponent: least-squares slope of log(figure) on log(feathers).",
    ]
    out["scaling"] = {"threads": opt.table_threads, "frames": opt.scaling_frames, "rows": rows, "exponents": exps}
    return "\n".join(text)


def section_threads(opt, runner, out):
    log(f"== threads: built-in model, incremental, {opt.scaling_frames} frames, feathers {opt.threads_feathers}, 1 vs 2 threads")
    rows = []
    for n in opt.threads_feathers:
        per = {}
        for t in (1, 2):
            glb = os.path.join(runner.runs_dir, f"threads_{n}_{t}.glb")
            args = ["--feathers", str(n), "--frames", str(opt.scaling_frames), "--mode", "incremental", "--threads", str(t), "--validate", "none", "--out", glb]
            report, cmd = runner.run(f"threads_{n}_{t}", None, args)
            if report is not None:
                s = summarise(report)
                s.update({"threads": t, "command": cmd, "glb": glb})
                per[t] = s
        if 1 not in per or 2 not in per:
            continue
        same = subprocess.run(["cmp", "-s", per[1]["glb"], per[2]["glb"]]).returncode == 0
        rows.append({
            "target_feathers": n,
            "feathers": per[1]["feathers"],
            "one_thread": per[1],
            "two_threads": per[2],
            "glb_identical": same,
            "frame_speedup": per[1]["frame_ms"] / per[2]["frame_ms"] if per[1].get("frame_ms") and per[2].get("frame_ms") else None,
            "adjust_speedup": per[1]["adjust_ms"] / per[2]["adjust_ms"] if per[1].get("adjust_ms") and per[2].get("adjust_ms") else None,
            "create_speedup": per[1]["create_seconds"] / per[2]["create_seconds"] if per[1].get("create_seconds") and per[2].get("create_seconds") else None,
        })
    header = ["feathers", "frame ms, 1 thread", "frame ms, 2 threads", "frame speed-up", "adjust speed-up", "create s, 1 / 2 threads", "create speed-up", "CPU / wall, 1 / 2 threads", ".glb byte-identical"]
    body = [[
        fmt(r["feathers"]), fmt(r["one_thread"].get("frame_ms")), fmt(r["two_threads"].get("frame_ms")), fmt(r["frame_speedup"], 2),
        fmt(r["adjust_speedup"], 2), f'{fmt(r["one_thread"].get("create_seconds"), 2)} / {fmt(r["two_threads"].get("create_seconds"), 2)}',
        fmt(r["create_speedup"], 2), f'{fmt(r["one_thread"].get("process_cpu_over_wall"), 2)} / {fmt(r["two_threads"].get("process_cpu_over_wall"), 2)}',
        "yes" if r["glb_identical"] else "**NO**",
    ] for r in rows]
    text = [
        f"### Threads: built-in model, incremental, {opt.scaling_frames} frames, validation off",
        "",
        md_table(header, body),
        "",
        "Speed-up = 1-thread time / 2-thread time, measured side by side in this run. The .glb files (rest pose plus every "
        "frame's feathers) are compared with cmp.",
    ]
    out["threads"] = {"frames": opt.scaling_frames, "rows": rows}
    return "\n".join(text)


def mib(kib, digits=1):
    return fmt(kib / 1024.0, digits) if kib is not None else "—"


def section_memory(opt, runner, out):
    rings, segments = opt.memory_resolution
    log(f"== memory: built-in model at {rings},{segments} ({2 * segments * (rings - 2)} triangles), about {opt.memory_feathers} feathers, "
        f"incremental, {opt.memory_threads} thread(s), {opt.memory_frames} steps")
    args = ["--model-resolution", f"{rings},{segments}", "--feathers", str(opt.memory_feathers), "--frames", str(opt.memory_frames),
            "--mode", "incremental", "--threads", str(opt.memory_threads), "--validate", "none"]
    report, cmd = runner.run("memory", None, args)
    if report is None:
        out["memory"] = {"command": cmd, "failed": True}
        return "### Memory\n\nThe host run failed: " + cmd
    s = summarise(report)
    phases = report.get("memory", {})
    # Step k is the k-th call of plumage_system_step (frames[k - 1]).
    steps = [{"step": f["index"] + 1, **{k: f.get(k) for k in ("rss_kib", "peak_rss_kib", "heap_kib")}} for f in report["frames"]]
    n = len(steps)
    early = min(opt.memory_early, n)
    checkpoints = sorted({k for k in (1, 10, early, n) if 1 <= k <= n} | set(range(100, n + 1, 100)))
    rows = [("after load", phases.get("after_load", {})), ("after create", phases.get("after_create", {}))]
    rows += [(f"after step {k}", steps[k - 1]) for k in checkpoints]
    m = {
        "command": cmd,
        "model_resolution": [rings, segments],
        "vertices": report["vertices"],
        "triangles": report["triangles"],
        "feathers": report["feathers"],
        "threads": opt.memory_threads,
        "steps": n,
        "early_step": early,
        "create_seconds": s.get("create_seconds"),
        "frame_ms": s.get("frame_ms"),
        "process_wall_seconds": s["process_wall_seconds"],
        "process_cpu_over_wall": s["process_cpu_over_wall"],
        "after_load": phases.get("after_load"),
        "after_create": phases.get("after_create"),
        "after_steps": steps[-1] if steps else None,
        "per_step": steps,
    }
    if n and early:
        late = [x for x in steps if x["step"] >= early]
        for key in ("rss_kib", "heap_kib"):
            a, b = steps[early - 1].get(key), steps[-1].get(key)
            pts = [(x["step"], x[key]) for x in late if x.get(key) is not None]
            slope = fit_slope(pts)
            m[f"{key}_growth_early_to_last"] = b - a if a is not None and b is not None else None
            m[f"{key}_max_after_early_over_early"] = max(p[1] for p in pts) - a if pts and a is not None else None
            m[f"{key}_slope_per_100_steps"] = 100 * slope if slope is not None else None
    out["memory"] = m

    def kib(v):
        return "—" if v is None else f"{v:+,} KiB".replace(",", " ")

    body = [[label, mib(r.get("rss_kib")), mib(r.get("peak_rss_kib")), mib(r.get("heap_kib"))] for label, r in rows]
    text = [
        f"### Memory: built-in model {rings},{segments} ({fmt(report['triangles'])} triangles), {fmt(report['feathers'])} feathers, "
        f"incremental, {opt.memory_threads} thread(s), {n} steps, validation off",
        "",
        md_table(["point of the run", "RSS MiB", "peak RSS MiB", "live heap MiB"], body),
        "",
    ]
    if n and early:
        text += [
            md_table(
                [f"from step {early} to step {n}", "RSS", "live heap"],
                [
                    ["last minus early", kib(m["rss_kib_growth_early_to_last"]), kib(m["heap_kib_growth_early_to_last"])],
                    ["highest minus early", kib(m["rss_kib_max_after_early_over_early"]), kib(m["heap_kib_max_after_early_over_early"])],
                    ["least-squares slope per 100 steps", kib(None if m["rss_kib_slope_per_100_steps"] is None else round(m["rss_kib_slope_per_100_steps"])),
                     kib(None if m["heap_kib_slope_per_100_steps"] is None else round(m["heap_kib_slope_per_100_steps"]))],
                ],
            ),
            "",
        ]
    text.append(
        "Read in-process by the host after each phase and after every step: RSS and peak RSS are VmRSS and VmHWM of "
        "/proc/self/status (the whole process: library, host, the mesh and the report it keeps); live heap is glibc "
        "mallinfo2 (in-use arena bytes plus mmapped blocks), which the library's allocations go through too. "
        f"Create took {fmt(s.get('create_seconds'), 1)} s, a step {fmt(s.get('frame_ms'), 0)} ms on average "
        f"(frame 0 left out); the run took {fmt(s['process_wall_seconds'], 0)} s at CPU / wall {fmt(s['process_cpu_over_wall'], 2)}. "
        "The clip's wave repeats every second after the first half second, so the steps cycle through the same poses. "
        "The host keeps its report in memory, one JSON entry more per step, so the live heap of the process grows by "
        "that entry each step even when the library's does not."
    )
    return "\n".join(text)


# ---- main -------------------------------------------------------------------


def user_args():
    """The command-line arguments as the user gave them to bench.sh (without --host)."""
    args, skip = [], False
    for a in sys.argv[1:]:
        if skip:
            skip = False
        elif a == "--host":
            skip = True
        elif not a.startswith("--host="):
            args.append(a)
    return args


def int_list(text):
    return [int(x) for x in text.split(",") if x]


def resolution(text):
    rings, segments = int_list(text)
    return rings, segments


SECTIONS = {"table": section_table, "scaling": section_scaling, "threads": section_threads, "memory": section_memory}
RESULTS = ("table1", "scaling", "threads", "memory")  # keys of `out` written as <key>.json


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sections", nargs="*", metavar="section", help="table, scaling, threads or memory (default: table scaling threads)")
    p.add_argument("--host", default="build-bench/plumage_gltf", help="the plumage_gltf binary")
    p.add_argument("--data", default=os.environ.get("PLUMAGE_DATA_DIR", "../shared/data"), help="model directory (default $PLUMAGE_DATA_DIR, else ../shared/data)")
    p.add_argument("--out", default="out/bench", help="output directory (default out/bench)")
    p.add_argument("--feathers", type=int, default=10000, help="feathers per model in the table (default 10000)")
    p.add_argument("--frames", type=int, default=30, help="frames per clip in the table, at most (default 30)")
    p.add_argument("--fps", type=float, default=30.0, help="clip sampling rate passed to the host (default 30)")
    p.add_argument("--table-threads", type=int, default=1, help="threads for the table and scaling runs (default 1, as the paper)")
    p.add_argument("--scaling-feathers", type=int_list, default=[1000, 4000, 16000, 64000], help="comma-separated (default 1000,4000,16000,64000)")
    p.add_argument("--scaling-frames", type=int, default=10, help="frames of the scaling and threads runs (default 10)")
    p.add_argument("--threads-feathers", type=int_list, default=[10000, 16000], help="comma-separated (default 10000,16000)")
    p.add_argument("--memory-resolution", type=resolution, default=(502, 200),
                   help="RINGS,SEGMENTS of the built-in model in the memory run (default 502,200: 200 000 triangles)")
    p.add_argument("--memory-feathers", type=int, default=50000, help="feathers in the memory run (default 50000)")
    p.add_argument("--memory-frames", type=int, default=400, help="steps in the memory run (default 400: 0.8 to 1.3 s each on 2 shared cores)")
    p.add_argument("--memory-threads", type=int, default=2, help="threads of the memory run (default 2)")
    p.add_argument("--memory-early", type=int, default=100, help="the early step that memory growth is measured from (default 100)")
    opt = p.parse_args()
    sections = opt.sections or ["table", "scaling", "threads"]
    for name in sections:
        if name not in SECTIONS:
            p.error(f"unknown section {name!r} ({', '.join(SECTIONS)})")
    if not os.access(opt.host, os.X_OK):
        sys.exit(f"bench.py: {opt.host} is not an executable; run scripts/bench.sh, which builds it")

    out = {"machine": machine(), "host": opt.host, "data_dir": opt.data}
    runner = Runner(opt.host, opt.out, opt.fps)
    started = time.monotonic()
    texts = []
    for name in sections:
        texts.append(SECTIONS[name](opt, runner, out))
    out["machine"]["load_average_at_end"] = load_average()
    out["seconds"] = round(time.monotonic() - started, 1)

    m = out["machine"]
    head = (
        f"## Plumage benchmarks, {m['date']}\n\n"
        f"Machine: {m['cores']} cores, {m['cpu']}, Linux {m['kernel']}; load average {m['load_average_at_start']} at start, "
        f"{m['load_average_at_end']} at end (the machine is shared: compare figures of one run only). Commit {m['git']}. "
        f"Command: `./scripts/bench.sh{''.join(' ' + a for a in user_args())}`; "
        f"took {out['seconds']} s."
    )
    markdown = head + "\n\n" + "\n\n".join(texts) + "\n"
    print(markdown)

    os.makedirs(opt.out, exist_ok=True)
    for key in RESULTS:
        if key in out:
            with open(os.path.join(opt.out, key + ".json"), "w") as f:
                json.dump({"machine": out["machine"], key: out[key]}, f, indent=2)
                f.write("\n")
    with open(os.path.join(opt.out, "bench.md"), "w") as f:
        f.write(markdown)
    log(f"wrote {opt.out}/bench.md and {', '.join(k + '.json' for k in RESULTS if k in out)}")


if __name__ == "__main__":
    main()
