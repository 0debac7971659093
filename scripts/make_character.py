#!/usr/bin/env python3
"""Writes a skinned, walking test character as .glb: a standing figure (+Y up,
facing +Z) made of capsules (torso, head, upper and lower arms and legs),
skinned to 16 joints (each capsule rigid to its bone, blended into the
neighbouring joint near its ends), with a one-second walk cycle (arms and
legs swinging, knees bending, the head nodding). The same figure as tests/common/character.rs.
Vertex attribute _FEATHER_TYPE is 1 on the legs and 0 elsewhere (for
--type-map), _LAYER is 1 on the arms and 0 elsewhere (for --layer-map).
With --parts the figure is two skinned meshes on the one skin ("trunk": the
torso and head; "limbs") and a rigid "crest" (a capsule on top of the head,
a mesh node child of the head joint): a character as a DCC holds one.

usage: make_character.py OUT.glb [--parts]   (needs numpy and pygltflib)
"""
import math
import sys

import numpy as np
import pygltflib as g

JOINTS = [  # (position at rest, parent)
    ((0.0, 1.0, 0.0), -1), ((0.0, 1.45, 0.0), 0), ((0.0, 1.6, 0.0), 1), ((0.0, 1.95, 0.0), 2),
    ((0.22, 1.45, 0.0), 1), ((0.55, 1.45, 0.0), 4), ((0.85, 1.45, 0.0), 5),
    ((-0.22, 1.45, 0.0), 1), ((-0.55, 1.45, 0.0), 7), ((-0.85, 1.45, 0.0), 8),
    ((0.11, 0.95, 0.0), 0), ((0.11, 0.52, 0.0), 10), ((0.11, 0.08, 0.0), 11),
    ((-0.11, 0.95, 0.0), 0), ((-0.11, 0.52, 0.0), 13), ((-0.11, 0.08, 0.0), 14),
]
NAMES = ["hips", "chest", "neck", "head", "upper_arm.L", "forearm.L", "hand.L", "upper_arm.R", "forearm.R", "hand.R",
         "thigh.L", "shin.L", "foot.L", "thigh.R", "shin.R", "foot.R"]
LIMBS = [(4, 5, 0.06), (5, 6, 0.05), (7, 8, 0.06), (8, 9, 0.05), (10, 11, 0.08), (11, 12, 0.065), (13, 14, 0.08), (14, 15, 0.065)]


def capsule(a, b, r, rings, cap, sides):
    a, b = np.asarray(a, float), np.asarray(b, float)
    axis = (b - a) / np.linalg.norm(b - a)
    length = np.linalg.norm(b - a)
    u = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    profile = [(-r, 0.0)]
    profile += [(-r * math.cos(math.pi / 2 * k / (cap + 1)), r * math.sin(math.pi / 2 * k / (cap + 1))) for k in range(1, cap + 1)]
    profile += [(length * k / rings, r) for k in range(rings + 1)]
    profile += [(length + r * math.cos(math.pi / 2 * k / (cap + 1)), r * math.sin(math.pi / 2 * k / (cap + 1))) for k in range(cap, 0, -1)]
    profile.append((length + r, 0.0))
    pos, along, start = [], [], []
    for i, (x, rad) in enumerate(profile):
        start.append(len(pos))
        for k in range(1 if i in (0, len(profile) - 1) else sides):
            t = 2 * math.pi * k / sides
            pos.append(a + axis * x + (u * math.cos(t) + v * math.sin(t)) * rad)
            along.append(min(max(x / length, 0.0), 1.0))
    tris, last = [], len(profile) - 1
    for k in range(sides):
        nk = (k + 1) % sides
        tris.append((start[0], start[1] + nk, start[1] + k))
        for i in range(1, last - 1):
            p, q = start[i], start[i + 1]
            tris += [(p + k, p + nk, q + nk), (p + k, q + nk, q + k)]
        tris.append((start[last], start[last - 1] + k, start[last - 1] + nk))
    return np.array(pos), np.array(along), np.array(tris)


