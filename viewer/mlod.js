// The motion-lod runtime in the page: its C ABI (crates/motion-lod-ffi, `motion_lod.h`) compiled
// to WebAssembly (`cargo xtask web` writes wasm/motion_lod.wasm), driven from JavaScript through
// the module's memory. Nothing is computed here: every pose, clip, foot lock and level of detail
// comes from the runtime; this file only moves numbers in and out of the structs the ABI defines.
//
// Layouts (wasm32: size_t and pointers are 4 bytes; the structs are `#[repr(C)]`):
//   MlodControls      48 bytes: dx, dz, turn, height (f32), style[8] (f32)
//   MlodDetail         8 bytes: level, joints (u32)
//   MlodJointTransform 28 bytes: rotation x, y, z, w (f32), translation x, y, z (f32)
//   MlodWalkerState  112 bytes: time_in_cycle_s (f64, 0), cycle_duration_s (f64, 8), cycle (u64,
//                     16), root_position (3 f64, 24), cycle_x (f64, 48), cycle_z (f64, 56),
//                     heading (f64, 64), root_rotation (4 f32, 72), body_scale (88), detail (92),
//                     cycles_begun (u32, 100), foot_locked (bool, 104)
//   MlodCamera        56 bytes: position (3 f64, 0), direction (3 f32, 24), fov_y, aspect,
//                     image_height_px, near_m, far_m (f32, 36..56)
// The walker's frame on the ground (cycle_x, cycle_z, heading), its root and the camera's eye are
// doubles: positions far from the origin keep millimetres (ABI 5).

export const ABI_VERSION = 5;
export const MAX_STYLES = 8;
export const CONTROLS_BYTES = 48;
export const STATE_BYTES = 112;
export const CAMERA_BYTES = 56;
export const TRANSFORM_FLOATS = 7;

const STATUS = ['ok', 'null pointer', 'invalid argument', 'invalid model', 'io', 'buffer too small',
  'not prepared', 'panic'];

/// An error of the runtime: the call, its status and the runtime's message.
export class RuntimeError extends Error {
  constructor(call, status, message) {
    super(`${call}: ${message || STATUS[status] || `status ${status}`}`);
    this.status = status;
  }
}

/// The instantiated module: its exports, its memory, and scratch buffers for the structs.
export class Runtime {
  /// Instantiates the module from its bytes (or a fetch Response).
  static async load(source) {
    const bytes = source instanceof Response ? await source.arrayBuffer() : source;
    const { instance } = await WebAssembly.instantiate(bytes, {});
    return new Runtime(instance);
  }

  constructor(instance) {
    this.x = instance.exports;
    if (this.x.mlod_abi_version() !== ABI_VERSION) {
      throw new Error(`the wasm has ABI ${this.x.mlod_abi_version()}, this page expects ${ABI_VERSION}`);
    }
    this.version = this.string(this.x.mlod_version());
    // Scratch structs the calls below pass (one page of the runtime's memory).
    this.scratch = this.alloc(1024);
  }

  /// The memory's views, made again after the memory grows (growth detaches the old ones).
  views() {
    const buffer = this.x.memory.buffer;
    if (this.buffer !== buffer) {
      this.buffer = buffer;
      this.v = { bytes: new Uint8Array(buffer), f32: new Float32Array(buffer),
        f64: new Float64Array(buffer), u32: new Uint32Array(buffer), i32: new Int32Array(buffer),
        dv: new DataView(buffer) };
    }
    return this.v;
  }

  get bytes() { return this.views().bytes; }
  get f32() { return this.views().f32; }
  get f64() { return this.views().f64; }
  get u32() { return this.views().u32; }
  get i32() { return this.views().i32; }
  get dv() { return this.views().dv; }

  /// A zero-filled buffer of `len` bytes in the runtime's memory (16-byte aligned).
  alloc(len) {
    const ptr = this.x.mlod_buffer_new(len);
    if (!ptr) throw new Error(`the runtime could not allocate ${len} bytes`);
    return ptr;
  }

  free(ptr, len) { this.x.mlod_buffer_free(ptr, len); }

