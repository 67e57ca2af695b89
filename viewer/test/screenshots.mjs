// Screenshots of the interactive page (panel included) and frame times per mode, for the docs.
//   node viewer/test/screenshots.mjs BAKE_DIR [OUT_DIR]     (OUT_DIR default out/viewer/docs)
// Frame time: N frames rendered back to back, each waited for (readPixels of one pixel), with the
// environment turning one degree per frame; headless Chromium with SwiftShader, i.e. on the CPU.
import { mkdirSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';
import { serve } from '../serve.mjs';

const repo = resolve(fileURLToPath(new URL('../..', import.meta.url)));
const bake = resolve(process.argv[2]);
const out = resolve(process.argv[3] ?? join(repo, 'out/viewer/docs'));
mkdirSync(out, { recursive: true });
const server = await serve({ root: repo, bake });
const origin = `http://127.0.0.1:${server.address().port}`;
const profile = mkdtempSync(join(tmpdir(), 'prtkit-viewer-chromium-'));
const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium', headless: true, userDataDir: profile,
  args: ['--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic'],
});
const results = [];
try {
  for (const [name, query, shot] of [
    ['grid', 'mode=grid&exposure=2.5', true],
    ['grid, SH diffuse', 'mode=grid&exposure=2.5&diffuse=sh', false],
    ['sphere', 'mode=sphere&r=0.2&m=1&exposure=2.5', true],
    ['sky', 'mode=sky&exposure=2.5', false],
  ]) {
    for (const [w, h] of [[640, 360], [800, 450], [1280, 720]]) {
      const page = await browser.newPage();
      const errors = [];
      page.on('pageerror', (e) => errors.push(e.message));
      page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
      await page.setViewport({ width: w, height: h, deviceScaleFactor: 1 });
      await page.goto(`${origin}/viewer/?ibl=/bake/&${query}`, { waitUntil: 'load' });
      if (!(await page.evaluate(() => window.prtkit.ready))) throw new Error(`${name}: ${errors.join('\n')}`);
      await new Promise((ok) => setTimeout(ok, 1500)); // a few frames of the animation loop
      if (shot && w === 800) await page.screenshot({ path: join(out, `viewer-${name}.png`) });
      const ms = await page.evaluate(() => window.prtkit.bench(30));
      results.push({ mode: name, size: `${w}x${h}`, ms, errors });
      console.log(`${name} ${w}x${h}: ${ms.toFixed(1)} ms/frame${errors.length ? ' ERRORS ' + errors.join('; ') : ''}`);
      await page.close();
    }
  }
  const page = await browser.newPage();
  await page.goto(`${origin}/viewer/?ibl=/bake/&test=1&res=64x64`);
  await page.evaluate(() => window.prtkit.ready);
  const gpu = await page.evaluate(() => window.prtkit.gpu());
  writeFileSync(join(out, 'frame-times.json'), JSON.stringify({ gpu, chromium: await browser.version(), results }, null, 2) + '\n');
  console.log(gpu);
} finally {
  await browser.close();
  server.close();
  rmSync(profile, { recursive: true, force: true });
}