def character():
    """The figure's arrays, and the vertex count of its trunk (torso and head
    come first)."""
    pos, tris, joints, weights, kind, layer = [], [], [], [], [], []

    def add(p, along, t, own, prev, nxt):
        base = sum(len(x) for x in pos)
        pos.append(p)
        tris.append(t + base)
        kind.extend([1.0 if own >= 10 else 0.0] * len(p))
        layer.extend([1.0 if 4 <= own < 10 else 0.0] * len(p))
        for s in along:
            other, w = own, 0.0
            if prev is not None and s < 0.15:
                other, w = prev, 0.5 * (0.15 - s) / 0.15
            elif nxt is not None and s > 0.85:
                other, w = nxt, 0.5 * (s - 0.85) / 0.15
            joints.append((own, other, 0, 0))
            weights.append((1.0 - w, w, 0.0, 0.0))

    j = lambda k: np.array(JOINTS[k][0])
    add(*capsule(j(0) - [0, 0.05, 0], j(1) + [0, 0.05, 0], 0.17, 10, 4, 24), 0, None, 1)
    add(*capsule(j(2), j(3) - [0, 0.1, 0], 0.1, 5, 4, 16), 2, 1, None)
    trunk = sum(len(x) for x in pos)
    for a, b, r in LIMBS:
        has_child = any(p == b for _, p in JOINTS)
        add(*capsule(j(a), j(b), r, 8, 3, 12), a, JOINTS[a][1], b if has_child else None)
    return np.concatenate(pos), np.concatenate(tris), np.array(joints), np.array(weights), np.array(kind), np.array(layer), trunk


def quat(axis, angle):
    s = math.sin(angle / 2)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2))


