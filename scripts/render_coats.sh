#!/usr/bin/env bash
# Dresses the shared models (Flamingo, Fox, bird from ../shared/data) and the
# built-in model with the glTF host at host defaults, at rest and for a short
# clip, renders each coat with Blender (rest pose, and the clip's last stepped
# frame, from two sides), and measures how each coat lies with
# scripts/coat_figures.py. Everything goes to OUT_DIR:
#   MODEL_rest.glb/.json, MODEL_clip.glb/.json       host output and report
#   MODEL_rest_A_001.png, MODEL_clip_A_010.png ...   renders, A = view
#   coat_figures.txt, coat_figures.json              the figures
#
# usage: scripts/render_coats.sh OUT_DIR
# environment (defaults): FEATHERS=2000 FRAMES=10 RES=640,480 MODELS="Flamingo Fox Fox@8 bird builtin"
#   (NAME@S: the clip only, from S seconds into it, files NAME_sS_clip.*; the Fox's
#   first seconds barely move, it walks from about 8 s)
#   DATA=../shared/data (from the repo root)  BUILD=build  BLENDER=blender
#   RENDER_GLB=/work/shared/tools/render_glb.py  PYTHON=python3 (with numpy)
#   HOST_ARGS="" (more host options for every run, e.g. "--shaft-segments 4")
#   VIEWS="35,25 -145,25 35,25@2.2" (azimuth,elevation[@zoom] of each view; the
#   third is a close-up of the middle of the body)
# A model whose file is missing is reported and skipped (exit status 1 at the end).
set -euo pipefail
if [ $# -ne 1 ] || [ "${1#-}" != "$1" ]; then
  sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
repo="$(cd "$(dirname "$0")/.." && pwd)"
out="$(mkdir -p "$1" && cd "$1" && pwd)"
FEATHERS="${FEATHERS:-2000}"
FRAMES="${FRAMES:-10}"
RES="${RES:-640,480}"
MODELS="${MODELS:-Flamingo Fox Fox@8 bird builtin}"
DATA="${DATA:-$repo/../shared/data}"
BUILD="${BUILD:-$repo/build}"
BLENDER="${BLENDER:-blender}"
RENDER_GLB="${RENDER_GLB:-/work/shared/tools/render_glb.py}"
PYTHON="${PYTHON:-python3}"
VIEWS="${VIEWS:-35,25 -145,25 35,25@2.2}"

for tool in cmake "$BLENDER" "$PYTHON"; do
  command -v "$tool" >/dev/null || { echo "render_coats.sh: $tool not found" >&2; exit 2; }
done
[ -f "$RENDER_GLB" ] || { echo "render_coats.sh: $RENDER_GLB not found" >&2; exit 2; }
"$PYTHON" -c 'import numpy' 2>/dev/null || { echo "render_coats.sh: $PYTHON has no numpy (pip install numpy)" >&2; exit 2; }

# The host, in release unless the build directory is already configured.
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S "$repo/cpp_examples" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
if ! cmake --build "$BUILD" -j2 --target plumage_gltf >"$out/build.log" 2>&1; then
  cat "$out/build.log" >&2
  exit 2
fi
rm -f "$out/build.log"
host="$BUILD/plumage_gltf"

status=0
coats=()
for entry in $MODELS; do
  model="${entry%%@*}"
  name="$model"
  start=()
  kinds="rest clip"
  if [ "$entry" != "$model" ]; then
    name="${model}_s${entry#*@}"
    start=(--start "${entry#*@}")
    kinds=clip
  fi
  input=()
  if [ "$model" != builtin ]; then
    if [ ! -f "$DATA/$model.glb" ]; then
      echo "render_coats.sh: $DATA/$model.glb missing, $model skipped" >&2
      status=1
      continue
    fi
    input=("$DATA/$model.glb")
  fi
  for kind in $kinds; do
    frames=0
    [ "$kind" = clip ] && frames="$FRAMES"
    glb="$out/${name}_$kind.glb"
    # shellcheck disable=SC2086
    "$host" "${input[@]}" "${start[@]}" --feathers "$FEATHERS" --frames "$frames" ${HOST_ARGS:-} --out "$glb" --report "$out/${name}_$kind.json" 2>&1 | { grep -v '^plumage_gltf: wrote' || true; }
    coats+=("$glb")
    # Rest: Blender frame 1 (no animation). Clip: the importer puts clip time t
    # at Blender frame t * 24, so a frame past the last key shows the last
    # stepped frame (STEP keys hold).
    bframe=1
    [ "$kind" = clip ] && bframe=$((FRAMES * 24 / 30 + 2))
    view_no=0
    for view in $VIEWS; do
      view_no=$((view_no + 1))
      prefix="$out/${name}_${kind}_v$view_no"
      zoom=1
      [ "${view#*@}" != "$view" ] && zoom="${view#*@}"
      if ! "$BLENDER" -b --factory-startup --python "$RENDER_GLB" -- "$glb" "$prefix" "$bframe" --res "$RES" --view "${view%@*}" --zoom "$zoom" \
        >"$prefix.log" 2>&1 || ! grep -q '^wrote ' "$prefix.log"; then
        echo "render_coats.sh: render of $glb (view $view) failed, see $prefix.log" >&2
        status=1
        continue
      fi
      rm -f "$prefix.log"
      echo "rendered ${prefix}_$(printf %03d "$bframe").png (view $view)"
    done
  done
done

if [ ${#coats[@]} -gt 0 ]; then
  "$PYTHON" "$repo/scripts/coat_figures.py" --frames --json "$out/coat_figures.json" "${coats[@]}" | tee "$out/coat_figures.txt"
fi
exit $status
