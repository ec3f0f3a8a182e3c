// Walkers driven through the runtime (mlod.js): the live crowd of the page, and the scripted runs
// the browser test compares with the native runtime (crates/motion-lod-ffi/tests/web_reference.rs
// walks the same scripts through the same C ABI in Rust).
import { Walker, TRANSFORM_FLOATS } from './mlod.js';

/// A crowd: walker i starts at `starts[i]` = [x, z, heading] and walks its cycle k with
/// `presets[(7 i + 3 k) mod presets.length]`, its path; every frame the model's distance policy
/// gives each walker its detail from the camera (out of view: root only), used from its next cycle.
export class Crowd {
  constructor(model, { starts, presets, radius = 1.2, footLock = true }) {
    this.model = model;
    this.presets = presets;
    this.radius = radius;
    this.walkers = starts.map(() => new Walker(model));
    for (const w of this.walkers) w.setFootLock(footLock);
    this.starts = starts;
    this.count = starts.length;
    this.visible = new Uint8Array(this.count);
    // The cycle whose controls each walker was last given (as its next cycle's).
    this.given = new Int32Array(this.count);
  }

  /// Walker i's controls for its cycle k.
  controlsFor(i, k) {
    return this.presets[(7 * i + 3 * k) % this.presets.length];
  }

  /// The first frame: each walker's detail from the camera at its start, then its walk starts.
  start(cameraPtr) {
    for (let i = 0; i < this.count; i++) {
      const [x, z, heading] = this.starts[i];
      const d = this.model.detailFromCamera(cameraPtr, x, 1.0, z, this.radius);
      this.visible[i] = d.visible ? 1 : 0;
      this.walkers[i].start(this.controlsFor(i, 0), d, x, z, heading);
      this.given[i] = 0;
    }
  }

  /// One frame `dt` seconds on: each walker's detail from the camera where it is, then its step
  /// with its next cycle's controls (written only when that cycle changes: the runtime keeps them).
  step(dt, cameraPtr) {
    const { walkers, visible, given, radius } = this;
    for (let i = 0; i < this.count; i++) {
      const w = walkers[i];
      visible[i] = w.detailFromCamera(cameraPtr, radius) ? 1 : 0;
      const next = w.cycle() + 1;
      if (given[i] !== next) {
        given[i] = next;
        w.advance(dt, this.controlsFor(i, next));
      } else {
        w.advance(dt, null);
      }
    }
  }

  free() {
    for (const w of this.walkers) w.free();
    this.walkers = [];
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
/// frames. Returns per frame and walker the root position (3) and [level, joints, visible]
/// (Float32Array each), and the joint transforms of every `sampleWalkers`-th walker at every
/// `sampleFrames`-th frame and the last.
export function runCrowd(runtime, model, script) {
  const { dt, frames, camera, starts, presets, radius, sampleWalkers, sampleFrames } = script;
  const n = starts.length;
  const J = model.joints;
  const cameraPtr = runtime.alloc(64);
  runtime.writeCamera(cameraPtr, camera);
  const crowd = new Crowd(model, { starts, presets, radius, footLock: true });
  const roots = new Float32Array(frames * n * 3);
  const details = new Float32Array(frames * n * 3);
  const sampled = [];
  try {
    for (let f = 0; f < frames; f++) {
      if (f === 0) crowd.start(cameraPtr);
      else crowd.step(dt, cameraPtr);
      for (let i = 0; i < n; i++) {
        const w = crowd.walkers[i];
        const at = (f * n + i) * 3;
        roots[at] = w.rootX(); roots[at + 1] = w.rootY(); roots[at + 2] = w.rootZ();
        details[at] = w.level(); details[at + 1] = w.joints(); details[at + 2] = crowd.visible[i];
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
