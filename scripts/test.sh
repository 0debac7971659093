#!/usr/bin/env bash
# Runs every test: the Rust tests (unit, integration, header drift), then the
# C++ tests under ctest, in a normal build and in an ASan+UBSan build, and the
# installed library from a separate consumer project (scripts/consumer_test.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
export PATH="$HOME/.cargo/bin:$PATH"

echo "== cargo test (release profile: the model tests are heavy)"
cargo test --release --all-targets

echo "== C++ build and ctest"
cmake -S cpp_examples -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure

echo "== install into a temporary prefix, then the separate consumer project against it"
scripts/consumer_test.sh build

echo "== C++ build and ctest under AddressSanitizer + UndefinedBehaviorSanitizer"
cmake -S cpp_examples -B build-sanitize -DCMAKE_BUILD_TYPE=Debug -DPLUMAGE_SANITIZE=ON -DPLUMAGE_TEST_HOOKS=ON >/dev/null
cmake --build build-sanitize -j"$(nproc)"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
  ctest --test-dir build-sanitize --output-on-failure