def main(out, parts=False):
    positions, triangles, joints, weights, kind, layer, trunk = character()
    times = np.linspace(0.0, 1.0, 25)
    swing = 0.6 * np.sin(2 * math.pi * times)
    rotations = {  # joint -> (axis, angle per key)
        4: ((0, 0, 1), -0.4 + 0.0 * swing), 7: ((0, 0, 1), 0.4 + 0.0 * swing),
        5: ((0, 1, 0), 0.5 * swing), 8: ((0, 1, 0), -0.5 * swing),
        10: ((1, 0, 0), swing), 13: ((1, 0, 0), -swing),
        11: ((1, 0, 0), 0.5 * np.abs(swing)), 14: ((1, 0, 0), 0.5 * np.abs(swing)),
        2: ((1, 0, 0), 0.2 * swing),  # the head nods
    }
    blob = bytearray()

    def view(data, target=None):
        while len(blob) % 4:
            blob.append(0)
        offset = len(blob)
        blob.extend(data.tobytes())
        gltf.bufferViews.append(g.BufferView(buffer=0, byteOffset=offset, byteLength=data.nbytes, target=target))
        return len(gltf.bufferViews) - 1

    def accessor(data, ctype, kind, target=None, minmax=False):
        acc = g.Accessor(bufferView=view(data, target), componentType=ctype, count=len(data), type=kind)
        if minmax:
            acc.min, acc.max = data.min(0).tolist(), data.max(0).tolist()
        gltf.accessors.append(acc)
        return len(gltf.accessors) - 1

    gltf = g.GLTF2(asset=g.Asset(generator="plumage make_character.py"), scene=0)
    nodes = []
    for k, ((p, parent), name) in enumerate(zip(JOINTS, NAMES)):
        base = np.array(JOINTS[parent][0]) if parent >= 0 else np.zeros(3)
        nodes.append(g.Node(name=name, translation=(np.array(p) - base).tolist(),
                            children=[c for c, (_, q) in enumerate(JOINTS) if q == k]))
    def primitive(lo, hi):
        tri = triangles[(triangles >= lo).all(1) & (triangles < hi).all(1)] - lo
        attrs = g.Attributes(
            POSITION=accessor(positions[lo:hi].astype(np.float32), g.FLOAT, g.VEC3, g.ARRAY_BUFFER, True),
            JOINTS_0=accessor(joints[lo:hi].astype(np.uint16), g.UNSIGNED_SHORT, g.VEC4, g.ARRAY_BUFFER),
            WEIGHTS_0=accessor(weights[lo:hi].astype(np.float32), g.FLOAT, g.VEC4, g.ARRAY_BUFFER))
        attrs._FEATHER_TYPE = accessor(kind[lo:hi].astype(np.float32), g.FLOAT, g.SCALAR, g.ARRAY_BUFFER)
        attrs._LAYER = accessor(layer[lo:hi].astype(np.float32), g.FLOAT, g.SCALAR, g.ARRAY_BUFFER)
        indices = accessor(tri.astype(np.uint32).reshape(-1), g.UNSIGNED_INT, g.SCALAR, g.ELEMENT_ARRAY_BUFFER)
        return g.Primitive(attributes=attrs, indices=indices)

    roots = [0]
    spans = [("trunk", 0, trunk), ("limbs", trunk, len(positions))] if parts else [("body", 0, len(positions))]
    gltf.meshes = []
    for name, lo, hi in spans:
        gltf.meshes.append(g.Mesh(name=name, primitives=[primitive(lo, hi)]))
        roots.append(len(nodes))
        nodes.append(g.Node(name=name, mesh=len(gltf.meshes) - 1, skin=0))
    if parts:
        # A rigid crest on the head: a capsule in the head joint's space.
        p, _, t = capsule((0.0, 0.0, -0.05), (0.0, 0.12, -0.12), 0.04, 3, 2, 10)
        crest = g.Attributes(POSITION=accessor(p.astype(np.float32), g.FLOAT, g.VEC3, g.ARRAY_BUFFER, True))
        crest_indices = accessor(t.astype(np.uint32).reshape(-1), g.UNSIGNED_INT, g.SCALAR, g.ELEMENT_ARRAY_BUFFER)
        gltf.meshes.append(g.Mesh(name="crest", primitives=[g.Primitive(attributes=crest, indices=crest_indices)]))
        nodes.append(g.Node(name="crest", mesh=len(gltf.meshes) - 1))
        nodes[3].children = list(nodes[3].children or []) + [len(nodes) - 1]
    gltf.nodes = nodes
    gltf.scenes = [g.Scene(nodes=roots)]
    inverse_bind = np.array([np.eye(4) for _ in JOINTS], np.float32)
    for k, (p, _) in enumerate(JOINTS):
        inverse_bind[k][3, :3] = -np.array(p)  # column-major: the translation is the last column
    gltf.skins = [g.Skin(joints=list(range(len(JOINTS))), inverseBindMatrices=accessor(inverse_bind.reshape(-1, 16), g.FLOAT, g.MAT4))]
    time_acc = accessor(times.astype(np.float32), g.FLOAT, g.SCALAR, minmax=True)
    gltf.accessors[time_acc].min, gltf.accessors[time_acc].max = [0.0], [1.0]
    samplers, channels = [], []
    for k, (axis, angles) in rotations.items():
        q = np.array([quat(axis, float(a)) for a in np.broadcast_to(angles, times.shape)], np.float32)
        samplers.append(g.AnimationSampler(input=time_acc, output=accessor(q, g.FLOAT, g.VEC4), interpolation="LINEAR"))
        channels.append(g.AnimationChannel(sampler=len(samplers) - 1, target=g.AnimationChannelTarget(node=k, path="rotation")))
    gltf.animations = [g.Animation(name="walk", samplers=samplers, channels=channels)]
    gltf.buffers = [g.Buffer(byteLength=len(blob))]
    gltf.set_binary_blob(bytes(blob))
    gltf.save_binary(out)


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3) or (len(sys.argv) == 3 and sys.argv[2] != "--parts"):
        sys.exit(__doc__)
    main(sys.argv[1], parts=len(sys.argv) == 3)
