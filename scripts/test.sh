#!/usr/bin/env bash
# Runs every test: the Rust tests (unit, integration, header drift) and clippy, then the
# C++ tests under ctest, in a normal build and in an ASan+UBSan build, and the
# installed library from a separate consumer project (scripts/consumer_test.sh,
# then from a library-only build: scripts/library_only_test.sh),
# and a short libFuzzer run over the host's glTF reader (scripts/fuzz_gltf.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
export PATH="$HOME/.cargo/bin:$PATH"

echo "== cargo test (release profile: the model tests are heavy)"
cargo test --release --all-targets

echo "== clippy: every target, warnings are errors"
cargo clippy --release --all-targets -- -D warnings

echo "== C++ build and ctest"
cmake -S cpp_examples -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure

echo "== install into a temporary prefix, then the separate consumer project against it"
scripts/consumer_test.sh build

echo "== the library alone: a library-only build (no tinygltf, no nlohmann-json) installed and consumed"
scripts/library_only_test.sh

echo "== Python package: pytest (venv in build/python-venv)"
py_env=build/python-venv
[ -x "$py_env/bin/python" ] || python3 -m venv "$py_env"
if ! "$py_env/bin/python" -c "import numpy, pytest, pxr, pygltflib" 2>/dev/null; then
  "$py_env/bin/python" -m pip install -q --disable-pip-version-check numpy pytest usd-core pygltflib
fi
"$py_env/bin/python" -m pip install -q --disable-pip-version-check ./python
py_status=0
PLUMAGE_GLTF_HOST="$PWD/build/plumage_gltf" "$py_env/bin/python" -m pytest -q python/tests || py_status=$?
if [ "$py_status" -ne 0 ]; then
  # 5 = pytest collected no test: a failure here, never a pass
  echo "error: pytest exited with $py_status" >&2
  exit "$py_status"
fi

echo "== glTF reader fuzzing (libFuzzer, ASan+UBSan), 20 s"
fuzz_status=0
scripts/fuzz_gltf.sh 20 || fuzz_status=$?
if [ "$fuzz_status" -eq 77 ]; then
  echo "SKIPPED (1): the glTF fuzz run: clang with libFuzzer is not installed"
elif [ "$fuzz_status" -ne 0 ]; then
  exit "$fuzz_status"
fi

echo "== C++ build and ctest under AddressSanitizer + UndefinedBehaviorSanitizer"
cmake -S cpp_examples -B build-sanitize -DCMAKE_BUILD_TYPE=Debug -DPLUMAGE_SANITIZE=ON -DPLUMAGE_TEST_HOOKS=ON >/dev/null
cmake --build build-sanitize -j"$(nproc)"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
  ctest --test-dir build-sanitize --output-on-failure
