#!/bin/sh
# Runs the host on INPUT (or its built-in model) and imports its .glb with
# Blender's glTF importer, headless (blender_import.py checks it). Exit 77
# (skipped) when Blender or the input model is missing.
#   blender_import.sh HOST WORK_DIR INPUT|builtin BODY_MATERIAL [textured]
set -eu
host=$1 work=$2 input=$3 material=$4 textured=${5:-}
if ! command -v blender >/dev/null 2>&1; then
  echo "SKIP: blender is not installed (Debian: apt-get install blender)"
  exit 77
fi
if [ "$input" != builtin ] && [ ! -f "$input" ]; then
  echo "SKIP: $input is missing"
  exit 77
fi
mkdir -p "$work"
out="$work/$(basename "$input" .glb).glb"
if [ "$input" = builtin ]; then
  "$host" --frames 2 --out "$out"
else
  "$host" "$input" --frames 2 --out "$out"
fi
exec blender -b --factory-startup --python "$(dirname "$0")/blender_import.py" -- "$out" "$material" $textured