  /// The NUL-terminated string at `ptr`.
  string(ptr) {
    const b = this.bytes;
    let end = ptr;
    while (b[end] !== 0) end++;
    return new TextDecoder().decode(b.subarray(ptr, end));
  }

  /// Throws the runtime's message when `status` is not 0.
  check(call, status) {
    if (status !== 0) throw new RuntimeError(call, status, this.string(this.x.mlod_last_error()));
  }

  /// Writes controls `{ dx, dz, turn, height, style }` (style: weights, or absent for the data's
  /// mix) as an MlodControls at `ptr`.
  writeControls(ptr, c) {
    const f = this.f32;
    const i = ptr >> 2;
    f[i] = c.dx; f[i + 1] = c.dz; f[i + 2] = c.turn; f[i + 3] = c.height;
    for (let s = 0; s < MAX_STYLES; s++) f[i + 4 + s] = c.style?.[s] ?? 0;
  }

  readControls(ptr) {
    const f = this.f32;
    const i = ptr >> 2;
    return { dx: f[i], dz: f[i + 1], turn: f[i + 2], height: f[i + 3],
      style: Array.from(f.subarray(i + 4, i + 4 + MAX_STYLES)) };
  }

  /// Writes a camera `{ position: [x,y,z], direction: [x,y,z] (unit), fovY, aspect, heightPx,
  /// near, far }` as an MlodCamera at `ptr`.
  writeCamera(ptr, c) {
    const d = this.f64;
    const k = ptr >> 3;
    d[k] = c.position[0]; d[k + 1] = c.position[1]; d[k + 2] = c.position[2];
    const f = this.f32;
    const i = (ptr + 24) >> 2;
    f[i] = c.direction[0]; f[i + 1] = c.direction[1]; f[i + 2] = c.direction[2];
    f[i + 3] = c.fovY; f[i + 4] = c.aspect; f[i + 5] = c.heightPx; f[i + 6] = c.near; f[i + 7] = c.far;
  }
}

/// A loaded model (`mlod_model_from_bytes`): its skeleton, control ranges and styles.
export class Model {
  constructor(runtime, fileBytes) {
    const rt = (this.rt = runtime);
    const data = new Uint8Array(fileBytes);
    const buf = rt.alloc(data.length);
    rt.bytes.set(data, buf);
    const out = rt.scratch;
    try {
      rt.check('mlod_model_from_bytes', rt.x.mlod_model_from_bytes(buf, data.length, out));
    } finally {
      rt.free(buf, data.length);
    }
    this.ptr = rt.u32[out >> 2];
    rt.check('mlod_model_sizes', rt.x.mlod_model_sizes(this.ptr, out, out + 4, out + 8, out + 12));
    const u = rt.u32;
    [this.levels, this.joints, this.animatedJoints, this.poseLen] = [u[out >> 2], u[(out >> 2) + 1],
      u[(out >> 2) + 2], u[(out >> 2) + 3]];
    rt.check('mlod_model_root_joint', rt.x.mlod_model_root_joint(this.ptr, out));
    this.root = rt.u32[out >> 2];
    // The skeleton: names, parents, rest offsets.
    this.names = [];
    this.parents = new Int32Array(this.joints);
    this.offsets = new Float32Array(3 * this.joints);
    const name = out + 64;
    for (let j = 0; j < this.joints; j++) {
      rt.check('mlod_model_joint', rt.x.mlod_model_joint(this.ptr, j, name, 256, out, out + 4));
      this.names.push(rt.string(name));
      this.parents[j] = rt.i32[(out + 4) >> 2];
      rt.check('mlod_model_joint_rest', rt.x.mlod_model_joint_rest(this.ptr, j, out + 8));
      this.offsets.set(rt.f32.subarray(((out + 8) >> 2) + 4, ((out + 8) >> 2) + 7), 3 * j);
    }
    rt.check('mlod_model_control_range',
      rt.x.mlod_model_control_range(this.ptr, out, out + CONTROLS_BYTES));
    this.min = rt.readControls(out);
    this.max = rt.readControls(out + CONTROLS_BYTES);
    // The controls the build left out (bit k: dx, dz, turn, height): a clip follows the data there.
    rt.check('mlod_model_ignored_controls', rt.x.mlod_model_ignored_controls(this.ptr, out));
    const bits = rt.u32[out >> 2];
    this.ignored = new Set(['dx', 'dz', 'turn', 'height'].filter((_, k) => bits & (1 << k)));
    rt.check('mlod_model_style_count', rt.x.mlod_model_style_count(this.ptr, out));
    const styles = rt.u32[out >> 2];
    this.styles = [];
    for (let s = 0; s < styles; s++) {
      rt.check('mlod_model_style_name', rt.x.mlod_model_style_name(this.ptr, s, name, 256, out));
      rt.check('mlod_model_style_share', rt.x.mlod_model_style_share(this.ptr, s, out + 4));
      this.styles.push({ name: rt.string(name), share: rt.f32[(out + 4) >> 2] });
    }
  }

