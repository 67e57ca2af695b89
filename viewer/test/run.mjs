// Browser tests of the viewer against prtkit's own outputs, in headless Chromium (SwiftShader).
//   node viewer/test/run.mjs [BIN_DIR]      (or PRTKIT_BIN=...; default target/release)
// Environment: CHROMIUM (default /usr/bin/chromium), PRTKIT_VIEWER_MAP (a lat-long .hdr/.exr;
// default ../shared/testdata/envmaps/uffizi_ict_latlong_256x128.hdr, else a synthetic sky made
// with sample-shader). Screenshots and figures go to out/viewer/. Last line: "N passed, M failed".
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, relative, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { PNG } from 'pngjs';
import puppeteer from 'puppeteer-core';
import { serve } from '../serve.mjs';

const repo = resolve(fileURLToPath(new URL('../..', import.meta.url)));
const bin = resolve(repo, process.argv[2] ?? process.env.PRTKIT_BIN ?? 'target/release');
const out = join(repo, 'out/viewer');
const chromium = process.env.CHROMIUM ?? '/usr/bin/chromium';
const t0 = Date.now();
mkdirSync(out, { recursive: true });

let passed = 0, failed = 0;
const figures = {};
function check(name, ok, detail) {
  if (ok) passed++; else failed++;
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${name}: ${detail}`);
}
function run(exe, args) {
  return execFileSync(join(bin, exe), args, { cwd: repo, stdio: ['ignore', 'pipe', 'pipe'] }).toString();
}
const url = (p) => '/' + relative(repo, p).split('\\').join('/');

// ---- the bake -------------------------------------------------------------------------------
for (const exe of ['ibl', 'render']) {
  if (!existsSync(join(bin, exe))) { console.error(`viewer tests: ${join(bin, exe)} missing (cargo build --release)`); process.exit(2); }
}
let map = process.env.PRTKIT_VIEWER_MAP ?? resolve(repo, '../shared/testdata/envmaps/uffizi_ict_latlong_256x128.hdr');
if (!existsSync(map)) {
  // The stand-in for the probe. Its sun is dimmed from the shader's 2000 to 200: the SH-diffuse
  // check compares order-2 SH irradiance with the exact irradiance cube, and a near-delta sun of
  // 2000 puts the truncation alone at 27 dB, below that check's bar, where the Uffizi probe's
  // broad windows leave it at 38 dB. At 200 the truncation is 42 dB and every other check is as
  // demanding.
  map = join(out, 'sky.exr');
  run('sample-shader', ['testdata/shaders/sky.sl', '--latlong', '256x128', '-p', 'sun_radiance=200', '-o', map, '-q']);
}
if (!map.startsWith(repo + '/')) { // the server serves the repository: copy the map in
  const copy = join(out, 'source' + map.slice(map.lastIndexOf('.')));
  writeFileSync(copy, readFileSync(map));
  map = copy;
}
const bake = join(out, 'bake');
rmSync(bake, { recursive: true, force: true });
run('ibl', [map, '-o', bake, '--size', '128', '--samples', '0', '-q']);
const manifest = JSON.parse(readFileSync(join(bake, 'ibl.json'), 'utf8'));
const M = manifest.frame.world_from_prtkit; // rows: d_out = M d_prtkit
const mul = (A, v) => A.map((row) => row[0] * v[0] + row[1] * v[1] + row[2] * v[2]);
const THREE_FROM_GL = [[-1, 0, 0], [0, 1, 0], [0, 0, 1]];

// ---- images ---------------------------------------------------------------------------------
function readPng(path) {
  const png = PNG.sync.read(readFileSync(path));
  return { width: png.width, height: png.height, rgba: png.data };
}
function writePng(path, img) {
  const png = new PNG({ width: img.width, height: img.height });
  img.rgba.copy ? img.rgba.copy(png.data) : png.data.set(img.rgba);
  writeFileSync(path, PNG.sync.write(png));
}
function fromPage(p) { // bottom-up RGBA from readPixels → top-down
  const src = Buffer.from(p.rgbaBottomUp, 'base64');
  const rgba = Buffer.alloc(src.length);
  const row = p.width * 4;
  for (let y = 0; y < p.height; y++) src.copy(rgba, y * row, (p.height - 1 - y) * row, (p.height - y) * row);
  return { width: p.width, height: p.height, rgba };
}
function mirrorX(img) {
  const rgba = Buffer.alloc(img.rgba.length);
  for (let y = 0; y < img.height; y++) {
    for (let x = 0; x < img.width; x++) {
      const a = (y * img.width + x) * 4, b = (y * img.width + img.width - 1 - x) * 4;
      for (let c = 0; c < 4; c++) rgba[a + c] = img.rgba[b + c];
    }
  }
  return { ...img, rgba };
}
// Mean |a − b| in sRGB codes and PSNR (peak 255) over the RGB of the pixels where mask is true.
function compare(a, b, mask = null) {
  let sum = 0, sq = 0, n = 0;
  for (let i = 0; i < a.width * a.height; i++) {
    if (mask && !mask[i]) continue;
    for (let c = 0; c < 3; c++) {
      const d = a.rgba[4 * i + c] - b.rgba[4 * i + c];
      sum += Math.abs(d); sq += d * d; n++;
    }
  }
  const mse = sq / n;
  return { mean: sum / n, psnr: mse === 0 ? Infinity : 10 * Math.log10((255 * 255) / mse), pixels: n / 3 };
}
function diffImage(a, b, gain = 8) {
  const rgba = Buffer.alloc(a.rgba.length);
  for (let i = 0; i < a.rgba.length; i += 4) {
    for (let c = 0; c < 3; c++) rgba[i + c] = Math.min(255, gain * Math.abs(a.rgba[i + c] - b.rgba[i + c]));
    rgba[i + 3] = 255;
  }
  return { ...a, rgba };
}

// prtkit render's camera (src/render/camera.rs): +Z up hint, ray through each pixel centre.
const sub = (a, b) => a.map((x, i) => x - b[i]);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
function sphereMask(eye, target, fov, w, h) {
  const f = norm(sub(target, eye));
  const right = norm(cross(f, [0, 0, 1]));
  const up = cross(right, f);
  const t = Math.tan((fov * Math.PI) / 360);
  const mask = new Uint8Array(w * h);
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const sx = (2 * (x + 0.5) / w - 1) * t * (w / h), sy = (1 - 2 * (y + 0.5) / h) * t;
      const d = norm([0, 1, 2].map((i) => f[i] + sx * right[i] + sy * up[i]));
      const b = dot(eye, d), c = dot(eye, eye) - 1;
      // Strictly inside the silhouette (one pixel of margin: a pixel whose centre grazes the rim
      // is the same pixel in both renders, but its neighbours mix sphere and sky differently).
      mask[y * w + x] = b * b - c > 0.02 ? 1 : 0;
    }
  }
  return mask;
}

// ---- the browser ----------------------------------------------------------------------------
const server = await serve({ root: repo });
const origin = `http://127.0.0.1:${server.address().port}`;
const profile = mkdtempSync(join(tmpdir(), 'prtkit-viewer-chromium-'));
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  userDataDir: profile,
  args: ['--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run',
    '--disable-quic', '--disable-dev-shm-usage'],
});
const pageErrors = [];
let gpuName = '';
async function view(params, { bench = 0, evaluate = null, arg = null, page: path = '/viewer/', requests = null } = {}) {
  const page = await browser.newPage();
  const logs = [];
  page.on('console', (m) => {
    const text = m.text();
    // Driver performance notes ("GPU stall due to ReadPixels") are not errors.
    if (/GL Driver Message \(OpenGL, Performance/.test(text)) return;
    if (/^BJS - \[[0-9:]+\]: Babylon\.js v[0-9.]+ - WebGL2$/.test(text)) return; // Babylon's start-up banner
    if (/^\[WebKit\], \[WebKit WebGL\], \[OpenGL ES 3\.0 \(WebGL 2\.0/.test(text)) return; // Filament's start-up banner
    if (m.type() === 'error' || /WebGL|GL_INVALID|GL ERROR/i.test(text)) logs.push(`${m.type()}: ${text}`);
  });
  page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
  if (requests) page.on('request', (r) => requests.push(r.url()));
  const [w, h] = params.res.split('x').map(Number);
  await page.setViewport({ width: w, height: h, deviceScaleFactor: 1 });
  const query = new URLSearchParams({ test: '1', ...params }).toString();
  await page.goto(`${origin}${path}?${query}`, { waitUntil: 'load' });
  const ok = await page.evaluate(() => window.prtkit.ready);
  const pixels = ok ? await page.evaluate(() => window.prtkit.pixels()) : null;
  const ms = ok && bench ? await page.evaluate((n) => window.prtkit.bench(n), bench) : null;
  const value = ok && evaluate ? await page.evaluate(evaluate, arg) : null;
  if (!gpuName && ok && path === '/viewer/') gpuName = await page.evaluate(() => window.prtkit.gpu());
  const errors = await page.evaluate(() => window.prtkit.errors.slice());
  await page.close();
  const all = [...logs, ...errors];
  if (all.length) pageErrors.push({ query, errors: all });
  if (!ok) throw new Error(`page failed: ${query}\n${all.join('\n')}`);
  return { image: fromPage(pixels), ms, value, errors: all };
}

// Cameras are given in prtkit's frame (+Z up), as to `render`; the page gets them in three.js's
// world: M e (glTF frame), then x negated when the page shows three.js's convention.
const toPage = (e, frame) => (frame === 'three' ? mul(THREE_FROM_GL, mul(M, e)) : mul(M, e)).map((x) => +x.toFixed(6)).join(',');
const FOV = 32, RES = '160x160';


// DIR/sphere.codes (encode-normals, onv-range, 32 bits), its report sphere.codes.json and
// DIR/decoder.glsl (--emit-decoder glsl) of a W×H lat-long table of the unit sphere's own normals
// in prtkit's frame (texel (x, y) at φ = 2π(x + ½)/W, θ = π(y + ½)/H); returns the normals.
function encodeSphereNormals(dir, W, H) {
  const normals = new Float32Array(W * H * 3);
  for (let y = 0; y < H; y++) {
    for (let x = 0; x < W; x++) {
      const t = (Math.PI * (y + 0.5)) / H, p = (2 * Math.PI * (x + 0.5)) / W, i = 3 * (y * W + x);
      normals[i] = Math.sin(t) * Math.cos(p); normals[i + 1] = Math.sin(t) * Math.sin(p); normals[i + 2] = Math.cos(t);
    }
  }
  writeFileSync(join(dir, 'sphere.f32'), Buffer.from(normals.buffer));
  run('encode-normals', [join(dir, 'sphere.f32'), '--scheme', 'onv-range', '--bits', '32', '-o', join(dir, 'sphere.codes'), '--report', join(dir, 'sphere.codes.json'), '-q']);
  writeFileSync(join(dir, 'decoder.glsl'), run('encode-normals', ['--emit-decoder', 'glsl', '--scheme', 'onv-range', '--bits', '32']));
  return normals;
}

// A fresh directory out/NAME holding sample-shader's sky, 256×128, as sky.exr.
function skyIn(name) {
  const dir = join(out, name);
  rmSync(dir, { recursive: true, force: true });
  mkdirSync(dir, { recursive: true });
  const sky = join(dir, 'sky.exr');
  run('sample-shader', ['testdata/shaders/sky.sl', '--latlong', '256x128', '-o', sky, '-q']);
  return { dir, sky };
}

// ---- SH irradiance, SHRMs, encoded normals (mode=irradiance|shrm|normals) ----------------------
// The map: sample-shader's sky (a sun at (0.45, 0.25, 0.6), nothing symmetric in x or y, so a
// mirrored or turned frame shows), 256×128, made here.
async function shTests() {
  const { dir, sky } = skyIn('sh');
  // The SH document is projected from convert's PFM copy of the map, the file the rotation test
  // turns (the EXR's and the PFM's projections differ by 5e-4 relative; the turn itself is exact).
  run('convert', [sky, '-o', join(dir, 'sky.pfm'), '-q']);
  run('sh-project', [join(dir, 'sky.pfm'), '-F', '2', '-o', join(dir, 'sky.sh.json'), '-q']);
  // −3 EV keeps the Lambert spheres below white (the sun's E/π is about 3); the SHRM highlights clip.
  let EXPOSURE = '-3';
  const [w, h] = RES.split('x').map(Number);
  const cams = [[3, -2.5, 1.2], [-1.5, 3.6, -1]];
  const pageCam = (eye, frame) => ({ eye: toPage(eye, frame), target: '0,0,0', fov: String(FOV), res: RES, exposure: EXPOSURE });
  // One scene in the page (both frames) against render's PNG: PSNR over the sphere; the other
  // frame's x convention with this frame's camera (the frame fix dropped) must fail the bar.
  async function against(name, refPng, eye, params, bar) {
    const ref = readPng(refPng);
    const mask = sphereMask(eye, [0, 0, 0], FOV, w, h);
    const fig = {};
    for (const frame of ['three', 'gl']) {
      let img = (await view({ ...params, frame, ...pageCam(eye, frame) })).image;
      if (frame === 'three') img = mirrorX(img);
      writePng(join(out, `${name}-viewer-${frame}.png`), img);
      writePng(join(out, `${name}-diff-${frame}-x8.png`), diffImage(img, ref));
      const c = compare(img, ref, mask);
      fig[frame] = c.psnr;
      check(`${name} (${frame} frame) vs render`, c.psnr >= bar, `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} sphere pixels (≥ ${bar}), mean |Δ| ${c.mean.toFixed(3)} codes`);
    }
    const wrong = mirrorX((await view({ ...params, frame: 'gl', ...pageCam(eye, 'three') })).image);
    const c = compare(wrong, ref, mask);
    fig.x_flipped = c.psnr;
    check(`${name}: the x flip dropped (gl frame, three's camera) fails`, c.psnr < bar - 5,
      `PSNR ${c.psnr.toFixed(2)} dB (must stay under ${bar - 5})`);
    figures[name] = fig;
    return fig;
  }
  const renderPng = (args, png, eye) => run('render', [...args, '--eye', eye.join(','), '--target', '0,0,0',
    '--fov', String(FOV), '--res', RES, '--png', png, '--exposure', EXPOSURE, '-q']);

  // 1. SH irradiance (sh-project's prtkit.sh) against render --shading irradiance --sh.
  const shUrl = url(join(dir, 'sky.sh.json'));
  for (const [i, eye] of cams.entries()) {
    const png = join(out, `irradiance-${i}-render.png`);
    renderPng([sky, '--shading', 'irradiance', '--sh', join(dir, 'sky.sh.json'), '--window', 'none'], png, eye);
    await against(`irradiance-${i}`, png, eye, { mode: 'irradiance', sh: shUrl, src: url(sky) }, 45);
  }
  // Rotation: the lighting turned 90° about +Z in the page (its SH coefficients rotated) against
  // render of the map itself turned 90° (its columns shifted by W/4: L'(φ) = L(φ − 90°)),
  // projected again by sh-project: an independent rotation.
  const pfm = readFileSync(join(dir, 'sky.pfm'));
  let nl = 0, hdr = 0;
  while (nl < 3) if (pfm[hdr++] === 0x0a) nl++;
  const turned = Buffer.from(pfm);
  const [PW, PH] = pfm.subarray(0, hdr).toString().split(/\s+/).slice(1, 3).map(Number);
  for (let y = 0; y < PH; y++) {
    for (let x = 0; x < PW; x++) {
      const from = hdr + 12 * (y * PW + ((x - PW / 4 + PW) % PW));
      pfm.copy(turned, hdr + 12 * (y * PW + x), from, from + 12);
    }
  }
  writeFileSync(join(dir, 'sky-turned90.pfm'), turned);
  run('sh-project', [join(dir, 'sky-turned90.pfm'), '-F', '2', '-o', join(dir, 'sky-turned90.sh.json'), '-q']);
  {
    const eye = cams[0];
    const png = join(out, 'irradiance-turned90-render.png');
    renderPng([join(dir, 'sky-turned90.pfm'), '--shading', 'irradiance', '--sh', join(dir, 'sky-turned90.sh.json'), '--window', 'none'], png, eye);
    const ref = readPng(png);
    const mask = sphereMask(eye, [0, 0, 0], FOV, w, h);
    const r = await view({ mode: 'irradiance', sh: shUrl, src: url(sky), rotate: '90', ...pageCam(eye, 'three') }, {
      evaluate: () => {
        const c = window.prtkit.sh(), rot = window.prtkit.rotateShZ;
        const err = (a, b) => Math.max(...a.flatMap((x, i) => x.map((v, k) => Math.abs(v - b[i][k]))));
        return { c, turned: rot(c, Math.PI / 2), full: err(rot(c, 2 * Math.PI), c), back: err(rot(rot(c, 0.7), -0.7), c),
          compose: err(rot(rot(c, 0.3), 0.4), rot(c, 0.7)) };
      },
    });
    const img = mirrorX(r.image);
    writePng(join(out, 'irradiance-turned90-viewer-three.png'), img);
    const c = compare(img, ref, mask);
    const bg = mask.map((x) => (x ? 0 : 1));
    const b = compare(img, ref, bg);
    const prt = JSON.parse(readFileSync(join(dir, 'sky-turned90.sh.json'), 'utf8')).coefficients;
    const scale = Math.max(...prt.flat().map(Math.abs));
    const coefErr = Math.max(...r.value.turned.flatMap((x, i) => x.map((v, k) => Math.abs(v - prt[i][k])))) / scale;
    figures.irradiance_turned90 = { psnr: c.psnr, background_mean: b.mean, coefficient_rel_error: coefErr, identity: r.value };
    delete figures.irradiance_turned90.identity.c; delete figures.irradiance_turned90.identity.turned;
    check('irradiance turned 90° in the page (SH rotation) vs render of the map turned 90°', c.psnr >= 45,
      `PSNR ${c.psnr.toFixed(2)} dB (≥ 45); coefficients vs sh-project of the turned map: max rel. error ${coefErr.toExponential(2)}; background (three's equirect, turned) mean |Δ| ${b.mean.toFixed(2)} codes`);
    check('irradiance turned: three\'s equirect background turned with it vs render\'s background of the turned map', b.mean <= 1.5,
      `mean |Δ| ${b.mean.toFixed(3)} codes (≤ 1.5)`);
    check('SH rotation identities (360°, +θ then −θ, 0.3 then 0.4 = 0.7)', Math.max(r.value.full, r.value.back, r.value.compose) <= 1e-6,
      `max |Δ| ${r.value.full.toExponential(1)}, ${r.value.back.toExponential(1)}, ${r.value.compose.toExponential(1)} (≤ 1e-6)`);
    check('irradiance turned: coefficients match sh-project of the turned map', coefErr <= 1e-6, `max rel. error ${coefErr.toExponential(2)} (≤ 1e-6)`);
    // The turn's direction reversed must fail.
    const wrong = mirrorX((await view({ mode: 'irradiance', sh: shUrl, rotate: '-90', ...pageCam(eye, 'three') })).image);
    const cw = compare(wrong, ref, mask);
    figures.irradiance_turned90.reversed_psnr = cw.psnr;
    check('irradiance turned the other way (−90°) fails', cw.psnr < 40, `PSNR ${cw.psnr.toFixed(2)} dB (< 40)`);
  }

  EXPOSURE = '-2';
  // 2. SHRMs (prefilter --shrm) against render --shading shrm: Phong s = 16 (P_B = 0) and a
  // Torrance–Sparrow σ = 0.3 (P_B = 6: the view bands, eq. 6, per pixel).
  for (const [name, brdf, extra] of [['shrm-phong16', 'phong:s=16', []], ['shrm-ts0.3', 'torrance-sparrow:sigma=0.3', ['--size', '128x64']]]) {
    const json = join(dir, `${name}.json`);
    run('prefilter', [sky, '--brdf', brdf, ...extra, '--shrm', join(dir, `${name}.exr`), '-o', json, '-q']);
    const eye = cams[0];
    const png = join(out, `${name}-render.png`);
    renderPng([sky, '--shading', 'shrm', '--shrm', json, '--brdf', brdf, '--window', 'none'], png, eye);
    await against(name, png, eye, { mode: 'shrm', shrm: url(json), src: url(sky) }, 35);
  }

  // 3. Normals from encode-normals: a 256×128 lat-long table of the sphere's own normals (prtkit's
  // frame), 32-bit onv-range codes, decoded in the shader by the emitted GLSL decoder.
  const NW = 256, NH = 128;
  const normals = encodeSphereNormals(dir, NW, NH);
  const report = JSON.parse(readFileSync(join(dir, 'sphere.codes.json'), 'utf8'));
  const nParams = { mode: 'normals', sh: shUrl, src: url(sky), codes: url(join(dir, 'sphere.codes')), report: url(join(dir, 'sphere.codes.json')),
    decoder: url(join(dir, 'decoder.glsl')), size: `${NW}x${NH}` };
  {
    const r = await view({ ...nParams, ...pageCam(cams[0], 'three') }, { evaluate: () => window.prtkit.decodedNormals() });
    let worst = 0;
    for (let i = 0; i < NW * NH; i++) {
      const a = [normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]], b = r.value.slice(3 * i, 3 * i + 3);
      const na = norm(a);
      worst = Math.max(worst, Math.atan2(Math.hypot(...cross(na, b)), dot(na, b)));
    }
    figures.normals_decode = { max_angle: worst, bound: report.bound, cpu_max: report.error.max };
    check('normals decoded on the GPU by the emitted GLSL decoder vs the source normals', worst <= report.bound,
      `max angle ${worst.toExponential(3)} rad over ${NW * NH} codes (≤ the report's bound ${report.bound.toExponential(3)}; encode-normals' own max ${report.error.max.toExponential(3)})`);
  }
  EXPOSURE = '-3';
  for (const [i, eye] of cams.entries()) {
    const png = join(out, `irradiance-${i}-render.png`); // the same scene: E(n) of the decoded normal
    await against(`normals-${i}`, png, eye, nParams, 45);
  }

  // 4. Frame time of each mode at 640×360 (SwiftShader: the CPU), the lighting turning 1° a frame
  // (SH modes: the 9 coefficients rotated in JS and uploaded every frame).
  const times = {};
  for (const [key, params] of [['irradiance', { mode: 'irradiance', sh: shUrl }], ['shrm-phong16', { mode: 'shrm', shrm: url(join(dir, 'shrm-phong16.json')) }],
    ['shrm-ts0.3', { mode: 'shrm', shrm: url(join(dir, 'shrm-ts0.3.json')) }], ['normals', nParams]]) {
    const r = await view({ ...params, src: url(sky), eye: '0,0,4', target: '0,0,0', fov: '32', res: '640x360', exposure: '-2.5' }, { bench: 10 });
    times[key] = r.ms;
    writePng(join(out, `mode-${key}.png`), r.image);
    console.log(`     frame time ${key} 640×360: ${r.ms.toFixed(1)} ms (CPU, SwiftShader)`);
  }
  figures.frame_ms_640x360_sh = times;
}

// ---- PRT relighting (mode=prt) against render --shading transfer ------------------------------
// The torus knot (its loops shadow each other) baked by `transfer` (shadowed, n = 5), relit in the
// page from sh-project's SH of the sky (order 4, the bake's bands) against render's CPU relighting
// of the same .glb, with the environment as stored and turned 60° (SH rotation in both).
// Compared over the mesh's pixels less a one-pixel rim (the two rasterizers' silhouettes differ).
function meshMask(img) {
  const { width: w, height: h } = img;
  const lit = (x, y) => x >= 0 && y >= 0 && x < w && y < h && [0, 1, 2].some((c) => img.rgba[4 * (y * w + x) + c] !== 0);
  const mask = new Array(w * h).fill(false);
  for (let y = 0; y < h; y++) for (let x = 0; x < w; x++) {
    mask[y * w + x] = [[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]].every(([dx, dy]) => lit(x + dx, y + dy));
  }
  return mask;
}
async function prtTests() {
  const { dir, sky } = skyIn('prt');
  const mesh = 'testdata/meshes/torus-knot.obj', glb = join(dir, 'knot5.glb');
  run('transfer', [mesh, '-n', '5', '--mode', 'shadowed', '--rays', '256', '--glb', glb, '-o', join(dir, 'knot5.json'), '-q']);
  run('sh-project', [sky, '-F', '4', '-o', join(dir, 'sky4.sh.json'), '-q']);
  const eye = [2.2, -3.4, 2.4], RESP = '200x200', EXP = '-2';
  const pageCam = (frame) => ({ eye: toPage(eye, frame), target: '0,0,0', fov: String(FOV), res: RESP, exposure: EXP });
  const params = { mode: 'prt', glb: url(glb), sh: url(join(dir, 'sky4.sh.json')) };
  const fig = {};
  for (const deg of [0, 60]) {
    const png = join(out, `prt-${deg}-render.png`);
    run('render', [sky, '--scene', mesh, '--shading', 'transfer', '--transfer', glb, '--env-rotation', String(deg),
      '--eye', eye.join(','), '--target', '0,0,0', '--fov', String(FOV), '--res', RESP, '--png', png, '--exposure', EXP, '-q']);
    const ref = readPng(png);
    for (const frame of ['three', 'gl']) {
      let img = (await view({ ...params, rotate: String(deg), frame, ...pageCam(frame) })).image;
      if (frame === 'three') img = mirrorX(img);
      writePng(join(out, `prt-${deg}-viewer-${frame}.png`), img);
      writePng(join(out, `prt-${deg}-diff-${frame}-x8.png`), diffImage(img, ref));
      const c = compare(img, ref, meshMask(img));
      fig[`turned${deg}_${frame}`] = c.psnr;
      check(`prt knot n = 5, environment turned ${deg}° (${frame} frame) vs render --shading transfer`, c.psnr >= 35,
        `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} mesh pixels (≥ 35), mean |Δ| ${c.mean.toFixed(3)} codes`);
    }
    if (deg === 0) continue;
    // Negative controls: the SH rotation's sign reversed, and the frame's x flip dropped.
    const reversed = mirrorX((await view({ ...params, rotate: String(-deg), ...pageCam('three') })).image);
    const r = compare(reversed, ref, meshMask(reversed));
    fig.reversed = r.psnr;
    check(`prt turned −${deg}° instead of ${deg}° fails`, r.psnr < 30, `PSNR ${r.psnr.toFixed(2)} dB (< 30)`);
    const flipped = mirrorX((await view({ ...params, rotate: String(deg), frame: 'gl', ...pageCam('three') })).image);
    const f = compare(flipped, ref, meshMask(flipped));
    fig.x_flipped = f.psnr;
    check('prt with the x flip dropped (gl frame, three\'s camera) fails', f.psnr < 30, `PSNR ${f.psnr.toFixed(2)} dB (< 30)`);
  }
  const r = await view({ ...params, rotate: '30', src: url(sky), eye: toPage([2.6, -4, 2.8], 'three'), target: '0,0,0', fov: '32', res: '640x360', exposure: EXP }, { bench: 20 });
  writePng(join(out, 'mode-prt.png'), r.image);
  fig.frame_ms_640x360 = r.ms;
  console.log(`     frame time prt (n = 5, knot) 640×360: ${r.ms.toFixed(1)} ms (CPU, SwiftShader)`);
  figures.prt = fig;
}

// ---- Glossy PRT (mode=prt, a transfer --factors bake) against render --shading transfer ----------
// The bowl holding a ball, Phong s = 8 factored on a 16² hemisphere grid (K = 10 of 16 terms),
// baked at n = 4 (shadowed); the page computes c_k per vertex from the transfer texture and
// evaluates B = Σ_k h_k(Fᵀω_o) c_k per pixel with the emitted GLSL snippet; render relights
// the same .glb on the CPU (its own h_k lookup, render::factored). Environment as stored and
// turned 60° (SH rotation per frame in the page), both frames, over the mesh less a rim.
async function glossyPrtTests() {
  const { dir, sky } = skyIn('prt-glossy');
  const mesh = 'testdata/meshes/bowl-ball.obj', glb = join(dir, 'g.glb'), glsl = join(dir, 'g.glsl');
  run('factor-brdf', ['phong:s=8', '--domain', 'hemisphere', '--resolution', '16', '--cosine',
    '--factors', join(dir, 'p.exr'), '--terms', '16', '-o', join(dir, 'p.json'), '-q']);
  run('transfer', [mesh, '-n', '4', '--factors', join(dir, 'p.json'), '-K', '10', '--glb', glb, '-o', join(dir, 'g.json'),
    '--glsl', glsl, '-q']);
  run('sh-project', [sky, '-F', '3', '-o', join(dir, 'sky3.sh.json'), '-q']);
  const eye = [1.3, -2.2, 2.4], target = [0, 0, -0.45], RESP = '200x200', EXP = '-3.5';
  const pageCam = (frame) => ({ eye: toPage(eye, frame), target: toPage(target, frame), fov: String(FOV), res: RESP, exposure: EXP });
  const params = { mode: 'prt', glb: url(glb), sh: url(join(dir, 'sky3.sh.json')), glsl: url(glsl) };
  const fig = {};
  for (const deg of [0, 60]) {
    const png = join(out, `prt-glossy-${deg}-render.png`);
    run('render', [sky, '--scene', mesh, '--brdf', 'phong:s=8', '--shading', 'transfer', '--transfer', glb, '--env-rotation', String(deg),
      '--eye', eye.join(','), '--target', target.join(','), '--fov', String(FOV), '--res', RESP, '--png', png, '--exposure', EXP, '-q']);
    const ref = readPng(png);
    for (const frame of ['three', 'gl']) {
      let img = (await view({ ...params, rotate: String(deg), frame, ...pageCam(frame) })).image;
      if (frame === 'three') img = mirrorX(img);
      writePng(join(out, `prt-glossy-${deg}-viewer-${frame}.png`), img);
      writePng(join(out, `prt-glossy-${deg}-diff-${frame}-x8.png`), diffImage(img, ref));
      const c = compare(img, ref, meshMask(img));
      fig[`turned${deg}_${frame}`] = c.psnr;
      check(`prt glossy bowl-ball (Phong s = 8, K = 10, n = 4), environment turned ${deg}° (${frame} frame) vs render --shading transfer`, c.psnr >= 35,
        `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} mesh pixels (≥ 35), mean |Δ| ${c.mean.toFixed(3)} codes`);
    }
    if (deg === 0) continue;
    const reversed = mirrorX((await view({ ...params, rotate: String(-deg), ...pageCam('three') })).image);
    const r = compare(reversed, ref, meshMask(reversed));
    fig.reversed = r.psnr;
    check(`prt glossy turned −${deg}° instead of ${deg}° fails`, r.psnr < 30, `PSNR ${r.psnr.toFixed(2)} dB (< 30)`);
    const flipped = mirrorX((await view({ ...params, rotate: String(deg), frame: 'gl', ...pageCam('three') })).image);
    const f = compare(flipped, ref, meshMask(flipped));
    fig.x_flipped = f.psnr;
    check('prt glossy with the x flip dropped (gl frame, three\'s camera) fails', f.psnr < 30, `PSNR ${f.psnr.toFixed(2)} dB (< 30)`);
  }
  // n = 3: 9 coefficients a term, so four-vectors of the transfer straddle two terms (the
  // vertex shader's other path).
  {
    const glb3 = join(dir, 'g3.glb'), glsl3 = join(dir, 'g3.glsl'), png = join(out, 'prt-glossy-n3-60-render.png');
    run('transfer', [mesh, '-n', '3', '--factors', join(dir, 'p.json'), '-K', '10', '--glb', glb3, '-o', join(dir, 'g3.json'), '--glsl', glsl3, '-q']);
    run('render', [sky, '--scene', mesh, '--brdf', 'phong:s=8', '--shading', 'transfer', '--transfer', glb3, '--env-rotation', '60',
      '--eye', eye.join(','), '--target', target.join(','), '--fov', String(FOV), '--res', RESP, '--png', png, '--exposure', EXP, '-q']);
    const ref = readPng(png);
    const img = mirrorX((await view({ ...params, glb: url(glb3), glsl: url(glsl3), rotate: '60', ...pageCam('three') })).image);
    writePng(join(out, 'prt-glossy-n3-60-viewer-three.png'), img);
    const c = compare(img, ref, meshMask(img));
    fig.n3_turned60_three = c.psnr;
    check('prt glossy n = 3 (terms straddle four-vectors), turned 60° (three frame) vs render --shading transfer', c.psnr >= 35,
      `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} mesh pixels (≥ 35), mean |Δ| ${c.mean.toFixed(3)} codes`);
  }
  const r = await view({ ...params, rotate: '30', src: url(sky), eye: toPage([1.6, -2.6, 2.2], 'three'), target: toPage(target, 'three'),
    fov: '32', res: '640x360', exposure: EXP }, { bench: 20 });
  writePng(join(out, 'mode-prt-glossy.png'), r.image);
  fig.frame_ms_640x360 = r.ms;
  console.log(`     frame time prt glossy (K = 10, n = 4, bowl-ball) 640×360: ${r.ms.toFixed(1)} ms (CPU, SwiftShader)`);
  figures.prt_glossy = fig;
}

// ---- The glossy snippet's h_k lookup itself against the documented rule --------------------------
// The image tests above cannot see every fault of the lookup: neighbouring φ columns of h differ
// little, so the last column's neighbour clamped instead of wrapped to column 0 (the seam at
// φ = 0) moves a pixel by a fraction of a code. Here the page runs the emitted snippet's own
// prtkitGlossyCosThetaPhi, prtkitGlossyTaps and prtkitGlossyH (window.prtkit.glossyLookup) for
// chosen directions of the normal's frame into an RGBA32F target, and each value is compared with
// the rule docs/transfer.md ("Glossy bakes") states, evaluated here in double precision from the
// .glb's glossy.h blob: bilinear between the cell centres cos θ_j = 1 − (j + ½)·span/N and
// φ_k = (k + ½)·2π/N, φ wrapping, cos θ clamped to the first and last rows (a hemisphere grid's
// views below the horizon read the horizon row), and within half a bin of a pole a linear blend
// into the mean of the pole's ring. The reference is written in another form than the snippet's
// index arithmetic: tent weights max(0, 1 − distance/bin) over every row and column, φ's distance
// taken around the circle.

// The glossy.h table of a transfer .glb (read from the file, not through the page).
function glossyTable(glbPath) {
  const b = readFileSync(glbPath);
  const jsonLength = b.readUInt32LE(12);
  const gltf = JSON.parse(b.subarray(20, 20 + jsonLength).toString());
  const bin = 20 + jsonLength + 8; // the BIN chunk's data, after its length and type
  const extras = gltf.meshes[0].extras;
  const g = extras['prtkit.transfer'].glossy, blob = extras['prtkit.blobs']['glossy.h'];
  const start = bin + (gltf.bufferViews[blob.bufferView].byteOffset ?? 0);
  const h = Array.from({ length: blob.count }, (_, i) => b.readFloatLE(start + 4 * i));
  return { N: g.resolution, K: g.terms, sphere: g.domain === 'sphere', h };
}
// h_t(w) for every term t by the documented rule; h[t·N² + j·N + k] is h_t of cell (j, k).
function glossyReference({ N, K, sphere, h }, w) {
  const TAU = 2 * Math.PI, dz = (sphere ? 2 : 1) / N, dphi = TAU / N;
  const zc = (j) => 1 - (j + 0.5) * dz;
  const z = Math.max(Math.min(w[2], 1), sphere ? -1 : 0);
  const phi = w[0] === 0 && w[1] === 0 ? 0 : (Math.atan2(w[1], w[0]) + TAU) % TAU;
  let pole = 0, poleRow = 0; // the pole's weight (1 at the pole, 0 half a bin away) and its ring
  if (z > zc(0)) pole = (z - zc(0)) / (dz / 2);
  else if (sphere && z < zc(N - 1)) [pole, poleRow] = [(zc(N - 1) - z) / (dz / 2), N - 1];
  const zr = Math.min(Math.max(z, zc(N - 1)), zc(0));
  const tent = (d, step) => Math.max(0, 1 - Math.abs(d) / step);
  const around = (d) => { const a = ((d % TAU) + TAU) % TAU; return Math.min(a, TAU - a); };
  const wRow = Array.from({ length: N }, (_, j) => tent(zr - zc(j), dz));
  const wCol = Array.from({ length: N }, (_, k) => tent(around(phi - (k + 0.5) * dphi), dphi));
  return Array.from({ length: K }, (_, t) => {
    let ring = 0, mean = 0;
    for (let j = 0; j < N; j++) for (let k = 0; k < N; k++) ring += wRow[j] * wCol[k] * h[t * N * N + j * N + k];
    for (let k = 0; k < N; k++) mean += h[t * N * N + poleRow * N + k] / N;
    return (1 - pole) * ring + pole * mean;
  });
}
// Directions (f32, as the page gets them): φ within half a column either side of the seam
// (between column N − 1 and column 0) and three φ away from it, at rows mid-table, within half a
// bin of the top pole (and on it), near the bottom (the sphere's pole; the hemisphere's horizon
// row, the horizon and below it); then 40 pseudo-random directions.
function glossyDirections(N, sphere) {
  const dz = (sphere ? 2 : 1) / N, bin = (2 * Math.PI) / N;
  const at = (z, phi) => { const s = Math.sqrt(1 - z * z); return [s * Math.cos(phi), s * Math.sin(phi), z].map(Math.fround); };
  const phis = [...[0, 0.05, 0.2, 0.45, -0.05, -0.2, -0.45].map((f) => f * bin), 1.3, 2.9, 4.4];
  const top = [1, 1 - 0.1 * dz, 1 - 0.4 * dz, 1 - 0.55 * dz];
  const bottom = sphere ? top.map((z) => -z) : [0.6 * dz, 0.4 * dz, 0, -0.3];
  const mid = sphere ? [0.7, 0.1, -0.45] : [0.83, 0.5, 0.21];
  const dirs = [...mid, ...top, ...bottom].flatMap((z) => phis.map((phi) => at(z, phi)));
  let seed = 12345;
  const rand = () => (seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648;
  for (let i = 0; i < 40; i++) dirs.push(at(sphere ? 2 * rand() - 1 : rand(), 2 * Math.PI * rand()));
  return dirs;
}
async function glossyLookupTests() {
  const { dir, sky } = skyIn('prt-lookup');
  run('sh-project', [sky, '-F', '1', '-o', join(dir, 'sky1.sh.json'), '-q']);
  const fig = {};
  // The image tests' grid (Phong s = 8, 16² hemisphere, cosine) and a 12² sphere grid (both poles).
  for (const g of [{ name: 'hemisphere16', args: ['--domain', 'hemisphere', '--resolution', '16', '--cosine'] },
    { name: 'sphere12', args: ['--domain', 'sphere', '--resolution', '12'] }]) {
    const glb = join(dir, `${g.name}.glb`), glsl = join(dir, `${g.name}.glsl`);
    run('factor-brdf', ['phong:s=8', ...g.args, '--factors', join(dir, `${g.name}.exr`), '--terms', '8', '-o', join(dir, `${g.name}.json`), '-q']);
    run('transfer', ['testdata/meshes/bowl-ball.obj', '-n', '2', '--rays', '16', '--factors', join(dir, `${g.name}.json`), '-K', '6',
      '--glb', glb, '-o', join(dir, `${g.name}-bake.json`), '--glsl', glsl, '-q']);
    const table = glossyTable(glb), dirs = glossyDirections(table.N, table.sphere);
    const got = (await view({ mode: 'prt', glb: url(glb), glsl: url(glsl), sh: url(join(dir, 'sky1.sh.json')), res: '16x16' },
      { evaluate: (d) => window.prtkit.glossyLookup(d), arg: dirs })).value;
    // Tolerance: f32 arithmetic in the shader. φ from a float atan is good to about 1e-6 rad,
    // which moves the bilinear weights by 2.5e-6·N/16 of a column, i.e. the value by that much of
    // the largest difference between neighbours (≤ 2 max|h_t|); the weights and the sum of at
    // most N + 4 products add a few float ulps. So |Δ| ≤ 1e-5 · max|h_t|, term by term.
    let worst = 0, worstAt = '';
    dirs.forEach((w, i) => {
      const want = glossyReference(table, w);
      for (let t = 0; t < table.K; t++) {
        const scale = Math.max(...table.h.slice(t * table.N ** 2, (t + 1) * table.N ** 2).map(Math.abs));
        const e = Math.abs(got[t][i] - want[t]) / scale;
        if (e > worst) [worst, worstAt] = [e, `term ${t}, w = (${w.map((x) => x.toFixed(4)).join(', ')})`];
      }
    });
    fig[g.name] = { values: dirs.length * table.K, max_rel_error: worst, at: worstAt };
    check(`glossy snippet's h_k lookup (${table.N}² ${table.sphere ? 'sphere' : 'hemisphere'} grid, K = ${table.K}) vs the documented rule, ${dirs.length} directions (φ seam, poles, horizon)`,
      worst <= 1e-5, `max |Δ| ${worst.toExponential(2)} of max|h_t| (≤ 1e-5) at ${worstAt}`);
  }
  figures.glossy_lookup = fig;
}

// ---- Compressed PRT (mode=prt, transfer --clusters C --pca P) against render --shading transfer --
// The page relights a clustered-PCA bake in compressed form (per frame the lighting against each
// cluster's mean and directions on the CPU, then P multiply-adds per vertex and term in the vertex
// shader); render relights the same .glb in compressed form on the CPU (render::transfer::relight).
// Diffuse (n = 3) and glossy (Phong s = 8, K = 10, n = 4) bakes of the bowl, as stored and turned
// 60°, both frames, over the mesh less a rim. Negative control: the same .glb with every vertex's
// cluster moved to the next one (c + 1 mod C; the page reads another cluster's mean and
// directions) must fail the bar.

// A copy of the .glb `from` at `to` with _PRT_CLUSTER's values c replaced by (c + 1) mod C.
function shiftClusters(from, to) {
  const b = Buffer.from(readFileSync(from));
  const jsonLength = b.readUInt32LE(12);
  const gltf = JSON.parse(b.subarray(20, 20 + jsonLength).toString());
  const bin = 20 + jsonLength + 8; // the BIN chunk's data, after its length and type
  const mesh = gltf.meshes[0];
  const C = mesh.extras['prtkit.transfer'].cpca.clusters;
  const accessor = gltf.accessors[mesh.primitives[0].attributes._PRT_CLUSTER];
  const view = gltf.bufferViews[accessor.bufferView];
  const start = bin + (view.byteOffset ?? 0) + (accessor.byteOffset ?? 0);
  for (let v = 0; v < accessor.count; v++) b.writeFloatLE((b.readFloatLE(start + 4 * v) + 1) % C, start + 4 * v);
  writeFileSync(to, b);
}
async function cpcaPrtTests() {
  const { dir, sky } = skyIn('prt-cpca');
  const mesh = 'testdata/meshes/bowl-ball.obj';
  run('factor-brdf', ['phong:s=8', '--domain', 'hemisphere', '--resolution', '16', '--cosine',
    '--factors', join(dir, 'p.exr'), '--terms', '16', '-o', join(dir, 'p.json'), '-q']);
  const bakes = [
    { name: 'diffuse', what: 'diffuse n = 3, 8 clusters × 4', n: 3, exp: '-2.5', brdf: [],
      args: ['-n', '3', '--rays', '256', '--clusters', '8', '--pca', '4'] },
    { name: 'glossy', what: 'glossy Phong s = 8, K = 10, n = 4, 16 clusters × 8', n: 4, exp: '-3.5', brdf: ['--brdf', 'phong:s=8'],
      args: ['-n', '4', '--factors', join(dir, 'p.json'), '-K', '10', '--clusters', '16', '--pca', '8'] },
  ];
  const eye = [1.3, -2.2, 2.4], target = [0, 0, -0.45], RESP = '200x200';
  const fig = {};
  for (const b of bakes) {
    const glb = join(dir, `${b.name}.glb`), glsl = join(dir, `${b.name}.glsl`), shifted = join(dir, `${b.name}-shifted.glb`);
    run('transfer', [mesh, ...b.args, '--glb', glb, '-o', join(dir, `${b.name}.json`), '--glsl', glsl, '-q']);
    const compression = JSON.parse(readFileSync(join(dir, `${b.name}.json`), 'utf8')).compression;
    shiftClusters(glb, shifted);
    const sh = join(dir, `sky${b.n - 1}.sh.json`);
    if (!existsSync(sh)) run('sh-project', [sky, '-F', String(b.n - 1), '-o', sh, '-q']);
    const pageCam = (frame) => ({ eye: toPage(eye, frame), target: toPage(target, frame), fov: String(FOV), res: RESP, exposure: b.exp });
    const params = { mode: 'prt', glb: url(glb), sh: url(sh), ...(b.brdf.length ? { glsl: url(glsl) } : {}) };
    const f = { relative_rms: compression.relative_rms };
    for (const deg of [0, 60]) {
      const png = join(out, `prt-cpca-${b.name}-${deg}-render.png`);
      run('render', [sky, '--scene', mesh, ...b.brdf, '--shading', 'transfer', '--transfer', glb, '--env-rotation', String(deg),
        '--eye', eye.join(','), '--target', target.join(','), '--fov', String(FOV), '--res', RESP, '--png', png, '--exposure', b.exp, '-q']);
      const ref = readPng(png);
      for (const frame of ['three', 'gl']) {
        let img = (await view({ ...params, rotate: String(deg), frame, ...pageCam(frame) })).image;
        if (frame === 'three') img = mirrorX(img);
        writePng(join(out, `prt-cpca-${b.name}-${deg}-viewer-${frame}.png`), img);
        writePng(join(out, `prt-cpca-${b.name}-${deg}-diff-${frame}-x8.png`), diffImage(img, ref));
        const c = compare(img, ref, meshMask(img));
        f[`turned${deg}_${frame}`] = c.psnr;
        check(`prt compressed ${b.what}, environment turned ${deg}° (${frame} frame) vs render --shading transfer`, c.psnr >= 35,
          `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} mesh pixels (≥ 35), mean |Δ| ${c.mean.toFixed(3)} codes`);
      }
      if (deg === 0) continue;
      const wrong = mirrorX((await view({ ...params, glb: url(shifted), rotate: String(deg), ...pageCam('three') })).image);
      writePng(join(out, `prt-cpca-${b.name}-${deg}-shifted-clusters-three.png`), wrong);
      const w = compare(wrong, ref, meshMask(wrong));
      f.clusters_shifted = w.psnr;
      check(`prt compressed ${b.name} with every vertex's cluster moved to the next (c + 1 mod C) fails`, w.psnr < 30,
        `PSNR ${w.psnr.toFixed(2)} dB (< 30)`);
    }
    if (b.name === 'glossy') {
      const r = await view({ ...params, rotate: '30', src: url(sky), eye: toPage([1.6, -2.6, 2.2], 'three'), target: toPage(target, 'three'),
        fov: '32', res: '640x360', exposure: b.exp }, { bench: 20 });
      writePng(join(out, 'mode-prt-cpca-glossy.png'), r.image);
      f.frame_ms_640x360 = r.ms;
      console.log(`     frame time prt compressed ${b.what} 640×360: ${r.ms.toFixed(1)} ms (CPU, SwiftShader)`);
    }
    fig[b.name] = f;
  }
  figures.prt_cpca = fig;
}

// One bake `b` ({ name, mesh, n, args, brdf, eye, target, exp }) of group `group`: baked by
// transfer (with its GLSL snippet, which a glossy bake's page needs), relit by the page with the
// environment turned 60° (three frame) and by render --shading transfer of the same .glb, compared
// over the mesh less a rim (PSNR ≥ 35 dB). Returns the PSNR.
async function relitAt60(dir, sky, b, group, label) {
  const glb = join(dir, `${b.name}.glb`), glsl = join(dir, `${b.name}.glsl`), png = join(out, `prt-${group}-${b.name}-60-render.png`);
  run('transfer', [b.mesh, ...b.args, '--glb', glb, '-o', join(dir, `${b.name}.json`), '--glsl', glsl, '-q']);
  const sh = join(dir, `sky${b.n - 1}.sh.json`);
  if (!existsSync(sh)) run('sh-project', [sky, '-F', String(b.n - 1), '-o', sh, '-q']);
  run('render', [sky, '--scene', b.mesh, ...b.brdf, '--shading', 'transfer', '--transfer', glb, '--env-rotation', '60',
    '--eye', b.eye.join(','), '--target', b.target.join(','), '--fov', String(FOV), '--res', '200x200', '--png', png, '--exposure', b.exp, '-q']);
  const ref = readPng(png);
  const params = { mode: 'prt', glb: url(glb), sh: url(sh), ...(b.brdf.length ? { glsl: url(glsl) } : {}) };
  const img = mirrorX((await view({ ...params, rotate: '60', eye: toPage(b.eye, 'three'), target: toPage(b.target, 'three'),
    fov: String(FOV), res: '200x200', exposure: b.exp })).image);
  writePng(join(out, `prt-${group}-${b.name}-60-viewer-three.png`), img);
  const c = compare(img, ref, meshMask(img));
  check(`prt ${label} ${b.name} (transfer ${b.args.join(' ')}), turned 60° (three frame) vs render --shading transfer`, c.psnr >= 35,
    `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} mesh pixels (≥ 35), mean |Δ| ${c.mean.toFixed(3)} codes`);
  return c.psnr;
}

// ---- Quantized PRT bakes (transfer --quantize) against render --shading transfer ---------------
// The page dequantizes on load (normalized codes times the .glb's scales, per value index or per
// cluster); render reads the same quantized .glb on the CPU. Diffuse (the knot, i16 and i8),
// glossy (the bowl with its ball, Phong s = 8, K = 10, n = 4, i8) and compressed (8 clusters × 4,
// i8), each turned 60° in the three frame, over the mesh less a rim.
async function quantizedPrtTests() {
  const { dir, sky } = skyIn('prt-quantized');
  const knot = 'testdata/meshes/torus-knot.obj', bowl = 'testdata/meshes/bowl-ball.obj';
  run('factor-brdf', ['phong:s=8', '--domain', 'hemisphere', '--resolution', '16', '--cosine',
    '--factors', join(dir, 'p.exr'), '--terms', '16', '-o', join(dir, 'p.json'), '-q']);
  const bakes = [
    { name: 'knot-i16', mesh: knot, n: 5, exp: '-2', eye: [2.2, -3.4, 2.4], target: [0, 0, 0], brdf: [],
      args: ['-n', '5', '--rays', '256', '--quantize', 'i16'] },
    { name: 'knot-i8', mesh: knot, n: 5, exp: '-2', eye: [2.2, -3.4, 2.4], target: [0, 0, 0], brdf: [],
      args: ['-n', '5', '--rays', '256', '--quantize', 'i8'] },
    { name: 'glossy-i8', mesh: bowl, n: 4, exp: '-3.5', eye: [1.3, -2.2, 2.4], target: [0, 0, -0.45], brdf: ['--brdf', 'phong:s=8'],
      args: ['-n', '4', '--factors', join(dir, 'p.json'), '-K', '10', '--quantize', 'i8'] },
    { name: 'cpca-i8', mesh: bowl, n: 3, exp: '-2.5', eye: [1.3, -2.2, 2.4], target: [0, 0, -0.45], brdf: [],
      args: ['-n', '3', '--rays', '256', '--clusters', '8', '--pca', '4', '--quantize', 'i8'] },
  ];
  const fig = {};
  for (const b of bakes) fig[b.name] = await relitAt60(dir, sky, b, 'quantized', 'quantized');
  figures.prt_quantized = fig;
}

// ---- Coloured PRT (transfer --albedo R,G,B or mesh: three transfer vectors per vertex) --------
// The page dots channel c's transfer with channel c of the lighting (the lighting uniform masked
// per channel); render does the same on the CPU. The corner (red and green walls, a white ball,
// its PLY's vertex colours) interreflected, uncompressed and by clustered PCA, and the knot in one
// colour, each turned 60° in the three frame, over the mesh less a rim.
async function colourPrtTests() {
  const { dir, sky } = skyIn('prt-colour');
  const corner = 'testdata/meshes/corner-ball.ply', knot = 'testdata/meshes/torus-knot.obj';
  const base = { n: 3, brdf: [], exp: '-1.5' }, bake = ['-n', '3', '--rays', '256'];
  const cornerCam = { eye: [2.2, -2.6, 1.8], target: [-0.3, 0.3, 0.3] };
  const bakes = [
    { ...base, ...cornerCam, name: 'corner-mesh', mesh: corner, args: [...bake, '--mode', 'interreflected', '--albedo', 'mesh'] },
    { ...base, ...cornerCam, name: 'corner-mesh-cpca', mesh: corner,
      args: [...bake, '--mode', 'interreflected', '--albedo', 'mesh', '--clusters', '8', '--pca', '4'] },
    { ...base, name: 'knot-orange', mesh: knot, eye: [2.2, -3.4, 2.4], target: [0, 0, 0], args: [...bake, '--albedo', '0.9,0.45,0.2'] },
  ];
  const fig = {};
  for (const b of bakes) fig[b.name] = await relitAt60(dir, sky, b, 'colour', 'coloured');
  figures.prt_colour = fig;
}

// ---- Diffuse PRT at n = 8 (16 four-vectors: past WebGL 2's 16 attributes with the position) ----
// The knot baked at n = 8 (64 coefficients), relit from a texture of the transfer read by
// gl_VertexID, against render --shading transfer of the same .glb, turned 60° in the three frame.
async function order8PrtTests() {
  const { dir, sky } = skyIn('prt-n8');
  const mesh = 'testdata/meshes/torus-knot.obj', glb = join(dir, 'knot8.glb'), sh = join(dir, 'sky7.sh.json');
  const png = join(out, 'prt-n8-60-render.png');
  run('transfer', [mesh, '-n', '8', '--rays', '256', '--glb', glb, '-o', join(dir, 'knot8.json'), '-q']);
  run('sh-project', [sky, '-F', '7', '-o', sh, '-q']);
  const eye = [2.2, -3.4, 2.4], EXP = '-2';
  run('render', [sky, '--scene', mesh, '--shading', 'transfer', '--transfer', glb, '--env-rotation', '60',
    '--eye', eye.join(','), '--target', '0,0,0', '--fov', String(FOV), '--res', '200x200', '--png', png, '--exposure', EXP, '-q']);
  const ref = readPng(png);
  const params = { mode: 'prt', glb: url(glb), sh: url(sh), rotate: '60', eye: toPage(eye, 'three'), target: '0,0,0', fov: String(FOV), res: '200x200', exposure: EXP };
  const r = await view(params, { evaluate: () => document.getElementById('source').textContent });
  const img = mirrorX(r.image);
  writePng(join(out, 'prt-n8-60-viewer-three.png'), img);
  const c = compare(img, ref, meshMask(img));
  check('prt knot n = 8 reads its 16 four-vectors from a texture', /read from a texture \(16 texels/.test(r.value), r.value);
  check('prt knot n = 8, turned 60° (three frame) vs render --shading transfer', c.psnr >= 35,
    `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} mesh pixels (≥ 35), mean |Δ| ${c.mean.toFixed(3)} codes`);
  const b = await view({ ...params, rotate: '30', src: url(sky), eye: toPage([2.6, -4, 2.8], 'three'), res: '640x360' }, { bench: 20 });
  writePng(join(out, 'mode-prt-n8.png'), b.image);
  console.log(`     frame time prt (n = 8, knot, transfer from a texture) 640×360: ${b.ms.toFixed(1)} ms (CPU, SwiftShader)`);
  figures.prt_n8 = { turned60_three: c.psnr, frame_ms_640x360: b.ms };
}

// ---- Every ibl --format and --container (the loader's decoders) ------------------------------
// The same bake written as each format and container, drawn by the page in the grid and one-sphere
// views (three frame), against the page's own rgba16f KTX2 drawing of it: what may differ is the
// format's rounding of the texels alone (b10g11r11: 6 and 5 mantissa bits, 2^−7 and 2^−6 relative;
// e5b9g9r9: 9 bits under the largest channel's exponent, 2^−9 of it), since the decoders are exact
// (an 11/10-bit float or a shared-exponent texel is a half). rgba16f DDS holds the KTX2's bytes:
// it must draw the same frame, pixel for pixel. The bar, 50 dB (an RMS difference of 0.8 codes), is
// what that rounding allows: 2^−6 relative in linear radiance (10-bit blue; 2^−7 for 11 bits) moves
// an 8-bit sRGB value by at most 1.7 codes (the curve's slope divides a relative change by about
// 2.4 above its linear toe), so every pixel stays within a code or two. Negative controls: the packed KTX2s rewritten with
// two channels swapped in every texel (the frame a decoder that reads the fields in the wrong
// order would draw) must fail the bar.

// A copy of a KTX2 file whose every 4-byte texel has `fields` (bit ranges [from, to, width]) swapped.
function swapFieldsKtx2(from, to, [a, b, width]) {
  const buf = Buffer.from(readFileSync(from));
  const levels = buf.readUInt32LE(40);
  const mask = (1 << width) - 1;
  for (let p = 0; p < Math.max(1, levels); p++) {
    const at = 80 + 24 * p, offset = Number(buf.readBigUInt64LE(at)), length = Number(buf.readBigUInt64LE(at + 8));
    for (let i = offset; i < offset + length; i += 4) {
      const w = buf.readUInt32LE(i), x = (w >>> a) & mask, y = (w >>> b) & mask;
      buf.writeUInt32LE(((w & ~((mask << a) | (mask << b))) | (x << b) | (y << a)) >>> 0, i);
    }
  }
  writeFileSync(to, buf);
}
async function formatTests() {
  const dir = join(out, 'formats');
  rmSync(dir, { recursive: true, force: true });
  mkdirSync(dir, { recursive: true });
  const bakes = [
    { name: 'rgba16f-ktx2', args: [] },
    { name: 'rgba16f-dds', args: ['--container', 'dds'], exact: true },
    { name: 'rgba32f-ktx2', args: ['--format', 'rgba32f'], bar: 50 },
    { name: 'rgba32f-dds', args: ['--format', 'rgba32f', '--container', 'dds'], bar: 50 },
    { name: 'b10g11r11-ktx2', args: ['--format', 'b10g11r11'], bar: 50 },
    { name: 'b10g11r11-dds', args: ['--format', 'b10g11r11', '--container', 'dds'], bar: 50 },
    { name: 'e5b9g9r9-ktx2', args: ['--format', 'e5b9g9r9'], bar: 50 },
    { name: 'e5b9g9r9-dds', args: ['--format', 'e5b9g9r9', '--container', 'dds'], bar: 50 },
  ];
  for (const b of bakes) run('ibl', [map, '-o', join(dir, b.name), '--size', '128', '--samples', '0', '-q', ...b.args]);
  // Negative controls: R and B swapped (e5b9g9r9: bits 0–8 and 18–26), R and G (b10g11r11: 0–10
  // and 11–21), in the specular and irradiance cubes.
  const swaps = [
    { name: 'e5b9g9r9-ktx2-rb-swapped', from: 'e5b9g9r9-ktx2', fields: [0, 18, 9], bar: 50 },
    { name: 'b10g11r11-ktx2-rg-swapped', from: 'b10g11r11-ktx2', fields: [0, 11, 11], bar: 50 },
  ];
  for (const w of swaps) {
    const to = join(dir, w.name);
    mkdirSync(to);
    for (const f of ['ibl.json', 'dfg.ktx2', 'sh.json']) writeFileSync(join(to, f), readFileSync(join(dir, w.from, f)));
    for (const f of ['specular.ktx2', 'irradiance.ktx2']) swapFieldsKtx2(join(dir, w.from, f), join(to, f), w.fields);
  }
  const views = [
    { name: 'grid', params: { mode: 'grid', res: '320x160', exposure: '0' } },
    { name: 'sphere', params: { mode: 'sphere', m: '1', r: '0.3', eye: toPage([0, -4, 0.6], 'three'), target: '0,0,0', fov: String(FOV), res: RES, exposure: '0' } },
  ];
  const fig = {};
  for (const v of views) {
    const ref = (await view({ ...v.params, ibl: url(join(dir, 'rgba16f-ktx2')) + '/' })).image;
    writePng(join(out, `formats-${v.name}-rgba16f-ktx2.png`), ref);
    for (const b of [...bakes.slice(1), ...swaps]) {
      const img = (await view({ ...v.params, ibl: url(join(dir, b.name)) + '/' })).image;
      writePng(join(out, `formats-${v.name}-${b.name}.png`), img);
      writePng(join(out, `formats-${v.name}-${b.name}-diff-x8.png`), diffImage(img, ref));
      const c = compare(img, ref);
      let max = 0;
      for (let i = 0; i < img.rgba.length; i++) if (i % 4 !== 3) max = Math.max(max, Math.abs(img.rgba[i] - ref.rgba[i]));
      fig[`${v.name}_${b.name}`] = { psnr: c.psnr, mean: c.mean, max };
      const what = `${v.name} view, ${b.name} bake vs the rgba16f KTX2 bake`;
      const detail = `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} pixels, mean |Δ| ${c.mean.toFixed(3)} codes, max ${max}`;
      if (b.exact) check(what, max === 0, `${detail} (must be 0: the same texels)`);
      else if (b.from) check(`${what} (control: two channels swapped in every texel) fails`, c.psnr < b.bar, `${detail} (must stay under ${b.bar})`);
      else check(what, c.psnr >= b.bar, `${detail} (≥ ${b.bar})`);
    }
  }
  figures.formats = fig;
}

// ---- Models (mode=model) lit by the split sum ------------------------------------------------
// testdata/meshes/sphere.obj (a UV sphere, 16 rings × 32 segments, exact vertex normals) at the
// origin, with the panel's r and m, against the page's own ray-cast sphere (mode=sphere) of the
// same material and camera, over the sphere less a rim (the polygon's silhouette differs); a
// tetrahedra.gltf page whose shading must not follow the panel's r and m (its glTF material is
// kept: the glTF default, white, metalness 1, roughness 1), and no WebGL error in either page.
async function modelTests() {
  const obj = url(join(repo, 'testdata/meshes/sphere.obj'));
  const [w, h] = RES.split('x').map(Number);
  const fig = {};
  for (const v of [{ name: 'gold-r0.3', m: 1, r: 0.3, eye: [0, -4, 0.6] }, { name: 'plastic-r0.5', m: 0, r: 0.5, eye: [3, -2.5, 1.2], base: [0.8, 0.2, 0.15] }]) {
    const base = (v.base ?? [1, 0.78, 0.34]).join(',');
    const params = { ibl: url(bake) + '/', m: String(v.m), r: String(v.r), base, eye: toPage(v.eye, 'three'), target: '0,0,0', fov: String(FOV), res: RES, exposure: '0' };
    const ref = (await view({ ...params, mode: 'sphere' })).image;
    const got = await view({ ...params, mode: 'model', model: obj });
    writePng(join(out, `model-sphere-obj-${v.name}.png`), got.image);
    writePng(join(out, `model-sphere-obj-${v.name}-diff-x8.png`), diffImage(got.image, ref));
    const mask = sphereMask(v.eye, [0, 0, 0], FOV, w, h);
    const c = compare(got.image, ref, mask);
    fig[`sphere_obj_${v.name}`] = c.psnr;
    check(`model sphere.obj ${v.name} (mode=model) vs the ray-cast sphere (mode=sphere)`, c.psnr >= 35,
      `PSNR ${c.psnr.toFixed(2)} dB over ${c.pixels} sphere pixels (≥ 35), mean |Δ| ${c.mean.toFixed(3)} codes`);
    check(`model sphere.obj ${v.name}: the page logged no WebGL, shader or page error`, got.errors.length === 0,
      got.errors.length ? got.errors.join('; ').slice(0, 500) : 'none');
    if (v.m === 0) {
      // Control: the panel's roughness ignored (the OBJ drawn at r = 0.05 instead) must fail.
      const wrong = (await view({ ...params, mode: 'model', model: obj, r: '0.05' })).image;
      const cw = compare(wrong, ref, mask);
      fig[`sphere_obj_${v.name}_r0.05`] = cw.psnr;
      check(`model sphere.obj at r = 0.05 vs the r = ${v.r} sphere (control) fails`, cw.psnr < 35, `PSNR ${cw.psnr.toFixed(2)} dB (< 35)`);
    }
  }
  // glTF: the file's material (glTF's default: white, metalness 1, roughness 1) whatever the panel says.
  const gltf = url(join(repo, 'testdata/meshes/tetrahedra.gltf'));
  const cam = { ibl: url(bake) + '/', eye: '3,2.5,6', target: '0.5,0.5,-1', fov: '40', res: '200x160', exposure: '0', base: '0.2,0.9,0.2' };
  const a = await view({ ...cam, mode: 'model', model: gltf, r: '0.1', m: '0' });
  const b = await view({ ...cam, mode: 'model', model: gltf, r: '0.9', m: '1' });
  const sky = (await view({ ...cam, mode: 'sky' })).image;
  writePng(join(out, 'model-tetrahedra-gltf.png'), a.image);
  const same = compare(a.image, b.image), drawn = compare(a.image, sky);
  let covered = 0;
  for (let i = 0; i < a.image.rgba.length; i += 4) if ([0, 1, 2].some((c) => a.image.rgba[i + c] !== sky.rgba[i + c])) covered++;
  fig.tetrahedra_gltf = { covered_pixels: covered, panel_change_mean: same.mean };
  check('model tetrahedra.gltf: drawn (pixels differ from the sky alone) and its glTF material kept (the panel\'s r, m, base change nothing)',
    covered > 500 && same.mean === 0, `${covered} pixels covered (> 500), mean |Δ| ${same.mean.toFixed(3)} codes between panel r/m/base settings (must be 0); vs sky ${drawn.mean.toFixed(2)} codes`);
  check('model tetrahedra.gltf: the page logged no WebGL, shader or page error', a.errors.length + b.errors.length === 0,
    [...a.errors, ...b.errors].join('; ').slice(0, 500) || 'none');
  await mtlTests(fig);
  figures.model = fig;
}

// OBJ materials (an .mtl library, three's MTLLoader): sphere.obj with a library against the same
// geometry without one, the panel's base colour set to what the library says, converted here:
// Kd is sRGB-encoded (MTLLoader linearizes it) and map_Kd an sRGB image, so the base colour is
// linear(Kd)·linear(texel). A uniform texture makes the reference one colour; the geometry is
// the same on both sides, so what may differ is the colour's rounding (bar: 1 code).
const srgbToLinear = (c) => (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4);
// In DIR: sphere-kd.obj (sphere.obj with kd.mtl: Kd 0.9 0.3 0.2), sphere-uv.obj (sphere.obj with
// texture coordinates, each vertex's (φ/2π, 1 − θ/π); faces v/vt/vn) and sphere-painted.obj (that,
// with painted.mtl: Kd 0.8 0.9 0.7 and map_Kd paint.png, 4×4 of sRGB (200, 120, 60)).
function writeMtlModels(dir) {
  const lines = readFileSync(join(repo, 'testdata/meshes/sphere.obj'), 'utf8').split('\n');
  const vt = lines.filter((l) => l.startsWith('v ')).map((l) => {
    const [x, y, z] = l.split(/\s+/).slice(1).map(Number);
    return `vt ${(((Math.atan2(y, x) / (2 * Math.PI)) + 1) % 1).toFixed(6)} ${(1 - Math.acos(Math.max(-1, Math.min(1, z))) / Math.PI).toFixed(6)}`;
  });
  const uvBody = [...lines.filter((l) => !l.startsWith('f ')), ...vt, ...lines.filter((l) => l.startsWith('f ')).map((l) => l.replace(/(\d+)\/\/(\d+)/g, '$1/$1/$2'))].join('\n');
  const png = new PNG({ width: 4, height: 4 });
  for (let i = 0; i < 16; i++) png.data.set([200, 120, 60, 255], 4 * i);
  writeFileSync(join(dir, 'paint.png'), PNG.sync.write(png));
  writeFileSync(join(dir, 'kd.mtl'), 'newmtl red\nKd 0.9 0.3 0.2\n');
  writeFileSync(join(dir, 'painted.mtl'), 'newmtl painted\nKd 0.8 0.9 0.7\nmap_Kd paint.png\n');
  writeFileSync(join(dir, 'sphere-kd.obj'), `mtllib kd.mtl\nusemtl red\n${lines.join('\n')}`);
  writeFileSync(join(dir, 'sphere-uv.obj'), uvBody);
  writeFileSync(join(dir, 'sphere-painted.obj'), `mtllib painted.mtl\nusemtl painted\n${uvBody}`);
}
async function mtlTests(fig) {
  const dir = join(out, 'model-mtl');
  rmSync(dir, { recursive: true, force: true });
  mkdirSync(dir, { recursive: true });
  writeMtlModels(dir);
  const lin = (rgb) => rgb.map(srgbToLinear);
  const cases = [
    { name: 'Kd', obj: 'sphere-kd.obj', plain: url(join(repo, 'testdata/meshes/sphere.obj')), base: lin([0.9, 0.3, 0.2]) },
    { name: 'Kd and map_Kd', obj: 'sphere-painted.obj', plain: url(join(dir, 'sphere-uv.obj')),
      base: lin([0.8, 0.9, 0.7]).map((k, i) => k * srgbToLinear([200, 120, 60][i] / 255)) },
  ];
  const cam = { ibl: url(bake) + '/', mode: 'model', m: '0', r: '0.5', eye: toPage([3, -2.5, 1.2], 'three'), target: '0,0,0', fov: String(FOV), res: RES, exposure: '0' };
  for (const c of cases) {
    const got = await view({ ...cam, model: url(join(dir, c.obj)), base: '1,1,1' });
    const ref = (await view({ ...cam, model: c.plain, base: c.base.map((x) => x.toFixed(7)).join(',') })).image;
    let max = 0;
    for (let i = 0; i < ref.rgba.length; i++) if (i % 4 !== 3) max = Math.max(max, Math.abs(got.image.rgba[i] - ref.rgba[i]));
    const slug = c.obj.replace('.obj', '');
    writePng(join(out, `model-mtl-${slug}.png`), got.image);
    fig[`mtl_${slug}_max`] = max;
    check(`model ${c.obj} (.mtl: ${c.name}) vs the same geometry without a library, the panel's base = the library's colour`,
      max <= 1 && got.errors.length === 0, `max |Δ| ${max} codes over the frame (≤ 1), errors: ${got.errors.join('; ').slice(0, 300) || 'none'}`);
  }
}

// ---- Files dropped on the page ----------------------------------------------------------------
// The page opened with a camera and material but no files; the test fetches the files in the
// page, makes File objects, puts them in a DataTransfer and dispatches a synthetic 'drop' on the
// page. The page must switch to the right mode and draw the same frame as the same files opened
// by URL (max difference 0), with no error.
// A folder ({folder: NAME, children: [...]}, children paths or folders) cannot be put in a
// DataTransfer by a script (the browser makes FileSystemEntry objects only for a user's drop), so
// a drop with folders is a stub: an event whose dataTransfer.items give webkitGetAsEntry()
// entries made in the page, a folder's reader handing its entries out two at a time, last first
// (readEntries gives batches, of up to 100, in no set order), then an empty batch.
async function dropView(params, files) {
  const page = await browser.newPage();
  const logs = [];
  page.on('console', (m) => { if (m.type() === 'error') logs.push(m.text()); });
  page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
  const [w, h] = params.res.split('x').map(Number);
  await page.setViewport({ width: w, height: h, deviceScaleFactor: 1 });
  await page.goto(`${origin}/viewer/?${new URLSearchParams({ test: '1', ...params })}`, { waitUntil: 'load' });
  await page.evaluate(() => window.prtkit.ready);
  const before = await page.evaluate(() => window.prtkit.state().mode);
  const ok = await page.evaluate(async (items) => {
    const file = async (p) => new File([await (await fetch(p)).blob()], p.split('/').pop());
    let dataTransfer;
    if (items.every((it) => typeof it === 'string')) {
      dataTransfer = new DataTransfer();
      for (const p of items) dataTransfer.items.add(await file(p));
    } else {
      const entry = async (it) => {
        if (typeof it === 'string') { const f = await file(it); return { isFile: true, isDirectory: false, name: f.name, file: (ok) => ok(f), f }; }
        const children = (await Promise.all(it.children.map(entry))).reverse();
        const createReader = () => {
          let i = 0;
          return { readEntries: (ok) => { const batch = children.slice(i, i + 2); i += batch.length; setTimeout(() => ok(batch)); } };
        };
        return { isFile: false, isDirectory: true, name: it.folder, createReader };
      };
      const entries = await Promise.all(items.map(entry));
      dataTransfer = { files: [], items: entries.map((e) => ({ kind: 'file', webkitGetAsEntry: () => e, getAsFile: () => e.f ?? null })) };
    }
    let drop;
    if (dataTransfer instanceof DataTransfer) drop = new DragEvent('drop', { dataTransfer, bubbles: true, cancelable: true });
    else {
      drop = new Event('drop', { bubbles: true, cancelable: true });
      Object.defineProperty(drop, 'dataTransfer', { value: dataTransfer });
    }
    document.body.dispatchEvent(drop);
    return window.prtkit.ready;
  }, files);
  const state = await page.evaluate(() => window.prtkit.state());
  const pixels = ok ? await page.evaluate(() => window.prtkit.pixels()) : null;
  const errors = [...logs, ...(await page.evaluate(() => window.prtkit.errors.slice()))];
  await page.close();
  const what = JSON.stringify(files);
  if (errors.length) pageErrors.push({ query: `drop ${what}`, errors });
  return { before, state, image: pixels ? fromPage(pixels) : null, errors };
}
async function dropTests() {
  const b = (f) => url(join(bake, f));
  const bakeFiles = ['ibl.json', 'specular.ktx2', 'irradiance.ktx2', 'dfg.ktx2', 'sh.json'].map(b);
  const cam = { eye: toPage([3, -2.5, 1.2], 'three'), target: '0,0,0', fov: String(FOV), res: RES, exposure: '0' };
  const { dir, sky } = skyIn('drop');
  run('sh-project', [sky, '-F', '2', '-o', join(dir, 'sky.sh.json'), '-q']);
  run('transfer', ['testdata/meshes/torus-knot.obj', '-n', '3', '--rays', '64', '--glb', join(dir, 'knot3.glb'), '-o', join(dir, 'knot3.json'), '-q']);
  run('prefilter', [sky, '--brdf', 'phong:s=16', '--shrm', join(dir, 'p16.exr'), '-o', join(dir, 'p16.json'), '-q']);
  const nd = join(dir, 'normals');
  mkdirSync(nd);
  encodeSphereNormals(nd, 128, 64);
  const d = (f) => url(join(dir, f));
  const normalsFiles = ['sphere.codes', 'sphere.codes.json', 'decoder.glsl'].map((f) => d(`normals/${f}`));
  const normalsByUrl = { mode: 'normals', codes: d('normals/sphere.codes'), report: d('normals/sphere.codes.json'), decoder: d('normals/decoder.glsl'),
    size: '128x64', sh: d('sky.sh.json'), exposure: '-3' };
  const bakeFolder = { folder: 'bake', children: readdirSync(bake).sort().map(b) };
  mkdirSync(join(dir, 'mtl'));
  writeMtlModels(join(dir, 'mtl'));
  const cases = [
    { name: 'a bake (ibl.json and its files), page in mode=sphere', start: { mode: 'sphere', m: '0', r: '0.5', base: '0.8,0.2,0.15' },
      files: bakeFiles, mode: 'sphere', byUrl: { mode: 'sphere', m: '0', r: '0.5', base: '0.8,0.2,0.15', ibl: url(bake) + '/' } },
    { name: 'a bake on an empty page', start: {}, files: bakeFiles, mode: 'grid', byUrl: { ibl: url(bake) + '/' } },
    { name: 'a .sh.json (sh-project)', start: { exposure: '-3' }, files: [url(join(dir, 'sky.sh.json'))], mode: 'irradiance',
      byUrl: { mode: 'irradiance', sh: url(join(dir, 'sky.sh.json')), exposure: '-3' } },
    { name: 'a bake with sphere.obj', start: { m: '1', r: '0.3' }, files: [...bakeFiles, url(join(repo, 'testdata/meshes/sphere.obj'))], mode: 'model',
      byUrl: { mode: 'model', m: '1', r: '0.3', ibl: url(bake) + '/', model: url(join(repo, 'testdata/meshes/sphere.obj')) } },
    { name: 'a bake with tetrahedra-bin.gltf and its .bin', start: {}, mode: 'model',
      files: [...bakeFiles, url(join(repo, 'testdata/meshes/tetrahedra-bin.gltf')), url(join(repo, 'testdata/meshes/tetrahedra.bin'))],
      byUrl: { mode: 'model', ibl: url(bake) + '/', model: url(join(repo, 'testdata/meshes/tetrahedra-bin.gltf')) }, cam: { eye: '3,2.5,6', target: '0.5,0.5,-1' } },
    { name: 'a transfer .glb with a .sh.json', start: { exposure: '-2' }, mode: 'prt',
      files: [url(join(dir, 'knot3.glb')), url(join(dir, 'sky.sh.json'))],
      byUrl: { mode: 'prt', glb: url(join(dir, 'knot3.glb')), sh: url(join(dir, 'sky.sh.json')), exposure: '-2' } },
    { name: 'an SHRM (prefilter --shrm: its prtkit.shrm document and EXR)', start: { exposure: '-2' }, mode: 'shrm',
      files: [d('p16.json'), d('p16.exr')], byUrl: { mode: 'shrm', shrm: d('p16.json'), exposure: '-2' } },
    { name: 'encoded normals (codes, report, GLSL decoder) with a .sh.json', start: { exposure: '-3' }, mode: 'normals',
      files: [...normalsFiles, d('sky.sh.json')], byUrl: normalsByUrl },
    { name: 'a folder: ibl -o DIR', start: {}, mode: 'grid', files: [bakeFolder], byUrl: { ibl: url(bake) + '/' } },
    { name: 'a folder holding a folder of encoded normals and a .sh.json', start: { exposure: '-3' }, mode: 'normals',
      files: [{ folder: 'out', children: [{ folder: 'normals', children: normalsFiles }, d('sky.sh.json')] }], byUrl: normalsByUrl },
    { name: 'a bake with an OBJ, its .mtl and its texture', start: { m: '0', r: '0.5' }, mode: 'model',
      files: [...bakeFiles, ...['sphere-painted.obj', 'painted.mtl', 'paint.png'].map((f) => d(`mtl/${f}`))],
      byUrl: { mode: 'model', m: '0', r: '0.5', ibl: url(bake) + '/', model: d('mtl/sphere-painted.obj') } },
    { name: 'a folder (ibl -o DIR) and a file (sphere.obj)', start: { m: '1', r: '0.3' }, mode: 'model',
      files: [bakeFolder, url(join(repo, 'testdata/meshes/sphere.obj'))],
      byUrl: { mode: 'model', m: '1', r: '0.3', ibl: url(bake) + '/', model: url(join(repo, 'testdata/meshes/sphere.obj')) } },
  ];
  const fig = {};
  for (const c of cases) {
    const camera = { ...cam, ...(c.cam ?? {}) };
    const d = await dropView({ ...camera, ...c.start }, c.files);
    const ref = (await view({ ...camera, ...c.byUrl })).image;
    let max = -1;
    if (d.image) { max = 0; for (let i = 0; i < ref.rgba.length; i++) if (i % 4 !== 3) max = Math.max(max, Math.abs(d.image.rgba[i] - ref.rgba[i])); }
    const slug = c.name.replace(/[^a-z0-9]+/gi, '-');
    if (d.image) writePng(join(out, `drop-${slug}.png`), d.image);
    fig[slug] = { mode: d.state.mode, max };
    check(`drop ${c.name}: mode ${c.mode}, the same frame as by URL, no error`, d.state.mode === c.mode && max === 0 && d.errors.length === 0,
      `mode ${d.before} → ${d.state.mode} (want ${c.mode}), max |Δ| ${max} codes against the URL-opened page (must be 0), errors: ${d.errors.join('; ').slice(0, 300) || 'none'}`);
  }
  // A model alone on an empty page has no bake to be lit by: a clear error naming the file, the
  // page left as it was.
  const lone = await dropView({ ...cam }, [url(join(repo, 'testdata/meshes/sphere.obj'))]);
  fig.model_without_bake = { mode: lone.state.mode, errors: lone.errors };
  const expected = pageErrors.findIndex((e) => e.errors === lone.errors);
  if (expected >= 0) pageErrors.splice(expected, 1); // this page's error is the one asked for
  check('drop sphere.obj on an empty page (no bake): a clear error naming the file, the mode unchanged',
    lone.state.mode === lone.before && lone.errors.length > 0 && lone.errors.every((e) => e.includes('sphere.obj') && e.includes('bake')),
    `mode ${lone.before} → ${lone.state.mode}, errors: ${lone.errors.join('; ').slice(0, 300) || 'none'}`);
  figures.drop = fig;
}

// ---- other engines: Babylon.js and Filament (viewer/engines/) ------------------------------------
// The reference is render's picture for a camera in the glTF frame: three.js's equirectangular view
// of the source map from the x-mirrored camera, mirrored back (the skybox tests above check that
// this view is the one prtkit's cube gives).
const ENGINE_VIEWS = [
  { name: 'front', eye: [0, -4, 0.3], fov: 60 },
  { name: 'side', eye: [4, 1.5, -0.5], fov: 60 },
];
// DIR/sky-NAME-reference(-TAG).png: render's picture of the source map for camera v (see above),
// 192² at v.fov unless fov and res say otherwise.
async function engineReference(dir, v, { fov = v.fov, res = '192x192', tag = '' } = {}) {
  const ref = mirrorX((await view({ mode: 'equirect', src: url(map), eye: toPage(v.eye, 'three'), target: '0,0,0', fov: String(fov), res, exposure: '0' })).image);
  writePng(join(dir, `sky-${v.name}-reference${tag}.png`), ref);
  return ref;
}
async function engineTests() {
  const dir = join(out, 'engines');
  rmSync(dir, { recursive: true, force: true });
  mkdirSync(dir, { recursive: true });
  const dds = join(dir, 'bake-dds');
  run('ibl', [map, '-o', dds, '--size', '128', '--samples', '0', '--container', 'dds', '-q']);
  const views = ENGINE_VIEWS;
  for (const v of views) {
    const res = '192x192', fov = String(v.fov);
    const ref = await engineReference(dir, v);
    const g = mul(M, v.eye);
    // Babylon's left-handed world (its default) holds a glTF point (x, y, z) at (−x, y, z) (what
    // its glTF loader's root does: 180° about +Y, then z mirrored); the right-handed one
    // (scene.useRightHandedSystem) holds it unchanged. The flip is the CubeTexture's reflection
    // matrix; the wrong one (none) must fail.
    for (const [hand, right, wrong] of [['left', 'x', 'none'], ['right', 'z', 'none']]) {
      const eye = (hand === 'left' ? [-g[0], g[1], g[2]] : g).map((x) => +x.toFixed(6)).join(',');
      const shot = async (flip) => {
        const requests = [];
        const img = (await view({ ibl: url(dds) + '/', hand, flip, mode: 'sky', eye, target: '0,0,0', fov, res },
          { page: '/viewer/engines/babylon.html', requests })).image;
        writePng(join(dir, `sky-${v.name}-babylon-${hand}-flip-${flip}.png`), img);
        return { img, foreign: requests.filter((r) => !r.startsWith(origin) && !r.startsWith('data:')) };
      };
      const good = await shot(right), bad = await shot(wrong);
      writePng(join(dir, `sky-${v.name}-babylon-${hand}-diff-x8.png`), diffImage(good.img, ref));
      const a = compare(good.img, ref), c = compare(bad.img, ref);
      figures[`babylon_sky_${v.name}_${hand}`] = { [`flip_${right}`]: a.mean, [`flip_${wrong}`]: c.mean };
      check(`Babylon.js skybox ${v.name} (${hand}-handed scene, cube looked up with ${right} negated) vs render's view`, a.mean <= 1 && good.foreign.length === 0,
        `mean |Δ| = ${a.mean.toFixed(3)} sRGB codes (≤ 1); requests outside 127.0.0.1: ${good.foreign.length}`);
      check(`Babylon.js skybox ${v.name} (${hand}-handed, no flip) differs from render's view`, c.mean > 4 * Math.max(a.mean, 0.5),
        `mean |Δ| = ${c.mean.toFixed(3)} sRGB codes (must be far above ${a.mean.toFixed(3)})`);
    }
  }
  // Filament (right-handed, +Y up: the glTF frame) with prtkit's cube as it is; the negative
  // control turns the IndirectLight (and so the skybox) 90° about +Y, the turn between cmgen's
  // lat-long frame and ibl's.
  for (const v of views) {
    const ref = readPng(join(dir, `sky-${v.name}-reference.png`));
    const eye = mul(M, v.eye).map((x) => +x.toFixed(6)).join(',');
    const shot = async (turn) => {
      const requests = [];
      const img = (await view({ ibl: url(bake) + '/', turn, eye, target: '0,0,0', fov: String(v.fov), res: '192x192' },
        { page: '/viewer/engines/filament.html', requests })).image;
      writePng(join(dir, `sky-${v.name}-filament-turn-${turn}.png`), img);
      return { img, foreign: requests.filter((r) => !r.startsWith(origin) && !r.startsWith('data:')) };
    };
    const good = await shot('0'), bad = await shot('90');
    writePng(join(dir, `sky-${v.name}-filament-diff-x8.png`), diffImage(good.img, ref));
    const a = compare(good.img, ref), c = compare(bad.img, ref);
    figures[`filament_sky_${v.name}`] = { turn_0: a.mean, turn_90: c.mean };
    check(`Filament skybox ${v.name} (specular.ktx2 faces via Texture.setImageCube, no flip) vs render's view`, a.mean <= 1 && good.foreign.length === 0,
      `mean |Δ| = ${a.mean.toFixed(3)} sRGB codes (≤ 1); requests outside 127.0.0.1: ${good.foreign.length}`);
    check(`Filament skybox ${v.name} turned 90° about +Y differs from render's view`, c.mean > 4 * Math.max(a.mean, 0.5),
      `mean |Δ| = ${c.mean.toFixed(3)} sRGB codes (must be far above ${a.mean.toFixed(3)})`);
  }
  await sampleViewerTests(dir, views);
  // A metallic PBR sphere lit by the same cube, left-handed scene, x flipped, beside
  // `render --shading ibl` of the same sphere and camera: a figure, not a check (Babylon picks
  // its mip per roughness by its own rule and adds its own BRDF terms; see docs/results/viewer.md).
  const eye = [0, -4, 0.6], g = mul(M, eye), res = '192x192';
  for (const r of ['0.05', '0.3']) {
    const refPng = join(dir, `sphere-r${r}-render.png`);
    run('render', [map, '--shading', 'ibl', '--ibl', join(bake, 'ibl.json'), '--brdf', `gltf:base=1/1/1,metalness=1,roughness=${r}`,
      '--eye', eye.join(','), '--target', '0,0,0', '--fov', '32', '--res', res, '--png', refPng, '--exposure', '0', '-q']);
    const sphere = (await view({ ibl: url(dds) + '/', hand: 'left', flip: 'x', mode: 'sphere', r, base: '1,1,1',
      eye: [-g[0], g[1], g[2]].map((x) => +x.toFixed(6)).join(','), target: '0,0,0', fov: '32', res },
    { page: '/viewer/engines/babylon.html' })).image;
    writePng(join(dir, `sphere-r${r}-babylon-left-flip-x.png`), sphere);
    const ref = readPng(refPng);
    writePng(join(dir, `sphere-r${r}-babylon-diff-x8.png`), diffImage(sphere, ref));
    const c = compare(sphere, ref, sphereMask(eye, [0, 0, 0], 32, 192, 192));
    figures[`babylon_sphere_r${r}_vs_render`] = { psnr_sphere: c.psnr, mean_sphere: c.mean };
    console.log(`     Babylon.js PBR sphere (metal, r = ${r}) vs render --shading ibl: PSNR ${c.psnr.toFixed(2)} dB, mean |Δ| ${c.mean.toFixed(2)} codes over the sphere (a figure, no bar)`);
  }
}

// ---- the Khronos glTF Sample Viewer (viewer/engines/gltf-sample-viewer.*) ----------------------
// Its renderer (npm @khronosgroup/gltf-viewer) draws the skybox from prtkit's specular.ktx2 (read by
// its own libktx reader) looked up at u_EnvRotation · d, u_EnvRotation = R_y(environmentRotation)
// (its default 90°). It encodes pow(c, 1/2.2) (tonemapping.glsl linearTosRGB) where the reference
// is sRGB-encoded: its codes are re-encoded with the sRGB curve (kept fractional) before comparing.
function gamma22ToSrgb(img) {
  const lut = new Float64Array(256);
  for (let c = 0; c < 256; c++) {
    const x = (c / 255) ** 2.2;
    lut[c] = 255 * (x <= 0.0031308 ? 12.92 * x : 1.055 * x ** (1 / 2.4) - 0.055);
  }
  const rgba = new Float64Array(img.rgba.length);
  for (let i = 0; i < rgba.length; i++) rgba[i] = i % 4 === 3 ? img.rgba[i] : lut[img.rgba[i]];
  return { ...img, rgba, png: { ...img, rgba: Buffer.from(rgba.map(Math.round)) } };
}
// Its skybox is not a pinhole view: cubemap.vert replaces the view-projection's translation column
// by (0, 0, 0, 0.1), so a vertex p of the unit cube lands where it would seen from 0.1 behind the
// cube's centre (clip w = −z_view + 0.1). The pixel whose camera ray is u shows the direction p
// where the ray from c = −0.1 f (f: the unit view direction) along u leaves the cube |p|∞ = 1.
// The reference for that pixel is render's view in direction p: read bilinearly from `wide`, a
// reference of the same camera at fov wideFov (one more pinhole: glTF frame, up +Y).
function sampleViewerReference(wide, wideFov, g, fov, w, h) {
  const f = norm(sub([0, 0, 0], g)), right = norm(cross(f, [0, 1, 0])), up = cross(right, f);
  const T = Math.tan((fov * Math.PI) / 360), Tw = Math.tan((wideFov * Math.PI) / 360);
  const c = f.map((x) => -0.1 * x);
  const rgba = new Float64Array(w * h * 4);
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const sx = (2 * (x + 0.5) / w - 1) * T * (w / h), sy = (1 - 2 * (y + 0.5) / h) * T;
      const u = [0, 1, 2].map((i) => f[i] + sx * right[i] + sy * up[i]);
      let t = Infinity;
      for (let i = 0; i < 3; i++) if (u[i] !== 0) t = Math.min(t, (Math.sign(u[i]) - c[i]) / u[i]);
      const p = [0, 1, 2].map((i) => c[i] + t * u[i]);
      const z = dot(p, f);
      const X = ((dot(p, right) / z / (Tw * (wide.width / wide.height)) + 1) / 2) * wide.width - 0.5;
      const Y = ((1 - dot(p, up) / z / Tw) / 2) * wide.height - 0.5;
      const x0 = Math.floor(X), y0 = Math.floor(Y), ax = X - x0, ay = Y - y0;
      if (x0 < 0 || y0 < 0 || x0 + 1 >= wide.width || y0 + 1 >= wide.height) throw new Error('the wide reference does not cover the Sample Viewer\'s view');
      for (let k = 0; k < 3; k++) {
        const at = (xx, yy) => wide.rgba[(yy * wide.width + xx) * 4 + k];
        rgba[(y * w + x) * 4 + k] = (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) + ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1));
      }
      rgba[(y * w + x) * 4 + 3] = 255;
    }
  }
  return { width: w, height: h, rgba };
}
async function sampleViewerTests(dir, views) {
  for (const v of views) {
    const pinhole = readPng(join(dir, `sky-${v.name}-reference.png`));
    const wideFov = 90, wide = await engineReference(dir, v, { fov: wideFov, res: '384x384', tag: '-wide' });
    const ref = sampleViewerReference(wide, wideFov, mul(M, v.eye), v.fov, 192, 192);
    writePng(join(dir, `sky-${v.name}-reference-gltf-sample-viewer.png`), { ...ref, rgba: Buffer.from(ref.rgba.map(Math.round)) });
    const eye = mul(M, v.eye).map((x) => +x.toFixed(6)).join(',');
    const shot = async (rot) => {
      const requests = [];
      const img = gamma22ToSrgb((await view({ ibl: url(bake) + '/', rot, eye, target: '0,0,0', fov: String(v.fov), res: '192x192' },
        { page: '/viewer/engines/gltf-sample-viewer.html', requests })).image);
      writePng(join(dir, `sky-${v.name}-gltf-sample-viewer-rot-${rot}.png`), img.png);
      return { img, foreign: requests.filter((r) => !r.startsWith(origin) && !r.startsWith('data:')) };
    };
    const good = await shot('0'), bad = await shot('90');
    writePng(join(dir, `sky-${v.name}-gltf-sample-viewer-diff-x8.png`), diffImage(good.img, ref));
    const a = compare(good.img, ref), c = compare(bad.img, ref), pin = compare(good.img, pinhole);
    figures[`gltf_sample_viewer_sky_${v.name}`] = { rot_0: a.mean, rot_90: c.mean, rot_0_vs_pinhole: pin.mean };
    console.log(`     glTF Sample Viewer skybox ${v.name}, environmentRotation 0, against the pinhole view itself: mean |Δ| ${pin.mean.toFixed(2)} codes (its skybox geometry, a figure)`);
    check(`glTF Sample Viewer skybox ${v.name} (specular.ktx2 via its libktx reader, environmentRotation 0) vs render's view`, a.mean <= 1 && good.foreign.length === 0,
      `mean |Δ| = ${a.mean.toFixed(3)} sRGB codes (≤ 1); requests outside 127.0.0.1: ${good.foreign.length}`);
    check(`glTF Sample Viewer skybox ${v.name} at its default environmentRotation 90 differs from render's view`, c.mean > 4 * Math.max(a.mean, 0.5),
      `mean |Δ| = ${c.mean.toFixed(3)} sRGB codes (must be far above ${a.mean.toFixed(3)})`);
  }
  // Spheres of its own glTF material lit by prtkit's specular, irradiance and DFG files, beside
  // `render --shading ibl`: figures, no bar (its lod is r·(mipCount − 1) of the reflected ray, where
  // render uses the dominant direction and the manifest's roughness per level, and it adds a
  // multiple-scattering term to the split sum, ibl.glsl's FmsEms).
  const eye = [0, -4, 0.6], g = mul(M, eye).map((x) => +x.toFixed(6)).join(','), res = '192x192';
  for (const s of [{ name: 'metal-r0.05', m: 1, r: 0.05, base: [1, 1, 1] }, { name: 'plastic-r0.5', m: 0, r: 0.5, base: [0.8, 0.2, 0.15] }]) {
    const refPng = join(dir, `sphere-${s.name}-render.png`);
    run('render', [map, '--shading', 'ibl', '--ibl', join(bake, 'ibl.json'), '--brdf', `gltf:base=${s.base.join('/')},metalness=${s.m},roughness=${s.r}`,
      '--eye', eye.join(','), '--target', '0,0,0', '--fov', '32', '--res', res, '--png', refPng, '--exposure', '0', '-q']);
    const img = gamma22ToSrgb((await view({ ibl: url(bake) + '/', mode: 'sphere', m: String(s.m), r: String(s.r), base: s.base.join(','), rot: '0', eye: g, target: '0,0,0', fov: '32', res },
      { page: '/viewer/engines/gltf-sample-viewer.html' })).image);
    writePng(join(dir, `sphere-${s.name}-gltf-sample-viewer.png`), img.png);
    const ref = readPng(refPng);
    writePng(join(dir, `sphere-${s.name}-gltf-sample-viewer-diff-x8.png`), diffImage(img, ref));
    const c = compare(img, ref, sphereMask(eye, [0, 0, 0], 32, 192, 192));
    figures[`gltf_sample_viewer_sphere_${s.name}_vs_render`] = { psnr_sphere: c.psnr, mean_sphere: c.mean };
    console.log(`     glTF Sample Viewer sphere (${s.name}) vs render --shading ibl: PSNR ${c.psnr.toFixed(2)} dB, mean |Δ| ${c.mean.toFixed(2)} codes over the sphere (a figure, no bar)`);
  }
}

