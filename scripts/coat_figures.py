#!/usr/bin/env python3
"""How a coat lies, measured from the geometry of a plumage_gltf output .glb alone.

usage: coat_figures.py [--json FILE] [--frames] COAT.glb [COAT.glb ...]
       coat_figures.py --self-test

For every pose in the file (the rest pose, then each stepped frame) and every
feather with a length:
  tip height  distance from the feather's tip to the nearest point of the body
              surface, in feather lengths (|tip - root|), not capped;
              median and 90th percentile (nearest rank)
  bristle %   share of feathers whose tip stands more than 0.5 lengths off
  pops %      share of feathers whose shaft angle to the body normal at the
              root changed by more than 5 degrees since the previous stepped
              frame (the first stepped frame has no previous one: "-")
  body move   how far the body moved since the previous stepped frame: the
              largest vertex displacement, in median feather lengths (context
              for the pops: a still body should not pop its feathers)
The body normal at a root is the welded body's smooth (area-weighted) vertex
normal, interpolated at the closest point of the body to the root.

Only numpy is needed. The layout of the feathers in the file is read in one
place, read_coat(); adapt that function when the host's layout changes.
"""

import json
import struct
import sys

import numpy as np

BRISTLE_LENGTHS = 0.5
POP_DEGREES = 5.0

# ---------------------------------------------------------------------------
# GLB reading (numpy only)

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def read_glb(path):
    """The JSON and binary chunk of a .glb."""
    with open(path, "rb") as f:
        data = f.read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67 or version != 2:
        raise ValueError(f"{path}: not a glTF 2.0 binary")
    gltf, binary, at = None, b"", 12
    while at < min(length, len(data)):
        size, kind = struct.unpack_from("<II", data, at)
        chunk = data[at + 8 : at + 8 + size]
        if kind == 0x4E4F534A:
            gltf = json.loads(chunk)
        elif kind == 0x004E4942:
            binary = chunk
        at += 8 + size
    if gltf is None:
        raise ValueError(f"{path}: no JSON chunk")
    return gltf, binary