  /// The detail the model's distance policy gives a point seen by `camera` (written at the
  /// runtime's `cameraPtr`), and whether it is in view: `{ level, joints, visible }`.
  detailFromCamera(cameraPtr, x, y, z, radius) {
    const rt = this.rt;
    const out = rt.scratch + 512;
    rt.check('mlod_model_detail_from_camera',
      rt.x.mlod_model_detail_from_camera(this.ptr, cameraPtr, x, y, z, radius, out, out + 8));
    const u = rt.u32;
    return { level: u[out >> 2], joints: u[(out >> 2) + 1], visible: rt.bytes[out + 8] !== 0 };
  }

  free() {
    this.rt.x.mlod_model_free(this.ptr);
    this.ptr = 0;
  }
}

/// A walker (`mlod_walker_new`) with its own structs in the runtime's memory: its controls, its
/// detail, its state and its joint transforms, read through typed views.
export class Walker {
  constructor(model) {
    const rt = (this.rt = model.rt);
    this.model = model;
    const out = rt.scratch;
    rt.check('mlod_walker_new', rt.x.mlod_walker_new(model.ptr, out));
    this.ptr = rt.u32[out >> 2];
    // One block: controls (48), detail (8), visible (8), state (112), transforms (28 J).
    this.blockLen = CONTROLS_BYTES + 16 + STATE_BYTES + 4 * TRANSFORM_FLOATS * model.joints;
    this.block = rt.alloc(this.blockLen);
    this.controls = this.block;
    this.detail = this.block + CONTROLS_BYTES;
    this.visible = this.detail + 8;
    this.state = this.detail + 16;
    this.transforms = this.state + STATE_BYTES;
  }

  /// Keeps the walker's controls and state in slots of a crowd's arrays instead of its own block
  /// (`mlod_walkers_step` reads and writes whole arrays).
  useSlots(controlsPtr, statePtr) {
    this.controls = controlsPtr;
    this.state = statePtr;
  }

  setFootLock(on) {
    this.rt.check('mlod_walker_set_foot_lock', this.rt.x.mlod_walker_set_foot_lock(this.ptr, on));
  }

  /// Sets the detail `{ level, joints }` the next call passes.
  setDetail(d) {
    const u = this.rt.u32;
    u[this.detail >> 2] = d.level;
    u[(this.detail >> 2) + 1] = d.joints;
  }

  /// Starts the walk at (x, z) facing `heading` with `controls` at `detail`.
  start(controls, detail, x, z, heading) {
    const rt = this.rt;
    rt.writeControls(this.controls, controls);
    this.setDetail(detail);
    rt.check('mlod_walker_start', rt.x.mlod_walker_start(this.ptr, this.model.ptr, this.controls,
      this.detail, x, z, heading, this.state));
  }

  /// The detail the camera at `cameraPtr` gives the walker where it is (kept for the next
  /// advance), and whether it is in view.
  detailFromCamera(cameraPtr, radius) {
    const rt = this.rt;
    rt.check('mlod_walker_detail_from_camera', rt.x.mlod_walker_detail_from_camera(this.ptr,
      this.model.ptr, cameraPtr, radius, this.detail, this.visible));
    return rt.bytes[this.visible] !== 0;
  }

