#!/usr/bin/env bash
# Benchmarks (issue 8): builds the glTF host in release and runs it over the
# shared models and the built-in model, then prints Markdown tables (the
# paper's Table 1, scaling in feather count, 1 vs 2 threads, and on request
# the memory of a 200 000-triangle, 50 000-feather run) and writes them as
# JSON under out/bench/. Figures only: nothing here fails on speed.
#
#   ./scripts/bench.sh                    # table, scaling, threads
#   ./scripts/bench.sh table              # one section (table | scaling | threads | memory)
#   ./scripts/bench.sh memory             # peak RSS and growth over 400 steps (6 to 10 min)
#   ./scripts/bench.sh --frames 60 table  # options: ./scripts/bench.sh --help
#
# Models come from $PLUMAGE_DATA_DIR, else ../shared/data; missing ones are
# named and skipped. Set CARGO_TARGET_DIR to share a cargo target directory.
# Criterion micro-benchmarks of the kernels are separate: `cargo bench`.
set -euo pipefail
cd "$(dirname "$0")/.."

case " $* " in
  *" --help "* | *" -h "*) exec python3 scripts/bench.py --help ;;
esac

scripts/ensure-deps.sh
build="${PLUMAGE_BENCH_BUILD_DIR:-build-bench}"
# The library is always built by cargo --release (see cpp_examples/cmake);
# Release here is for the C++ host.
cmake -S cpp_examples -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target plumage_gltf >&2
exec python3 scripts/bench.py --host "$build/plumage_gltf" "$@"
