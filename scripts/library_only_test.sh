#!/usr/bin/env bash
# The library installed alone (README, "Installing"), as an engine team
# would, on a machine without tinygltf and nlohmann-json:
#  1. configures cpp_examples in a temporary directory with both hidden
#     from find_package (CMAKE_DISABLE_FIND_PACKAGE_*) and no tests: the
#     automatic library-only fallback must say so, and the build must have
#     no target but the library's; builds it;
#  2. installs that build into a temporary prefix, checks the files and the
#     SONAME, and builds and runs the consumer project against it with
#     find_package and pkg-config (scripts/consumer_test.sh);
#  3. configures -DPLUMAGE_LIBRARY_ONLY=ON with the tests: no glTF host, no
#     test of it, but the library's own tests and the engine example.
# Run by scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fail() { echo "library_only_test: $*" >&2; exit 1; }

# Every target of a Makefile build tree but CMake's own.
targets() {
  cmake --build "$1" --target help | sed -n 's/^\.\.\. \([^ ]*\).*/\1/p' |
    grep -v -x -e all -e clean -e depend -e edit_cache -e rebuild_cache -e test \
      -e install -e install/local -e install/strip -e list_install_components | sort | tr '\n' ' '
}

lib="$work/library"
if ! cmake -S cpp_examples -B "$lib" -G "Unix Makefiles" -DCMAKE_BUILD_TYPE=Release -DPLUMAGE_BUILD_TESTS=OFF \
     -DCMAKE_DISABLE_FIND_PACKAGE_TinyGLTF=ON -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON >"$work/configure.log" 2>&1; then
  cat "$work/configure.log" >&2
  fail "the library-only configure failed"
fi
grep -q "not found: building the library only" "$work/configure.log" ||
  fail "no library-only warning without tinygltf and nlohmann-json"
[[ "$(targets "$lib")" == "plumage_cargo " ]] || fail "the library-only build has targets: $(targets "$lib")"
cmake --build "$lib" >/dev/null
echo "library_only_test: configured without tinygltf and nlohmann-json (the fallback warned) and built: only the library"

scripts/consumer_test.sh "$lib"
# What was installed, and nothing else (cmake --install writes the manifest into the build).
version="$(sed -n 's/^version = "\([0-9]*\.[0-9]*\.[0-9]*\)"$/\1/p' Cargo.toml | head -n1)"
installed="$(sed 's|.*/prefix/||' "$lib/install_manifest.txt" | LC_ALL=C sort | tr '\n' ' ')"
wanted="include/plumage.h include/plumage.hpp lib/cmake/Plumage/PlumageConfig.cmake lib/cmake/Plumage/PlumageConfigVersion.cmake "
wanted+="lib/libplumage.a lib/libplumage.so lib/libplumage.so.${version%%.*} lib/libplumage.so.$version lib/pkgconfig/plumage.pc "
[[ "$installed" == "$wanted" ]] || fail "installed: $installed; wanted: $wanted"
echo "library_only_test: installed the nine files of the library and nothing else"

with_tests="$work/library-tests"
cmake -S cpp_examples -B "$with_tests" -G "Unix Makefiles" -DPLUMAGE_LIBRARY_ONLY=ON >"$work/configure-tests.log" 2>&1 ||
  { cat "$work/configure-tests.log" >&2; fail "the -DPLUMAGE_LIBRARY_ONLY=ON configure failed"; }
if grep -q "not found" "$work/configure-tests.log"; then
  fail "-DPLUMAGE_LIBRARY_ONLY=ON still looked for the glTF host's packages"
fi
tests="$(ctest --test-dir "$with_tests" -N 2>/dev/null | sed -n 's/^ *Test *#[0-9]*: //p')"
for t in smoke reliability threads instancing engine_example; do
  grep -q -x "$t" <<<"$tests" || fail "-DPLUMAGE_LIBRARY_ONLY=ON has no test $t"
done
if grep -E -x 'host_.*|eval_.*|output_.*|blender_.*|gltf_fuzz_replay' <<<"$tests"; then
  fail "-DPLUMAGE_LIBRARY_ONLY=ON registers the glTF host's tests above"
fi
if grep -q -w -e plumage_gltf -e plumage_gltf_scene <<<"$(targets "$with_tests")"; then
  fail "-DPLUMAGE_LIBRARY_ONLY=ON has glTF host targets"
fi
echo "library_only_test: -DPLUMAGE_LIBRARY_ONLY=ON: $(wc -l <<<"$tests") tests (the engine example's included), none of the glTF host's"
