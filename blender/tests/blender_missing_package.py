"""Run inside Blender (headless) by python/tests/test_blender.py without the
plumage package on Blender's path:
    blender -b --factory-startup --python-exit-code 1 --python blender_missing_package.py -- ADDON_ZIP
Installs and enables the add-on and tries to dress a cube. Prints one line
`PLUMAGE_RESULT {json}` with what the user is told."""

import json
import sys

import bpy

addon_zip = sys.argv[sys.argv.index("--") + 1]
bpy.ops.preferences.addon_install(filepath=addon_zip, overwrite=True)
bpy.ops.preferences.addon_enable(module="plumage_feathers")
import plumage_feathers  # noqa: E402

bpy.ops.mesh.primitive_cube_add()
try:
    bpy.ops.plumage.dress()
    told = ""
except RuntimeError as e:
    told = str(e)
print("PLUMAGE_RESULT " + json.dumps({"import_error": plumage_feathers.IMPORT_ERROR, "operator_error": told}))
