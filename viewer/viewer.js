// Plumage's web viewer: draws what the glTF host writes with
// `--instances DIR` (format in cpp_examples/gltf_host/instance_writer.h).
//
// Two ways to draw the same frame, with the same camera, lights and
// fragment shader:
//   records   one three.js InstancedMesh of the template card; each
//             feather's 36-byte PlumageFeatherInstance is an instance, its
//             fields instanced attributes, placed and bent by the
//             repository's reference shader (shaders/feather_instance.vert,
//             ported by glsl.js); after the first frame only the records
//             on the frame's changed-feather list are uploaded.
//   geometry  the copied-out feathers (plumage_system_feather_geometry) as
//             an ordinary mesh, for the frames the host wrote them for
//             (the rest pose and the last frame).
// The body is drawn the same way in both.
import * as THREE from 'three';
import { FEATHER_FRAGMENT, PLAIN_VERTEX, toGlslEs300 } from './glsl.js';
import { shaderNormals } from './record.js';

const RECORD_BYTES = 36;
const FLOATS_PER_RECORD = RECORD_BYTES / 4;
const SHORTS_PER_RECORD = RECORD_BYTES / 2;

async function fetchBytes(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: ${response.status} ${response.statusText}`);
  return response.arrayBuffer();
}

async function fetchText(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: ${response.status} ${response.statusText}`);
  return response.text();
}

// Runs of consecutive indices: [[first, count], ...] from an increasing list.
export function runs(indices) {
  const out = [];
  for (const i of indices) {
    const last = out[out.length - 1];
    if (last && last[0] + last[1] === i) last[1] += 1;
    else out.push([i, 1]);
  }
  return out;
}

export class FeatherViewer {
  // canvas: where to draw; shaderUrl: the reference vertex shader.
  constructor(canvas, { width, height, antialias = true, shaderUrl = '../shaders/feather_instance.vert' } = {}) {
    this.canvas = canvas;
    this.shaderUrl = shaderUrl;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(1);
    this.renderer.setClearColor(0xdfe6ee, 1);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(30, 1, 0.01, 1000);
    this.setSize(width ?? canvas.clientWidth, height ?? canvas.clientHeight);
    this.mode = 'records';
    this.frame = -1;
    this.uploads = { full: 0, partial: 0, records: 0 };  // what went to the GPU since load
    const lightDir = (x, y, z) => new THREE.Vector3(x, y, z).normalize();
    this.lighting = {
      u_lit: { value: 1 },
      u_ambient: { value: new THREE.Vector3(0.2, 0.21, 0.25) },
      u_light_dir: { value: [lightDir(-0.5, 0.8, 0.35), lightDir(0.6, -0.2, 0.8)] },
      u_light_color: { value: [new THREE.Vector3(1.0, 0.93, 0.82), new THREE.Vector3(0.3, 0.34, 0.42)] },
    };
    this.mvp = { value: new THREE.Matrix4() };
  }

  setSize(width, height) {
    this.width = width;
    this.height = height;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
  }

  // Reads DIR/manifest.json and what never changes: the card, the body's
  // triangles and the reference shader.
  async load(dataUrl) {
    this.base = new URL(dataUrl.endsWith('/') ? dataUrl : `${dataUrl}/`, location.href);
    const at = (name) => new URL(name, this.base).href;
    this.manifest = JSON.parse(await fetchText(at('manifest.json')));
    const m = this.manifest;
    if (m.format !== 'plumage-instances' || m.version !== 1 || m.record_bytes !== RECORD_BYTES) {
      throw new Error(`${at('manifest.json')} is not a version 1 plumage-instances manifest with ${RECORD_BYTES}-byte records`);
    }
    this.at = at;
    const [template, bodyIndices, shader] = await Promise.all([
      fetchBytes(at(m.template.file)),
      fetchBytes(at(m.body.indices)),
      fetchText(new URL(this.shaderUrl, location.href).href),
    ]);
    this.referenceShader = shader;
    this.buildRecordsMesh(template, toGlslEs300(shader, { withVersion: false }));
    this.buildBody(new Uint32Array(bodyIndices));
    this.frameCamera();
    this.recordsFrame = -1;  // the frame whose records the GPU holds
  }

