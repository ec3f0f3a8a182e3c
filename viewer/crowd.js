// Walkers driven through the runtime (mlod.js): the live crowd of the page, and the scripted runs
// the browser test compares with the native runtime (crates/motion-lod-ffi/tests/web_reference.rs
// walks the same scripts through the same C ABI in Rust).
import { Walker, TRANSFORM_FLOATS, CONTROLS_BYTES, STATE_BYTES } from './mlod.js';

/// A crowd: walker i starts at `starts[i]` = [x, z, heading] and walks its cycle k with
/// `presets[(7 i + 3 k) mod presets.length]`, its path; every frame the model's distance policy
/// gives each walker its detail from the camera (out of view: root only), used from its next cycle.
export class Crowd {
  constructor(model, { starts, presets, radius = 1.2, footLock = true }) {
    const rt = (this.rt = model.rt);
    this.model = model;
    this.presets = presets;
    this.radius = radius;
    this.starts = starts;
    const n = (this.count = starts.length);
    // The arrays `mlod_walkers_step` takes: walker pointers, next controls, states, visibility.
    this.lens = [4 * n, CONTROLS_BYTES * n, STATE_BYTES * n, n];
    [this.ptrs, this.controls, this.states, this.visiblePtr] = this.lens.map((len) => rt.alloc(Math.max(len, 16)));
    this.walkers = starts.map((_, i) => {
      const w = new Walker(model);
      w.useSlots(this.controls + CONTROLS_BYTES * i, this.states + STATE_BYTES * i);
      w.setFootLock(footLock);
      return w;
    });
    const u32 = rt.u32;
    this.walkers.forEach((w, i) => { u32[(this.ptrs >> 2) + i] = w.ptr; });
    // The cycle whose controls each walker's slot holds (as its next cycle's).
    this.given = new Int32Array(n);
  }

  /// Whether walker i was in view at the last frame (0 or 1).
  get visible() {
    return this.rt.bytes.subarray(this.visiblePtr, this.visiblePtr + this.count);
  }

  /// Walker i's controls for its cycle k.
  controlsFor(i, k) {
    return this.presets[(7 * i + 3 * k) % this.presets.length];
  }

  /// The first frame: each walker's detail from the camera at its start, then its walk starts;
  /// its slot then holds its second cycle's controls.
  start(cameraPtr) {
    for (let i = 0; i < this.count; i++) {
      const [x, z, heading] = this.starts[i];
      const d = this.model.detailFromCamera(cameraPtr, x, 1.0, z, this.radius);
      const w = this.walkers[i];
      w.start(this.controlsFor(i, 0), d, x, z, heading);
      this.rt.bytes[this.visiblePtr + i] = d.visible ? 1 : 0;
      this.rt.writeControls(w.controls, this.controlsFor(i, 1));
      this.given[i] = 1;
    }
  }

  /// One frame `dt` seconds on, in one call of the runtime (`mlod_walkers_step`): each walker's
  /// detail from the camera where it is, then its step with its next cycle's controls; a walker
  /// that began a cycle gets the controls of the one after in its slot.
  step(dt, cameraPtr) {
    const rt = this.rt;
    const status = rt.x.mlod_walkers_step(this.ptrs, this.count, this.model.ptr, cameraPtr, this.radius, dt,
      this.controls, this.states, this.visiblePtr);
    if (status !== 0) rt.check('mlod_walkers_step', status);
    const u32 = rt.u32;
    const { given } = this;
    for (let i = 0; i < this.count; i++) {
      const s = (this.states + STATE_BYTES * i) >> 2;
      const next = u32[s + 4] + 1;
      if (given[i] !== next) {
        given[i] = next;
        rt.writeControls(this.controls + CONTROLS_BYTES * i, this.controlsFor(i, next));
      }
    }
  }

  free() {
    for (const w of this.walkers) w.free();
    this.walkers = [];
    [this.ptrs, this.controls, this.states, this.visiblePtr].forEach((p, k) => this.rt.free(p, Math.max(this.lens[k], 16)));
  }
}

/// The floats of a walker's state the test compares, in order: time in cycle, cycle, root
/// position (3), root rotation (4), cycle x, cycle z, heading, body scale, level, joints, foot
/// locked.
export const STATE_VALUES = 16;

function stateValues(w, out, at) {
  const s = w.readState();
  const v = [s.timeInCycle, s.cycle, ...s.root, ...s.rootRotation, s.cycleX, s.cycleZ, s.heading,
    s.bodyScale, s.level, s.joints, s.footLocked ? 1 : 0];
  out.set(v, at);
}

/// Runs a scripted walk: one walker started with `cycles[0]` at (x, z, heading), then `frames - 1`
/// steps of `dt`, each giving the controls and detail of `cycles[min(cycle + 1, last)]` for the
/// next cycle. Returns every frame's state (Float64Array, STATE_VALUES a frame) and joint
/// transforms (Float32Array, 7 a joint: rotation x, y, z, w, translation x, y, z).
export function runWalk(runtime, model, script) {
  const { dt, frames, cycles, x, z, heading, footLock } = script;
  const J = model.joints;
  const states = new Float64Array(frames * STATE_VALUES);
  const joints = new Float32Array(frames * J * TRANSFORM_FLOATS);
  const w = new Walker(model);
  try {
    w.setFootLock(footLock);
    w.start(cycles[0].controls, cycles[0].detail, x, z, heading);
    for (let f = 0; f < frames; f++) {
      if (f > 0) {
        const k = Math.min(w.cycle() + 1, cycles.length - 1);
        w.setDetail(cycles[k].detail);
        w.advance(dt, cycles[k].controls);
      }
      stateValues(w, states, f * STATE_VALUES);
      const at = w.computeTransforms();
      joints.set(runtime.f32.subarray(at, at + J * TRANSFORM_FLOATS), f * J * TRANSFORM_FLOATS);
    }
  } finally {
    w.free();
  }
  return { states, joints };
}