def accessor(gltf, binary, index):
    """An accessor as an array (count, width); sparse accessors are not used by the host."""
    a = gltf["accessors"][index]
    dtype = np.dtype(_COMPONENTS[a["componentType"]])
    width = _WIDTH[a["type"]]
    count = a["count"]
    if "bufferView" not in a:
        return np.zeros((count, width), dtype)
    view = gltf["bufferViews"][a["bufferView"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    stride = view.get("byteStride", dtype.itemsize * width)
    rows = np.ndarray((count, width), dtype, buffer=binary, offset=start, strides=(stride, dtype.itemsize))
    return np.array(rows)


def mesh_poses(gltf, binary, name):
    """(rest positions, [positions per morph target], triangle indices) of the
    first primitive of the mesh called `name`; each frame is a morph target."""
    mesh = next((m for m in gltf["meshes"] if m.get("name") == name), None)
    if mesh is None:
        raise ValueError(f"no mesh named {name!r}")
    prim = mesh["primitives"][0]
    if prim.get("mode", 4) != 4:
        raise ValueError(f"mesh {name!r} is not a triangle list")
    rest = accessor(gltf, binary, prim["attributes"]["POSITION"]).astype(np.float64)
    frames = [rest + accessor(gltf, binary, t["POSITION"]) for t in prim.get("targets", [])]
    tris = accessor(gltf, binary, prim["indices"]).reshape(-1, 3).astype(np.int64)
    return rest, frames, tris


def frame_times(gltf, binary):
    """Seconds of each morph target (the STEP keys of the host's animation), or None."""
    for anim in gltf.get("animations", []):
        for s in anim["samplers"]:
            return accessor(gltf, binary, s["input"])[:, 0].astype(np.float64)
    return None


def read_coat(path):
    """The coat in a plumage_gltf .glb: the body's triangles and, per pose
    (rest first, then each stepped frame), the body vertices and every
    feather's root and tip.

    Layout written by cpp_examples/gltf_host/gltf_writer.cpp: a mesh "body"
    and a mesh "feathers"; each stepped frame is a morph target (a
    displacement from rest). The feathers' vertices carry `_FEATHER_ID` and
    `TEXCOORD_0` (u from 0 at the root to 1 at the tip along the shaft, v =
    0.5 on the shaft), so a feather's root and tip are its shaft vertices
    (v = 0.5) of smallest and largest u, whatever the number of shaft
    segments. Files without those attributes (older hosts: two triangles a
    feather, (root, tip, left corner), (root, right corner, tip)) are read
    through the first triangle's first two indices.
    """
    gltf, binary = read_glb(path)
    body_rest, body_frames, body_tris = mesh_poses(gltf, binary, "body")
    f_rest, f_frames, f_tris = mesh_poses(gltf, binary, "feathers")
    prim = next(m for m in gltf["meshes"] if m.get("name") == "feathers")["primitives"][0]
    attributes = prim["attributes"]
    if "_FEATHER_ID" in attributes and "TEXCOORD_0" in attributes:
        ids = accessor(gltf, binary, attributes["_FEATHER_ID"])[:, 0].astype(np.int64)
        uv = accessor(gltf, binary, attributes["TEXCOORD_0"]).astype(np.float64)
        shaft = np.flatnonzero(np.abs(uv[:, 1] - 0.5) < 1e-4)
        # Per feather (in id order), the shaft vertex of smallest u and of largest u.
        by_root = shaft[np.lexsort((uv[shaft, 0], ids[shaft]))]
        by_tip = shaft[np.lexsort((-uv[shaft, 0], ids[shaft]))]
        first = np.r_[True, ids[by_root][1:] != ids[by_root][:-1]]
        root_i, tip_i = by_root[first], by_tip[first]
        if len(np.unique(ids)) != len(root_i):
            raise ValueError(f"{path}: a feather without shaft vertices")
    else:
        if len(f_tris) % 2:
            raise ValueError(f"{path}: odd feather triangle count {len(f_tris)}")
        first_t, second = f_tris[0::2], f_tris[1::2]
        root_i, tip_i = first_t[:, 0], first_t[:, 1]
        scale = max(float(np.ptp(f_rest, axis=0).max()), 1e-30) if len(f_rest) else 1.0
        for a, b in ((second[:, 0], root_i), (second[:, 2], tip_i)):
            if np.abs(f_rest[a] - f_rest[b]).max(initial=0.0) > 1e-5 * scale:
                raise ValueError(f"{path}: feather triangles are not (root, tip, left), (root, right, tip)")
    poses = []
    for body, feathers in zip([body_rest] + body_frames, [f_rest] + f_frames):
        poses.append({"body": body, "root": feathers[root_i], "tip": feathers[tip_i]})
    return {"body_triangles": body_tris, "poses": poses, "times": frame_times(gltf, binary)}


# ---------------------------------------------------------------------------
# Geometry


def closest_on_triangles(p, a, b, c):
    """Closest points of triangles (a, b, c) to points p (all (n, 3)), as
    barycentric weights (n, 3) (Ericson, Real-Time Collision Detection 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    n = len(p)
    w = np.zeros((n, 3))
    done = np.zeros(n, bool)

    def put(mask, weights):
        m = mask & ~done
        w[m] = weights[m] if weights.ndim == 2 else weights
        done[m] = True

    with np.errstate(divide="ignore", invalid="ignore"):
        put((d1 <= 0) & (d2 <= 0), np.array([1.0, 0, 0]))
        put((d3 >= 0) & (d4 <= d3), np.array([0, 1.0, 0]))
        v = d1 / (d1 - d3)
        put((vc <= 0) & (d1 >= 0) & (d3 <= 0), np.stack([1 - v, v, 0 * v], 1))
        put((d6 >= 0) & (d5 <= d6), np.array([0, 0, 1.0]))
        t = d2 / (d2 - d6)
        put((vb <= 0) & (d2 >= 0) & (d6 <= 0), np.stack([1 - t, 0 * t, t], 1))
        u = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        put((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), np.stack([0 * u, 1 - u, u], 1))
        s = 1.0 / (va + vb + vc)
        inside = np.stack([1 - (vb + vc) * s, vb * s, vc * s], 1)
    put(np.ones(n, bool), np.nan_to_num(inside, nan=1.0 / 3))
    return w


def closest_on_mesh(points, verts, tris, chunk=256):
    """For each point, the nearest point of the triangle mesh: (distance,
    triangle index, barycentric weights). Exact: a triangle is tested only
    when its bounding sphere could hold something nearer than the best
    centroid, which bounds the answer from above."""
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    centre = (a + b + c) / 3
    radius = np.sqrt(np.max([((x - centre) ** 2).sum(1) for x in (a, b, c)], 0))
    dist = np.empty(len(points))
    tri = np.empty(len(points), np.int64)
    bary = np.empty((len(points), 3))
    for s in range(0, len(points), chunk):
        p = points[s : s + chunk]
        dc = np.sqrt(((p[:, None, :] - centre[None, :, :]) ** 2).sum(2))
        upper = dc.min(1)
        pi, ti = np.nonzero(dc - radius[None, :] <= upper[:, None] * (1 + 1e-9) + 1e-12)
        w = closest_on_triangles(p[pi], a[ti], b[ti], c[ti])
        q = w[:, :1] * a[ti] + w[:, 1:2] * b[ti] + w[:, 2:] * c[ti]
        d = np.sqrt(((p[pi] - q) ** 2).sum(1))
        order = np.lexsort((d, pi))  # per point, nearest first
        pi, ti, w, d = pi[order], ti[order], w[order], d[order]
        first = np.r_[True, pi[1:] != pi[:-1]]
        dist[s + pi[first]] = d[first]
        tri[s + pi[first]] = ti[first]
        bary[s + pi[first]] = w[first]
    return dist, tri, bary


def weld(verts):
    """Index of each vertex's first exact duplicate (the host writes the body as a soup)."""
    _, first, inverse = np.unique(verts, axis=0, return_index=True, return_inverse=True)
    return first[inverse.reshape(-1)]


def vertex_normals(verts, tris, welded):
    """Smooth unit normals, area-weighted, over vertices welded by rest position."""
    t = welded[tris]
    face = np.cross(verts[t[:, 1]] - verts[t[:, 0]], verts[t[:, 2]] - verts[t[:, 0]])
    acc = np.zeros_like(verts)
    for k in range(3):
        np.add.at(acc, t[:, k], face)
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    return np.divide(acc, length, out=np.zeros_like(acc), where=length > 0)[welded]


# ---------------------------------------------------------------------------
# Figures


def nearest_rank(sorted_values, q):
    k = int(np.ceil(q * len(sorted_values)))
    return float(sorted_values[min(max(k, 1), len(sorted_values)) - 1])


def pose_figures(pose, tris, welded):
    """Tip heights and shaft angles of one pose."""
    body, root, tip = pose["body"], pose["root"], pose["tip"]
    shaft = tip - root
    length = np.linalg.norm(shaft, axis=1)
    placed = length > 0
    tip_dist, _, _ = closest_on_mesh(tip[placed], body, tris)
    height = tip_dist / length[placed]
    _, root_tri, root_w = closest_on_mesh(root[placed], body, tris)
    normals = vertex_normals(body, tris, welded)
    n = np.einsum("ij,ijk->ik", root_w, normals[tris[root_tri]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    cosine = np.einsum("ij,ij->i", shaft[placed] / length[placed, None], n)
    angle = np.full(len(root), np.nan)
    angle[placed] = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
    h = np.sort(height)
    return {
        "feathers": int(placed.sum()),
        "left_out": int((~placed).sum()),
        "tip_height_median": nearest_rank(h, 0.5) if len(h) else float("nan"),
        "tip_height_p90": nearest_rank(h, 0.9) if len(h) else float("nan"),
        "bristle_percent": 100.0 * float((h > BRISTLE_LENGTHS).sum()) / max(len(h), 1),
        "_angle": angle,
    }


def coat_figures(path):
    """Figures of every pose of a coat: rest, then the stepped frames."""
    coat = read_coat(path)
    tris = coat["body_triangles"]
    welded = weld(coat["poses"][0]["body"])
    rows = []
    previous = None
    lengths = np.linalg.norm(coat["poses"][0]["tip"] - coat["poses"][0]["root"], axis=1)
    unit = float(np.median(lengths[lengths > 0])) if (lengths > 0).any() else 1.0
    for k, pose in enumerate(coat["poses"]):
        r = pose_figures(pose, tris, welded)
        angle = r.pop("_angle")
        r["pose"] = "rest" if k == 0 else f"frame {k - 1}"
        if coat["times"] is not None and k > 0:
            r["seconds"] = float(coat["times"][k - 1])
        r["pops_percent"] = None
        r["body_move"] = None
        if previous is not None:
            r["body_move"] = float(np.linalg.norm(pose["body"] - coat["poses"][k - 1]["body"], axis=1).max()) / unit
            both = ~np.isnan(angle) & ~np.isnan(previous)
            r["pops_percent"] = 100.0 * float((np.abs(angle - previous)[both] > POP_DEGREES).sum()) / max(int(both.sum()), 1)
            r["max_angle_change_deg"] = float(np.abs(angle - previous)[both].max()) if both.any() else 0.0
        if k > 0:
            previous = angle
        rows.append(r)
    return rows


def summary(rows):
    """Rest figures, and over the stepped frames the mean of each figure and the worst."""
    out = {"rest": {k: rows[0][k] for k in ("feathers", "left_out", "tip_height_median", "tip_height_p90", "bristle_percent")}}
    frames = rows[1:]
    if frames:
        out["frames"] = len(frames)
        for key in ("tip_height_median", "tip_height_p90", "bristle_percent"):
            v = [r[key] for r in frames]
            out[key + "_mean"] = float(np.mean(v))
            out[key + "_max"] = float(np.max(v))
        pops = [r["pops_percent"] for r in frames if r["pops_percent"] is not None]
        out["pops_percent_mean"] = float(np.mean(pops)) if pops else None
        out["pops_percent_max"] = float(np.max(pops)) if pops else None
        moves = [r["body_move"] for r in frames if r["body_move"] is not None]
        out["body_move_mean"] = float(np.mean(moves)) if moves else None
    return out


def fmt(v, digits=2):
    return "-" if v is None else f"{v:.{digits}f}"


def main(argv):
    if argv[:1] == ["--self-test"]:
        return self_test()
    json_out, per_frame, paths = None, False, []
    i = 0
    while i < len(argv):
        if argv[i] == "--json":
            json_out = argv[i + 1]
            i += 2
        elif argv[i] == "--frames":
            per_frame = True
            i += 1
        elif argv[i].startswith("-"):
            print(__doc__, file=sys.stderr)
            return 2
        else:
            paths.append(argv[i])
            i += 1
    if not paths:
        print(__doc__, file=sys.stderr)
        return 2
    results = {}
    print(f"{'coat':<28} {'pose':<9} {'feathers':>8} {'median':>7} {'p90':>6} {'bristle%':>8} {'pops%':>6} {'move':>5}")
    for path in paths:
        try:
            rows = coat_figures(path)
        except (OSError, ValueError, KeyError, IndexError) as e:
            print(f"{path}: {e}", file=sys.stderr)
            return 3
        results[path] = {"poses": rows, "summary": summary(rows)}
        name = path.rsplit("/", 1)[-1]
        for r in rows if per_frame else rows[:1]:
            print(
                f"{name:<28} {r['pose']:<9} {r['feathers']:>8} {fmt(r['tip_height_median']):>7} {fmt(r['tip_height_p90']):>6} "
                f"{fmt(r['bristle_percent'], 1):>8} {fmt(r['pops_percent'], 1):>6} {fmt(r['body_move']):>5}"
            )
        s = results[path]["summary"]
        if "frames" in s:
            print(
                f"{name:<28} {'mean ' + str(s['frames']) + 'f':<9} {'':>8} {fmt(s['tip_height_median_mean']):>7} "
                f"{fmt(s['tip_height_p90_mean']):>6} {fmt(s['bristle_percent_mean'], 1):>8} {fmt(s['pops_percent_mean'], 1):>6} {fmt(s['body_move_mean']):>5}"
                f"   (max: median {fmt(s['tip_height_median_max'])}, p90 {fmt(s['tip_height_p90_max'])},"
                f" bristle {fmt(s['bristle_percent_max'], 1)}, pops {fmt(s['pops_percent_max'], 1)})"
            )
    if json_out:
        with open(json_out, "w") as f:
            json.dump(results, f, indent=1)
    return 0


# ---------------------------------------------------------------------------
# Self-test: a coat whose figures are known, written as the host writes it.


def _write_glb(path, body_rest, body_frames, body_tris, f_rest, f_frames, f_tris):
    blob = bytearray()
    views, accessors = [], []

    def add(array, kind, component):
        raw = np.ascontiguousarray(array).tobytes()
        blob.extend(b"\0" * (-len(blob) % 4))
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(raw)})
        blob.extend(raw)
        accessors.append({"bufferView": len(views) - 1, "componentType": component, "count": len(array), "type": kind})
        return len(accessors) - 1

    meshes = []
    for name, rest, frames, tris in (("body", body_rest, body_frames, body_tris), ("feathers", f_rest, f_frames, f_tris)):
        prim = {
            "attributes": {"POSITION": add(rest.astype(np.float32), "VEC3", 5126)},
            "indices": add(tris.reshape(-1).astype(np.uint32), "SCALAR", 5125),
            "targets": [{"POSITION": add((fr - rest).astype(np.float32), "VEC3", 5126)} for fr in frames],
        }
        meshes.append({"name": name, "primitives": [prim]})
    gltf = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": meshes,
        "nodes": [{"mesh": 0, "name": "body"}, {"mesh": 1, "name": "feathers"}],
        "scenes": [{"nodes": [0, 1]}],
    }
    js = json.dumps(gltf).encode()
    js += b" " * (-len(js) % 4)
    blob.extend(b"\0" * (-len(blob) % 4))
    total = 12 + 8 + len(js) + 8 + len(blob)
    with open(path, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, total))
        f.write(struct.pack("<II", len(js), 0x4E4F534A) + js)
        f.write(struct.pack("<II", len(blob), 0x004E4942) + bytes(blob))