  material(vertexShader, uniforms) {
    return new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader,
      fragmentShader: FEATHER_FRAGMENT,
      side: THREE.DoubleSide,
      uniforms: { ...this.lighting, u_model_view_projection: this.mvp, ...uniforms },
    });
  }

  featherColors() {
    return {
      u_root_color: { value: new THREE.Vector3(0.62, 0.44, 0.27) },
      u_tip_color: { value: new THREE.Vector3(0.3, 0.17, 0.09) },
      u_shaft: { value: 1 },
    };
  }

  buildRecordsMesh(template, vertexShader) {
    const t = this.manifest.template;
    const n = this.manifest.feathers;
    const V = t.vertices;
    const positions = new Float32Array(template, 0, 3 * V);
    const uvs = new Float32Array(template, 12 * V, 2 * V);
    const segments = new Uint32Array(template, 20 * V, V);
    this.vertexSegments = segments;
    const indices = new Uint32Array(template, 24 * V, 3 * t.triangles);
    const card = new THREE.BufferGeometry();
    card.setAttribute('a_card', new THREE.BufferAttribute(positions, 3));
    card.setAttribute('a_uv', new THREE.BufferAttribute(uvs, 2));
    card.setAttribute('a_segment', new THREE.BufferAttribute(segments, 1));  // UNSIGNED_INT: an integer attribute
    card.setIndex(new THREE.BufferAttribute(indices, 1));

    // The records: one buffer of 36-byte structs, seen as floats for the
    // float fields and as shorts for the snorm16 ones. three.js takes a
    // buffer's element type from its typed array, so the two views are
    // two GL buffers holding the same bytes.
    this.records = new ArrayBuffer(n * RECORD_BYTES);
    this.floatRecords = new THREE.InstancedInterleavedBuffer(new Float32Array(this.records), FLOATS_PER_RECORD, 1);
    this.shortRecords = new THREE.InstancedInterleavedBuffer(new Int16Array(this.records), SHORTS_PER_RECORD, 1);
    this.floatRecords.setUsage(THREE.DynamicDrawUsage);
    this.shortRecords.setUsage(THREE.DynamicDrawUsage);
    const layout = this.manifest.record_layout;
    const floatField = (name, size) => new THREE.InterleavedBufferAttribute(this.floatRecords, size, layout[name].offset / 4);
    const shortField = (name, size) => {
      const a = new THREE.InterleavedBufferAttribute(this.shortRecords, size, layout[name].offset / 2);
      a.gpuType = THREE.IntType;  // glVertexAttribIPointer, as the reference shader's ivec inputs want
      return a;
    };
    if (layout.width.offset !== layout.length.offset + 4) throw new Error('length and width are not side by side');
    card.setAttribute('i_root', floatField('root', 3));
    card.setAttribute('i_rotation', shortField('rotation', 4));
    card.setAttribute('i_size', floatField('length', 2));
    card.setAttribute('i_bends', shortField('bends', 3));

    const material = this.material(vertexShader, { ...this.featherColors(), u_segments: { value: t.segments } });
    this.recordsMesh = new THREE.InstancedMesh(card, material, n);
    this.recordsMesh.frustumCulled = false;
    this.scene.add(this.recordsMesh);
  }

  buildBody(indices) {
    const nv = this.manifest.body.vertices;
    const g = new THREE.BufferGeometry();
    this.bodyPositions = new THREE.BufferAttribute(new Float32Array(3 * nv), 3);
    this.bodyPositions.setUsage(THREE.DynamicDrawUsage);
    g.setAttribute('position', this.bodyPositions);
    g.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(3 * nv), 3));
    g.setAttribute('uv', new THREE.BufferAttribute(new Float32Array(2 * nv), 2));
    g.setIndex(new THREE.BufferAttribute(indices, 1));
    const colour = new THREE.Vector3(0.62, 0.58, 0.56);
    this.bodyMesh = new THREE.Mesh(g, this.material(PLAIN_VERTEX, { u_root_color: { value: colour }, u_tip_color: { value: colour }, u_shaft: { value: 0 } }));
    this.bodyMesh.frustumCulled = false;
    this.scene.add(this.bodyMesh);
    this.geometryMesh = null;
  }

  // A camera that takes in the body at rest, from above and in front
  // (+z), the box's corners inside 90 % of the picture.
  frameCamera() {
    const lo = new THREE.Vector3(...this.manifest.body.rest_min);
    const hi = new THREE.Vector3(...this.manifest.body.rest_max);
    const centre = lo.clone().add(hi).multiplyScalar(0.5);
    const back = new THREE.Vector3(0.15, 0.55, 1).normalize();  // from the centre towards the camera
    const right = new THREE.Vector3(0, 1, 0).cross(back).normalize();
    const up = back.clone().cross(right);
    const tanV = Math.tan(THREE.MathUtils.degToRad(this.camera.fov) / 2) * 0.9;
    const tanH = tanV * this.camera.aspect;
    let distance = 1e-6;
    for (let c = 0; c < 8; ++c) {
      const corner = new THREE.Vector3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z).sub(centre);
      const depth = corner.dot(back);
      distance = Math.max(distance, depth + Math.abs(corner.dot(right)) / tanH, depth + Math.abs(corner.dot(up)) / tanV);
    }
    this.target = centre;
    this.camera.position.copy(centre).addScaledVector(back, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 10;
    this.camera.up.set(0, 1, 0);
    this.camera.lookAt(centre);
    this.camera.updateProjectionMatrix();
  }

  frames() {
    return this.manifest.frames;
  }

  // Whole records of frame k, uploaded in full.
  async uploadRecords(k) {
    const bytes = await fetchBytes(this.at(this.manifest.frames[k].records));
    new Uint8Array(this.records).set(new Uint8Array(bytes));
    this.floatRecords.needsUpdate = true;
    this.shortRecords.needsUpdate = true;
    this.recordsFrame = k;
    this.uploads.full += 1;
    this.uploads.records += this.manifest.feathers;
  }

  // Frame k from frame k - 1 on the GPU: only the listed records are
  // written and uploaded. With `poison`, every other record of the CPU-side
  // buffer is overwritten with garbage first, so the picture can only be
  // right if the GPU kept the unlisted records from before and got exactly
  // the listed ones.
  async applyChanged(k, { poison = false } = {}) {
    const f = this.manifest.frames[k];
    if (this.recordsFrame !== k - 1) throw new Error(`the GPU holds frame ${this.recordsFrame}, not ${k - 1}`);
    const [bytes, changedBytes] = await Promise.all([fetchBytes(this.at(f.records)), fetchBytes(this.at(f.changed))]);
    const listed = new Uint32Array(changedBytes);
    const src = new Uint8Array(bytes);
    const dst = new Uint8Array(this.records);
    if (poison) dst.fill(0x7f);
    for (const [first, count] of runs(listed)) {
      dst.set(src.subarray(first * RECORD_BYTES, (first + count) * RECORD_BYTES), first * RECORD_BYTES);
      this.floatRecords.addUpdateRange(first * FLOATS_PER_RECORD, count * FLOATS_PER_RECORD);
      this.shortRecords.addUpdateRange(first * SHORTS_PER_RECORD, count * SHORTS_PER_RECORD);
    }
    if (listed.length > 0) {
      // With no range, three.js would upload the whole buffer: nothing to send then.
      this.floatRecords.needsUpdate = true;
      this.shortRecords.needsUpdate = true;
    }
    this.recordsFrame = k;
    this.uploads.partial += 1;
    this.uploads.records += listed.length;
    return listed.length;
  }

  async showBody(k) {
    const bytes = await fetchBytes(this.at(this.manifest.frames[k].body));
    this.bodyPositions.array.set(new Float32Array(bytes));
    this.bodyPositions.needsUpdate = true;
    this.bodyMesh.geometry.computeVertexNormals();
  }

  // The copied-out feathers of frame k. Their normals are the copied-out
  // ones (area-weighted over each vertex's triangles), or with
  // `shaderNormals` the ones the reference shader gives (each segment's own,
  // computed from the frame's records): a diagnostic that leaves positions
  // as the only difference between the two paths.
  async buildGeometry(k, { shaderNormals: useShaderNormals = false } = {}) {
    const f = this.manifest.frames[k];
    if (!f.geometry) throw new Error(`frame ${k} has no copied-out geometry (the host writes it for the rest pose and the last frame)`);
    const bytes = await fetchBytes(this.at(f.geometry));
    const n = this.manifest.feathers * this.manifest.template.vertices;
    const t = this.manifest.feathers * this.manifest.template.triangles;
    const normals = useShaderNormals
      ? shaderNormals(await fetchBytes(this.at(f.records)), this.manifest.feathers, this.vertexSegments)
      : new Float32Array(bytes, 12 * n, 3 * n);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(bytes, 0, 3 * n), 3));
    g.setAttribute('normal', new THREE.BufferAttribute(normals, 3));
    g.setAttribute('uv', new THREE.BufferAttribute(new Float32Array(bytes, 24 * n, 2 * n), 2));
    g.setIndex(new THREE.BufferAttribute(new Uint32Array(bytes, 32 * n, 3 * t), 1));
    if (this.geometryMesh) {
      this.scene.remove(this.geometryMesh);
      this.geometryMesh.geometry.dispose();
    } else {
      this.geometryMaterial = this.material(PLAIN_VERTEX, this.featherColors());
    }
    this.geometryMesh = new THREE.Mesh(g, this.geometryMaterial);
    this.geometryMesh.frustumCulled = false;
    this.scene.add(this.geometryMesh);
    this.geometryFrame = k;
    this.geometryNormals = useShaderNormals ? 'shader' : 'copied';
  }

  // Shows frame k: from records (the changed ones only when the GPU holds
  // frame k - 1, unless `full`; `poison` as for applyChanged) or from the
  // copied-out geometry.
  async show(k, { mode = this.mode, full = false, poison = false, shaderNormals = false } = {}) {
    this.mode = mode;
    if (mode === 'records') {
      if (!full && this.recordsFrame === k - 1) await this.applyChanged(k, { poison });
      else if (full || this.recordsFrame !== k) await this.uploadRecords(k);
    } else if (this.geometryFrame !== k || this.geometryNormals !== (shaderNormals ? 'shader' : 'copied')) {
      await this.buildGeometry(k, { shaderNormals });
    }
    await this.showBody(k);
    this.recordsMesh.visible = mode === 'records';
    if (this.geometryMesh) this.geometryMesh.visible = mode === 'geometry';
    this.frame = k;
  }

  setLit(lit) {
    this.lighting.u_lit.value = lit ? 1 : 0;
  }

  setBodyVisible(visible) {
    this.bodyMesh.visible = visible;
  }

  render() {
    this.camera.updateMatrixWorld();
    this.mvp.value.multiplyMatrices(this.camera.projectionMatrix, this.camera.matrixWorldInverse);
    this.renderer.render(this.scene, this.camera);
  }

  // The picture as RGBA bytes, top row first, base64 (for the test).
  pixelsBase64() {
    const gl = this.renderer.getContext();
    const w = this.width, h = this.height;
    const raw = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, raw);
    const flipped = new Uint8Array(raw.length);
    for (let y = 0; y < h; ++y) flipped.set(raw.subarray((h - 1 - y) * w * 4, (h - y) * w * 4), y * w * 4);
    let text = '';
    for (let i = 0; i < flipped.length; i += 0x8000) text += String.fromCharCode.apply(null, flipped.subarray(i, i + 0x8000));
    return btoa(text);
  }
}