  /// Moves the walk `dt` seconds on; `controls` (or null: keep) and the kept detail are those of
  /// the next cycle. Returns the cycles begun.
  advance(dt, controls) {
    const rt = this.rt;
    if (controls) rt.writeControls(this.controls, controls);
    rt.check('mlod_walker_advance', rt.x.mlod_walker_advance(this.ptr, this.model.ptr, dt,
      controls ? this.controls : 0, this.detail, this.state));
    return rt.u32[(this.state + 100) >> 2];
  }

  /// Computes the joint transforms of the last frame (cycle frame) into the walker's block and
  /// returns their offset in floats into the runtime's memory.
  computeTransforms() {
    const rt = this.rt;
    rt.check('mlod_walker_joint_transforms', rt.x.mlod_walker_joint_transforms(this.ptr,
      this.model.ptr, this.transforms, this.model.joints));
    return this.transforms >> 2;
  }

  /// The lower-level path: builds the clip for `controls` at `detail` (no walk) and returns its
  /// duration in seconds.
  prepare(controls, detail) {
    const rt = this.rt;
    rt.writeControls(this.controls, controls);
    this.setDetail(detail);
    const cycle = rt.scratch + 256;
    rt.check('mlod_walker_prepare', rt.x.mlod_walker_prepare(this.ptr, this.model.ptr, this.controls,
      this.detail, cycle));
    return rt.dv.getFloat64(cycle, true);
  }

  /// Evaluates the prepared clip `seconds` into it (kept for `computeTransforms`).
  pose(seconds) {
    this.rt.check('mlod_walker_pose', this.rt.x.mlod_walker_pose(this.ptr, this.model.ptr, seconds, 0, 0));
  }

  /// The pose vector of the last frame as shown (with the foot lock), in the cycle frame: a new
  /// Float32Array of the model's pose length.
  shownPose() {
    const rt = this.rt;
    const n = this.model.poseLen;
    // A buffer of the walker's own, allocated at the first call (a recording asks every frame).
    this.poseBuffer ||= rt.alloc(4 * n);
    rt.check('mlod_walker_shown_pose', rt.x.mlod_walker_shown_pose(this.ptr, this.model.ptr, this.poseBuffer, n));
    return rt.f32.slice(this.poseBuffer >> 2, (this.poseBuffer >> 2) + n);
  }

  /// The state as an object.
  readState() {
    const dv = this.rt.dv;
    const s = this.state;
    return {
      timeInCycle: dv.getFloat64(s, true),
      cycleDuration: dv.getFloat64(s + 8, true),
      cycle: Number(dv.getBigUint64(s + 16, true)),
      root: [dv.getFloat64(s + 24, true), dv.getFloat64(s + 32, true), dv.getFloat64(s + 40, true)],
      cycleX: dv.getFloat64(s + 48, true),
      cycleZ: dv.getFloat64(s + 56, true),
      heading: dv.getFloat64(s + 64, true),
      rootRotation: [0, 1, 2, 3].map((k) => dv.getFloat32(s + 72 + 4 * k, true)),
      bodyScale: dv.getFloat32(s + 88, true),
      level: dv.getUint32(s + 92, true),
      joints: dv.getUint32(s + 96, true),
      cyclesBegun: dv.getUint32(s + 100, true),
      footLocked: dv.getUint8(s + 104) !== 0,
    };
  }

  /// The current cycle's index (cheap: no object; below 2^32).
  cycle() { return this.rt.u32[(this.state + 16) >> 2]; }

  /// The current detail's level and joints, and the root's world position (x, y, z), cheaply.
  level() { return this.rt.u32[(this.state + 92) >> 2]; }
  joints() { return this.rt.u32[(this.state + 96) >> 2]; }
  rootX() { return this.rt.f64[(this.state + 24) >> 3]; }
  rootY() { return this.rt.f64[(this.state + 32) >> 3]; }
  rootZ() { return this.rt.f64[(this.state + 40) >> 3]; }

  free() {
    this.rt.x.mlod_walker_free(this.ptr);
    this.rt.free(this.block, this.blockLen);
    if (this.poseBuffer) this.rt.free(this.poseBuffer, 4 * this.model.poseLen);
    this.ptr = 0;
  }
}
