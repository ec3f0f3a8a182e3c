// Headless Chromium test of the viewer as `motion-lod view` serves it.
//
//   node checks/browser.mjs --bin target/debug/motion-lod --walk walk.glb [--crowd crowd.glb]
//                           [--screenshot docs/figures/viewer.png]
//
// For the walk: starts `motion-lod view`, opens the printed address in Chromium (Debian's package,
// $CHROMIUM or /usr/bin/chromium, software WebGL), waits until the animation runs, takes two
// screenshots 0.6 s apart and checks that the character is drawn (pixels of its level colour
// where its bones project) and that it moves between the two. For the crowd clip: that it loads
// and shows a legend of at least two levels. No page error is allowed.
import { mkdirSync, writeFileSync } from 'node:fs';
import { dirname } from 'node:path';
import { chromium } from 'playwright-core';
import { PNG } from 'pngjs';
import { CHROMIUM_ARGS, chromiumPath, options, serve as serveFile, tally } from './common.mjs';

const args = options();
const bin = args.bin ?? 'target/debug/motion-lod';
if (!args.walk) throw new Error('--walk FILE.glb is required');
const browserPath = chromiumPath();

const servers = [];
async function serve(file) {
  const server = await serveFile(bin, file);
  servers.push(server.child);
  return server.url;
}

const { check, done } = tally();

// Pixels of the walk's colour (level 0: sRGB 220, 30, 30, shaded): clearly red.
const isCharacter = (r, g, b) => r > 50 && r > 1.5 * g + 10 && r > 1.5 * b + 10;

function redMask(png, box) {
  const mask = new Set();
  const x0 = Math.max(0, Math.floor(box.x0) - 12);
  const y0 = Math.max(0, Math.floor(box.y0) - 40);
  const x1 = Math.min(png.width - 1, Math.ceil(box.x1) + 12);
  const y1 = Math.min(png.height - 1, Math.ceil(box.y1) + 40);
  for (let y = y0; y <= y1; y++) {
    for (let x = x0; x <= x1; x++) {
      const i = 4 * (y * png.width + x);
      if (isCharacter(png.data[i], png.data[i + 1], png.data[i + 2])) mask.add(y * png.width + x);
    }
  }
  return mask;
}

const browser = await chromium.launch({ executablePath: browserPath, args: CHROMIUM_ARGS, timeout: 60000 });
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 600 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => m.type() === 'error' && errors.push(m.text()));
  const url = await serve(args.walk);
  console.log(`walk served at ${url}`);
  await page.goto(url);
  await page.waitForFunction(() => window.viewer?.ready && window.viewer.time() > 0.5, null, { timeout: 60000 });
  const t1 = await page.evaluate(() => window.viewer.time());
  const box1 = await page.evaluate(() => window.viewer.characterScreenBox());
  const shot1 = PNG.sync.read(await page.screenshot());
  await page.waitForTimeout(600);
  const t2 = await page.evaluate(() => window.viewer.time());
  const box2 = await page.evaluate(() => window.viewer.characterScreenBox());
  const shotBytes = await page.screenshot();
  const shot2 = PNG.sync.read(shotBytes);
  check(t2 !== t1, `the animation runs (t = ${t1.toFixed(2)} s, then ${t2.toFixed(2)} s)`);
  const inView = (b) => b && b.x1 > 0 && b.y1 > 0 && b.x0 < shot1.width && b.y0 < shot1.height;
  check(inView(box1) && inView(box2), `the character is in view (bones within ${JSON.stringify(box1, (k, v) => (typeof v === 'number' ? Math.round(v) : v))})`);
  const union = {
    x0: Math.min(box1.x0, box2.x0),
    y0: Math.min(box1.y0, box2.y0),
    x1: Math.max(box1.x1, box2.x1),
    y1: Math.max(box1.y1, box2.y1),
  };
  const m1 = redMask(shot1, union);
  const m2 = redMask(shot2, union);
  check(m1.size > 400 && m2.size > 400, `the character is drawn where its bones are (${m1.size} and ${m2.size} pixels of its colour)`);
  let changed = 0;
  for (const p of m1) if (!m2.has(p)) changed++;
  for (const p of m2) if (!m1.has(p)) changed++;
  check(changed > 100, `the character moves between the screenshots (${changed} pixels changed)`);
  const legend = await page.locator('#legend li').count();
  check(legend >= 1, `a legend is shown (${legend} entries)`);
  if (args.screenshot) {
    mkdirSync(dirname(args.screenshot), { recursive: true });
    writeFileSync(args.screenshot, shotBytes);
    console.log(`screenshot written to ${args.screenshot}`);
  }
  if (args.crowd) {
    const crowdUrl = await serve(args.crowd);
    await page.goto(crowdUrl);
    await page.waitForFunction(() => window.viewer?.ready && window.viewer.time() > 0.3, null, { timeout: 60000 });
    const entries = await page.locator('#legend li').count();
    check(entries >= 2, `the crowd clip plays with a legend of ${entries} levels`);
    if (args['crowd-screenshot']) writeFileSync(args['crowd-screenshot'], await page.screenshot());
  }
  check(errors.length === 0, `no page errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
} finally {
  await browser.close();
  for (const s of servers) s.kill();
}
done();
