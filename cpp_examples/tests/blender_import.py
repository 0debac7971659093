# Imports a host .glb with Blender's glTF importer (headless) and checks what
# a DCC user gets: the feathers mesh with all its vertices and the default
# feather material (alpha clipped, both sides, the 128x64 vane image), the
# body with its material, and no importer warning.
#   blender -b --factory-startup --python blender_import.py -- OUT.glb BODY_MATERIAL [textured]
import json
import struct
import sys

import numpy

if not hasattr(numpy, "bool"):
    numpy.bool = bool  # Debian's numpy against Blender 3.4's importer

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
path, body_material = argv[0], argv[1]
textured = "textured" in argv[2:]
with open(path, "rb") as f:
    data = f.read()
doc = json.loads(data[20 : 20 + struct.unpack("<I", data[12:16])[0]])
feather_mesh = next(m for m in doc["meshes"] if m["name"] == "feathers")
feather_vertices = doc["accessors"][feather_mesh["primitives"][0]["attributes"]["POSITION"]]["count"]
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)


class Warnings:
    # The importer reports through the operator; its warnings also go to stdout.
    def __init__(self):
        self.lines = []
        self.stdout = sys.stdout

    def write(self, text):
        self.lines.append(text)
        self.stdout.write(text)

    def flush(self):
        self.stdout.flush()


bpy.ops.wm.read_factory_settings(use_empty=True)
capture = Warnings()
sys.stdout = capture
result = bpy.ops.import_scene.gltf(filepath=path)
sys.stdout = capture.stdout
check(result == {"FINISHED"}, f"import: {result}")
check(not any("WARNING" in line.upper() for line in capture.lines), "importer warnings: " + "".join(capture.lines))

objects = {o.name: o for o in bpy.context.scene.objects if o.type == "MESH"}
check(set(objects) == {"body", "feathers"}, f"mesh objects {sorted(objects)}")
feathers, body = objects.get("feathers"), objects.get("body")
if feathers is not None:
    check(len(feathers.data.vertices) == feather_vertices, f"feather vertices {len(feathers.data.vertices)} != {feather_vertices}")
    mats = [m for m in feathers.data.materials if m is not None]
    check(len(mats) == 1 and mats[0].name == "feathers", f"feather materials {[m.name for m in mats]}")
    if mats:
        m = mats[0]
        check(m.blend_method == "CLIP" and not m.use_backface_culling, f"feathers: blend {m.blend_method}, culling {m.use_backface_culling}")
        images = [n.image for n in m.node_tree.nodes if n.type == "TEX_IMAGE" and n.image is not None]
        check(len(images) == 1 and tuple(images[0].size) == (128, 64), f"feather images {[tuple(i.size) for i in images]}")
    check("TEXCOORD_0" in feathers.data.uv_layers or len(feathers.data.uv_layers) == 1, "feathers have no UV layer")
if body is not None:
    mats = [m for m in body.data.materials if m is not None]
    check(len(mats) == 1 and mats[0].name == body_material, f"body materials {[m.name for m in mats]} (want {body_material})")
    if mats:
        images = [n for n in mats[0].node_tree.nodes if n.type == "TEX_IMAGE"]
        check((len(images) == 1) == textured and (len(body.data.uv_layers) == 1) == textured, f"body textured: {len(images)} images, {len(body.data.uv_layers)} UV layers")

print("blender_import:", "ok" if not failures else "FAILED")
for f in failures:
    print("  FAILED:", f)
sys.exit(1 if failures else 0)
