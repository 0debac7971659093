#!/usr/bin/env bash
# Fuzzes the host's glTF reader (cpp_examples/fuzz/gltf_fuzz.cpp) with
# clang's libFuzzer under AddressSanitizer and UndefinedBehaviorSanitizer.
#
#   scripts/fuzz_gltf.sh              # 30 s (what scripts/test.sh runs, with 20)
#   scripts/fuzz_gltf.sh 3600         # an hour
#   scripts/fuzz_gltf.sh --runs 1000000
#   PLUMAGE_FUZZ_MODELS=1 scripts/fuzz_gltf.sh 600   # also mutate the animated test models
#
# Builds build-fuzz/gltf_fuzzer (tinygltf compiled in, so its parser is
# instrumented too), then fuzzes a working corpus in build-fuzz/corpus
# seeded from cpp_examples/fuzz/corpus and cpp_examples/fuzz/regressions.
# With PLUMAGE_FUZZ_MODELS=1 the working corpus is build-fuzz/corpus-models,
# seeded also with the test models (../shared/data or $PLUMAGE_DATA_DIR, read
# at run time, never copied into the repository), inputs up to 1 MiB.
# A crash, sanitizer report, leak, timeout (10 s an input) or allocation
# beyond 2 GB stops the run with its input saved as
# build-fuzz/crashes/crash-*: fix the bug, then keep the input in
# cpp_examples/fuzz/regressions/ (ctest gltf_fuzz_replay runs it).
# Prints the inputs run; exits 77 (a skip) when clang's libFuzzer is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=30
runs=-1
case "${1:-}" in
  --runs) runs="${2:?--runs needs a count}"; seconds=0 ;;
  "") ;;
  *) seconds="$1" ;;
esac

out=build-fuzz
fuzzer="$out/gltf_fuzzer"
cxx="${CLANGXX:-clang++}"
if ! command -v "$cxx" >/dev/null 2>&1; then
  echo "SKIP gltf fuzz: $cxx not found (apt-get install clang)" >&2
  exit 77
fi
mkdir -p "$out/obj" "$out/corpus" "$out/crashes"
flags=(-std=c++17 -g -O1 -DTINYGLTF_NO_STB_IMAGE -DTINYGLTF_NO_STB_IMAGE_WRITE
       -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
       -Icpp_examples/gltf_host)
sources=(cpp_examples/fuzz/gltf_fuzz.cpp cpp_examples/fuzz/tinygltf_impl.cpp
         cpp_examples/gltf_host/gltf_loader.cpp cpp_examples/gltf_host/gltf_scene.cpp
         cpp_examples/gltf_host/accessor.cpp cpp_examples/gltf_host/animation.cpp)
# Rebuild each object only when its source (or a host header) changed.
objects=()
for src in "${sources[@]}"; do
  obj="$out/obj/$(basename "${src%.cpp}").o"
  objects+=("$obj")
  if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ -n "$(find cpp_examples/gltf_host -name '*.h' -newer "$obj" | head -1)" ]; then
    if ! "$cxx" "${flags[@]}" -c "$src" -o "$obj" 2>"$out/build.log"; then
      if grep -q "fuzzer" "$out/build.log" && ! grep -q "error: .*\.cpp" "$out/build.log"; then
        cat "$out/build.log" >&2
        echo "SKIP gltf fuzz: $cxx cannot build with -fsanitize=fuzzer" >&2
        exit 77
      fi
      cat "$out/build.log" >&2
      exit 1
    fi
  fi
done
if ! "$cxx" "${flags[@]}" "${objects[@]}" -o "$fuzzer" 2>"$out/build.log"; then
  cat "$out/build.log" >&2
  if grep -q "libclang_rt.fuzzer\|fuzzer" "$out/build.log"; then
    echo "SKIP gltf fuzz: the libFuzzer runtime is missing (apt-get install clang)" >&2
    exit 77
  fi
  exit 1
fi

corpus="$out/corpus"
max_len=65536
seeds=(cpp_examples/fuzz/corpus/* cpp_examples/fuzz/regressions/*)
if [ "${PLUMAGE_FUZZ_MODELS:-0}" = 1 ]; then
  corpus="$out/corpus-models"
  max_len=1048576
  data="${PLUMAGE_DATA_DIR:-../shared/data}"
  compgen -G "$data/*.glb" >/dev/null || { echo "gltf fuzz: PLUMAGE_FUZZ_MODELS=1 but no .glb in $data" >&2; exit 1; }
  seeds+=("$data"/*.glb)
fi
mkdir -p "$corpus"
# Seed the working corpus (files already there are kept as they are).
for seed in "${seeds[@]}"; do
  [ -f "$seed" ] && [ ! -e "$corpus/$(basename "$seed")" ] && cp "$seed" "$corpus/"
done
log="$out/last_run.log"
status=0
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 "$fuzzer" \
  -dict=cpp_examples/fuzz/gltf.dict -max_total_time="$seconds" -runs="$runs" \
  -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len="$max_len" \
  -artifact_prefix="$out/crashes/" -print_final_stats=1 "$corpus" >"$log" 2>&1 || status=$?
ran=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
if [ "$status" -ne 0 ]; then
  tail -60 "$log" >&2
  echo "gltf fuzz: FAILED after ${ran:-?} inputs; the input is in $out/crashes/ (full log $log)" >&2
  exit 1
fi
echo "gltf fuzz: ${ran:-?} inputs, no crash, no sanitizer report ($(ls "$corpus" | wc -l) in the working corpus; log $log)"