/// Runs a scripted crowd (`Crowd` with the script's starts, presets and camera) for `frames`
/// frames. Returns per frame and walker the root position (3, Float64Array) and [level, joints,
/// visible] (Float32Array), and the joint transforms of every `sampleWalkers`-th walker at every
/// `sampleFrames`-th frame and the last.
export function runCrowd(runtime, model, script) {
  const { dt, frames, camera, starts, presets, radius, sampleWalkers, sampleFrames } = script;
  const n = starts.length;
  const J = model.joints;
  const cameraPtr = runtime.alloc(64);
  runtime.writeCamera(cameraPtr, camera);
  const crowd = new Crowd(model, { starts, presets, radius, footLock: true });
  const roots = new Float64Array(frames * n * 3);
  const details = new Float32Array(frames * n * 3);
  const sampled = [];
  try {
    for (let f = 0; f < frames; f++) {
      if (f === 0) crowd.start(cameraPtr);
      else crowd.step(dt, cameraPtr);
      const visible = crowd.visible;
      for (let i = 0; i < n; i++) {
        const w = crowd.walkers[i];
        const at = (f * n + i) * 3;
        roots[at] = w.rootX(); roots[at + 1] = w.rootY(); roots[at + 2] = w.rootZ();
        details[at] = w.level(); details[at + 1] = w.joints(); details[at + 2] = visible[i];
      }
      if (f % sampleFrames === 0 || f === frames - 1) {
        for (let i = 0; i < n; i += sampleWalkers) {
          const at = crowd.walkers[i].computeTransforms();
          sampled.push(runtime.f32.slice(at, at + J * TRANSFORM_FLOATS));
        }
      }
    }
  } finally {
    crowd.free();
    runtime.free(cameraPtr, 64);
  }
  const joints = new Float32Array(sampled.length * J * TRANSFORM_FLOATS);
  sampled.forEach((s, k) => joints.set(s, k * J * TRANSFORM_FLOATS));
  return { roots, details, joints };
}

/// Times the pose kernel as the native benchmark does (crates/motion-lod-ffi/examples/pose_bench.rs):
/// one clip at `detail` for mid-range controls, then `batch` poses at spread times per sample, with
/// and without the joint transforms (FK). Returns the median nanoseconds a call of each.
export function benchPose(model, detail, { batch = 20000, samples = 15 } = {}) {
  const w = new Walker(model);
  const mid = (k) => 0.5 * (model.min[k] + model.max[k]);
  const duration = w.prepare({ dx: mid('dx'), dz: mid('dz'), turn: mid('turn'), height: mid('height') }, detail);
  const median = (v) => v.sort((a, b) => a - b)[v.length >> 1];
  const time = (fk) => {
    const per = [];
    for (let s = 0; s < samples + 2; s++) {
      const t0 = performance.now();
      for (let i = 0; i < batch; i++) {
        w.pose((duration * i) / batch);
        if (fk) w.computeTransforms();
      }
      if (s >= 2) per.push(((performance.now() - t0) * 1e6) / batch);
    }
    return median(per);
  };
  try {
    return { poseNs: time(false), poseFkNs: time(true) };
  } finally {
    w.free();
  }
}

/// Times `mlod_walkers_step` per walker as the native benchmark does (pose_bench.rs, `crowd_step`):
/// 2,000 walkers on a grid 2 m apart started at level 0, the camera at the grid's near edge
/// looking along `directionZ` (+1 over the crowd, -1 away: every walker root only). Returns the
/// median nanoseconds a walker.
export function benchStep(model, directionZ, { samples = 15 } = {}) {
  const rt = model.rt;
  const n = 2000;
  const mid = (k) => 0.5 * (model.min[k] + model.max[k]);
  const controls = { dx: mid('dx'), dz: mid('dz'), turn: mid('turn'), height: mid('height') };
  const starts = Array.from({ length: n }, (_, i) => [((i % 50) - 24.5) * 2, Math.floor(i / 50) * 2, 0]);
  const crowd = new Crowd(model, { starts, presets: [controls] });
  const camera = rt.alloc(64);
  rt.writeCamera(camera, { position: [0, 1.7, -8], direction: [0, 0, directionZ], fovY: 1.0471976,
    aspect: 16 / 9, heightPx: 1080, near: 0.1, far: 0 });
  const detail = { level: 0, joints: model.animatedJoints };
  try {
    crowd.walkers.forEach((w, i) => w.start(controls, detail, starts[i][0], starts[i][1], 0));
    crowd.walkers.forEach((w) => rt.writeControls(w.controls, controls));
    const per = [];
    // 90 steps of 1/60 s (more than a cycle) warm up: every walker then walks at its detail.
    for (let s = 0; s < samples + 90; s++) {
      const t0 = performance.now();
      crowd.step(1 / 60, camera);
      if (s >= 90) per.push(((performance.now() - t0) * 1e6) / n);
    }
    return per.sort((a, b) => a - b)[per.length >> 1];
  } finally {
    crowd.free();
    rt.free(camera, 64);
  }
}
