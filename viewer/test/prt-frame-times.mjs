// Frame time of glossy PRT in the page: scripts/demo.sh step 9's bake (bowl-ball, Phong s = 8,
// n = 8, K from --energy 0.99) against the same bake compressed by clustered PCA
// (--clusters 32 --pca 8, relit in compressed form), at 640×360 and 64×36 (the latter: mostly the
// vertex stage), in headless Chromium on SwiftShader (the CPU).
//   node viewer/test/prt-frame-times.mjs [BIN_DIR] [OUT_DIR]   (default target/release, out/viewer/prt-frame-times)
// Bakes with the demo's own commands (plus --glsl, which the page needs), lights them with
// sample-shader's sky (sh-project -F 7; the frame time does not depend on the lighting), and
// benches each N = 30 frames back to back, each waited for, the lighting turning 1° a frame;
// three rounds, alternating. Writes frame-times.json and prints a Markdown table.
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, relative, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';
import { serve } from '../serve.mjs';

const repo = resolve(fileURLToPath(new URL('../..', import.meta.url)));
const bin = resolve(repo, process.argv[2] ?? 'target/release');
const out = resolve(repo, process.argv[3] ?? 'out/viewer/prt-frame-times');
rmSync(out, { recursive: true, force: true });
mkdirSync(out, { recursive: true });
const run = (exe, args) => execFileSync(join(bin, exe), args, { cwd: repo, stdio: ['ignore', 'pipe', 'inherit'] }).toString();
const url = (p) => '/' + relative(repo, p).split('\\').join('/');
const mesh = 'testdata/meshes/bowl-ball.obj';

// scripts/demo.sh step 9, then the same with --clusters 32 --pca 8.
run('factor-brdf', ['phong:s=8', '--domain', 'hemisphere', '--resolution', '32', '--cosine', '--factors', join(out, 'phong8.exr'),
  '--terms', '32', '-o', join(out, 'phong8.json'), '-q']);
const bakes = [['uncompressed', []], ['CPCA 32 × 8', ['--clusters', '32', '--pca', '8']]].map(([name, extra], i) => {
  const stem = join(out, i ? 'glossy-cpca' : 'glossy');
  run('transfer', [mesh, '-n', '8', '--factors', join(out, 'phong8.json'), '--energy', '0.99', ...extra,
    '--glb', stem + '.glb', '-o', stem + '.json', '--glsl', stem + '.glsl', '-q']);
  const doc = JSON.parse(readFileSync(stem + '.json', 'utf8'));
  return { name, glb: stem + '.glb', glsl: stem + '.glsl', terms: doc.glossy.terms, order: doc.order, compression: doc.compression ?? null };
});
run('sample-shader', ['testdata/shaders/sky.sl', '--latlong', '256x128', '-o', join(out, 'sky.exr'), '-q']);
run('sh-project', [join(out, 'sky.exr'), '-F', '7', '-o', join(out, 'sky7.sh.json'), '-q']);

const server = await serve({ root: repo });
const origin = `http://127.0.0.1:${server.address().port}`;
const profile = mkdtempSync(join(tmpdir(), 'prtkit-viewer-chromium-'));
const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium', headless: true, userDataDir: profile,
  args: ['--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic'],
});
// The camera of the viewer tests' glossy frame time (three.js world: prtkit's mirrored in x).
const view = { eye: '-1.6,2.2,2.6', target: '0,-0.45,0', fov: '32', exposure: '-3.5', rotate: '30' };
const results = [];
let gpu = '';
try {
  for (let round = 0; round < 3; round++) {
    for (const b of bakes) {
      for (const res of ['640x360', '64x36']) {
        const page = await browser.newPage();
        const errors = [];
        page.on('pageerror', (e) => errors.push(e.message));
        page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
        const [w, h] = res.split('x').map(Number);
        await page.setViewport({ width: w, height: h, deviceScaleFactor: 1 });
        const query = new URLSearchParams({ test: '1', mode: 'prt', glb: url(b.glb), glsl: url(b.glsl), sh: url(join(out, 'sky7.sh.json')),
          src: url(join(out, 'sky.exr')), res, ...view });
        await page.goto(`${origin}/viewer/?${query}`, { waitUntil: 'load' });
        if (!(await page.evaluate(() => window.prtkit.ready))) throw new Error(`${b.name}: ${errors.join('\n')}`);
        const ms = await page.evaluate(() => window.prtkit.bench(30));
        const cpu = b.compression ? await page.evaluate(() => window.prtkit.cpcaProjectMs(20)) : null;
        if (round === 0 && res === '640x360') await page.screenshot({ path: join(out, `${b.compression ? 'cpca' : 'uncompressed'}.png`) });
        errors.push(...(await page.evaluate(() => window.prtkit.errors.slice())));
        gpu ||= await page.evaluate(() => window.prtkit.gpu());
        results.push({ bake: b.name, res, round, ms, cluster_projection_ms: cpu, errors });
        console.error(`${b.name} ${res} round ${round}: ${ms.toFixed(1)} ms/frame${cpu != null ? `, per-cluster projection ${cpu.toFixed(2)} ms` : ''}${errors.length ? ' ERRORS ' + errors.join('; ') : ''}`);
        await page.close();
      }
    }
  }
} finally {
  await browser.close();
  server.close();
  rmSync(profile, { recursive: true, force: true });
}
const summary = bakes.map((b) => {
  const of = (res) => results.filter((r) => r.bake === b.name && r.res === res).map((r) => r.ms);
  const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
  const proj = results.filter((r) => r.bake === b.name && r.cluster_projection_ms != null).map((r) => r.cluster_projection_ms);
  return { bake: b.name, order: b.order, terms: b.terms, compression: b.compression, ms_640x360: of('640x360'), ms_64x36: of('64x36'),
    median_640x360: median(of('640x360')), median_64x36: median(of('64x36')), cluster_projection_ms: proj.length ? median(proj) : null };
});
writeFileSync(join(out, 'frame-times.json'), JSON.stringify({ gpu, summary, results }, null, 2) + '\n');
const range = (a) => `${Math.min(...a).toFixed(0)}–${Math.max(...a).toFixed(0)}`;
console.log('| bake (bowl-ball, Phong s = 8, n = 8) | per vertex | 640×360 ms (median; 3 runs) | 64×36 ms | CPU per-cluster projection ms |');
console.log('| --- | --- | ---: | ---: | ---: |');
for (const s of summary) {
  const perVertex = s.compression
    ? `cluster + ${s.compression.components} weights (relative RMS error ${(100 * s.compression.relative_rms).toFixed(1)} %)`
    : `${s.terms}·${s.order ** 2} = ${s.terms * s.order ** 2} values`;
  console.log(`| K = ${s.terms}, ${s.bake} | ${perVertex} | ${s.median_640x360.toFixed(1)} (${range(s.ms_640x360)}) | ${s.median_64x36.toFixed(1)} (${range(s.ms_64x36)}) | ${s.cluster_projection_ms == null ? '—' : s.cluster_projection_ms.toFixed(2)} |`);
}
console.log(`\n${gpu}; ${relative(repo, out)}/frame-times.json`);
