#!/usr/bin/env bash
# The library as an installed system library (README, "Installing"):
# installs the CMake build BUILD_DIR (default build, already built) into a
# fresh temporary prefix, checks the files and the SONAME, then configures,
# builds and runs the separate consumer project cpp_examples/consumer
# against that prefix (find_package and pkg-config) and checks that its
# programs load the installed library. Run by scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"

cmake --install "$build" --prefix "$prefix" >/dev/null
version="$(sed -n 's/^version = "\([0-9]*\.[0-9]*\.[0-9]*\)"$/\1/p' Cargo.toml | head -n1)"
major="${version%%.*}"
lib="$prefix/lib"
fail() { echo "consumer_test: $*" >&2; exit 1; }

for f in "$lib/libplumage.so.$version" "$lib/libplumage.a" "$prefix/include/plumage.h" "$prefix/include/plumage.hpp" \
         "$lib/cmake/Plumage/PlumageConfig.cmake" "$lib/cmake/Plumage/PlumageConfigVersion.cmake" "$lib/pkgconfig/plumage.pc"; do
  [[ -f "$f" && ! -L "$f" ]] || fail "missing or not a regular file: ${f#"$prefix"/}"
done
[[ "$(readlink "$lib/libplumage.so.$major")" == "libplumage.so.$version" ]] || fail "libplumage.so.$major is not a link to libplumage.so.$version"
[[ "$(readlink "$lib/libplumage.so")" == "libplumage.so.$major" ]] || fail "libplumage.so is not a link to libplumage.so.$major"
soname="$(readelf -d "$lib/libplumage.so.$version" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')"
[[ "$soname" == "libplumage.so.$major" ]] || fail "SONAME is '$soname', wanted libplumage.so.$major"
echo "consumer_test: installed plumage $version into a temporary prefix, SONAME $soname"

PKG_CONFIG_PATH="$lib/pkgconfig" cmake -S cpp_examples/consumer -B "$work/build" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$work/build" -j"$(nproc)" >/dev/null

# The shared programs load the installed copy through its SONAME; the static one loads none.
for exe in consumer_cxx consumer_c99_pkgconfig; do
  readelf -d "$work/build/$exe" | grep -q "NEEDED.*\[libplumage.so.$major\]" || fail "$exe does not need libplumage.so.$major"
  loaded="$(ldd "$work/build/$exe" | sed -n 's/.*libplumage\.so[^ ]* => \([^ ]*\) .*/\1/p')"
  [[ "$(realpath "$loaded")" == "$(realpath "$lib/libplumage.so.$version")" ]] || fail "$exe loads '$loaded', not the installed library"
done
if readelf -d "$work/build/consumer_c99_static" | grep -q "NEEDED.*libplumage"; then
  fail "consumer_c99_static needs libplumage.so"
fi
ctest --test-dir "$work/build" --output-on-failure
