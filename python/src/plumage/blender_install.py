"""`python -m plumage.blender_install [--blender PATH] [--target DIR] [--addon DIR [--enable]]`:
puts this package, with the library it carries, where Blender's own Python
finds it.

Run it with the Python where `pip install ./python` installed the package.
It asks Blender (``--blender``, else $PLUMAGE_BLENDER, else ``blender`` on
PATH) for its user modules folder (``bpy.utils.user_resource('SCRIPTS',
path='modules')``, which honours BLENDER_USER_SCRIPTS), copies the package
there (replacing an older copy), then starts Blender again to check that
``import plumage`` works in it and that numpy is there (Blender ships it).
``--target`` copies to another folder instead (checked only when it is a
``modules`` folder Blender can be pointed at). ``--addon DIR`` also copies
the add-on folder (``blender/plumage_feathers`` of the repository) to the
user add-ons folder; with ``--enable`` it is also enabled (in a Blender
started for it: ``bpy.ops.preferences.addon_enable`` then
``bpy.ops.wm.save_userpref``, so the user's preferences keep it on),
otherwise enable it in Edit > Preferences > Add-ons.
Exit status 0 when Blender imports the package (and, with ``--enable``, the
add-on is on in a new Blender), 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Dict, List, Optional

from ._ffi import library_path

PROBE = r"""
import json, sys
import bpy
out = {"version": bpy.app.version_string, "python": sys.version.split()[0],
       "modules": bpy.utils.user_resource('SCRIPTS', path='modules'),
       "addons": bpy.utils.user_resource('SCRIPTS', path='addons')}
try:
    import numpy
    out["numpy"] = numpy.__version__
except ImportError as e:
    out["numpy"] = None
try:
    import plumage
    out["plumage"] = plumage.version()
    out["plumage_file"] = plumage.__file__
except Exception as e:
    out["plumage"] = None
    out["plumage_error"] = f"{type(e).__name__}: {e}"
out["addons_enabled"] = sorted(a.module for a in bpy.context.preferences.addons)
print("PLUMAGE_PROBE " + json.dumps(out))
"""

# Enables add-on MODULE and saves the preferences (run in the Blender the user starts, not --factory-startup)
ENABLE = r"""
import json, sys
import bpy
module = sys.argv[sys.argv.index("--") + 1]
out = {}
try:
    bpy.ops.preferences.addon_enable(module=module)
    bpy.ops.wm.save_userpref()
    out["enabled"] = module in {a.module for a in bpy.context.preferences.addons}
except Exception as e:
    out["enabled"] = False
    out["error"] = f"{type(e).__name__}: {e}"
print("PLUMAGE_ENABLE " + json.dumps(out))
"""


def find_blender(explicit: Optional[str]) -> str:
    candidates: List[Optional[str]] = [explicit, os.environ.get("PLUMAGE_BLENDER"), shutil.which("blender")]
    if sys.platform == "darwin":
        candidates.append("/Applications/Blender.app/Contents/MacOS/Blender")
    for c in candidates:
        if c and (Path(c).is_file() or shutil.which(c)):
            return c
    raise SystemExit("Blender not found: pass --blender PATH (or set PLUMAGE_BLENDER)")


def probe(blender: str, env: Optional[Dict[str, str]] = None, factory: bool = False) -> Dict[str, object]:
    """What Blender says about its folders, its Python, numpy and plumage."""
    cmd = [blender, "-b"] + (["--factory-startup"] if factory else []) + ["--python-exit-code", "1", "--python-expr", PROBE]
    run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=300)
    for line in run.stdout.splitlines():
        if line.startswith("PLUMAGE_PROBE "):
            found: Dict[str, object] = json.loads(line[len("PLUMAGE_PROBE "):])
            return found
    raise SystemExit(f"{blender} did not answer (exit {run.returncode}):\n{run.stdout[-2000:]}")


def enable_addon(blender: str, module: str, env: Optional[Dict[str, str]] = None) -> Dict[str, object]:
    """Enables the add-on in Blender's preferences and saves them."""
    cmd = [blender, "-b", "--python-exit-code", "1", "--python-expr", ENABLE, "--", module]
    run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=300)
    for line in run.stdout.splitlines():
        if line.startswith("PLUMAGE_ENABLE "):
            found: Dict[str, object] = json.loads(line[len("PLUMAGE_ENABLE "):])
            if not found.get("enabled") and "error" not in found:
                found["error"] = run.stdout[-2000:]
            return found
    return {"enabled": False, "error": f"{blender} did not answer (exit {run.returncode}):\n{run.stdout[-2000:]}"}


