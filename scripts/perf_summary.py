#!/usr/bin/env python3
"""Summarises `perf script --no-inline -F tid,ip,sym` output (samples with
call stacks, leaf first) as Markdown: where a frame's time goes by phase
(inclusive), and the top functions by self time.

    perf script -i perf.data --no-inline -F tid,ip,sym | python3 scripts/perf_summary.py [--within SYMBOL]

With --within, only samples with SYMBOL on their stack are counted (e.g.
plumage::frame::step::step_coat for the frames alone).

Phases match symbols by prefix, so `sample_roots` also covers
`sample_roots_with_progress` (the library is built with line
tables, not frame pointers, so record with --call-graph dwarf). Inlined
functions count towards the function they were inlined into.
"""

import collections
import sys

# (label, symbol) in the order they are shown; a sample counts for every
# phase whose symbol is on its stack.
PHASES = [
    ("create: sampling (sample_roots)", "plumage::sampling::sample_roots"),
    ("create + rebuild frames: frame::solve", "plumage::frame::solve::solve"),
    ("frames: step_coat (incremental, legacy)", "plumage::frame::step::step_coat"),
    ("  pose_roots", "plumage::roots::pose_roots"),
    ("  contacts (Contacts::update)", "plumage::animation::contact::Contacts::update"),
    ("  R_k (surroundings_displacement)", "plumage::frame::step::surroundings_displacement"),
    ("  Neighbourhoods::rebuild", "plumage::ordering::neighbours::Neighbourhoods::rebuild"),
    ("  PriorityOrder::update_frame", "plumage::ordering::dynamic_order::<impl plumage::ordering::order_graph::PriorityOrder>::update_frame"),
    ("  PriorityOrder::build_static", "plumage::ordering::static_order::<impl plumage::ordering::order_graph::PriorityOrder>::build_static"),
    ("  BodyIndex::rebuild", "plumage::body::BodyIndex::rebuild"),
    ("  Adjuster::adjust_in_order", "plumage::adjustment::levels::Adjuster::adjust_in_order"),
    ("    adjust_feather", "plumage::adjustment::steps::adjust_feather"),
    ("      HeightField::rasterise", "plumage::adjustment::height_field::HeightField::rasterise"),
    ("      BodyIndex / TriangleGrid::query_box", "plumage::triangle_grid::TriangleGrid::query_box"),
    ("      min_pitch_slope (steps 1, 3)", "plumage::adjustment::steps::<impl plumage::adjustment::height_field::HeightField>::min_pitch_slope"),
    ("      settling_lateral_slope (step 2)", "plumage::adjustment::steps::<impl plumage::adjustment::height_field::HeightField>::settling_lateral_slope"),
    ("      combine_heights", "plumage::adjustment::steps::<impl plumage::adjustment::height_field::HeightField>::combine_heights"),
    ("Coat::export", "plumage::coat::Coat::export"),
    ("host: ProceduralBody::pose_at", "plumage_host::ProceduralBody::pose_at"),
]


def read_samples(stream):
    samples, cur = [], None
    for line in stream:
        if not line.strip():
            continue
        # A sample starts with its thread id alone on a line (perf pads
        # short ids with spaces); its frames follow, indented, as "ip sym".
        if line.strip().isdigit():
            cur = []
            samples.append(cur)
        elif cur is not None:
            parts = line.strip().split(None, 1)
            cur.append(parts[1] if len(parts) > 1 else "[unknown]")
    return [s for s in samples if s]


def indent(label):
    """Leading pairs of spaces become nesting marks (Markdown drops spaces)."""
    depth = (len(label) - len(label.lstrip(" "))) // 2
    return "· " * depth + label.strip()


def short(sym, width=100):
    return sym if len(sym) <= width else sym[: width - 1] + "…"


def main():
    within = None
    if len(sys.argv) == 3 and sys.argv[1] == "--within":
        within = sys.argv[2]
    elif len(sys.argv) != 1:
        sys.exit("usage: perf_summary.py [--within SYMBOL] < perf-script-output")
    samples = read_samples(sys.stdin)
    total = len(samples)
    if within:
        samples = [s for s in samples if any(f.startswith(within) for f in s)]
    n = len(samples)
    if n == 0:
        sys.exit("perf_summary.py: no samples" + (f" with {within} on the stack" if within else " on stdin"))
    print(f"{n} samples" + (f" of {total} (those within `{within}`)" if within else "") + "\n")
    print("| phase (inclusive) | % of samples |")
    print("|---|---:|")
    for label, sym in PHASES:
        k = sum(1 for s in samples if any(f.startswith(sym) for f in s))
        if k:
            print(f"| {indent(label)} | {100.0 * k / n:.1f} |")
    print()
    self_time = collections.Counter(s[0] for s in samples)
    print("| function (self time) | % of samples |")
    print("|---|---:|")
    for sym, k in self_time.most_common(15):
        print(f"| `{short(sym)}` | {100.0 * k / n:.1f} |")


if __name__ == "__main__":
    main()
