// Headless Chromium compiles the GPU crowd's shaders through WebGPU (issue 32: the same shaders in
// the browser): every compute pass of the crowd and the preview's render pipelines, with Chromium's
// WGSL compiler (Tint, stricter than wgpu's naga in places) on its software adapter (SwiftShader).
//
//   node checks/webgpu.mjs --ref target/web-ref
//
// target/web-ref/gpu-crowd.wgsl, gpu-preview.wgsl and gpu-entries.json are written by
// `cargo test -p gpu-crowd --test webgpu` (the fixture model's crowd with seams and the foot lock).
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
} finally {
  await browser.close();
}
done();
