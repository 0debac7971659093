#!/usr/bin/env bash
# Profiles one host run with perf (software cpu-clock sampling with DWARF
# call stacks: works without hardware counters, e.g. in a VM) and prints
# where the time goes as Markdown (scripts/perf_summary.py): the whole run,
# then the frames alone (step_coat). Uses the host
# built by scripts/bench.sh. Arguments go to plumage_gltf; the default is
# the built-in model, 10 000 feathers, 15 incremental frames on one thread.
#
#   ./scripts/profile.sh
#   ./scripts/profile.sh ../shared/data/Fox.glb --feathers 10000 --frames 15 --mode legacy --threads 1
set -euo pipefail
cd "$(dirname "$0")/.."
host="${PLUMAGE_BENCH_BUILD_DIR:-build-bench}/plumage_gltf"
[ -x "$host" ] || { echo "profile.sh: $host missing; run scripts/bench.sh first (it builds it)" >&2; exit 1; }
command -v perf >/dev/null || { echo "profile.sh: perf is not installed (apt-get install linux-perf)" >&2; exit 1; }
[ $# -gt 0 ] || set -- --feathers 10000 --frames 15 --mode incremental --threads 1
mkdir -p out/profile
data=out/profile/perf.data
perf record -q -e cpu-clock -F 499 --call-graph dwarf,16384 -o "$data" -- "$host" "$@" --validate none >&2
perf script -i "$data" --no-inline -F tid,ip,sym 2>/dev/null > out/profile/perf.txt
python3 scripts/perf_summary.py < out/profile/perf.txt
# The frames alone (nothing when no frame was stepped).
if grep -q "plumage::frame::step::step_coat" out/profile/perf.txt; then
  echo
  python3 scripts/perf_summary.py --within plumage::frame::step::step_coat < out/profile/perf.txt
fi