// PRTKIT_VIEWER_TESTS=ibl|engines|gsv|formats|model|drop|sh|prt|glossy|lookup|cpca|quantized|n8 runs one group (development; prt
// includes glossy, lookup, cpca, quantized and n8; glossy includes lookup); all by default.
const only = process.env.PRTKIT_VIEWER_TESTS ?? '';
try {
  if (!only || only === 'ibl') {
  // 1. Skybox (specular.ktx2 level 0 in the viewer) against three.js's own view of the source map.
  const skyViews = [
    { name: 'front', eye: [0, -4, 0.3], fov: 60 },
    { name: 'side', eye: [4, 1.5, -0.5], fov: 60 },
    { name: 'up', eye: [-1, -1.5, -3.5], fov: 75 },
  ];
  const exposure = '0';
  for (const v of skyViews) {
    const cam = (frame) => ({ eye: toPage(v.eye, frame), target: '0,0,0', fov: String(v.fov), res: '192x192', exposure });
    const ref = (await view({ mode: 'equirect', src: url(map), ...cam('three') })).image;
    const sky = (await view({ mode: 'sky', ibl: url(bake) + '/', ...cam('three') })).image;
    const builtin = (await view({ mode: 'sky', sky: 'builtin', ibl: url(bake) + '/', ...cam('three') })).image;
    const raw = (await view({ mode: 'sky', frame: 'gl', ibl: url(bake) + '/', ...cam('three') })).image;
    writePng(join(out, `sky-${v.name}-three-equirect.png`), ref);
    writePng(join(out, `sky-${v.name}-viewer.png`), sky);
    writePng(join(out, `sky-${v.name}-diff-x8.png`), diffImage(sky, ref));
    const a = compare(sky, ref), b = compare(builtin, ref), c = compare(raw, ref);
    figures[`sky_${v.name}`] = { viewer_vs_three_equirect: a.mean, builtin_vs_three_equirect: b.mean, raw_gl_vs_three_equirect: c.mean };
    check(`skybox ${v.name}: viewer (specular.ktx2 level 0, x negated) vs three.js EquirectangularReflectionMapping`, a.mean <= 1,
      `mean |Δ| = ${a.mean.toFixed(3)} sRGB codes (≤ 1)`);
    check(`skybox ${v.name}: three's built-in scene.background with the loader's cube vs three's equirect`, b.mean <= 1,
      `mean |Δ| = ${b.mean.toFixed(3)} sRGB codes (≤ 1): three negates x itself`);
    check(`skybox ${v.name}: raw GL direction (no x negation) differs from three's view`, c.mean > 4 * Math.max(a.mean, 0.5),
      `mean |Δ| = ${c.mean.toFixed(3)} sRGB codes (must be far above the ${a.mean.toFixed(3)} of the negated lookup)`);
  }

  // 2. IBL spheres against prtkit render --shading ibl, same camera, no tone mapping, sRGB PNG.
  const sphereViews = [
    { name: 'gold-r0.3', m: 1, r: 0.3, eye: [0, -4, 0.6] },
    { name: 'plastic-r0.5', m: 0, r: 0.5, eye: [3, -2.5, 1.2], base: [0.8, 0.2, 0.15] },
    { name: 'metal-r0.8', m: 1, r: 0.8, eye: [-2.6, 2.8, -1], base: [0.95, 0.93, 0.88] },
    { name: 'mirror-r0.05', m: 1, r: 0.05, eye: [1.5, 3.6, 1], base: [0.95, 0.95, 0.95] },
  ];
  for (const v of sphereViews) {
    const base = v.base ?? [1, 0.78, 0.34];
    const refPng = join(out, `sphere-${v.name}-render.png`);
    run('render', [map, '--shading', 'ibl', '--ibl', join(bake, 'ibl.json'),
      '--brdf', `gltf:base=${base.join('/')},metalness=${v.m},roughness=${v.r}`,
      '--eye', v.eye.join(','), '--target', '0,0,0', '--fov', String(FOV), '--res', RES,
      '--png', refPng, '--exposure', exposure, '-q']);
    const ref = readPng(refPng);
    const [w, h] = RES.split('x').map(Number);
    const mask = sphereMask(v.eye, [0, 0, 0], FOV, w, h);
    for (const frame of ['three', 'gl']) {
      const params = { mode: 'sphere', ibl: url(bake) + '/', frame, m: String(v.m), r: String(v.r), base: base.join(','),
        eye: toPage(v.eye, frame), target: '0,0,0', fov: String(FOV), res: RES, exposure };
      let img = (await view(params)).image;
      // In three.js's convention the world is prtkit's mirrored in x: the same camera, mirrored,
      // sees the mirror image of render's picture.
      if (frame === 'three') img = mirrorX(img);
      writePng(join(out, `sphere-${v.name}-viewer-${frame}.png`), img);
      writePng(join(out, `sphere-${v.name}-diff-${frame}-x8.png`), diffImage(img, ref));
      const s = compare(img, ref, mask), all = compare(img, ref);
      figures[`sphere_${v.name}_${frame}`] = { psnr_sphere: s.psnr, mean_sphere: s.mean, psnr_frame: all.psnr, pixels: s.pixels };
      // The issue asks ≥ 35 dB. This test asks 45: an environment mirrored in x (the frame bug
      // this test exists for) still scores 37–39 dB on the rough spheres here, 26–32 dB on the
      // glossy ones; the right frame scores 53–64 dB.
      check(`IBL sphere ${v.name} (${frame} frame) vs render --shading ibl`, s.psnr >= 45,
        `PSNR ${s.psnr.toFixed(2)} dB over ${s.pixels} sphere pixels (≥ 45; the issue's bar is 35), mean |Δ| ${s.mean.toFixed(3)} codes; whole frame ${all.psnr.toFixed(2)} dB`);
      if (frame === 'three' && v.m === 0) {
        // The SH path (sh.json, same frame matrix) against render's irradiance cube: what differs
        // is the order-2 truncation of E/π, so the bar is looser; a frame error in the SH lookup
        // would show as a mirrored diffuse gradient.
        let shImg = mirrorX((await view({ ...params, diffuse: 'sh' })).image);
        writePng(join(out, `sphere-${v.name}-viewer-three-sh.png`), shImg);
        const t = compare(shImg, ref, mask);
        figures[`sphere_${v.name}_three_sh`] = { psnr_sphere: t.psnr, mean_sphere: t.mean };
        check(`IBL sphere ${v.name} (three frame, SH diffuse) vs render (irradiance cube)`, t.psnr >= 35,
          `PSNR ${t.psnr.toFixed(2)} dB (≥ 35), mean |Δ| ${t.mean.toFixed(3)} codes`);
      }
      if (frame === 'gl') {
        // Raw WebGL row of the conventions table: the skybox sampled with the unchanged world
        // direction is render's background (the source map in prtkit's frame) — off the sphere.
        const bg = mask.map((_, i) => (mask[i] ? 0 : 1));
        const grown = bg.map((x, i) => (x && !mask[i - 1] && !mask[i + 1] && !mask[i - w] && !mask[i + w] && !mask[i - 2] && !mask[i + 2] ? 1 : 0));
        const b = compare(img, ref, grown);
        figures[`background_${v.name}_gl`] = { mean: b.mean };
        check(`background ${v.name}: raw GL lookup of specular.ktx2 vs render's background`, b.mean <= 1.5,
          `mean |Δ| ${b.mean.toFixed(3)} codes (≤ 1.5: the cube level 0 against render's direct lat-long lookup)`);
      }
    }
  }

  // 3. Frame time per mode (SwiftShader: the CPU), and a grid screenshot.
  const times = {};
  for (const [mode, extra] of [['sky', {}], ['sphere', { m: '1', r: '0.3' }], ['grid', {}], ['grid', { diffuse: 'sh' }]]) {
    const key = mode + (extra.diffuse ? '+sh' : '');
    const eye = mode === 'grid' ? '0,0,17' : '0,0,4';
    const r = await view({ mode, ibl: url(bake) + '/', eye, target: '0,0,0', fov: '32', res: '640x360', exposure, ...extra }, { bench: 20 });
    times[key] = r.ms;
    writePng(join(out, `mode-${key}.png`), r.image);
    console.log(`     frame time ${key} 640×360: ${r.ms.toFixed(1)} ms (CPU, SwiftShader)`);
  }
  figures.frame_ms_640x360 = times;
  }
  if (!only || only === 'engines') await engineTests();
  if (only === 'gsv') { // the Sample Viewer's checks alone (development)
    const dir = join(out, 'engines');
    mkdirSync(dir, { recursive: true });
    for (const v of ENGINE_VIEWS) await engineReference(dir, v);
    await sampleViewerTests(dir, ENGINE_VIEWS);
  }
  if (!only || only === 'formats') await formatTests();
  if (!only || only === 'model') await modelTests();
  if (!only || only === 'drop') await dropTests();
  if (!only || only === 'sh') await shTests();
  if (!only || only === 'prt') await prtTests();
  if (!only || only === 'prt' || only === 'glossy') await glossyPrtTests();
  if (!only || only === 'prt' || only === 'glossy' || only === 'lookup') await glossyLookupTests();
  if (!only || only === 'prt' || only === 'cpca') await cpcaPrtTests();
  if (!only || only === 'prt' || only === 'quantized') await quantizedPrtTests();
  if (!only || only === 'prt' || only === 'n8') await order8PrtTests();
  if (!only || only === 'prt' || only === 'colour') await colourPrtTests();
} catch (e) {
  check('viewer pages', false, e.stack ?? String(e));
} finally {
  await browser.close();
  server.close();
  rmSync(profile, { recursive: true, force: true });
}

check('no WebGL or page errors', pageErrors.length === 0,
  pageErrors.length ? JSON.stringify(pageErrors, null, 1).slice(0, 2000) : `none in any page (${gpuName})`);
figures.gpu = gpuName;
figures.seconds = (Date.now() - t0) / 1000;
writeFileSync(join(out, 'figures.json'), JSON.stringify(figures, null, 2) + '\n');
console.log(`viewer tests: ${figures.seconds.toFixed(1)} s; screenshots and figures.json in ${relative(repo, out)}/`);
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
