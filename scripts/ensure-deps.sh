#!/usr/bin/env bash
# Makes sure the build tools are present: cargo (must already be installed),
# cmake, g++, pkg-config, Debian's libtinygltf-dev (and glslang-tools,
# clang, chromium, nodejs and npm when it can). Installs the missing
# Debian packages when run as root with apt-get; otherwise stops and prints
# the exact command to run.
set -euo pipefail

export PATH="$HOME/.cargo/bin:$PATH"
if ! command -v cargo >/dev/null 2>&1; then
  echo "error: cargo is not installed. Install the Rust toolchain (rustup, stable >= 1.85) and run again." >&2
  exit 1
fi

# Clippy lints every target in the test command: added with rustup when
# the toolchain lacks it.
if ! cargo clippy --version >/dev/null 2>&1; then
  if command -v rustup >/dev/null 2>&1; then
    rustup component add clippy
  else
    echo "error: cargo clippy is missing and rustup is not there to add it: install clippy for your toolchain." >&2
    exit 1
  fi
fi

missing=()
command -v cmake >/dev/null 2>&1 || missing+=(cmake)
command -v g++ >/dev/null 2>&1 || missing+=(g++)
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
[ -f /usr/include/tiny_gltf.h ] || missing+=(libtinygltf-dev)
[ -f /usr/include/nlohmann/json.hpp ] || missing+=(nlohmann-json3-dev)
# The Python package's tests run in a venv (scripts/test.sh).
command -v python3 >/dev/null 2>&1 || missing+=(python3)
if command -v python3 >/dev/null 2>&1; then
  venv_probe=$(mktemp -d)
  python3 -m venv "$venv_probe/v" >/dev/null 2>&1 || missing+=(python3-venv)
  rm -rf "$venv_probe"
fi

# Optional tools, installed when this runs as root with apt-get and skipped
# (each test that needs one is then a counted skip) when they cannot be:
# clang with libFuzzer runs the glTF reader's fuzz target (scripts/fuzz_gltf.sh);
# glslangValidator compiles the reference shader (ctest shader_compiles);
# headless Chromium, node and npm run the render test (scripts/render_test.sh).
optional=()
command -v clang++ >/dev/null 2>&1 || optional+=(clang)
command -v glslangValidator >/dev/null 2>&1 || optional+=(glslang-tools)
command -v node >/dev/null 2>&1 || optional+=(nodejs)
command -v npm >/dev/null 2>&1 || optional+=(npm)
command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || optional+=(chromium)

if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing: ${missing[*]}" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq "${missing[@]}" >/dev/null
  else
    echo "error: missing ${missing[*]}. Run:" >&2
    echo "  sudo apt-get update && sudo apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
fi

if [ ${#optional[@]} -gt 0 ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "installing (optional): ${optional[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  [ ${#missing[@]} -gt 0 ] || apt-get update -qq >/dev/null 2>&1 || true
  if ! apt-get install -y -qq "${optional[@]}" >/dev/null 2>&1; then
    echo "warning: could not install ${optional[*]}; the tests that need them report themselves skipped" >&2
  fi
fi
