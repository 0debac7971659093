#!/usr/bin/env bash
# The main job: builds the library and the C++ programs, then runs them.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cmake -S cpp_examples -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)"
./build/plumage_smoke "$@"
