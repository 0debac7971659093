// The render test (run by scripts/render_test.sh): the host's --instances
// output drawn in headless Chromium by viewer/, and
//   1. the shader port: the GLSL ES 3.00 the viewer runs is the reference
//      shader with only its version line changed (and compiles, with
//      glslangValidator where it is installed);
//   2. the changed-feather list against a full upload, on the CPU: each
//      frame's listed records written over the previous frame's records
//      give the new frame's records byte for byte;
//   3. the same on the GPU: from the previous frame's records on the GPU,
//      only the listed ones uploaded (from a CPU buffer whose other
//      records are garbage) draw exactly the picture a full upload draws;
//   4. the rest pose and the last frame drawn from the records (reference
//      shader, InstancedMesh) and from the copied-out geometry, same camera,
//      lights and size: the share of differing pixels and the mean absolute
//      difference, lit, lit with the shader's normals put on the geometry,
//      and unlit (flat colour), against the limits below; and how far the
//      copied-out normals lie from the shader's.
//
//   node render_test.mjs --chromium PATH --work DIR --compare NAME [--png-prefix P] NAME...
// Each NAME is a directory under DIR written by the host with --instances.
// Exit 0 when every check passes, 1 when one fails.
import { spawnSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';
import { ES_HEADER, REFERENCE_VERSION, toGlslEs300 } from '../glsl.js';
import { decodeRecord, shaderNormals } from '../record.js';
import { serve } from '../serve.mjs';
import { encodePng } from './png.mjs';

const REPO = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..');
const WIDTH = 960;
const HEIGHT = 540;
const RECORD_BYTES = 36;

// Limits on the share of the foreground (pixels that are not background in
// either picture), from what the test measured in headless Chromium
// (SwiftShader) at 960 x 540 without antialiasing, on the built-in swimmer
// (1 472 feathers, 15 % of the picture) and the tube (812, 31 %):
// - unlit (flat colour), and lit with the shader's own normals put on the
//   copied-out geometry, only positions differ (records reconstruct them
//   within 1e-4 feather lengths): 2.2-2.6 % of the foreground differs at
//   all, 0.05-0.08 % by more than 8 levels, 0.03-0.05 levels on average.
//   Limits: 5 %, 0.25 %, 0.1 levels.
// - lit as a renderer draws them, the copied-out normals are area-weighted
//   over each vertex's triangles where the reference shader gives every
//   vertex its segment's own normal (6.4-6.6 degrees apart on average, up
//   to 35): 73-79 % of the foreground differs at all, 4.4-5.3 % by more
//   than 8 levels, 1.4-1.7 levels on average. Limits: 12 % and 4 levels;
//   and some difference must show (the two paths really are two).
const LIMITS = {
  'unlit': { over8: 0.0025, mean: 0.1, differing: 0.05 },
  'lit, shader normals': { over8: 0.0025, mean: 0.1, differing: 0.05 },
  'lit': { over8: 0.12, mean: 4 },
};

const args = process.argv.slice(2);
const option = (name, fallback) => {
  const i = args.indexOf(name);
  if (i < 0) return fallback;
  return args.splice(i, 2)[1];
};
const chromium = option('--chromium');
const work = option('--work');
const compare = option('--compare');
const pngPrefix = option('--png-prefix', 'render');
const names = args;
let failures = 0;
const fail = (what) => {
  failures += 1;
  console.log(`FAIL: ${what}`);
};

// 1. The shader port.
function checkShaderPort() {
  const reference = readFileSync(path.join(REPO, 'shaders/feather_instance.vert'), 'utf8');
  const es = toGlslEs300(reference);
  const a = reference.split('\n');
  const b = es.split('\n');
  const same = a[0].trim() === REFERENCE_VERSION && b[0] === '#version 300 es' &&
    b.slice(1, 1 + ES_HEADER.length).join('\n') === ES_HEADER.join('\n') &&
    b.slice(1 + ES_HEADER.length).join('\n') === a.slice(1).join('\n');
  if (!same) fail('the GLSL ES 3.00 port differs from the reference shader beyond its first line');
  const file = path.join(work, 'feather_instance_es300.vert');
  writeFileSync(file, es);
  const glslang = spawnSync('glslangValidator', [file], { encoding: 'utf8' });
  if (glslang.error) {
    console.log('shader port: only the version line differs; glslangValidator not found, so the ES compile check is left to Chromium');
  } else if (glslang.status !== 0) {
    fail(`glslangValidator rejects the GLSL ES 3.00 port:\n${glslang.stdout}${glslang.stderr}`);
  } else {
    console.log(`shader port: only the version line differs (+ ${ES_HEADER.length} precision lines); glslangValidator compiles ${path.basename(file)}`);
  }
}

// 2. The changed list on the CPU.
function checkChangedOnCpu(name) {
  const dir = path.join(work, name);
  const manifest = JSON.parse(readFileSync(path.join(dir, 'manifest.json'), 'utf8'));
  const n = manifest.feathers;
  const read = (file) => readFileSync(path.join(dir, file));
  let buffer = null;
  const listedPerFrame = [];
  let matching = 0;
  for (const f of manifest.frames) {
    const records = read(f.records);
    const changedBytes = read(f.changed);
    const listed = new Uint32Array(changedBytes.buffer, changedBytes.byteOffset, changedBytes.length / 4);
    if (records.length !== n * RECORD_BYTES) fail(`${name} frame ${f.index}: ${records.length} record bytes for ${n} feathers`);
    if (listed.length !== f.changed_count) fail(`${name} frame ${f.index}: ${listed.length} listed, the manifest says ${f.changed_count}`);
    for (let i = 0; i < listed.length; ++i) {
      if (listed[i] >= n || (i > 0 && listed[i] <= listed[i - 1])) {
        fail(`${name} frame ${f.index}: the list is not increasing within 0..${n - 1} at position ${i}`);
        break;
      }
    }
    if (buffer === null) {
      if (!f.all || listed.length !== n) fail(`${name}: the first frame does not list every feather`);
      buffer = Buffer.alloc(n * RECORD_BYTES, 0x7f);
    }
    let identical = 0;
    for (const i of listed) {
      const rec = records.subarray(i * RECORD_BYTES, (i + 1) * RECORD_BYTES);
      if (rec.equals(buffer.subarray(i * RECORD_BYTES, (i + 1) * RECORD_BYTES))) identical += 1;
      rec.copy(buffer, i * RECORD_BYTES);
    }
    if (!buffer.equals(records)) {
      let wrong = 0;
      for (let i = 0; i < n; ++i) {
        if (!buffer.subarray(i * RECORD_BYTES, (i + 1) * RECORD_BYTES).equals(records.subarray(i * RECORD_BYTES, (i + 1) * RECORD_BYTES))) wrong += 1;
      }
      fail(`${name} frame ${f.index}: after applying the ${listed.length} listed records, ${wrong} records differ from the full upload`);
      records.copy(buffer);
    } else {
      matching += 1;
    }
    listedPerFrame.push(`${listed.length}${f.all ? ' (all)' : ''}${identical ? `, ${identical} unchanged` : ''}`);
  }
  console.log(`${name}: changed list vs full upload, bytes: ${n} feathers, listed per frame ${listedPerFrame.join(' | ')}; ` +
    `${matching} of ${manifest.frames.length} frames (the first from nothing) built from the listed records alone equal the full records`);
  return manifest;
}

// How far the copied-out normals lie from the reference shader's (each
// segment's own): the angle at every vertex of a placed feather.
function normalAngles(name, manifest, frame) {
  const dir = path.join(work, name);
  const V = manifest.template.vertices;
  const n = manifest.feathers;
  const template = readFileSync(path.join(dir, manifest.template.file));
  const segments = new Uint32Array(template.buffer.slice(template.byteOffset + 20 * V, template.byteOffset + 24 * V));
  const records = readFileSync(path.join(dir, frame.records));
  const geometry = readFileSync(path.join(dir, frame.geometry));
  const copied = new Float32Array(geometry.buffer.slice(geometry.byteOffset + 12 * n * V, geometry.byteOffset + 24 * n * V));
  const shader = shaderNormals(records, n, segments);
  const angles = [];
  for (let f = 0; f < n; ++f) {
    if (!(decodeRecord(records, f).length > 0)) continue;
    for (let v = f * V; v < (f + 1) * V; ++v) {
      let dot = 0;
      for (let c = 0; c < 3; ++c) dot += copied[3 * v + c] * shader[3 * v + c];
      angles.push((Math.acos(Math.min(1, Math.max(-1, dot))) * 180) / Math.PI);
    }
  }
  angles.sort((a, b) => a - b);
  const mean = angles.reduce((a, b) => a + b, 0) / angles.length;
  const q = (p) => angles[Math.min(angles.length - 1, Math.floor(p * angles.length))];
  return `copied-out normals vs the shader's segment normals over ${angles.length} vertices: mean ${mean.toFixed(2)} deg, ` +
    `median ${q(0.5).toFixed(2)}, 95th percentile ${q(0.95).toFixed(2)}, largest ${angles[angles.length - 1].toFixed(2)}`;
}

function compareImages(a, b) {
  let differing = 0;
  let over8 = 0;
  let sum = 0;
  let foreground = 0;
  let sumForeground = 0;
  const background = [a[0], a[1], a[2]];
  const diff = Buffer.alloc(a.length);
  for (let p = 0; p < a.length; p += 4) {
    let d = 0;
    let s = 0;
    for (let c = 0; c < 3; ++c) {
      const e = Math.abs(a[p + c] - b[p + c]);
      d = Math.max(d, e);
      s += e;
    }
    const isBackground = (q) => q[p] === background[0] && q[p + 1] === background[1] && q[p + 2] === background[2];
    if (!isBackground(a) || !isBackground(b)) {
      foreground += 1;
      sumForeground += s / 3;
    }
    sum += s / 3;
    if (d > 0) differing += 1;
    if (d > 8) over8 += 1;
    const v = Math.min(255, 8 * d);
    diff[p] = 255;
    diff[p + 1] = 255 - v;
    diff[p + 2] = 255 - v;
    diff[p + 3] = 255;
  }
  const pixels = a.length / 4;
  return {
    differingPixels: differing,
    differing: differing / pixels,
    over8: over8 / pixels,
    mean: sum / pixels,
    foreground: foreground / pixels,
    differingOfForeground: differing / Math.max(foreground, 1),
    over8OfForeground: over8 / Math.max(foreground, 1),
    meanForeground: sumForeground / Math.max(foreground, 1),
    diff,
  };
}

const pct = (x) => `${(100 * x).toFixed(3)} %`;

async function main() {
  checkShaderPort();
  const manifests = {};
  for (const name of names) manifests[name] = checkChangedOnCpu(name);

  const { server, url } = await serve({ data: work });
  const browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--disable-dev-shm-usage'],
  });
  try {
    for (const name of names) {
      const page = await browser.newPage();
      const errors = [];
      page.on('console', (m) => { if (m.type() === 'error' || m.type() === 'warning') errors.push(m.text()); });
      page.on('pageerror', (e) => errors.push(String(e)));
      await page.setViewport({ width: WIDTH, height: HEIGHT });
      await page.goto(`${url}/viewer/?data=/data/${name}/&test=1&width=${WIDTH}&height=${HEIGHT}&aa=0`, { waitUntil: 'load' });
      await page.waitForFunction('window.plumageReady === true || window.plumageError !== undefined', { timeout: 60000 });
      const error = await page.evaluate(() => window.plumageError);
      if (error) throw new Error(`${name}: the viewer failed: ${error}`);
      const webgl = await page.evaluate(() => {
        const gl = window.plumageViewer.renderer.getContext();
        const info = gl.getExtension('WEBGL_debug_renderer_info');
        return `${gl.getParameter(gl.VERSION)}, ${info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER)}`;
      });
      // Draws frame k and returns its pixels.
      const draw = async (k, options) => {
        const b64 = await page.evaluate(async (k, options) => {
          const v = window.plumageViewer;
          v.setLit(options.lit ?? true);
          const geometryOptions = { shaderNormals: options.shaderNormals ?? false };
          if (options.changed) {
            const before = v.uploads.partial;
            await v.show(k, { mode: 'records', full: false, poison: true });
            if (v.uploads.partial !== before + 1) throw new Error(`frame ${k} was not drawn from a partial upload`);
          }
          else {
            await v.show(k, { mode: options.mode ?? 'records', full: options.full ?? true, ...geometryOptions });
          }
          v.render();
          return v.pixelsBase64();
        }, k, options);
        return Buffer.from(b64, 'base64');
      };
      const blank = (pixels) => {
        let other = 0;
        for (let p = 4; p < pixels.length; p += 4) if (pixels[p] !== pixels[0] || pixels[p + 1] !== pixels[1] || pixels[p + 2] !== pixels[2]) other += 1;
        return other / (pixels.length / 4);
      };

      // 3. Partial uploads on the GPU: one chain of frames, each uploading
      // only its listed records, against full uploads of each frame.
      const m = manifests[name];
      const chain = [];
      await draw(0, { full: true });
      for (let k = 1; k < m.frames.length; ++k) chain.push(await draw(k, { changed: true }));
      const partial = [];
      for (let k = 1; k < m.frames.length; ++k) {
        const fromFull = await draw(k, { full: true });
        const c = compareImages(chain[k - 1], fromFull);
        partial.push(c.differingPixels);
        if (c.differingPixels !== 0) fail(`${name} frame ${k}: drawn after uploading only the listed records since frame 0, ${c.differingPixels} pixels differ from a full upload`);
        if (blank(fromFull) < 0.01) fail(`${name} frame ${k}: the picture is blank`);
      }
      console.log(`${name}: GPU, frames 1..${m.frames.length - 1} from frame 0 uploading only the listed records (the others garbage on the CPU side) ` +
        `vs full uploads: differing pixels per frame ${partial.join(', ')} of ${WIDTH * HEIGHT} (${webgl})`);

      // 4. Records against copied-out geometry, on the frames that have it:
      // lit, lit with the shader's normals on the geometry, and unlit.
      for (const f of m.frames.filter((g) => g.geometry)) {
        console.log(`${name} frame ${f.index}${f.time === null ? ' (rest)' : ''}: ${normalAngles(name, m, f)}`);
        for (const [kind, lit, shaderNormals] of [['lit', true, false], ['lit, shader normals', true, true], ['unlit', false, false]]) {
          const records = await draw(f.index, { mode: 'records', lit });
          const geometry = await draw(f.index, { mode: 'geometry', lit, shaderNormals });
          const c = compareImages(records, geometry);
          const covered = blank(records);
          const label = `${name} frame ${f.index}, ${kind}`;
          console.log(`${label}: records vs geometry at ${WIDTH}x${HEIGHT}, foreground ${pct(c.foreground)} of the image; ` +
            `differing pixels ${pct(c.differingOfForeground)} of the foreground (${pct(c.differing)} of the image), ` +
            `more than 8 levels ${pct(c.over8OfForeground)} (${pct(c.over8)}), ` +
            `mean absolute difference ${c.meanForeground.toFixed(4)} levels of 255 over the foreground (${c.mean.toFixed(4)} over the image)`);
          if (covered < 0.05) fail(`${label}: only ${pct(covered)} of the picture is not background`);
          const limit = LIMITS[kind];
          const figures = { differing: c.differingOfForeground, over8: c.over8OfForeground, mean: c.meanForeground };
          for (const key of Object.keys(limit)) {
            const show = (x) => (key === 'mean' ? `${x.toFixed(4)} levels` : pct(x));
            if (!(figures[key] <= limit[key])) fail(`${label}: ${key} ${show(figures[key])} of the foreground, above the limit ${show(limit[key])}`);
          }
          if (kind === 'lit' && c.differing === 0) fail(`${label}: the two pictures are identical, though the normals differ: is one path drawn twice?`);
          if (blank(geometry) < 0.05) fail(`${label}: the geometry's picture is blank`);
          if (name === compare && kind === 'lit' && f.index === m.frames.length - 1) {
            const save = (suffix, rgba) => {
              const file = path.join(work, `${pngPrefix}_${suffix}.png`);
              writeFileSync(file, encodePng(WIDTH, HEIGHT, rgba));
              return file;
            };
            console.log(`wrote ${save('records', records)}, ${save('geometry', geometry)}, ${save('difference', c.diff)}`);
          }
        }
      }
      if (errors.length) fail(`${name}: the page logged:\n  ${errors.join('\n  ')}`);
      await page.close();
    }
  } finally {
    await browser.close();
    server.close();
  }
}

try {
  await main();
} catch (e) {
  fail(e.stack ?? String(e));
}
console.log(failures === 0 ? 'render test: all checks passed' : `render test: ${failures} check(s) failed`);
process.exit(failures === 0 ? 0 : 1);
