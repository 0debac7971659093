// Writes a small animated glTF for the render test: a closed tube along x
// (0 to 4, radius 0.4, capped) with one morph target that bends its back
// half (x > 2) up and back; the front half's displacement is exactly 0, so
// its vertices stay put bit for bit and the host's changed-feather list is
// a part of the coat, not all of it (on the built-in swimmer every root
// moves each frame, so every feather is listed).
//   node tube_glb.mjs OUT.glb
import { writeFileSync } from 'node:fs';

export function tubeGlb({ rings = 40, segments = 20, length = 4, radius = 0.4 } = {}) {
  const pos = [];
  const disp = [];
  const idx = [];
  const vertex = (x, y, z) => {
    pos.push(x, y, z);
    const s = Math.max(0, x - length / 2) / (length / 2);
    disp.push(0, 0.6 * s * s, -0.3 * s * s);
    return pos.length / 3 - 1;
  };
  for (let r = 0; r < rings; ++r) {
    const x = (length * r) / (rings - 1);
    for (let s = 0; s < segments; ++s) {
      const a = (2 * Math.PI * s) / segments;
      vertex(x, radius * Math.cos(a), radius * Math.sin(a));
    }
  }
  const at = (r, s) => r * segments + (s % segments);
  for (let r = 0; r + 1 < rings; ++r) {
    for (let s = 0; s < segments; ++s) {
      idx.push(at(r, s), at(r, s + 1), at(r + 1, s + 1), at(r, s), at(r + 1, s + 1), at(r + 1, s));
    }
  }
  const front = vertex(0, 0, 0);
  const back = vertex(length, 0, 0);
  for (let s = 0; s < segments; ++s) {
    idx.push(front, at(0, s + 1), at(0, s));
    idx.push(back, at(rings - 1, s), at(rings - 1, s + 1));
  }
  const times = [0, 0.5, 1];
  const weights = [0, 1, 0];

  const parts = [new Float32Array(pos), new Float32Array(disp), new Uint32Array(idx), new Float32Array(times), new Float32Array(weights)];
  const views = [];
  let offset = 0;
  for (const p of parts) {
    views.push({ buffer: 0, byteOffset: offset, byteLength: p.byteLength });
    offset += p.byteLength;  // every part is 4-byte aligned
  }
  const bounds = (a) => {
    const lo = [Infinity, Infinity, Infinity];
    const hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < a.length; ++i) {
      lo[i % 3] = Math.min(lo[i % 3], Math.fround(a[i]));
      hi[i % 3] = Math.max(hi[i % 3], Math.fround(a[i]));
    }
    return { min: lo, max: hi };
  };
  const gltf = {
    asset: { version: '2.0', generator: 'plumage render test' },
    buffers: [{ byteLength: offset }],
    bufferViews: views,
    accessors: [
      { bufferView: 0, componentType: 5126, count: pos.length / 3, type: 'VEC3', ...bounds(pos) },
      { bufferView: 1, componentType: 5126, count: disp.length / 3, type: 'VEC3', ...bounds(disp) },
      { bufferView: 2, componentType: 5125, count: idx.length, type: 'SCALAR' },
      { bufferView: 3, componentType: 5126, count: times.length, type: 'SCALAR', min: [0], max: [1] },
      { bufferView: 4, componentType: 5126, count: weights.length, type: 'SCALAR' },
    ],
    meshes: [{ name: 'tube', primitives: [{ attributes: { POSITION: 0 }, indices: 2, targets: [{ POSITION: 1 }] }], weights: [0] }],
    nodes: [{ name: 'tube', mesh: 0 }],
    scenes: [{ nodes: [0] }],
    scene: 0,
    animations: [{ name: 'bend', samplers: [{ input: 3, output: 4, interpolation: 'LINEAR' }], channels: [{ sampler: 0, target: { node: 0, path: 'weights' } }] }],
  };
  let json = Buffer.from(JSON.stringify(gltf));
  json = Buffer.concat([json, Buffer.alloc((4 - (json.length % 4)) % 4, 0x20)]);
  const bin = Buffer.concat(parts.map((p) => Buffer.from(p.buffer)));
  const head = Buffer.alloc(12);
  head.write('glTF', 0, 'latin1');
  head.writeUInt32LE(2, 4);
  head.writeUInt32LE(12 + 8 + json.length + 8 + bin.length, 8);
  const chunkHead = (n, type) => {
    const b = Buffer.alloc(8);
    b.writeUInt32LE(n, 0);
    b.write(type, 4, 'latin1');
    return b;
  };
  return Buffer.concat([head, chunkHead(json.length, 'JSON'), json, chunkHead(bin.length, 'BIN\0'), bin]);
}

if (process.argv[1] && process.argv[1].endsWith('tube_glb.mjs')) {
  writeFileSync(process.argv[2], tubeGlb());
}
