#!/bin/sh
# The render test (ctest render_viewer): the host writes --instances output
# for the built-in swimmer and for a tube whose front half holds still
# (viewer/test/tube_glb.mjs), then viewer/test/render_test.mjs draws it in
# headless Chromium through viewer/ (three.js, the reference shader on an
# InstancedMesh) and checks it: records against the copied-out geometry,
# the changed-feather list against full uploads, the shader port.
#   scripts/render_test.sh HOST WORK_DIR
# Exit 77 (skipped) when Chromium, node or npm is missing or the npm
# packages cannot be installed; PLUMAGE_CHROMIUM names another browser.
set -eu
host=$1 work=$2
repo=$(cd "$(dirname "$0")/.." && pwd)
viewer="$repo/viewer"

skip() {
  echo "SKIPPED: render test: $*"
  exit 77
}

command -v node >/dev/null 2>&1 || skip "node is not installed (Debian: apt-get install nodejs npm)"
command -v npm >/dev/null 2>&1 || skip "npm is not installed (Debian: apt-get install npm)"
node -e 'process.exit(Number(process.versions.node.split(".")[0]) >= 18 ? 0 : 1)' ||
  skip "node $(node --version) is older than 18, which puppeteer-core needs"
chromium=${PLUMAGE_CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}
[ -n "$chromium" ] && [ -x "$chromium" ] || skip "chromium is not installed (Debian: apt-get install chromium)"

# three and puppeteer-core at the versions viewer/package.json names, in
# viewer/node_modules (git-ignored).
have_packages() {
  (cd "$viewer" && node -e '
    const fs = require("fs");
    const p = JSON.parse(fs.readFileSync("package.json", "utf8"));
    const want = { ...p.dependencies, ...p.devDependencies };
    for (const [name, version] of Object.entries(want)) {
      const file = `node_modules/${name}/package.json`;
      if (!fs.existsSync(file) || JSON.parse(fs.readFileSync(file, "utf8")).version !== version) process.exit(1);
    }')
}
if ! have_packages; then
  echo "render test: installing three and puppeteer-core into viewer/node_modules (npm install)"
  mkdir -p "$work"
  if ! (cd "$viewer" && npm install --no-package-lock --no-audit --no-fund >"$work/npm-install.log" 2>&1) || ! have_packages; then
    grep -m 1 "error code" "$work/npm-install.log" | sed 's/^/  /' || true
    skip "npm install in viewer/ failed (is the npm registry reachable?); log in $work/npm-install.log"
  fi
fi

rm -rf "$work/builtin" "$work/tube"
mkdir -p "$work"
"$host" --feathers 1500 --frames 3 --threads 1 --validate none --instances "$work/builtin"
node "$viewer/test/tube_glb.mjs" "$work/tube.glb"
"$host" "$work/tube.glb" --feathers 800 --frames 4 --threads 1 --validate none --instances "$work/tube"
exec node "$viewer/test/render_test.mjs" --chromium "$chromium" --work "$work" --compare builtin builtin tube
