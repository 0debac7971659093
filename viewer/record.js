// PlumageFeatherInstance records read on the CPU, for the viewer's and the
// test's diagnostics (drawing is the reference shader's job): the normal
// the shader gives a card vertex, as it computes it.
export const RECORD_BYTES = 36;
const BEND_SCALE = 3.1415927 / 32767;  // PLUMAGE_INSTANCE_BEND_RANGE / 32767

// Record f of `bytes` (an ArrayBuffer or typed array of whole records).
export function decodeRecord(bytes, f) {
  const view = bytes instanceof ArrayBuffer ? new DataView(bytes) : new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const at = f * RECORD_BYTES;
  const q = [0, 1, 2, 3].map((i) => view.getInt16(at + 12 + 2 * i, true) / 32767);
  const norm = Math.hypot(...q);
  return {
    root: [0, 1, 2].map((i) => view.getFloat32(at + 4 * i, true)),
    rotation: q.map((x) => x / norm),
    length: view.getFloat32(at + 20, true),
    width: view.getFloat32(at + 24, true),
    bends: [0, 1, 2].map((i) => view.getInt16(at + 28 + 2 * i, true)),
  };
}

// q v q* for a unit quaternion q = [x, y, z, w] (as the shader's rotate()).
export function rotate(q, v) {
  const [x, y, z, w] = q;
  const t = [2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])];
  return [
    v[0] + w * t[0] + (y * t[2] - z * t[1]),
    v[1] + w * t[1] + (z * t[0] - x * t[2]),
    v[2] + w * t[2] + (x * t[1] - y * t[0]),
  ];
}

// The shader's v_normal for a vertex carried by shaft segment k: the
// segment's own normal, turned by the bends of the joints before it.
export function segmentNormal(record, k) {
  let angle = 0;
  for (let j = 0; j < k; ++j) angle += record.bends[j] * BEND_SCALE;
  return rotate(record.rotation, [-Math.sin(angle), 0, Math.cos(angle)]);
}

// Every vertex's shader normal, feather after feather (the order of the
// copied-out geometry): 3 floats per vertex.
export function shaderNormals(records, featherCount, vertexSegments) {
  const V = vertexSegments.length;
  const out = new Float32Array(3 * V * featherCount);
  for (let f = 0; f < featherCount; ++f) {
    const r = decodeRecord(records, f);
    for (let v = 0; v < V; ++v) out.set(segmentNormal(r, vertexSegments[v]), 3 * (f * V + v));
  }
  return out;
}
