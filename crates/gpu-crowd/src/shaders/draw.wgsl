// The GPU crowd's walkers as an engine's shaders read them (`gpu_crowd::DRAW_WGSL`): what a
// vertex or compute shader needs to draw the crowd from the buffers `GpuCrowd::draw_pages` gives,
// with no read-back. Bind a page's walker buffer as `array<CrowdWalker>` and its joint buffer as
// `array<f32>` (both read-only storage), then for walker `i < DrawPage::walkers`:
//
//   let w = walkers[i];
//   if (crowd_visible(w)) { ... }
//   let root = crowd_root(w);                    // world position (m) of the root
//   for (var k = 0u; k < crowd_joint_count(w); k++) {
//       let p = crowd_joint(w, k, slots);        // index of joint k's x in the joint buffer
//       let pos = vec3<f32>(joints[p], joints[p + slots], joints[p + 2u * slots]);
//   }
//
// Joint k is the k-th position after the root, in the order of `crowd_sim::Crowd::joint_positions`
// (the clip's active joints in row order), so that the bones of `crowd_sim::ClipSource::bones`
// index `0` for the root and `1 + k` for joint k. `slots` is `DrawPage::joint_slots`.

// One walker, as the crowd's shaders hold it (they include this file: `Walker` there is this
// struct).
struct CrowdWalker {
    t: f32, cur_dur: f32, hold_s: f32, pend_u: f32,
    root_x: f32, root_y: f32, root_z: f32, height: f32,
    base_x: f32, base_z: f32, heading: f32, sin_h: f32,
    cos_h: f32, s: f32, stride: f32, body_scale: f32,
    path_cx: f32, path_cz: f32, path_a: f32, path_b: f32,
    path_rot: f32, path_dir: f32, c_dx: f32, c_dz: f32,
    c_turn: f32, c_height: f32, m_dx: f32, m_dz: f32,
    m_turn: f32, init_phase: f32, init_hold: f32, base_lo_x: f32,
    base_lo_z: f32, heading_lo: f32, s_lo: f32, shown: u32,
    cur_acc: u32, cur_joints: u32, pend_acc: u32, pend_joints: u32,
    style: u32, slot: u32, mode: u32, flags: u32,
}

const CROWD_NO_SLOT: u32 = 0xffffffffu;

// Whether the walker's box was in the view frustum this frame (as `Crowd::is_visible`: its box
// from the last frame's root, with the crowd's margin).
fn crowd_visible(w: CrowdWalker) -> bool {
    return (w.flags & 1u) != 0u;
}

// The walker's root in the world (m) after the last step.
fn crowd_root(w: CrowdWalker) -> vec3<f32> {
    return vec3<f32>(w.root_x, w.root_y, w.root_z);
}

// The walker's height (m): a root-only walker is drawn at half of it above its root's ground
// point, as the CPU renderer's dot.
fn crowd_height(w: CrowdWalker) -> f32 {
    return w.height;
}

// Joint positions after the root written this frame: 0 for a root-only walker (or one waiting
// for a joint slot), else the clip's joints (more while a seam fades joints out).
fn crowd_joint_count(w: CrowdWalker) -> u32 {
    if (w.cur_joints == 0u || w.slot == CROWD_NO_SLOT) {
        return 0u;
    }
    return w.shown;
}

// Index of joint `k`'s x in the page's joint buffer; y and z follow `slots` and `2 slots` later.
fn crowd_joint(w: CrowdWalker, k: u32, slots: u32) -> u32 {
    return 3u * k * slots + w.slot;
}

// The walker's accuracy level (0 = full detail), or `CROWD_NO_SLOT` for a root-only walker: the
// bin of `FrameStats::level_histogram` is the level, or the number of levels for root only.
fn crowd_level(w: CrowdWalker) -> u32 {
    if (w.cur_joints == 0u) {
        return CROWD_NO_SLOT;
    }
    return w.cur_acc;
}
