// The live page's figures for README, measured in one run (not a test: it asserts nothing):
//   1. the pose kernel, native (crates/motion-lod-ffi/examples/pose_bench.rs, release) against the
//      runtime compiled to WebAssembly in headless Chromium (`benchPose` of viewer/crowd.js): the
//      median nanoseconds a call at every level, and their ratio;
//   2. the live crowd in headless Chromium (software GL: SwiftShader) at growing walker counts:
//      milliseconds a frame (the interval between animation frames), split into the runtime
//      (clips and poses; FK) and drawing, and the largest count kept at 60 fps.
//
//   node checks/bench.mjs --bin target/release/motion-lod --native target/release/examples/pose_bench
//                         --model MODEL.mlod [--counts 1000,3000,10000,30000,100000]
import { execFileSync } from 'node:child_process';
import { statSync } from 'node:fs';
import { chromium } from 'playwright-core';
import { CHROMIUM_ARGS, chromiumPath, options, serve } from './common.mjs';

const args = options();
const counts = (args.counts ?? '1000,3000,10000,30000,100000').split(',').map(Number);
if (!args.model || !args.native || !args.bin) throw new Error('--bin, --native and --model are required');

const server = await serve(args.bin, args.model);
const browser = await chromium.launch({ executablePath: chromiumPath(), args: CHROMIUM_ARGS });
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 540 } });
  await page.goto(`${server.url}?fast`);
  await page.waitForFunction(() => window.live?.ready, null, { timeout: 60000 });
  const model = await page.evaluate(() => window.live.model());
  console.log(`model ${args.model}: ${model.joints} joints, ${model.levels} levels`);
  console.log(`wasm: ${statSync('viewer/wasm/motion_lod.wasm').size} bytes`);
  // The page's frame loop stops while the kernels are timed, on both sides.
  await page.evaluate(() => window.live.pause(true));
  console.log('\n| level | native pose (ns) | wasm pose (ns) | ratio | native pose + FK (ns) | wasm pose + FK (ns) | ratio |');
  console.log('|---|---|---|---|---|---|---|');
  for (let level = 0; level < model.levels; level++) {
    const native = JSON.parse(execFileSync(args.native, [args.model, String(level)], { encoding: 'utf8' }));
    const wasm = await page.evaluate((l) => window.live.benchPose(l), level);
    console.log(`| ${level} | ${native.poseNs.toFixed(0)} | ${wasm.poseNs.toFixed(0)} | ${(wasm.poseNs / native.poseNs).toFixed(2)} | ` +
      `${native.poseFkNs.toFixed(0)} | ${wasm.poseFkNs.toFixed(0)} | ${(wasm.poseFkNs / native.poseFkNs).toFixed(2)} |`);
  }
  const native = JSON.parse(execFileSync(args.native, [args.model, '0'], { encoding: 'utf8' }));
  const away = await page.evaluate(() => window.live.benchStep(-1));
  const facing = await page.evaluate(() => window.live.benchStep(1));
  console.log('\n| crowd step (mlod_walkers_step, 2,000 walkers) | native (ns a walker) | wasm (ns a walker) | ratio |');
  console.log('|---|---|---|---|');
  console.log(`| camera facing the crowd | ${native.stepFacingNs.toFixed(0)} | ${facing.toFixed(0)} | ${(facing / native.stepFacingNs).toFixed(2)} |`);
  console.log(`| camera facing away (all root only) | ${native.stepAwayNs.toFixed(0)} | ${away.toFixed(0)} | ${(away / native.stepAwayNs).toFixed(2)} |`);
  await page.evaluate(() => window.live.pause(false));
  console.log('\n| walkers | ms a frame | frames/s | runtime: clips and poses (ms) | FK (ms) | drawing (ms) | in view with joints | root only |');
  console.log('|---|---|---|---|---|---|---|---|');
  let kept = 0;
  for (const n of counts) {
    await page.evaluate((c) => window.live.setMode('crowd', c), n);
    await page.waitForTimeout(2000);
    await page.evaluate(() => window.live.resetTiming());
    await page.waitForTimeout(4000);
    const t = await page.evaluate(() => window.live.timing());
    const animated = t.levels.slice(0, -1).reduce((a, b) => a + b, 0);
    console.log(`| ${n} | ${t.frameMs.toFixed(1)} | ${(1000 / t.frameMs).toFixed(1)} | ${t.runtimeMs.toFixed(2)} | ${t.fkMs.toFixed(2)} | ` +
      `${t.drawMs.toFixed(2)} | ${animated} | ${t.levels.at(-1)} |`);
    if (t.frameMs <= 1000 / 60 * 1.05) kept = n;
  }
  console.log(`\nlargest crowd at 60 fps: ${kept || 'none of those measured'}`);
  console.log(`machine: ${execFileSync('nproc', { encoding: 'utf8' }).trim()} cores; ${await browser.version()}`);
} finally {
  await browser.close();
  server.child.kill();
}
