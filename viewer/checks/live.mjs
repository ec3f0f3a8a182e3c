// Headless Chromium test of the live page (issue 31): the runtime compiled to WebAssembly, served
// by `motion-lod view MODEL.mlod` from the binary's embedded copy, gives the same poses as the
// native runtime, and a walker steered from the keyboard changes its walk at its next cycle.
//
//   node checks/live.mjs --bin target/debug/motion-lod --ref target/web-ref [--screenshot FILE]
//                        [--crowd-screenshot FILE]
//
// target/web-ref/ is written by `cargo test -p motion-lod-ffi --test integration web_reference::`: the model,
// the scripts (a walk whose controls and detail change over 10 cycles; a crowd of 1,000 walkers
// for 300 frames, their details from a camera) and what the native runtime gives for them. The
// page runs the same scripts (viewer/crowd.js) and every value must agree within 1e-5 (metres,
// seconds, quaternion components; details and visibility exactly).
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { chromium } from 'playwright-core';
import { CHROMIUM_ARGS, chromiumPath, options, serve as serveFile, tally } from './common.mjs';

const args = options();
const bin = args.bin ?? 'target/debug/motion-lod';
const ref = args.ref ?? 'target/web-ref';
const TOLERANCE = 1e-5;
const browserPath = chromiumPath();
if (!existsSync(join(ref, 'script.json'))) {
  throw new Error(`${ref}/script.json is missing: run \`cargo test -p motion-lod-ffi --test integration web_reference::\` first`);
}

const { check, done } = tally();
const serve = (file) => serveFile(bin, file);

const typed = (bytes, Type) => new Type(bytes.buffer, bytes.byteOffset, bytes.byteLength / Type.BYTES_PER_ELEMENT);
const fromBase64 = (s, Type) => typed(Buffer.from(s, 'base64'), Type);

/// The largest difference between two arrays and where, or null when their lengths differ.
export function compare(page, native) {
  if (page.length !== native.length) return null;
  let worst = 0;
  let at = -1;
  for (let i = 0; i < page.length; i++) {
    const d = Math.abs(page[i] - native[i]);
    if (!(d <= worst)) {
      worst = d;
      at = i;
    }
  }
  return { worst, at };
}

const script = JSON.parse(readFileSync(join(ref, 'script.json'), 'utf8'));
const expected = {
  walk_states: [Float64Array, 'walk_states.f64'],
  walk_joints: [Float32Array, 'walk_joints.f32'],
  crowd_roots: [Float64Array, 'crowd_roots.f64'],
  crowd_details: [Float32Array, 'crowd_details.f32'],
  crowd_joints: [Float32Array, 'crowd_joints.f32'],
};

// The comparison can fail: a value moved by twice the tolerance is caught.
{
  const a = new Float32Array([0, 1, 2]);
  const b = Float32Array.from(a);
  b[1] += 2 * TOLERANCE;
  const c = compare(a, b);
  check(c.worst > TOLERANCE && c.at === 1, 'the comparison flags a value moved by 2e-5');
}