def _kite(root, pitch_deg, length=1.0, width=0.4):
    """Four corners (root, tip, left, right) of a feather on the floor z = 0, shaft along +x pitched up."""
    a = np.radians(pitch_deg)
    d = np.array([np.cos(a), 0.0, np.sin(a)])
    mid = root + 0.5 * length * d
    side = np.array([0.0, width / 2, 0.0])
    return [root, root + length * d, mid + side, mid - side]


def self_test():
    import os
    import tempfile

    # Body: a floor z = 0 as a soup of two triangles (split vertices, as the host writes).
    floor = np.array([[-10, -10, 0], [10, -10, 0], [10, 10, 0], [-10, -10, 0], [10, 10, 0], [-10, 10, 0]], float)
    floor_tris = np.arange(6).reshape(2, 3)
    roots = [np.array([x, 0.0, 0.0]) for x in (-4.0, -2.0, 0.0, 2.0)]
    pitches = [[0, 10, 40, 60], [3, 10, 40, 60], [3, 20, 40, 60]]  # rest, frame 0, frame 1
    ok = True
    for layout in (4, 6):

        def feathers(p):
            verts = []
            for r, pitch in zip(roots, p):
                root, tip, left, right = _kite(r, pitch)
                verts += [root, tip, left, right] if layout == 4 else [root, tip, left, root, right, tip]
            return np.array(verts)

        local = [0, 1, 2, 0, 3, 1] if layout == 4 else [0, 1, 2, 3, 4, 5]
        tris = np.array([[f * layout + i for i in local] for f in range(len(roots))]).reshape(-1, 3)
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "coat.glb")
            _write_glb(path, floor, [floor, floor + [0.5, 0, 0]], floor_tris, feathers(pitches[0]), [feathers(p) for p in pitches[1:]], tris)
            rows = coat_figures(path)
        heights = [sorted(np.sin(np.radians(p))) for p in pitches]
        checks = [
            (len(rows) == 3, "three poses"),
            (abs(rows[0]["tip_height_median"] - heights[0][1]) < 1e-5, f"rest median {rows[0]['tip_height_median']}"),
            (abs(rows[0]["tip_height_p90"] - heights[0][3]) < 1e-5, f"rest p90 {rows[0]['tip_height_p90']}"),
            (rows[0]["bristle_percent"] == 50.0, f"rest bristles {rows[0]['bristle_percent']}"),
            (rows[1]["pops_percent"] is None, "no previous frame for frame 0"),
            (rows[2]["pops_percent"] == 25.0, f"frame 1 pops {rows[2]['pops_percent']}"),
            (rows[1]["body_move"] is None and abs(rows[2]["body_move"] - 0.5) < 1e-6, f"body moves {rows[1]['body_move']}, {rows[2]['body_move']}"),
            (abs(rows[2]["max_angle_change_deg"] - 10.0) < 1e-3, f"frame 1 largest change {rows[2].get('max_angle_change_deg')}"),
        ]
        for good, what in checks:
            if not good:
                ok = False
                print(f"FAIL ({layout} vertices per feather): {what}")
    # A tip beside a triangle's edge, nearest to the edge's interior, and one off a corner.
    tri = np.array([[0, 1, 2]])
    v = np.array([[0.0, 0, 0], [2, 0, 0], [0, 2, 0]])
    d, _, _ = closest_on_mesh(np.array([[1.0, -1.0, 0.0], [3.0, 0.0, 1.0], [1.0, 1.0, 0.5]]), v, tri)
    if not np.allclose(d, [1.0, np.sqrt(2.0), 0.5]):
        ok = False
        print(f"FAIL: point-triangle distances {d}")
    print("self-test:", "ok" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
