#!/usr/bin/env bash
# The main job: builds the library and the C++ programs, then dresses the
# built-in animated model with the glTF host, writing out/plumage.glb and
# out/report.json. Extra arguments go to plumage_gltf, e.g.
#   ./scripts/run.sh ../shared/data/Fox.glb --frames 60 --feathers 800
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/ensure-deps.sh
cmake -S cpp_examples -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)"
mkdir -p out
./build/plumage_gltf --out out/plumage.glb --report out/report.json "$@"
echo "Open the .glb in any glTF viewer (its animation plays the feathers frame by frame); the report is JSON."
