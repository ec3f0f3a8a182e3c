// Headless Chromium compiles the GPU crowd's shaders through WebGPU (issue 32: the same shaders in
// the browser): every compute pass of the crowd and the preview's render pipelines, with Chromium's
// WGSL compiler (Tint, stricter than wgpu's naga in places) on its software adapter (SwiftShader).
//
// Then the page runs a crowd handed over by the native crowd (`GpuCrowd::host_state`: 300 walkers
// of the fixture model, seams, the foot lock and 40 joint slots, after `GpuCrowd::new`) for 60
// frames with those shaders, writing the native crowd's frame uniforms and counter resets and
// dispatching its passes as it does, and every walker's detail must equal the native crowd's after
// them and every position lie within 1e-4 m of it (issue 32's bound between the GPU and the CPU
// crowd; here two implementations of WebGPU and Vulkan on the CPU).
//
//   node checks/webgpu.mjs --ref target/web-ref
//
// target/web-ref/gpu-crowd.wgsl, gpu-preview.wgsl, gpu-entries.json and gpu-run/ are written by
// `cargo test -p gpu-crowd --test webgpu` (gpu-run/ on lavapipe).
import { existsSync, mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';
import { CHROMIUM_ARGS, chromiumPath, options, tally } from './common.mjs';

const args = options();
const ref = args.ref ?? 'target/web-ref';
for (const f of ['gpu-crowd.wgsl', 'gpu-preview.wgsl', 'gpu-entries.json']) {
  if (!existsSync(join(ref, f))) {
    throw new Error(`${ref}/${f} is missing: run \`cargo test -p gpu-crowd --test webgpu\` first`);
  }
}
const runDir = join(ref, 'gpu-run');
if (!existsSync(join(runDir, 'run.json'))) {
  throw new Error(`${runDir}/run.json is missing: run \`cargo test -p gpu-crowd --test webgpu\` with an adapter first`);
}
const run = JSON.parse(readFileSync(join(runDir, 'run.json'), 'utf8'));
const bin = (name) => readFileSync(join(runDir, name)).toString('base64');
const TOLERANCE = 1e-4;
const crowd = readFileSync(join(ref, 'gpu-crowd.wgsl'), 'utf8');
const preview = readFileSync(join(ref, 'gpu-preview.wgsl'), 'utf8');
const entries = JSON.parse(readFileSync(join(ref, 'gpu-entries.json'), 'utf8'));

const { check, done } = tally();
// WebGPU needs a secure context: a page from a file.
const dir = mkdtempSync(join(tmpdir(), 'mlod-webgpu-'));
writeFileSync(join(dir, 'blank.html'), '<!doctype html><title>WebGPU</title>');
const browser = await chromium.launch({
  executablePath: chromiumPath(),
  args: [...CHROMIUM_ARGS, '--enable-unsafe-webgpu'],
});
try {
  const page = await browser.newPage();
  await page.goto(pathToFileURL(join(dir, 'blank.html')).href);
  const result = await page.evaluate(async ({ crowd, preview, entries }) => {
    if (!navigator.gpu) return { error: 'no navigator.gpu (WebGPU off)' };
    const adapter = await navigator.gpu.requestAdapter();
    if (!adapter) return { error: 'no WebGPU adapter' };
    const limits = adapter.limits;
    const device = await adapter.requestDevice({
      requiredLimits: {
        maxComputeWorkgroupStorageSize: limits.maxComputeWorkgroupStorageSize,
        maxStorageBuffersPerShaderStage: limits.maxStorageBuffersPerShaderStage,
      },
    });
    const errors = async (module) =>
      (await module.getCompilationInfo()).messages
        .filter((m) => m.type === 'error')
        .map((m) => `${m.lineNum}:${m.linePos} ${m.message}`);
    const scoped = async (make) => {
      device.pushErrorScope('validation');
      make();
      const e = await device.popErrorScope();
      return e ? e.message.split('\n')[0] : null;
    };
    const out = { adapter: `${adapter.info?.vendor ?? ''} ${adapter.info?.architecture ?? ''}`.trim() };
    // The check can fail: the literal Tint refused before (the shortest decimal of f32::MAX).
    out.control = await errors(device.createShaderModule({ code: 'const M: f32 = 3.4028235e38;' }));
    const cm = device.createShaderModule({ code: crowd });
    out.crowd = await errors(cm);
    out.compute = {};
    for (const e of entries.compute) {
      out.compute[e] = await scoped(() =>
        device.createComputePipeline({ layout: 'auto', compute: { module: cm, entryPoint: e } }));
    }
    const pm = device.createShaderModule({ code: preview });
    out.preview = await errors(pm);
    out.render = {};
    for (const vs of entries.vertex) {
      const buffers = vs === 'grid_vs'
        ? [{ arrayStride: 12, attributes: [{ shaderLocation: 0, offset: 0, format: 'float32x3' }] }]
        : [];
      out.render[vs] = await scoped(() =>
        device.createRenderPipeline({
          layout: 'auto',
          vertex: { module: pm, entryPoint: vs, buffers },
          fragment: { module: pm, entryPoint: entries.fragment[0], targets: [{ format: 'rgba8unorm' }] },
          primitive: { topology: vs === 'grid_vs' ? 'line-list' : 'triangle-list' },
          depthStencil: { format: 'depth32float', depthWriteEnabled: true, depthCompare: 'less-equal' },
        }));
    }
    return out;
  }, { crowd, preview, entries });
  if (result.error) {
    check(false, `WebGPU in headless Chromium: ${result.error}`);
  } else {
    check(true, `a WebGPU adapter in headless Chromium: ${result.adapter}`);
    check(result.control.length > 0, `Tint refuses a literal beyond f32 (the check can fail): ${result.control[0] ?? 'accepted'}`);
    check(result.crowd.length === 0, `the crowd's compute shaders compile (${crowd.length} bytes of WGSL)${result.crowd.length ? ': ' + result.crowd.slice(0, 3).join('; ') : ''}`);
    for (const [e, err] of Object.entries(result.compute)) {
      check(err === null, `compute pipeline \`${e}\`${err ? ': ' + err : ''}`);
    }
    check(result.preview.length === 0, `the preview's shaders compile${result.preview.length ? ': ' + result.preview.slice(0, 3).join('; ') : ''}`);
    for (const [e, err] of Object.entries(result.render)) {
      check(err === null, `render pipeline \`${e}\` + \`fs\`${err ? ': ' + err : ''}`);
    }
  }
  // The handed-over crowd, run in the page.
  const handed = {
    run,
    wgsl: readFileSync(join(runDir, 'crowd.wgsl'), 'utf8'),
    buffers: run.buffers.map((b) => ({ ...b, data: bin(`binding${b.binding}.bin`) })),
    uniforms: bin('uniforms.bin'),
  };
  const ran = await page.evaluate(async ({ run, wgsl, buffers, uniforms }) => {
    const bytes = (b64) => Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const b64 = (u8) => {
      let s = '';
      for (let i = 0; i < u8.length; i += 0x8000) s += String.fromCharCode(...u8.subarray(i, i + 0x8000));
      return btoa(s);
    };
    const adapter = await navigator.gpu.requestAdapter();
    const device = await adapter.requestDevice({
      requiredLimits: {
        maxComputeWorkgroupStorageSize: adapter.limits.maxComputeWorkgroupStorageSize,
        maxStorageBuffersPerShaderStage: adapter.limits.maxStorageBuffersPerShaderStage,
      },
    });
    device.pushErrorScope('validation');
    const module = device.createShaderModule({ code: wgsl });
    const type = { Uniform: 'uniform', Storage: 'storage', ReadOnlyStorage: 'read-only-storage' };
    // The page's bind group holds every binding but 10 (the dispatch arguments); `build_args`'s
    // holds the counters (3) and the arguments.
    const layoutOf = (list) => device.createBindGroupLayout({
      entries: list.map((b) => ({
        binding: b.binding,
        visibility: GPUShaderStage.COMPUTE,
        buffer: { type: type[b.kind] },
      })),
    });
    const main = buffers.filter((b) => b.binding !== 10);
    const argsOnly = buffers.filter((b) => b.binding === 3 || b.binding === 10);
    const layout = layoutOf(main);
    const argsLayout = layoutOf(argsOnly);
    const pipelineLayout = device.createPipelineLayout({ bindGroupLayouts: [layout] });
    const argsPipelineLayout = device.createPipelineLayout({ bindGroupLayouts: [argsLayout] });
    const pipelines = Object.fromEntries(run.passes.map(([entry, dispatch]) => [
      entry,
      device.createComputePipeline({
        layout: dispatch === 'Arguments' ? argsPipelineLayout : pipelineLayout,
        compute: { module, entryPoint: entry },
      }),
    ]));
    const gpu = {};
    for (const b of buffers) {
      const data = bytes(b.data);
      const usage = b.kind === 'Uniform'
        ? GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST
        : GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST
          | (b.binding === 10 ? GPUBufferUsage.INDIRECT : 0);
      const buffer = device.createBuffer({ size: Math.max(4, data.length), usage, mappedAtCreation: true });
      new Uint8Array(buffer.getMappedRange()).set(data);
      buffer.unmap();
      gpu[b.binding] = buffer;
    }
    const bindOf = (layout, list) => device.createBindGroup({
      layout,
      entries: list.map((b) => ({ binding: b.binding, resource: { buffer: gpu[b.binding] } })),
    });
    const bind = bindOf(layout, main);
    const argsBind = bindOf(argsLayout, argsOnly);
    const frames = bytes(uniforms);
    const [gx, gy] = run.workgroups;
    for (let f = 0; f < run.frames; f++) {
      device.queue.writeBuffer(gpu[0], 0, frames, f * run.uniform_bytes, run.uniform_bytes);
      for (const [offset, values] of run.resets) {
        device.queue.writeBuffer(gpu[3], offset, new Uint32Array(values));
      }
      const encoder = device.createCommandEncoder();
      const pass = encoder.beginComputePass();
      pass.setBindGroup(0, bind);
      for (const [entry, dispatch] of run.passes) {
        pass.setPipeline(pipelines[entry]);
        if (dispatch === 'Walkers') pass.dispatchWorkgroups(gx, gy);
        else if (dispatch === 'One') pass.dispatchWorkgroups(1);
        else if (dispatch === 'Arguments') {
          pass.setBindGroup(0, argsBind);
          pass.dispatchWorkgroups(1);
          pass.setBindGroup(0, bind);
        } else pass.dispatchWorkgroupsIndirect(gpu[10], 0);
      }
      pass.end();
      device.queue.submit([encoder.finish()]);
    }
    const read = async (buffer) => {
      const staging = device.createBuffer({ size: buffer.size, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
      const encoder = device.createCommandEncoder();
      encoder.copyBufferToBuffer(buffer, 0, staging, 0, buffer.size);
      device.queue.submit([encoder.finish()]);
      await staging.mapAsync(GPUMapMode.READ);
      const out = b64(new Uint8Array(staging.getMappedRange().slice(0)));
      staging.unmap();
      return out;
    };
    const walkers = await read(gpu[2]);
    const joints = await read(gpu[9]);
    const error = await device.popErrorScope();
    return { error: error ? error.message : null, walkers, joints };
  }, handed);
  check(ran.error === null, `the handed-over crowd runs ${run.frames} frames in the page${ran.error ? ': ' + ran.error : ''}`);
  // Every walker's detail and positions, from either side's walker and joint buffers (bytes).
  const decode = (wb, jb) => {
    const w = new Uint32Array(wb.buffer, wb.byteOffset, wb.byteLength / 4);
    const wf = new Float32Array(wb.buffer, wb.byteOffset, wb.byteLength / 4);
    const j = new Float32Array(jb.buffer, jb.byteOffset, jb.byteLength / 4);
    const F = run.fields;
    const out = [];
    for (let i = 0; i < run.walkers; i++) {
      const o = i * F.words;
      const p = [wf[o + F.root], wf[o + F.root + 1], wf[o + F.root + 2]];
      const slot = w[o + F.slot];
      if (w[o + F.cur_joints] > 0 && slot !== 0xffffffff) {
        for (let k = 0; k < w[o + F.shown]; k++) {
          for (let c = 0; c < 3; c++) p.push(j[(3 * k + c) * run.slots + slot]);
        }
      }
      out.push({ detail: [w[o + F.cur_acc], w[o + F.cur_joints]], p });
    }
    return out;
  };
  const native = decode(readFileSync(join(runDir, 'expected-walkers.bin')),
    readFileSync(join(runDir, 'expected-joints.bin')));
  const browserSide = decode(Buffer.from(ran.walkers, 'base64'), Buffer.from(ran.joints, 'base64'));
  let details = 0;
  let worst = 0;
  let at = null;
  let withJoints = 0;
  for (let i = 0; i < run.walkers; i++) {
    const a = browserSide[i];
    const b = native[i];
    if (a.detail[0] !== b.detail[0] || a.detail[1] !== b.detail[1] || a.p.length !== b.p.length) {
      details++;
      continue;
    }
    if (b.detail[1] > 0) withJoints++;
    for (let k = 0; k < a.p.length; k++) {
      const d = Math.abs(a.p[k] - b.p[k]);
      if (!(d <= worst)) {
        worst = d;
        at = `walker ${i}, value ${k}`;
      }
    }
  }
  check(details === 0, `every walker's detail as the native crowd's after ${run.frames} frames (${details} differ; ${withJoints} with joints)`);
  check(worst <= TOLERANCE, `every position within ${TOLERANCE} m of the native crowd's: worst ${worst.toExponential(2)} m${at ? ' (' + at + ')' : ''}`);
} finally {
  await browser.close();
}
done();