const server = await serve(join(ref, 'model.mlod'));
console.log(server.line);
const browser = await chromium.launch({ executablePath: browserPath, args: CHROMIUM_ARGS, timeout: 60000 });
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 600 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => m.type() === 'error' && errors.push(m.text()));
  await page.goto(server.url);
  await page.waitForFunction(() => window.live?.ready, null, { timeout: 60000 });
  const info = await page.evaluate(() => ({ version: window.live.version, model: window.live.model() }));
  check(info.model.joints === script.joints, `the page loaded the served model (${info.model.joints} joints, ` +
    `${info.model.levels} levels, styles ${info.model.styles.map((s) => s.name).join(', ')}; runtime ${info.version})`);

  // 1. The scripts: the page's poses against the native runtime's.
  const started = Date.now();
  const got = await page.evaluate((s) => window.live.runScripts(s), script);
  console.log(`scripts ran in the page in ${((Date.now() - started) / 1000).toFixed(1)} s`);
  for (const [name, [Type, file]] of Object.entries(expected)) {
    const native = typed(readFileSync(join(ref, file)), Type);
    const mine = fromBase64(got[name], Type);
    const c = compare(mine, native);
    const exact = name === 'crowd_details';
    check(c !== null && (exact ? c.worst === 0 : c.worst <= TOLERANCE),
      c === null ? `${name}: ${mine.length} values from the page, ${native.length} native`
        : `${name}: ${native.length} values, largest difference ${c.worst.toExponential(2)}${c.at >= 0 ? ` (value ${c.at})` : ''}, ` +
          `${exact ? 'must be 0' : `tolerance ${TOLERANCE}`}`);
  }

  // 2. Steering: keys change the controls; the walk takes them at its next cycle.
  await page.evaluate(() => window.live.setMode('walk'));
  const sample = async (n, into) => {
    for (let k = 0; k < n; k++) {
      into.push(await page.evaluate(() => window.live.state()));
      await page.waitForTimeout(100);
    }
  };
  // The cycle frame's origin of every cycle seen, and each cycle's length (origin to origin).
  const lengths = (trace) => {
    const origin = new Map(trace.map((s) => [s.cycle, [s.cycleX, s.cycleZ]]));
    const out = new Map();
    for (const [c, [x, z]] of origin) {
      const next = origin.get(c + 1);
      if (next) out.set(c, Math.hypot(next[0] - x, next[1] - z));
    }
    return out;
  };
  const early = [];
  await sample(30, early);
  const before = await page.evaluate(() => ({ state: window.live.state(), controls: window.live.controls() }));
  for (let k = 0; k < 8; k++) await page.keyboard.press('KeyW');
  for (let k = 0; k < 3; k++) await page.keyboard.press('KeyE');
  const pressed = await page.evaluate(() => ({ state: window.live.state(), controls: window.live.controls() }));
  check(pressed.controls.dz > before.controls.dz && pressed.controls.dx > before.controls.dx,
    `W and E raise the speed (${before.controls.dz.toFixed(2)} -> ${pressed.controls.dz.toFixed(2)} m a cycle) ` +
    `and the sidestep (${before.controls.dx.toFixed(3)} -> ${pressed.controls.dx.toFixed(3)} m a cycle)`);
  const trace = [];
  await sample(50, trace);
  // Until the cycle ends, the walk goes on as it was built: its cycle frame stays.
  const sameCycle = trace.filter((s) => s.cycle === pressed.state.cycle);
  check(sameCycle.every((s) => s.cycleX === pressed.state.cycleX && s.cycleZ === pressed.state.cycleZ),
    `the cycle under way keeps its frame (${sameCycle.length} samples of cycle ${pressed.state.cycle})`);
  const all = lengths([...early, ...trace]);
  const old = [...all].filter(([c]) => c < pressed.state.cycle).map(([, l]) => l);
  const fresh = [...all].filter(([c]) => c > pressed.state.cycle).map(([, l]) => l);
  const mean = (v) => v.reduce((a, b) => a + b, 0) / v.length;
  check(old.length > 0 && fresh.length > 0 && mean(fresh) > mean(old) + 0.05,
    `the next cycles are longer: ${old.map((l) => l.toFixed(2)).join(', ')} m before the keys, ` +
    `${fresh.map((l) => l.toFixed(2)).join(', ')} m from the next cycle on`);
  check(trace.filter((s) => s.footLocked).length > trace.length / 2,
    `the foot lock runs (${trace.filter((s) => s.footLocked).length} of ${trace.length} samples)`);
  // A control the model ignores is shown as such, and its keys say so instead of moving it.
  const shown = await page.evaluate(() => ['dz', 'turn', 'dx', 'height'].map((n) =>
    [n, document.getElementById(n).disabled, document.getElementById(`${n}-out`).textContent]));
  const ignored = new Set(info.model.ignored);
  check(shown.every(([n, disabled, text]) => disabled === ignored.has(n) && (text === 'ignored') === ignored.has(n)),
    `controls the model ignores (${info.model.ignored.join(', ') || 'none'}) are shown ignored: ${shown.map(([n, d, t]) => `${n} ${t}`).join(', ')}`);
  if (ignored.has('turn')) {
    await page.keyboard.press('KeyA');
    await page.waitForTimeout(300); // the readout keeps the notice over the next frames
    const said = await page.evaluate(() => document.getElementById('walk-readout').textContent);
    check(said.includes('ignores turn'), `A on a model that ignores turn says so: "${said}"`);
  }

  // 3. A steered walk recorded from the page passes the motion-quality meter
  //    (`motion-lod quality --recorded`) at the thresholds of native walks: pop at most 1.25x and
  //    skate at most 1.5x the data's.
  //    From mid-range controls, slower, a sidestep each way, then faster again (the controls at the
  //    edges of the data's range are issue 34's grid).
  await page.evaluate(() => { window.live.resetControls(); window.live.setMode('walk'); });
  await page.evaluate(() => window.live.startRecording());
  const keys = ['KeyS', 'KeyS', 'KeyQ', 'KeyQ', 'KeyQ', 'KeyE', 'KeyE', 'KeyE', 'KeyW'];
  for (let k = 0; k < 400 && (await page.evaluate(() => window.live.recordedFrames())) < 420; k++) {
    if (k % 10 === 0 && keys.length) await page.keyboard.press(keys.shift());
    await page.waitForTimeout(50);
  }
  const recordingFile = join(ref, 'page-walk.json');
  writeFileSync(recordingFile, JSON.stringify(await page.evaluate(() => window.live.stopRecording())));
  const q = JSON.parse(execFileSync(bin, ['quality', join(ref, 'model.mlod'), '--recorded', recordingFile, '--json'],
    { encoding: 'utf8' }));
  const pop = q.recorded.pop_cm / q.data.pop_cm;
  const skate = q.recorded.skate_cm_s / q.data.skate_cm_s;
  check(q.seams >= 3 && pop <= 1.25 && skate <= 1.5,
    `the walk recorded from the page (${q.frames} frames, ${q.seams} seams, steered) passes the meter: ` +
    `pop ${pop.toFixed(2)}x and skate ${skate.toFixed(2)}x the data (at most 1.25x and 1.5x), ` +
    `floating ${q.recorded.floating_cm.toFixed(2)} cm`);
  if (args.screenshot) {
    mkdirSync(dirname(args.screenshot), { recursive: true });
    writeFileSync(args.screenshot, await page.screenshot());
    console.log(`screenshot written to ${args.screenshot}`);
  }

  // 3. The live crowd: the policy from the page's camera gives near walkers joints, far ones less.
  await page.evaluate(() => window.live.setMode('crowd', 1000));
  await page.waitForTimeout(3000);
  const t = await page.evaluate(() => window.live.timing());
  const animated = t.levels.slice(0, -1).reduce((a, b) => a + b, 0);
  check(t.frames > 0 && animated > 0 && t.levels.at(-1) > 0,
    `the crowd of 1,000 runs: ${animated} walkers in view with joints, ${t.levels.at(-1)} root only; ` +
    `runtime ${t.runtimeMs.toFixed(2)} ms + FK ${t.fkMs.toFixed(2)} ms a frame`);
  if (args['crowd-screenshot']) {
    mkdirSync(dirname(args['crowd-screenshot']), { recursive: true });
    writeFileSync(args['crowd-screenshot'], await page.screenshot());
    console.log(`screenshot written to ${args['crowd-screenshot']}`);
  }
  check(errors.length === 0, `no page errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);

  // 4. `motion-lod view` without a file serves the page alone; a model picked in it opens.
  const bare = await serve(null);
  try {
    const other = await browser.newPage({ viewport: { width: 960, height: 600 } });
    const pageErrors = [];
    other.on('pageerror', (e) => pageErrors.push(String(e)));
    await other.goto(bare.url);
    await other.waitForFunction(() => window.live && !window.live.ready && !document.getElementById('message').hidden,
      null, { timeout: 60000 });
    await other.setInputFiles('#open', join(ref, 'model.mlod'));
    await other.waitForFunction(() => window.live?.ready, null, { timeout: 60000 });
    const picked = await other.evaluate(() => ({ joints: window.live.model().joints,
      name: document.getElementById('file-name').textContent }));
    check(picked.joints === script.joints && pageErrors.length === 0,
      `a model picked in the page served without a file opens: "${picked.name}"`);
  } finally {
    bare.child.kill();
  }
} finally {
  await browser.close();
  server.child.kill();
}
done();