def install(target: Path) -> Path:
    """Copies this package (with its library) into `target`/plumage."""
    package = Path(__file__).resolve().parent
    lib = library_path()
    if not lib.is_file():
        raise SystemExit(f"the library is not at {lib}: pip install ./python first")
    dest = target / "plumage"
    if dest.resolve() == package:
        return dest
    target.mkdir(parents=True, exist_ok=True)
    tmp = target / ".plumage.installing"
    shutil.rmtree(tmp, ignore_errors=True)
    shutil.copytree(package, tmp, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    if lib.parent.resolve() != package:  # $PLUMAGE_LIBRARY: ship that one
        shutil.copy2(lib, tmp / lib.name)
    shutil.rmtree(dest, ignore_errors=True)
    tmp.rename(dest)
    return dest


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m plumage.blender_install", description=__doc__.split("\n\n")[0])
    parser.add_argument("--blender", help="the Blender program (default: $PLUMAGE_BLENDER, then blender on PATH)")
    parser.add_argument("--target", help="copy into this folder instead of Blender's user modules folder")
    parser.add_argument("--addon", help="also copy this add-on folder (the repository's blender/plumage_feathers) to Blender's user add-ons")
    parser.add_argument("--enable", action="store_true", help="with --addon: also enable it and save Blender's preferences")
    args = parser.parse_args(argv)
    if args.enable and not args.addon:
        parser.error("--enable enables the add-on --addon installs: give --addon DIR too")

    blender = find_blender(args.blender)
    info = probe(blender)
    print(f"Blender {info['version']} (Python {info['python']}, numpy {info['numpy'] or 'MISSING'})")
    target = Path(args.target) if args.target else Path(str(info["modules"]))
    dest = install(target)
    print(f"installed the package in {dest}")
    if args.addon:
        src = Path(args.addon)
        if not (src / "__init__.py").is_file():
            raise SystemExit(f"{src} is not an add-on folder (no __init__.py)")
        addons = Path(str(info["addons"]))
        shutil.rmtree(addons / src.name, ignore_errors=True)
        shutil.copytree(src, addons / src.name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        print(f"installed the add-on in {addons / src.name}" + ("" if args.enable else ": enable it in Edit > Preferences > Add-ons (or pass --enable)"))
        if args.enable:
            enabled = enable_addon(blender, src.name)
            if not enabled.get("enabled"):
                print(f"Blender did not enable the add-on {src.name}: {enabled.get('error')}", file=sys.stderr)
                return 1
            print(f"enabled the add-on {src.name} (saved in Blender's preferences)")

    # the check: Blender as the user starts it imports the package
    env = dict(os.environ)
    if args.target:
        if target.name != "modules":
            print(f"not checked: Blender looks in a scripts folder's 'modules'; point BLENDER_USER_SCRIPTS at {target.parent} if it is one")
            return 0
        env["BLENDER_USER_SCRIPTS"] = str(target.parent)
    after = probe(blender, env)
    if not after.get("plumage"):
        print(f"Blender cannot import it: {after.get('plumage_error')}", file=sys.stderr)
        return 1
    print(f"Blender imports plumage {after['plumage']} from {after['plumage_file']}")
    if not after.get("numpy"):
        print("Blender's Python has no numpy: the add-on needs it", file=sys.stderr)
        return 1
    if args.enable and str(Path(args.addon).name) not in (after.get("addons_enabled") or []):
        print(f"the add-on {Path(args.addon).name} is not on in a new Blender: were the preferences saved?", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
