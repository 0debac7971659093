#!/usr/bin/env bash
# The engine example's figures (BENCHMARKS.md, "Issue #32: the engine
# example"): builds plumage_engine_example in a library-only Release build
# (build-engine/, no tinygltf needed), then runs it once per case, one after
# the other in this one invocation: each feather count (default 2000 and
# 10000) × the library's defaults and the kite × the whole limb moving and
# its near half held still, 120 frames each, validated after the last
# (untimed). Prints every command on stderr and a Markdown table of time and
# bytes per frame on stdout. Figures only: nothing fails on speed (a run
# fails only when the example does: its buffer missed a change).
#
#   ./scripts/engine_bench.sh                               # about 1.5 min on 2 shared cores
#   ./scripts/engine_bench.sh --feathers 2000 --frames 30   # smaller
set -euo pipefail
cd "$(dirname "$0")/.."

feathers="2000 10000"
frames=120
while [[ $# -gt 0 ]]; do
  case "$1" in
    --feathers) feathers="${2//,/ }"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    -h | --help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "engine_bench: unknown option $1 (--feathers N[,N...], --frames N)" >&2; exit 2 ;;
  esac
done

build="${PLUMAGE_ENGINE_BUILD_DIR:-build-engine}"
cmake -S cpp_examples -B "$build" -DCMAKE_BUILD_TYPE=Release -DPLUMAGE_LIBRARY_ONLY=ON >/dev/null
cmake --build "$build" --target plumage_engine_example >&2
exe="$build/plumage_engine_example"

# 1234567 -> "1 234 567", as BENCHMARKS.md writes counts.
group() { sed -e ':a' -e 's/\([0-9]\)\([0-9]\{3\}\)\($\|[^0-9]\)/\1 \2\3/' -e 'ta' <<<"$1"; }
field() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<"$2"; }

echo "Commit $(git rev-parse --short HEAD) ($(git status --porcelain --untracked-files=no | grep -q . && echo 'with local changes' || echo clean)), $(date -u +%Y-%m-%dT%H:%MZ), load average at the start $(cut -d' ' -f1-3 /proc/loadavg)."
echo "$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'), $(nproc) cores. The capsule: $("$exe" --frames 1 --feathers 100 | sed -n 's/^engine_example: capsule of \([0-9]*\) triangles, \([0-9]*\) vertices.*/\1 triangles, \2 vertices/p'); threads = 1, $frames frames at 60 fps."
echo
echo "| feathers | preset | moving | step ms, mean | step ms, p95 | readjusted / frame | listed / frame | records + changed list, bytes / frame | ranges / frame | every record, bytes | full geometry, bytes / frame | full geometry ÷ records + list | records pull + copy ms | geometry pull ms | CPU / wall | pairs, penetrations after the last frame |"
echo "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
for n in $feathers; do
  for preset in default kite; do
    for wave in whole far-half; do
      cmd=("$exe" --feathers "$n" --preset "$preset" --wave "$wave" --frames "$frames" --validate)
      echo "${cmd[*]}" >&2
      out="$("${cmd[@]}")"
      r="$(grep '^RESULT ' <<<"$out")"
      v="$(sed -n 's/.*: \([0-9]*\) intersecting pairs, \([0-9]*\) body penetrations.*/\1, \2/p' <<<"$out")"
      moving="whole limb"
      [[ "$wave" == far-half ]] && moving="far half"
      printf '| %s | %s | %s | %s | %s | %s (%s %%) | %s (%s %%) | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' \
        "$(group "$(field feathers "$r")")" "$preset" "$moving" "$(printf %.1f "$(field step_ms_mean "$r")")" "$(printf %.1f "$(field step_ms_p95 "$r")")" \
        "$(field adjusted_mean "$r")" "$(awk -v a="$(field adjusted_mean "$r")" -v n="$(field feathers "$r")" 'BEGIN { printf "%.1f", 100 * a / n }')" \
        "$(field listed_mean "$r")" "$(field listed_percent "$r")" \
        "$(group "$(field record_bytes_mean "$r")")" "$(field ranges_mean "$r")" "$(group "$(field all_records_bytes "$r")")" \
        "$(group "$(field geometry_bytes "$r")")" "$(printf %.1f "$(field ratio "$r")")" \
        "$(printf %.2f "$(field pull_ms_mean "$r")")" "$(printf %.2f "$(field geometry_ms_mean "$r")")" "$(field cpu_per_wall "$r")" "$v"
    done
  done
done
echo
echo "Load average at the end $(cut -d' ' -f1-3 /proc/loadavg)."
