// The GPU crowd's compute shaders (crate `gpu-crowd`). The host prepends the model's sizes as
// constants (see `tables.rs`) and the double-float library (`df.wgsl`); every array index below is
// bounded by those constants.
//
// Passes per frame: `advance` (cull, detail from the tabulated policy, clock, cycle ends with the
// path controller, clip builds scheduled), `build_args` (indirect dispatch size), `grant` (with
// fewer joint slots free than walkers asking for one: which get one, nearest first),
// `seam_capture` (with seams on: one workgroup per scheduled clip, the outgoing clip's displayed
// state before the build overwrites it), `build` (one workgroup per scheduled clip: kriging
// weights, core, G(c), time table, root motion), `seam_start` (with seams on: the seam transition
// into the new clip), `fix_free` (the joint-slot stack after its pops, the end of a round), `pose_fk` (pose at the
// clip's phase with the running seam and the foot lock, forward kinematics, placement in the
// world). The passes from `advance` to `fix_free` are one round of cycle ends and clip builds; a
// frame whose step is long enough that a walker may end several cycles in it (the host decides,
// from the shortest clip built so far, `C_MIN_DUR`) runs more rounds before `pose_fk`, catch-up
// rounds (`advance` with `CATCH_UP`), until no walker's clock is past its clip's end
// (`C_BEHIND`), as the CPU walker's loop over its cycle ends in one frame. Seam state lives in
// each joint slot after its clip (see "Seam inertialization" below), foot lock state after it (see
// "Foot lock"); with SEAM_LEVELS = 0 the host runs neither seam pass and allocates no seam state,
// with LOCK_LEVELS = 0 the lock does not run and has no state.

// One walker: `CrowdWalker` of `draw.wgsl` (`gpu_crowd::DRAW_WGSL`, prepended to this source), the
// layout engines' shaders read, so that there is one definition of it.
alias Walker = CrowdWalker;

struct Frame {
    planes: array<vec4<f32>, 6>,
    eye: vec4<f32>,
    dt: f32, margin: f32, n: u32, n_slots: u32,
    vis_entries: u32, hid_entries: u32, df_zero: u32, pad1: u32,
    // Policy table: (start distance bits, accuracy, joints, 0); visible entries first.
    policy: array<vec4<u32>, POLICY_MAX>,
}

// Counters: [0..3] unused (the indirect dispatch's arguments are `dispatch_args`), then the round's
// builds, the frame's counts, the
// free-stack top, the shortest clip duration ever built (its f32 bits: kept across frames), the
// walkers whose positions came out NaN or infinite (how many, the first), the walkers inside a
// running seam transition, the walkers whose foot lock corrected a leg, the rounds run this frame,
// the walkers whose clock is still past their clip's end after the last round, the builds of the
// frame (every round's), the round's grant threshold (`grant`: a key, high and low word), the
// round's builds with joints of walkers without a slot (askers, counted by `advance` for `grant`)
// and the level histogram. The host resets the frame's counts before each
// frame (all but the free-stack top and the shortest duration).
const C_BUILDS: u32 = 3u;
const C_VISIBLE: u32 = 4u;
const C_SLOT_FAULTS: u32 = 5u;
const C_FREE_TOP: u32 = 6u;
const C_MIN_DUR: u32 = 7u;
const C_NONFINITE: u32 = 8u;
const C_NONFINITE_FIRST: u32 = 9u;
const C_SEAMS: u32 = 10u;
const C_LOCKS: u32 = 11u;
const C_ROUND: u32 = 12u;
const C_BEHIND: u32 = 13u;
const C_BUILT: u32 = 14u;
const C_GRANT_HI: u32 = 15u;
const C_GRANT_LO: u32 = 16u;
const C_ASKERS: u32 = 17u;
const C_HIST: u32 = 18u;
// Walker flags: in view (set by a frame's first round), slot fault counted this frame.
const F_VISIBLE: u32 = 1u;
const F_SLOT_FAULT: u32 = 2u;

const NONE: u32 = 0xffffffffu;
const MODE_CYCLE: u32 = 0u;
const MODE_REFINE: u32 = 1u;
const MODE_INIT: u32 = 2u;
const WG: u32 = 64u;
const MAX_X: u32 = 65535u;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> mtab: array<vec4<u32>, META_VEC4>;
@group(0) @binding(2) var<storage, read_write> walkers: array<Walker>;
@group(0) @binding(3) var<storage, read_write> counters: array<atomic<u32>>;
// The round's scheduled builds: walker indices in [0, n), each one's grant key at the same entry
// plus n.
@group(0) @binding(4) var<storage, read_write> build_list: array<u32>;
@group(0) @binding(5) var<storage, read_write> free_stack: array<u32>;
@group(0) @binding(6) var<storage, read> md: array<f32>;
@group(0) @binding(7) var<storage, read_write> small_clips: array<f32>;
@group(0) @binding(8) var<storage, read_write> big_clips: array<f32>;
@group(0) @binding(9) var<storage, read_write> joints_out: array<f32>;

// 0, read from the frame: bits the double-float library's `keep` XORs in (df.wgsl).
fn df_zero() -> u32 {
    return frame.df_zero;
}

fn mi(k: u32) -> u32 {
    return mtab[k / 4u][k % 4u];
}

// ---------------------------------------------------------------------------------------------
// Paths (crowd_sim::path) and the path controller, in double-float: the CPU crowd evaluates them
// in f64 (EllipsePath::point_f64, closest_param_near, path_controls) and rounds their answers
// once, so both crowds round the same values.

// A point or direction on the ground, each coordinate a double-float.
struct DfVec2 {
    x: vec2<f32>,
    y: vec2<f32>,
}

// The path's rotation: (sin hi, sin lo, cos hi, cos lo) of f64::from(rot).
fn path_rotation(w: Walker) -> vec4<f32> {
    return df_sincos(vec2<f32>(w.path_rot, 0.0));
}

// R(rot) (x, y).
fn df_rotate(rot: vec4<f32>, x: vec2<f32>, y: vec2<f32>) -> DfVec2 {
    let sr = rot.xy;
    let cr = rot.zw;
    return DfVec2(df_add(df_mul(cr, x), -df_mul(sr, y)), df_add(df_mul(sr, x), df_mul(cr, y)));
}

// EllipsePath::point_f64: c + R(rot) (a cos s, b sin s).
fn path_point(w: Walker, rot: vec4<f32>, s: vec2<f32>) -> DfVec2 {
    return path_point_sc(w, rot, df_sincos(s));
}

// path_point with df_sincos(s) given (the controller reads the point and the velocity at one s).
fn path_point_sc(w: Walker, rot: vec4<f32>, sc: vec4<f32>) -> DfVec2 {
    let v = df_rotate(rot, df_mul_f(sc.zw, w.path_a), df_mul_f(sc.xy, w.path_b));
    return DfVec2(df_add(vec2<f32>(w.path_cx, 0.0), v.x), df_add(vec2<f32>(w.path_cz, 0.0), v.y));
}

// EllipsePath::velocity_f64: dir R(rot) (-a sin s, b cos s), with df_sincos(s) given.
fn path_velocity_sc(w: Walker, rot: vec4<f32>, sc: vec4<f32>) -> DfVec2 {
    let v = df_rotate(rot, df_mul_f(sc.xy, -w.path_a), df_mul_f(sc.zw, w.path_b));
    return DfVec2(df_mul_f(v.x, w.path_dir), df_mul_f(v.y, w.path_dir));
}

fn df_dist2(a: DfVec2, b: DfVec2) -> vec2<f32> {
    let dx = df_add(a.x, -b.x);
    let dy = df_add(a.y, -b.y);
    return df_add(df_mul(dx, dx), df_mul(dy, dy));
}

fn df_less(a: vec2<f32>, b: vec2<f32>) -> bool {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
}

// atan2(y, x) (f64's): WGSL's f32 atan2, then one step of theta + atan((y cos - x sin) /
// (x cos + y sin)) with the step's atan taken as its argument (the neglected cube is below
// 1e-15 for any f32 start within 1e-5 rad).
fn df_atan2(y: vec2<f32>, x: vec2<f32>) -> vec2<f32> {
    let t0 = atan2(y.x, x.x);
    let sc = df_sincos(vec2<f32>(t0, 0.0));
    let num = df_add(df_mul(y, sc.zw), -df_mul(x, sc.xy));
    let den = df_add(df_mul(x, sc.zw), df_mul(y, sc.xy));
    return df_add(vec2<f32>(t0, 0.0), df_div(num, den));
}

const DF_TENTH: vec2<f32> = vec2<f32>(0.10000000149011612, -1.4901161415892261e-09);
const DF_GOLDEN: vec2<f32> = vec2<f32>(0.6180340051651001, -5.165099903337023e-09);

// EllipsePath::closest_param_sampled.
fn closest_param_sampled(w: Walker, rot: vec4<f32>, p: DfVec2, s_guess: vec2<f32>) -> vec2<f32> {
    var best = s_guess;
    var best_d = df_dist2(path_point(w, rot, s_guess), p);
    for (var k = -8; k <= 8; k++) {
        let s = df_add(s_guess, df_mul_f(DF_TENTH, f32(k)));
        let d = df_dist2(path_point(w, rot, s), p);
        if (df_less(d, best_d)) {
            best_d = d;
            best = s;
        }
    }
    var lo = df_add(best, -DF_TENTH);
    var hi = df_add(best, DF_TENTH);
    for (var k = 0; k < 16; k++) {
        let m1 = df_add(hi, -df_mul(DF_GOLDEN, df_add(hi, -lo)));
        let m2 = df_add(lo, df_mul(DF_GOLDEN, df_add(hi, -lo)));
        if (df_less(df_dist2(path_point(w, rot, m1), p), df_dist2(path_point(w, rot, m2), p))) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    return df_mul_f(df_add(lo, hi), 0.5);
}

// EllipsePath::closest_param_near: Newton's iteration in f32 from atan2(a y, b x) to about
// 1e-5 rad (WGSL's sin and cos), then in double-float to the CPU's step of 1e-9 rad.
fn closest_param_near(w: Walker, rot: vec4<f32>, p: DfVec2, s_guess: vec2<f32>) -> vec2<f32> {
    let a = w.path_a;
    let b = w.path_b;
    let sr = rot.xy;
    let cr = rot.zw;
    let vx = df_add(p.x, vec2<f32>(-w.path_cx, 0.0));
    let vy = df_add(p.y, vec2<f32>(-w.path_cz, 0.0));
    let x = df_add(df_mul(cr, vx), df_mul(sr, vy));
    let y = df_add(-df_mul(sr, vx), df_mul(cr, vy));
    let k = df_add(two_prod(b, b), -two_prod(a, a));
    let ax = df_mul_f(x, a);
    let by = df_mul_f(y, b);
    var theta = atan2(a * y.x, b * x.x);
    for (var it = 0; it < 6; it++) {
        let s = sin(theta);
        let c = cos(theta);
        let g = k.x * s * c + ax.x * s - by.x * c;
        let dg = k.x * (c * c - s * s) + ax.x * c + by.x * s;
        if (!(dg > 0.0)) {
            break;
        }
        let stp = g / dg;
        theta -= stp;
        if (abs(stp) <= 1e-5) {
            break;
        }
    }
    var th = vec2<f32>(theta, 0.0);
    var converged = false;
    for (var it = 0; it < 4; it++) {
        let sc = df_sincos(th);
        let s = sc.xy;
        let c = sc.zw;
        let g = df_add(df_add(df_mul(df_mul(k, s), c), df_mul(ax, s)), -df_mul(by, c));
        let dg = df_add(
            df_add(df_mul(k, df_add(df_mul(c, c), -df_mul(s, s))), df_mul(ax, c)),
            df_mul(by, s));
        if (!(dg.x > 0.0)) {
            break;
        }
        let stp = df_div(g, dg);
        th = df_add(th, -stp);
        if (abs(stp.x) <= 1e-9) {
            converged = true;
            break;
        }
    }
    let delta = df_wrap_angle(df_add(th, -s_guess));
    if (converged && abs(delta.x) <= 0.9) {
        return df_add(s_guess, delta);
    }
    return closest_param_sampled(w, rot, p, s_guess);
}

// The world coordinate origin + v of a double-float origin and an f32 offset, rounded to f32 as
// the CPU's `(frame.x + f64::from(v)) as f32` (CycleFrame::to_world).
fn place(origin: vec2<f32>, v: f32) -> f32 {
    let s = two_sum(origin.x, v);
    return s.x + (s.y + origin.y);
}

fn clamp_control(v: f32, lo: f32, hi: f32) -> f32 {
    if (v != v) {
        return 0.5 * (lo + hi);
    }
    return clamp(v, lo, hi);
}

// ---------------------------------------------------------------------------------------------
// Culling and the policy.

fn visible_of(w: Walker) -> bool {
    let m = frame.margin;
    let r = 0.4 * w.height + m;
    let bmin = vec3<f32>(w.root_x - r, -m, w.root_z - r);
    let bmax = vec3<f32>(w.root_x + r, 1.1 * w.height + m, w.root_z + r);
    var inside = true;
    for (var k = 0u; k < 6u; k++) {
        let pl = frame.planes[k];
        let n = pl.xyz;
        let q = select(bmin, bmax, n >= vec3<f32>(0.0));
        inside = inside && (dot(n, q) + pl.w >= 0.0);
    }
    return inside;
}

// The policy's detail at `d` metres: the last table entry whose start is at most `d`.
fn policy_detail(d: f32, visible: bool) -> vec2<u32> {
    var first = 0u;
    var count = frame.vis_entries;
    if (!visible) {
        first = frame.vis_entries;
        count = frame.hid_entries;
    }
    var e = frame.policy[first];
    for (var k = 1u; k < count; k++) {
        let c = frame.policy[first + k];
        if (bitcast<f32>(c.x) <= d) {
            e = c;
        } else {
            break;
        }
    }
    return e.yz;
}

fn walker_index(gid: vec3<u32>, nw: vec3<u32>) -> u32 {
    return gid.x + gid.y * nw.x * WG;
}

var<workgroup> wg_visible: atomic<u32>;
var<workgroup> wg_askers: atomic<u32>;

// Whether `advance` runs a catch-up round: the host makes a second pipeline of `advance` with it
// set, so that the frame's first round compiles to the pass it always was.
override CATCH_UP: bool = false;

// One round's clocks and cycle ends (the CPU walker's `advance`). The frame's first round adds the
// time step, decrements the spread of first builds, makes one cycle end or starts a mid-cycle
// refinement, and counts the walkers in view. A catch-up round (any after the first, `CATCH_UP`)
// takes only the walkers whose clock is still past the end of the clip the last round built and
// makes their next cycle end, as the CPU walker's loop does: no time added, the hold clock left
// (a cycle end has zeroed it), no refinement (the CPU refines only in a frame without a cycle
// end), nothing counted again (the culling and the policy's detail, from the root placed at the
// last frame, are the first round's).
@compute @workgroup_size(64)
fn advance(@builtin(global_invocation_id) gid: vec3<u32>,
           @builtin(num_workgroups) nw: vec3<u32>,
           @builtin(local_invocation_index) lid: u32) {
    if (lid == 0u) {
        atomicStore(&wg_visible, 0u);
        atomicStore(&wg_askers, 0u);
    }
    workgroupBarrier();
    let i = walker_index(gid, nw);
    let catch_up = CATCH_UP;
    if (i < frame.n && (!catch_up || walkers[i].t >= walkers[i].cur_dur)) {
        var w = walkers[i];
        let vis = visible_of(w);
        let eye = frame.eye.xyz;
        let dist = length(vec3<f32>(w.root_x, w.root_y, w.root_z) - eye);
        let d = policy_detail(dist, vis);
        let dt = frame.dt;
        if (!catch_up) {
            w.t += dt;
        }
        var build = false;
        if (w.t >= w.cur_dur) {
            let end = w.cur_dur;
            w.t -= end;
            // CycleFrame::next in double-float: the origin moves by the clip's displacement
            // rotated by the heading, the heading turns by the clip's turn.
            let h = vec2<f32>(w.heading, w.heading_lo);
            let hsc = df_sincos(h);
            let bx = df_add(df_add(vec2<f32>(w.base_x, w.base_lo_x), df_mul_f(hsc.zw, w.m_dx)),
                df_mul_f(hsc.xy, w.m_dz));
            let bz = df_add(df_add(vec2<f32>(w.base_z, w.base_lo_z), -df_mul_f(hsc.xy, w.m_dx)),
                df_mul_f(hsc.zw, w.m_dz));
            let nh = df_wrap_angle(df_add(h, vec2<f32>(w.m_turn, 0.0)));
            w.base_x = bx.x;
            w.base_lo_x = bx.y;
            w.base_z = bz.x;
            w.base_lo_z = bz.y;
            w.heading = nh.x;
            w.heading_lo = nh.y;
            let nsc = df_sincos(nh);
            w.sin_h = nsc.x;
            w.cos_h = nsc.z;
            // path_controls: pure pursuit one stride ahead, clamped into the model's range.
            let base = DfVec2(bx, bz);
            let rot = path_rotation(w);
            let s = closest_param_near(w, rot, base, vec2<f32>(w.s, w.s_lo));
            w.s = s.x;
            w.s_lo = s.y;
            let v0 = path_velocity_sc(w, rot, df_sincos(s));
            var speed = df_sqrt(df_add(df_mul(v0.x, v0.x), df_mul(v0.y, v0.y)));
            if (speed.x < 1e-3) {
                speed = vec2<f32>(1e-3, 0.0);
            }
            let s_t = df_add(s, df_div(vec2<f32>(w.path_dir * w.stride, 0.0), speed));
            let sc_t = df_sincos(s_t);
            let tgt = path_point_sc(w, rot, sc_t);
            let ddx = df_add(tgt.x, -bx);
            let ddz = df_add(tgt.y, -bz);
            let vt = path_velocity_sc(w, rot, sc_t);
            let turn = df_wrap_angle(df_add(df_atan2(vt.x, vt.y), -nh)).x;
            // d . left(h) and d . forward(h): left = (cos h, -sin h), forward = (sin h, cos h).
            let sh = nsc.xy;
            let ch = nsc.zw;
            let dx = df_add(df_mul(ddx, ch), -df_mul(ddz, sh)).x;
            let dz = df_add(df_mul(ddx, sh), df_mul(ddz, ch)).x;
            w.c_dx = clamp_control(dx, md[RANGE_OFF + 0u], md[RANGE_OFF + 4u]);
            w.c_dz = clamp_control(dz, md[RANGE_OFF + 1u], md[RANGE_OFF + 5u]);
            w.c_turn = clamp_control(turn, md[RANGE_OFF + 2u], md[RANGE_OFF + 6u]);
            w.c_height = clamp_control(w.height, md[RANGE_OFF + 3u], md[RANGE_OFF + 7u]);
            w.mode = MODE_CYCLE;
            build = true;
            w.hold_s = 0.0;
        }
        if (!catch_up && w.hold_s > 0.0) {
            w.hold_s -= dt;
        }
        let finer = d.x < w.cur_acc || d.y > w.cur_joints;
        if (!catch_up && !build && w.hold_s <= 0.0 && finer) {
            w.hold_s = 0.0;
            w.pend_u = w.t / w.cur_dur;
            w.mode = MODE_REFINE;
            build = true;
        }
        if (build) {
            w.pend_acc = d.x;
            w.pend_joints = d.y;
            if (d.y == 0u && w.slot != NONE) {
                // A root-only clip lives in the walker's own small clip: give the slot back, its
                // foot lock released (the CPU walker's, as it leaves the levels with joints).
                lock_clear(w.slot);
                let top = atomicAdd(&counters[C_FREE_TOP], 1u);
                free_stack[top] = w.slot;
                w.slot = NONE;
            }
            if (d.y > 0u && w.slot == NONE) {
                atomicAdd(&wg_askers, 1u);
            }
            let k = atomicAdd(&counters[C_BUILDS], 1u);
            build_list[k] = i;
            build_list[frame.n + k] = grant_key(dist, vis);
        }
        if (!catch_up) {
            w.flags = select(0u, F_VISIBLE, vis);
            if (vis) {
                atomicAdd(&wg_visible, 1u);
            }
        }
        walkers[i] = w;
    }
    workgroupBarrier();
    if (lid == 0u) {
        let v = atomicLoad(&wg_visible);
        if (v > 0u) {
            atomicAdd(&counters[C_VISIBLE], v);
        }
        let a = atomicLoad(&wg_askers);
        if (a > 0u) {
            atomicAdd(&counters[C_ASKERS], a);
        }
    }
}

// The arguments of the round's indirect dispatches (x, y, z workgroups), written by `build_args`.
// A buffer of its own, bound only with `build_args`'s bind group (the counters and it): WebGPU
// forbids a dispatch to read its arguments from a buffer it also binds for writing (Chromium
// refuses such a pass; wgpu let the counters serve as both).
@group(0) @binding(10) var<storage, read_write> dispatch_args: array<u32, 3>;

// The round's build dispatch, its builds added to the frame's; the walkers left behind are
// counted afresh by this round's builds.
@compute @workgroup_size(1)
fn build_args() {
    let n = atomicLoad(&counters[C_BUILDS]);
    dispatch_args[0] = min(n, MAX_X);
    dispatch_args[1] = (n + MAX_X - 1u) / MAX_X;
    dispatch_args[2] = 1u;
    atomicAdd(&counters[C_BUILT], n);
    atomicStore(&counters[C_BEHIND], 0u);
}

// ---------------------------------------------------------------------------------------------
// Joint-slot grants. A walker whose scheduled build has joints competes for a joint slot: one that
// holds a slot for it, and one that asks for one. When the slots free after `advance` (its
// releases done) are at least the walkers asking, every one gets a slot and nothing is decided
// here. Otherwise the slots go to the competing walkers nearest first, by their grant key: walkers
// in view before walkers out of view, then by distance from the eye (the policy's distance), then
// by walker index. The keys are all different (the index), so the winners are exactly those whose
// key is below the key ranked `holders + free` (from 0), found by a radix select over the 64-bit
// keys in one workgroup. A holder that loses gives its slot back (its build made root only, as a
// walker leaving the levels with joints), and `build` gives a slot to exactly the askers that win.
// The same walkers win whatever the order of the GPU's threads.

// The key of a walker at `dist` metres from the eye, in view or not (high word; the low word is
// the walker's index): the distance's bits (ordered like the non-negative floats they are; the
// sign bit of a NaN cleared), with the top bit set out of view.
fn grant_key(dist: f32, vis: bool) -> u32 {
    return (bitcast<u32>(dist) & 0x7fffffffu) | select(0x80000000u, 0u, vis);
}

// Whether key (hi, lo) is below the round's threshold (C_GRANT_HI, C_GRANT_LO).
fn grant_wins(hi: u32, lo: u32) -> bool {
    let thr_hi = atomicLoad(&counters[C_GRANT_HI]);
    let thr_lo = atomicLoad(&counters[C_GRANT_LO]);
    return hi < thr_hi || (hi == thr_hi && lo < thr_lo);
}

const GRANT_WG: u32 = 256u;
var<workgroup> gr_holders: atomic<u32>;
var<workgroup> gr_hist: array<atomic<u32>, 256>;
// Selection state: [0] whether to select, [1] the rank still sought among the keys matching the
// prefix, [2] the prefix's high word, [3] its low word.
var<workgroup> gr_sel: array<u32, 4>;

// The round's grant threshold: (u32::MAX, u32::MAX), above every key, when the free slots cover
// the walkers asking; otherwise the key ranked `holders + free`, the losing holders' slots given
// back. One workgroup (per page).
@compute @workgroup_size(256)
fn grant(@builtin(local_invocation_index) lid: u32) {
    // Most rounds: the free slots cover the askers (`advance` counted them), decided at once.
    if (lid == 0u) {
        let free = u32(max(bitcast<i32>(atomicLoad(&counters[C_FREE_TOP])), 0));
        let askers = atomicLoad(&counters[C_ASKERS]);
        gr_sel[0] = select(0u, 1u, askers > free);
        gr_sel[1] = free;
        gr_sel[2] = 0u;
        gr_sel[3] = 0u;
        if (askers <= free) {
            atomicStore(&counters[C_GRANT_HI], NONE);
            atomicStore(&counters[C_GRANT_LO], NONE);
        }
        atomicStore(&gr_holders, 0u);
    }
    if (workgroupUniformLoad(&gr_sel[0]) == 0u) {
        return;
    }
    // Too few: the holders competing add their slots to the free ones.
    let count = atomicLoad(&counters[C_BUILDS]);
    for (var e = lid; e < count; e += GRANT_WG) {
        let i = build_list[e];
        if (walkers[i].pend_joints > 0u && walkers[i].slot != NONE) {
            atomicAdd(&gr_holders, 1u);
        }
    }
    workgroupBarrier();
    if (lid == 0u) {
        gr_sel[1] += atomicLoad(&gr_holders);
    }
    workgroupBarrier();
    // Eight passes of eight bits, from the top: the keys matching the prefix found so far are
    // counted by their next digit, and the digit holding the rank sought extends the prefix.
    for (var round_digit = 0u; round_digit < 8u; round_digit++) {
        atomicStore(&gr_hist[lid], 0u);
        workgroupBarrier();
        let shift = 24u - 8u * (round_digit % 4u);
        // The bits above the digit: of the high word in the first four passes, then all of the
        // high word and those of the low word.
        let above = ~((2u << (shift + 7u)) - 1u);
        let hi_mask = select(0xffffffffu, select(0u, above, shift < 24u), round_digit < 4u);
        let lo_mask = select(0u, select(0u, above, shift < 24u), round_digit >= 4u);
        let p_hi = gr_sel[2];
        let p_lo = gr_sel[3];
        for (var e = lid; e < count; e += GRANT_WG) {
            let i = build_list[e];
            if (walkers[i].pend_joints > 0u) {
                let hi = build_list[frame.n + e];
                if ((hi & hi_mask) == p_hi && (i & lo_mask) == p_lo) {
                    let word = select(i, hi, round_digit < 4u);
                    atomicAdd(&gr_hist[(word >> shift) & 0xffu], 1u);
                }
            }
        }
        workgroupBarrier();
        if (lid == 0u) {
            var rank = gr_sel[1];
            var digit = 255u;
            for (var b = 0u; b < 256u; b++) {
                let c = atomicLoad(&gr_hist[b]);
                if (rank < c) {
                    digit = b;
                    break;
                }
                rank -= c;
            }
            gr_sel[1] = rank;
            if (round_digit < 4u) {
                gr_sel[2] |= digit << shift;
            } else {
                gr_sel[3] |= digit << shift;
            }
        }
        workgroupBarrier();
    }
    if (lid == 0u) {
        atomicStore(&counters[C_GRANT_HI], gr_sel[2]);
        atomicStore(&counters[C_GRANT_LO], gr_sel[3]);
    }
    // Every thread reads the threshold from the workgroup (the stores above are not visible to
    // the other threads through the storage buffer before the next round_digit).
    let thr_hi = gr_sel[2];
    let thr_lo = gr_sel[3];
    for (var e = lid; e < count; e += GRANT_WG) {
        let i = build_list[e];
        let hi = build_list[frame.n + e];
        let wins = hi < thr_hi || (hi == thr_hi && i < thr_lo);
        if (!wins && walkers[i].pend_joints > 0u && walkers[i].slot != NONE) {
            // A holder that loses: root only until its policy asks again (as `advance` releases).
            var w = walkers[i];
            lock_clear(w.slot);
            let top = atomicAdd(&counters[C_FREE_TOP], 1u);
            free_stack[top] = w.slot;
            w.slot = NONE;
            w.pend_acc = LAST_LEVEL;
            w.pend_joints = 0u;
            if ((w.flags & F_SLOT_FAULT) == 0u) {
                atomicAdd(&counters[C_SLOT_FAULTS], 1u);
                w.flags |= F_SLOT_FAULT;
            }
            walkers[i] = w;
        }
    }
}

// The end of a round: the joint-slot stack after its pops, the build list and the askers emptied
// for the next round, the round counted.
@compute @workgroup_size(1)
fn fix_free() {
    let top = bitcast<i32>(atomicLoad(&counters[C_FREE_TOP]));
    if (top < 0) {
        atomicStore(&counters[C_FREE_TOP], 0u);
    }
    atomicStore(&counters[C_BUILDS], 0u);
    atomicStore(&counters[C_ASKERS], 0u);
    atomicAdd(&counters[C_ROUND], 1u);
}


// The variogram at the squared distance h2 (Variogram::eval_squared, in double-float).
fn variogram_df(h2: vec2<f32>) -> vec2<f32> {
    let h = df_sqrt(h2);
    if (!(h.x > 0.0)) {
        return vec2<f32>(0.0, 0.0);
    }
    var unit = h;
    switch (VG_MODEL) {
        case 0u: { unit = h; }
        case 1u: { unit = df_exp(df_mul(VG_EXPONENT, df_log(h))); }
        case 2u: {
            var t = df_div(h, VG_RANGE);
            if (t.x >= 1.0) {
                t = vec2<f32>(1.0, 0.0);
            }
            let t3 = df_mul(t, df_mul(t, t));
            unit = df_add(df_mul_f(t, 1.5), df_mul_f(t3, -0.5));
        }
        case 3u: {
            unit = df_add(vec2<f32>(1.0, 0.0), -df_exp(df_div(df_mul_f(h, -3.0), VG_RANGE)));
        }
        default: {
            let r = df_div(h, VG_RANGE);
            unit = df_add(vec2<f32>(1.0, 0.0), -df_exp(df_mul_f(df_mul(r, r), -3.0)));
        }
    }
    return df_add(VG_NUGGET, df_mul(VG_SILL, unit));
}

// ---------------------------------------------------------------------------------------------
// Clip build: one workgroup per scheduled walker.

var<workgroup> wb_info: array<u32, 12>;
var<workgroup> wb_count: u32;
var<workgroup> wb_raw: array<f32, D_MAX>;
var<workgroup> wb_c: array<vec2<f32>, D_MAX1>;
var<workgroup> wb_x: array<vec2<f32>, S1>;
var<workgroup> wb_w: array<f32, RS_MAX>;
var<workgroup> wb_k: array<f32, K_MAX>;
var<workgroup> wb_groot: array<f32, GROOT_MAX>;
var<workgroup> wb_dt: array<vec2<f32>, T>;

// ControlSpace::implied_of for dimension k of the raw controls in wb_raw.
fn implied_of(k: u32) -> f32 {
    let lo = md[CS_MIN + k];
    let hi = md[CS_MAX + k];
    if (md[CS_SCALE + k] > 0.0) {
        return clamp(wb_raw[k], lo, hi);
    }
    if (HAS_IMPLIED == 0u) {
        return 0.5 * (lo + hi);
    }
    let beta = CS_IMPLIED + k * (D + 1u);
    var v = md[beta + D];
    for (var j = 0u; j < D; j++) {
        let bj = md[beta + j];
        if (bj != 0.0) {
            v = v + bj * clamp(wb_raw[j], md[CS_MIN + j], md[CS_MAX + j]);
        }
    }
    return clamp(v, lo, hi);
}

@compute @workgroup_size(64)
fn build(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let entry = wid.y * MAX_X + wid.x;
    if (lid == 0u) {
        wb_count = atomicLoad(&counters[C_BUILDS]);
    }
    let count = workgroupUniformLoad(&wb_count);
    if (entry >= count) {
        return;
    }
    if (lid == 0u) {
        let i = build_list[entry];
        var w = walkers[i];
        wb_info[4] = 0u;
        var acc = w.pend_acc;
        var joints = w.pend_joints;
        if (joints == 0u) {
            acc = LAST_LEVEL;
        } else if (w.slot == NONE) {
            // An asker: a slot if `grant` let it win (there is then one on the stack for it).
            var top = -1;
            if (grant_wins(build_list[frame.n + entry], i)) {
                top = bitcast<i32>(atomicSub(&counters[C_FREE_TOP], 1u)) - 1;
            }
            if (top >= 0) {
                w.slot = free_stack[u32(top)];
            } else {
                // No joint slot for it: a root-only clip, and a retry when slots free up (the
                // walker counted once a frame, however many rounds it retries in).
                if ((w.flags & F_SLOT_FAULT) == 0u) {
                    atomicAdd(&counters[C_SLOT_FAULTS], 1u);
                    w.flags |= F_SLOT_FAULT;
                }
                acc = LAST_LEVEL;
                joints = 0u;
                w.pend_acc = LAST_LEVEL;
                w.pend_joints = 0u;
                if (w.mode == MODE_REFINE && w.cur_joints == 0u) {
                    // Its retry, shown root only already: the root-only clip it has is the one
                    // this build would make (a refinement keeps the controls), so none is made
                    // and none counted.
                    wb_info[4] = 1u;
                    atomicSub(&counters[C_BUILT], 1u);
                }
            }
        }
        walkers[i] = w;
        wb_info[0] = i;
        wb_info[1] = acc;
        wb_info[2] = joints;
        wb_info[3] = w.slot;
        wb_raw[0] = w.c_dx;
        wb_raw[1] = w.c_dz;
        wb_raw[2] = w.c_turn;
        wb_raw[3] = w.c_height;
        for (var k = 4u; k < D; k++) {
            wb_raw[k] = md[STYLE_OFF + w.style * (D - 4u) + (k - 4u)];
        }
    }
    if (workgroupUniformLoad(&wb_info[4]) == 1u) {
        return;
    }
    let lvl = wb_info[1];
    let joints = wb_info[2];
    let key = mi(LEVELS + 4u * lvl);
    let rp = mi(LEVELS + 4u * lvl + 1u);
    let rt = mi(LEVELS + 4u * lvl + 2u);
    let rs = mi(LEVELS + 4u * lvl + 3u);
    let kb = KEYS + 8u * key;
    let big_p = mi(kb);
    let big_t = mi(kb + 1u);
    let big_s = mi(kb + 2u);
    let off_core = mi(kb + 3u);
    let off_up = mi(kb + 4u);
    let off_ut = mi(kb + 5u);
    let off_a = mi(kb + 6u);
    let off_v = mi(kb + 7u);
    let rows = 7u + 3u * joints;

    // 1. Clamp and scale the controls.
    if (lid < D) {
        let v = clamp(wb_raw[lid], md[CS_MIN + lid], md[CS_MAX + lid]);
        wb_c[lid] = df_mul_f(two_sum(v, -md[CS_OFFSET + lid]), md[CS_SCALE + lid]);
    }
    if (lid == D) {
        wb_c[D] = vec2<f32>(1.0, 0.0);
    }
    workgroupBarrier();
    // 2. x = [gamma(|c' - c_i|) ; 1].
    for (var i = lid; i < S; i += WG) {
        var h2 = vec2<f32>(0.0, 0.0);
        for (var k = 0u; k < D; k++) {
            if (md[CS_SCALE + k] != 0.0) {
                let diff = df_add(wb_c[k], vec2<f32>(-md[CS_SAMPLES + i + S * k], 0.0));
                h2 = df_add(h2, df_mul(diff, diff));
            }
        }
        wb_x[i] = variogram_df(h2);
    }
    if (lid == 0u) {
        wb_x[S] = vec2<f32>(1.0, 0.0);
    }
    workgroupBarrier();
    // 3-4. w = A x + V [c' ; 1] in double-float (A = Q_top - V P_C in f64, stored transposed as
    //      (S + 1) x R_S high parts, then as many low parts).
    let a_lo = off_a + (S + 1u) * big_s;
    for (var l = lid; l < rs; l += WG) {
        var acc = vec2<f32>(0.0, 0.0);
        for (var j = 0u; j <= S; j++) {
            let e = j * big_s + l;
            acc = df_add(acc, df_mul(vec2<f32>(md[off_a + e], md[a_lo + e]), wb_x[j]));
        }
        for (var m = 0u; m <= D; m++) {
            acc = df_add(acc, df_mul_f(wb_c[m], md[off_v + l + big_s * m]));
        }
        wb_w[l] = acc.x + acc.y;
    }
    workgroupBarrier();
    // 5. K(c) = Z[:rp, :rt, :rs] x_3 w, rp x rt column-major.
    for (var e = lid; e < rp * rt; e += WG) {
        let i = e % rp;
        let j = e / rp;
        var acc = 0.0;
        for (var l = 0u; l < rs; l++) {
            acc = acc + wb_w[l] * md[off_core + i + big_p * (j + big_t * l)];
        }
        wb_k[e] = acc;
    }
    workgroupBarrier();
    // 6. G(c) = U_P[:rows, :rp] K(c), into the walker's clip: element (r, b) at r * stride_t + b.
    let wi = wb_info[0];
    let slot = wb_info[3];
    for (var e = lid; e < rows * rt; e += WG) {
        let r = e % rows;
        let b = e / rows;
        var acc = 0.0;
        for (var i = 0u; i < rp; i++) {
            acc = acc + md[off_up + r + P * i] * wb_k[i + rp * b];
        }
        if (r < 7u) {
            wb_groot[r * RT_MAX + b] = acc;
        }
        if (joints > 0u) {
            big_clips[(r * RT_MAX + b) * frame.n_slots + slot] = acc;
        } else {
            small_clips[(r * RT_LAST + b) * frame.n + wi] = acc;
        }
    }
    workgroupBarrier();
    // 7. Time increments at every aligned frame: dt_j = G[6, :] . U_T[j, :rt] / time_scale.
    for (var j = lid; j < T; j += WG) {
        var acc = vec2<f32>(0.0, 0.0);
        for (var b = 0u; b < rt; b++) {
            acc = df_add(acc, two_prod(wb_groot[6u * RT_MAX + b], md[off_ut + j * big_t + b]));
        }
        wb_dt[j] = df_mul(INV_TIME_SCALE, acc);
    }
    workgroupBarrier();
    if (lid != 0u) {
        return;
    }
    // The time table (cumulative), the clip's duration.
    // Playback times in double-float: high parts, then low parts.
    var time = vec2<f32>(0.0, 0.0);
    for (var j = 0u; j < T; j++) {
        if (j > 0u) {
            let inc = wb_dt[j - 1u];
            let ok = (inc.x > MIN_INCREMENT.x || (inc.x == MIN_INCREMENT.x && inc.y >= MIN_INCREMENT.y)) && inc.x < 1e30;
            time = df_add(time, select(MIN_INCREMENT, inc, ok));
        }
        if (joints > 0u) {
            big_clips[(P * RT_MAX + j) * frame.n_slots + slot] = time.x;
            big_clips[(P * RT_MAX + T + j) * frame.n_slots + slot] = time.y;
        } else {
            small_clips[(7u * RT_LAST + j) * frame.n + wi] = time.x;
            small_clips[(7u * RT_LAST + T + j) * frame.n + wi] = time.y;
        }
    }
    // 8. Root motion: the root rows at aligned frames 0 and T - 1.
    var start: array<f32, 7>;
    var end: array<f32, 7>;
    for (var r = 0u; r < 7u; r++) {
        var s0 = 0.0;
        var s1 = 0.0;
        for (var b = 0u; b < rt; b++) {
            let g = wb_groot[r * RT_MAX + b];
            s0 = s0 + md[off_ut + b] * g;
            s1 = s1 + md[off_ut + (T - 1u) * big_t + b] * g;
        }
        start[r] = s0;
        end[r] = s1;
    }
    var w = walkers[wi];
    w.m_dx = end[0] - start[0];
    w.m_dz = end[2] - start[2];
    w.m_turn = implied_of(2u);
    // Body scale: the implied height over the rig's stature.
    var scale = 1.0;
    if (STATURE > 0.0 && md[CS_MIN + 3u] != md[CS_MAX + 3u]) {
        let sc = implied_of(3u) / STATURE;
        if (sc > 0.0 && sc < 1e30) {
            scale = sc;
        }
    }
    w.body_scale = scale;
    let dur = max(time.x + time.y, 1e-3);
    w.cur_acc = w.pend_acc;
    w.cur_joints = w.pend_joints;
    w.cur_dur = dur;
    if (w.mode == MODE_REFINE) {
        w.t = min(w.pend_u * dur, dur * 0.999999);
    } else if (w.mode == MODE_INIT) {
        w.t = w.init_phase * dur;
        w.hold_s = w.init_hold * dur;
    }
    // The shortest clip built so far (the bits of positive f32 values order as the values; read
    // first, so that the builds of a frame rarely contend for the atomic), and the walkers whose
    // clock is still past the new clip's end: another cycle end is due in this frame.
    let bits = bitcast<u32>(dur);
    if (dur > 0.0 && bits < atomicLoad(&counters[C_MIN_DUR])) {
        atomicMin(&counters[C_MIN_DUR], bits);
    }
    if (w.t >= dur) {
        atomicAdd(&counters[C_BEHIND], 1u);
    }
    walkers[wi] = w;
}

// ---------------------------------------------------------------------------------------------
// Pose and forward kinematics: one thread per walker.

fn quat_mul(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(
        a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
        a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
        a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
        a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z);
}

fn quat_rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let b = q.xyz;
    let w = q.w;
    let b2 = dot(b, b);
    return v * (w * w - b2) + b * (dot(v, b) * 2.0) + cross(b, v) * (w * 2.0);
}

fn exp_to_quat(v: vec3<f32>) -> vec4<f32> {
    let theta = length(v);
    let hf = 0.5 * theta;
    let sc = sincos_f32(hf);
    var k = 0.0;
    if (theta < 1e-3) {
        k = 0.5 - theta * theta / 48.0;
    } else {
        k = sc.x / theta;
    }
    return vec4<f32>(v * k, sc.y);
}

var<workgroup> wg_hist: array<atomic<u32>, HIST_BINS>;
// Walkers of the workgroup inside a seam transition after the frame.
var<workgroup> wg_seams: atomic<u32>;
// Walkers of the workgroup whose foot lock corrected a leg this frame.
var<workgroup> wg_locks: atomic<u32>;

// Whether a coordinate of `v` is NaN or infinite (all exponent bits set: a test on the bits,
// which a compiler that assumes finite floats cannot fold away as it may `v != v`).
fn not_finite(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return any(e == vec3<u32>(0x7f800000u));
}

@compute @workgroup_size(64)
fn pose_fk(@builtin(global_invocation_id) gid: vec3<u32>,
           @builtin(num_workgroups) nw: vec3<u32>,
           @builtin(local_invocation_index) lid: u32) {
    for (var b = lid; b < HIST_BINS; b += WG) {
        atomicStore(&wg_hist[b], 0u);
    }
    if (lid == 0u) {
        atomicStore(&wg_seams, 0u);
        atomicStore(&wg_locks, 0u);
    }
    workgroupBarrier();
    let i = walker_index(gid, nw);
    if (i < frame.n) {
        pose_one(i);
    }
    workgroupBarrier();
    for (var b = lid; b < HIST_BINS; b += WG) {
        let v = atomicLoad(&wg_hist[b]);
        if (v > 0u) {
            atomicAdd(&counters[C_HIST + b], v);
        }
    }
    if (lid == 0u) {
        let v = atomicLoad(&wg_seams);
        if (v > 0u) {
            atomicAdd(&counters[C_SEAMS], v);
        }
        let l = atomicLoad(&wg_locks);
        if (l > 0u) {
            atomicAdd(&counters[C_LOCKS], l);
        }
    }
}

fn clip_at(big: bool, e: u32) -> f32 {
    if (big) {
        return big_clips[e];
    }
    return small_clips[e];
}

// Playback time -> phase (ClipKernel::phase_at, in f32) of the clip whose double-float time
// table starts at element `tt` (high parts, then low parts; `stride`, `base` as in `clip_at`).
fn clip_phase(big: bool, tt: u32, stride: u32, base: u32, t: f32) -> f32 {
    let duration = vec2<f32>(clip_at(big, (tt + T - 1u) * stride + base), clip_at(big, (tt + 2u * T - 1u) * stride + base));
    var phase = 0.0;
    if (T >= 2u && duration.x > 0.0) {
        let tq = min(max(t, 0.0), duration.x + duration.y);
        var k = min(u32(tq / duration.x * f32(T - 1u)), T - 2u);
        loop {
            if (k == 0u) { break; }
            let tk = vec2<f32>(clip_at(big, (tt + k) * stride + base), clip_at(big, (tt + T + k) * stride + base));
            if (tk.x < tq || (tk.x == tq && tk.y <= 0.0)) { break; }
            k -= 1u;
        }
        loop {
            if (k + 2u >= T) { break; }
            let tk1 = vec2<f32>(clip_at(big, (tt + k + 1u) * stride + base), clip_at(big, (tt + T + k + 1u) * stride + base));
            if (tk1.x > tq || (tk1.x == tq && tk1.y > 0.0)) { break; }
            k += 1u;
        }
        let t0 = vec2<f32>(clip_at(big, (tt + k) * stride + base), clip_at(big, (tt + T + k) * stride + base));
        let t1 = vec2<f32>(clip_at(big, (tt + k + 1u) * stride + base), clip_at(big, (tt + T + k + 1u) * stride + base));
        let num = df_add(vec2<f32>(tq, 0.0), -t0);
        let den = df_add(t1, -t0);
        let f = clamp((num.x + num.y) / (den.x + den.y), 0.0, 1.0);
        phase = f32(k) + f;
    }
    return phase;
}

// The time weights w_T (eq. 5) at `phase` of a level's `rt` time factors (`big_t` columns from
// `off_ut`).
fn time_weights(phase: f32, rt: u32, big_t: u32, off_ut: u32) -> array<f32, RT_MAX> {
    let ph = clamp(phase, 0.0, f32(T - 1u));
    let i0 = min(u32(floor(ph)), T - 2u);
    let i1 = min(i0 + 1u, T - 1u);
    let a = ph - f32(i0);
    var wt: array<f32, RT_MAX>;
    for (var b = 0u; b < rt; b++) {
        wt[b] = (1.0 - a) * md[off_ut + i0 * big_t + b] + a * md[off_ut + i1 * big_t + b];
    }
    return wt;
}

// Forward kinematics of the rig's first `count` joints (Rig::joint_transforms_of, scaled): the
// ground point under the root, the root at the pose's root rows, then each joint at its parent's
// transform times its offset scaled by `scale`, turned by its pose rows when it is one of the
// first `posed` rotating joints, else by its rest rotation.
fn rig_fk(pose: ptr<function, array<f32, P>>, count: u32, posed: u32, scale: f32,
          pos: ptr<function, array<vec3<f32>, NJ>>, rot: ptr<function, array<vec4<f32>, NJ>>) {
    let root = vec3<f32>((*pose)[0], (*pose)[1], (*pose)[2]);
    let ground = vec3<f32>(root.x, 0.0, root.z);
    for (var j = 0u; j < count; j++) {
        let role = mi(RIG + 4u * j);
        let k = mi(RIG + 4u * j + 1u);
        let parent = mi(RIG + 4u * j + 2u);
        let rest = vec4<f32>(md[RIG_F + 7u * j + 3u], md[RIG_F + 7u * j + 4u], md[RIG_F + 7u * j + 5u], md[RIG_F + 7u * j + 6u]);
        if (role == 0u) {
            (*pos)[j] = ground;
            (*rot)[j] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        } else if (role == 1u) {
            (*pos)[j] = root;
            (*rot)[j] = exp_to_quat(vec3<f32>((*pose)[3], (*pose)[4], (*pose)[5]));
        } else {
            var local = rest;
            if (role == 2u && k < posed) {
                let r = 7u + 3u * k;
                local = exp_to_quat(vec3<f32>((*pose)[r], (*pose)[r + 1u], (*pose)[r + 2u]));
            }
            let off = vec3<f32>(md[RIG_F + 7u * j], md[RIG_F + 7u * j + 1u], md[RIG_F + 7u * j + 2u]);
            let pp = (*pos)[parent];
            let pr = (*rot)[parent];
            (*pos)[j] = pp + quat_rotate(pr, off * scale);
            (*rot)[j] = quat_mul(pr, local);
        }
    }
}

fn pose_one(i: u32) {
    var w = walkers[i];
    let joints = w.cur_joints;
    var lvl = w.cur_acc;
    if (joints == 0u) {
        lvl = LAST_LEVEL;
    }
    let key = mi(LEVELS + 4u * lvl);
    let rt = mi(LEVELS + 4u * lvl + 2u);
    let kb = KEYS + 8u * key;
    let big_t = mi(kb + 1u);
    let off_ut = mi(kb + 5u);
    let rows = 7u + 3u * joints;
    let n = frame.n;
    let ns = frame.n_slots;
    let slot = w.slot;
    // Playback time -> phase (ClipKernel::phase_at, in f32).
    var tt = 0u;
    var stride = n;
    var base = i;
    var gst = RT_LAST;
    if (joints > 0u) {
        tt = P * RT_MAX;
        stride = ns;
        base = slot;
        gst = RT_MAX;
    } else {
        tt = 7u * RT_LAST;
    }
    let big = joints > 0u;
    let phase = clip_phase(big, tt, stride, base, w.t);
    // Time weights w_T (eq. 5).
    let wt = time_weights(phase, rt, big_t, off_ut);
    // The pose rows: G w_T.
    var pose: array<f32, P>;
    for (var r = 0u; r < rows; r++) {
        var acc = 0.0;
        for (var b = 0u; b < rt; b++) {
            let e = (r * gst + b) * stride + base;
            let g = clip_at(joints > 0u, e);
            acc = acc + wt[b] * g;
        }
        pose[r] = acc;
    }
    // The running seam (the CPU walker's `displayed`, then its pose stage's `finish_after`):
    // joints it fades out are drawn beyond the clip's.
    var shown = joints;
    if (SEAM_LEVELS > 0u && joints > 0u) {
        let sr = u32(seam_get(SB_ROWS, slot));
        if (sr > 0u) {
            let clock = w.t - seam_get(SB_START, slot);
            for (var r = rows; r < sr; r++) {
                pose[r] = seam_get(SB_BASE + r, slot);
            }
            let ab = seam_coeffs(clock);
            for (var r = 0u; r < sr; r++) {
                if (r < 3u || r > 6u) {
                    pose[r] += seam_row(slot, r, ab);
                }
            }
            let v = seam_root(slot, ab, vec3<f32>(pose[3], pose[4], pose[5]));
            pose[3] = v.x;
            pose[4] = v.y;
            pose[5] = v.z;
            shown = max(joints, (sr - 7u) / 3u);
            let x = SEAM_DECAY * clock;
            if (x > F32_MAX || (1.0 + x) * exp(-x) < 1e-4) {
                seam_set(SB_ROWS, slot, 0.0);
                seam_set(SB_START, slot, 0.0);
            } else {
                atomicAdd(&wg_seams, 1u);
            }
        }
    }
    w.shown = shown;
    let sh = w.sin_h;
    let ch = w.cos_h;
    let bx = vec2<f32>(w.base_x, w.base_lo_x);
    let bz = vec2<f32>(w.base_z, w.base_lo_z);
    // The foot lock (the CPU walker's pose stage): a visible walker at one of the first
    // LOCK_LEVELS levels with joints plants its feet; any other lets go.
    if (LOCK_LEVELS > 0u && joints > 0u) {
        if ((w.flags & F_VISIBLE) != 0u && w.cur_acc < LOCK_LEVELS) {
            if (foot_lock(&pose, slot, joints, w.body_scale, bx, bz, w.heading)) {
                atomicAdd(&wg_locks, 1u);
            }
        } else {
            lock_clear(slot);
        }
    }
    var root = vec3<f32>(pose[0], pose[1], pose[2]);
    var bad = false;
    if (joints > 0u) {
        // Forward kinematics over the rig (Rig::joint_positions_scaled).
        var pos: array<vec3<f32>, NJ>;
        var rot: array<vec4<f32>, NJ>;
        rig_fk(&pose, NJ, shown, w.body_scale, &pos, &rot);
        root = pos[ROOT_JOINT];
        for (var k = 0u; k < shown; k++) {
            let q = pos[mi(ROTATING + k)];
            let world = vec3<f32>(place(bx, q.x * ch + q.z * sh), q.y, place(bz, -q.x * sh + q.z * ch));
            bad = bad || not_finite(world);
            joints_out[(3u * k) * ns + slot] = world.x;
            joints_out[(3u * k + 1u) * ns + slot] = world.y;
            joints_out[(3u * k + 2u) * ns + slot] = world.z;
        }
    }
    w.root_x = place(bx, root.x * ch + root.z * sh);
    w.root_y = root.y;
    w.root_z = place(bz, -root.x * sh + root.z * ch);
    walkers[i] = w;
    if (bad || not_finite(vec3<f32>(w.root_x, w.root_y, w.root_z))) {
        // The model overflows for this walker's clip (the CPU runtime's KernelError::Overflow).
        atomicAdd(&counters[C_NONFINITE], 1u);
        atomicMin(&counters[C_NONFINITE_FIRST], i);
    }
    var bin = LEVEL_COUNT;
    if (joints > 0u) {
        bin = min(w.cur_acc, LEVEL_COUNT - 1u);
    }
    atomicAdd(&wg_hist[bin], 1u);
}

// ---------------------------------------------------------------------------------------------
// Seam inertialization (lod_policy::SeamTransition and SeamScratch, as crowd_sim's walker uses
// them): a clip change at one of the first SEAM_LEVELS levels between two clips with joints starts
// offsets, decaying with a critically damped spring, from the displayed state of the outgoing clip
// (its pose and its velocity by a finite difference over SEAM_STEP, re-expressed in the next cycle
// frame at a cycle end) to the incoming clip's. Their state lives in the walker's joint slot,
// after its clip in `big_clips` (same stride, `frame.n_slots`): offset, velocity and base rows
// (3 P), then the transition's rows (0: none runs), its start in clip time and the captured rows
// (0: none captured), these counts as f32 values. `seam_capture` (before `build` overwrites the clip) writes the captured
// state's pose and velocity into the offset and velocity rows, `seam_start` (after `build`) turns
// them into the transition; `pose_one` applies it and ends it.

const SB_OFF: u32 = P * RT_MAX + 2u * T;
const SB_VEL: u32 = SB_OFF + P;
const SB_BASE: u32 = SB_OFF + 2u * P;
const SB_ROWS: u32 = SB_OFF + 3u * P;
const SB_START: u32 = SB_ROWS + 1u;
const SB_CAPT: u32 = SB_ROWS + 2u;
// The largest finite f32, written exactly (hexadecimal): 3.4028235 x 10^38, the shortest decimal
// that rounds to it, is above it, and Tint (Chromium's WebGPU) refuses such a literal as out of
// range.
const F32_MAX: f32 = 0x1.fffffep+127f;
const TAU: f32 = 6.2831855;

fn seam_get(k: u32, slot: u32) -> f32 {
    return big_clips[k * frame.n_slots + slot];
}

fn seam_set(k: u32, slot: u32, v: f32) {
    big_clips[k * frame.n_slots + slot] = v;
}

// The spring's weights of the offset and its velocity `clock` seconds after the seam:
// ((1 + d t) e^{-d t}, t e^{-d t}) (SeamTransition::apply).
fn seam_coeffs(clock: f32) -> vec2<f32> {
    let t = max(clock, 0.0);
    let e = exp(-SEAM_DECAY * t);
    return vec2<f32>((1.0 + SEAM_DECAY * t) * e, t * e);
}

// The offset of row `r` (not a root orientation or time row) at the spring's weights `ab`.
fn seam_row(slot: u32, r: u32, ab: vec2<f32>) -> f32 {
    return ab.x * seam_get(SB_OFF + r, slot) + ab.y * seam_get(SB_VEL + r, slot);
}

// The root orientation `v` (rows 3..6) with the offset rotation at the spring's weights `ab`
// applied on the left, on the branch nearest `v`.
fn seam_root(slot: u32, ab: vec2<f32>, v: vec3<f32>) -> vec3<f32> {
    let x = vec3<f32>(seam_get(SB_OFF + 3u, slot), seam_get(SB_OFF + 4u, slot), seam_get(SB_OFF + 5u, slot));
    let u = vec3<f32>(seam_get(SB_VEL + 3u, slot), seam_get(SB_VEL + 4u, slot), seam_get(SB_VEL + 5u, slot));
    let o = ab.x * x + ab.y * u;
    let q = quat_mul(exp_map_quat(o), exp_map_quat(v));
    return nearest_branch(quat_exp_map(q), v);
}

// lod_policy::exp_map_to_quat: Quat::from_axis_angle(v / |v|, |v|), the identity below 1e-12.
fn exp_map_quat(v: vec3<f32>) -> vec4<f32> {
    let angle = length(v);
    if (angle > 1e-12) {
        let axis = v / angle;
        let sc = sincos_f32(angle * 0.5);
        return vec4<f32>(axis * sc.x, sc.y);
    }
    return vec4<f32>(0.0, 0.0, 0.0, 1.0);
}

// lod_policy::quat_to_exp_map (glam's to_axis_angle).
fn quat_exp_map(q_in: vec4<f32>) -> vec3<f32> {
    var q = q_in;
    if (q.w < 0.0) {
        q = -q;
    }
    let len = length(q.xyz);
    if (len >= 1e-8) {
        let angle = 2.0 * atan2_f32(len, q.w);
        if (abs(angle) >= 1e-12) {
            return (q.xyz / len) * angle;
        }
    }
    return vec3<f32>(0.0, 0.0, 0.0);
}

fn quat_conj(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// f32::round: halves away from zero.
fn round_away(x: f32) -> f32 {
    return sign(x) * floor(abs(x) + 0.5);
}

// lod_policy::nearest_branch: the exponential map of the rotation `v` on the branch nearest
// `reference`.
fn nearest_branch(v: vec3<f32>, reference: vec3<f32>) -> vec3<f32> {
    let angle = length(v);
    if (angle < 1e-6) {
        return v;
    }
    let axis = v / angle;
    let k = round_away((dot(axis, reference) - angle) / TAU);
    let w = axis * (angle + k * TAU);
    if (length(w - reference) <= length(v - reference)) {
        return w;
    }
    return v;
}

// The two times whose poses give the velocity at `t` of a clip of `dur` seconds (lod_policy's
// difference_window): backward when there is room, else forward.
fn seam_window(t: f32, dur: f32) -> vec2<f32> {
    let h = max(min(SEAM_STEP, 0.25 * dur), 1e-4);
    if (t - h >= 0.0) {
        return vec2<f32>(t - h, t);
    }
    return vec2<f32>(t, t + h);
}

// Per seam workgroup: [0] slot, [1] clip rows, [2] other rows (the running seam's at a capture,
// the captured at a start), [3] r_T of the clip's level, [4] 1 when the state's pose is the later
// sample, [5] 1 at a cycle end (capture).
var<workgroup> ws_u: array<u32, 6>;
// [0], [1] the two sample times, [2] the running seam's start (capture), [3..6] the outgoing
// clip's root motion (capture).
var<workgroup> ws_f: array<f32, 6>;
var<workgroup> ws_rows: u32;
var<workgroup> ws_wt0: array<f32, RT_MAX>;
var<workgroup> ws_wt1: array<f32, RT_MAX>;

// Sets the workgroup's two samples of the clip with joints in `slot` at level `lvl`: the times of
// the difference window at `t` of `dur`, their time weights; returns r_T.
fn seam_samples(slot: u32, lvl: u32, t: f32, dur: f32) -> u32 {
    let key = mi(LEVELS + 4u * lvl);
    let rt = mi(LEVELS + 4u * lvl + 2u);
    let kb = KEYS + 8u * key;
    let big_t = mi(kb + 1u);
    let off_ut = mi(kb + 5u);
    let win = seam_window(t, dur);
    let tt = P * RT_MAX;
    let ns = frame.n_slots;
    ws_wt0 = time_weights(clip_phase(true, tt, ns, slot, win.x), rt, big_t, off_ut);
    ws_wt1 = time_weights(clip_phase(true, tt, ns, slot, win.y), rt, big_t, off_ut);
    ws_f[0] = win.x;
    ws_f[1] = win.y;
    ws_u[4] = select(0u, 1u, win.y == t);
    return rt;
}

// Row `r` of the clip in `slot` at the workgroup's sample `which` (its pose, G w_T).
fn sample_row(slot: u32, r: u32, rt: u32, which: u32) -> f32 {
    var acc = 0.0;
    for (var b = 0u; b < rt; b++) {
        let g = big_clips[(r * RT_MAX + b) * frame.n_slots + slot];
        if (which == 0u) {
            acc = acc + ws_wt0[b] * g;
        } else {
            acc = acc + ws_wt1[b] * g;
        }
    }
    return acc;
}

// The seven root rows (root position, orientation, time increment) at sample `which`.
fn sample_root(slot: u32, rt: u32, which: u32) -> array<f32, 7> {
    var p: array<f32, 7>;
    for (var r = 0u; r < 7u; r++) {
        p[r] = sample_row(slot, r, rt, which);
    }
    return p;
}

// The velocity from sample `a` to `b` over `h` seconds (PoseState::set; zero for an `h` that is
// not finite and positive).
fn finite_difference(a: f32, b: f32, h: f32) -> f32 {
    if (h > 0.0 && h <= F32_MAX) {
        return (b - a) / h;
    }
    return 0.0;
}

// The root's angular velocity from orientation `a` to `b` over `h` seconds (PoseState::set).
fn angular_velocity(a: vec3<f32>, b: vec3<f32>, h: f32) -> vec3<f32> {
    if (h > 0.0 && h <= F32_MAX) {
        return quat_exp_map(quat_mul(exp_map_quat(b), quat_conj(exp_map_quat(a)))) / h;
    }
    return vec3<f32>(0.0, 0.0, 0.0);
}

// SeamScratch::capture for one build: the displayed state (the clip's pose with the running seam,
// the joints it fades out included) of the outgoing clip at the time it is left, written into the
// slot's offset (pose) and velocity rows; one workgroup per scheduled build (those that start no
// seam return at once).
@compute @workgroup_size(64)
fn seam_capture(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let entry = wid.y * MAX_X + wid.x;
    if (lid == 0u) {
        ws_rows = 0u;
        if (entry < atomicLoad(&counters[C_BUILDS])) {
            let w = walkers[build_list[entry]];
            // Walker::seams: both clips with joints, the incoming one at a seamed level.
            if (w.pend_acc < SEAM_LEVELS && w.pend_joints > 0u && w.cur_joints > 0u && w.slot != NONE) {
                let slot = w.slot;
                let rows = 7u + 3u * w.cur_joints;
                let sr = u32(seam_get(SB_ROWS, slot));
                // A cycle end leaves the clip at its end, a refinement at the walker's clock.
                var t = w.t;
                if (w.mode == MODE_CYCLE) {
                    t = w.cur_dur;
                }
                ws_u[0] = slot;
                ws_u[1] = rows;
                ws_u[2] = sr;
                ws_u[3] = seam_samples(slot, w.cur_acc, t, w.cur_dur);
                ws_u[5] = select(0u, 1u, w.mode == MODE_CYCLE);
                ws_f[2] = seam_get(SB_START, slot);
                ws_f[3] = w.m_dx;
                ws_f[4] = w.m_dz;
                ws_f[5] = w.m_turn;
                ws_rows = max(rows, sr);
            }
        }
    }
    let shown = workgroupUniformLoad(&ws_rows);
    if (shown == 0u) {
        return;
    }
    let slot = ws_u[0];
    let rows = ws_u[1];
    let sr = ws_u[2];
    let rt = ws_u[3];
    let later = ws_u[4] == 1u;
    let t0 = ws_f[0];
    let t1 = ws_f[1];
    let h = t1 - t0;
    let ab0 = seam_coeffs(t0 - ws_f[2]);
    let ab1 = seam_coeffs(t1 - ws_f[2]);
    for (var u = lid; u < 1u + (shown - 7u) / 3u; u += WG) {
        if (u == 0u) {
            // The root rows.
            var p0 = sample_root(slot, rt, 0u);
            var p1 = sample_root(slot, rt, 1u);
            var o0 = vec3<f32>(p0[3], p0[4], p0[5]);
            var o1 = vec3<f32>(p1[3], p1[4], p1[5]);
            if (sr > 0u) {
                for (var r = 0u; r < 3u; r++) {
                    p0[r] += seam_row(slot, r, ab0);
                    p1[r] += seam_row(slot, r, ab1);
                }
                o0 = seam_root(slot, ab0, o0);
                o1 = seam_root(slot, ab1, o1);
            }
            var pos = vec3<f32>(p0[0], p0[1], p0[2]);
            var orient = o0;
            if (later) {
                pos = vec3<f32>(p1[0], p1[1], p1[2]);
                orient = o1;
            }
            var vel = vec3<f32>(finite_difference(p0[0], p1[0], h), finite_difference(p0[1], p1[1], h),
                finite_difference(p0[2], p1[2], h));
            var ang = angular_velocity(o0, o1, h);
            if (ws_u[5] == 1u) {
                // PoseState::into_next_frame: into the cycle frame after the clip's root motion.
                let hf = -ws_f[5] * 0.5;
                let hsc = sincos_f32(hf);
                let q = vec4<f32>(0.0, hsc.x, 0.0, hsc.y);
                pos = quat_rotate(q, pos - vec3<f32>(ws_f[3], 0.0, ws_f[4]));
                orient = quat_exp_map(quat_mul(q, exp_map_quat(orient)));
                vel = quat_rotate(q, vel);
                ang = quat_rotate(q, ang);
            }
            for (var c = 0u; c < 3u; c++) {
                seam_set(SB_OFF + c, slot, pos[c]);
                seam_set(SB_VEL + c, slot, vel[c]);
                seam_set(SB_OFF + 3u + c, slot, orient[c]);
                seam_set(SB_VEL + 3u + c, slot, ang[c]);
            }
            seam_set(SB_OFF + 6u, slot, select(p0[6], p1[6], later));
            seam_set(SB_VEL + 6u, slot, finite_difference(p0[6], p1[6], h));
        } else {
            let r0 = 7u + 3u * (u - 1u);
            for (var r = r0; r < r0 + 3u; r++) {
                var a = 0.0;
                var b = 0.0;
                if (r < rows) {
                    a = sample_row(slot, r, rt, 0u);
                    b = sample_row(slot, r, rt, 1u);
                } else {
                    // A joint the running seam fades out (SeamTransition::fill_beyond).
                    a = seam_get(SB_BASE + r, slot);
                    b = a;
                }
                if (r < sr) {
                    a += seam_row(slot, r, ab0);
                    b += seam_row(slot, r, ab1);
                }
                seam_set(SB_OFF + r, slot, select(a, b, later));
                seam_set(SB_VEL + r, slot, finite_difference(a, b, h));
            }
        }
    }
    if (lid == 0u) {
        seam_set(SB_CAPT, slot, f32(shown));
    }
}

// SeamScratch::start_from_rest for one build: the transition from the captured state to the
// incoming clip at its start (a cycle end) or at the phase it is shown from (a refinement); joints
// only one side shows fade from or to their rest rotations (on the branch nearest the other
// side's). A build with joints that captured nothing ends the slot's transition (a clip change
// without a seam); one workgroup per scheduled build.
@compute @workgroup_size(64)
fn seam_start(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let entry = wid.y * MAX_X + wid.x;
    if (lid == 0u) {
        ws_rows = 0u;
        if (entry < atomicLoad(&counters[C_BUILDS])) {
            let w = walkers[build_list[entry]];
            let slot = w.slot;
            if (w.cur_joints > 0u && slot != NONE) {
                let captured = u32(seam_get(SB_CAPT, slot));
                if (captured == 0u) {
                    seam_set(SB_ROWS, slot, 0.0);
                    seam_set(SB_START, slot, 0.0);
                } else {
                    let rows = 7u + 3u * w.cur_joints;
                    var t_in = 0.0;
                    if (w.mode == MODE_REFINE) {
                        t_in = w.pend_u * w.cur_dur;
                    }
                    ws_u[0] = slot;
                    ws_u[1] = rows;
                    ws_u[2] = captured;
                    ws_u[3] = seam_samples(slot, w.cur_acc, t_in, w.cur_dur);
                    let wide = max(rows, captured);
                    seam_set(SB_ROWS, slot, f32(wide));
                    seam_set(SB_START, slot, t_in);
                    seam_set(SB_CAPT, slot, 0.0);
                    ws_rows = wide;
                }
            }
        }
    }
    let wide = workgroupUniformLoad(&ws_rows);
    if (wide == 0u) {
        return;
    }
    let slot = ws_u[0];
    let rows = ws_u[1];
    let captured = ws_u[2];
    let rt = ws_u[3];
    let later = ws_u[4] == 1u;
    let h = ws_f[1] - ws_f[0];
    for (var u = lid; u < 1u + (wide - 7u) / 3u; u += WG) {
        if (u == 0u) {
            let p0 = sample_root(slot, rt, 0u);
            let p1 = sample_root(slot, rt, 1u);
            let o0 = vec3<f32>(p0[3], p0[4], p0[5]);
            let o1 = vec3<f32>(p1[3], p1[4], p1[5]);
            let ang = angular_velocity(o0, o1, h);
            for (var r = 0u; r < 7u; r++) {
                let next = select(p0[r], p1[r], later);
                if (r < 3u) {
                    let v = finite_difference(p0[r], p1[r], h);
                    seam_set(SB_OFF + r, slot, seam_get(SB_OFF + r, slot) - next);
                    seam_set(SB_VEL + r, slot, seam_get(SB_VEL + r, slot) - v);
                }
                seam_set(SB_BASE + r, slot, next);
            }
            let on = select(o0, o1, later);
            let op = vec3<f32>(seam_get(SB_OFF + 3u, slot), seam_get(SB_OFF + 4u, slot), seam_get(SB_OFF + 5u, slot));
            let vp = vec3<f32>(seam_get(SB_VEL + 3u, slot), seam_get(SB_VEL + 4u, slot), seam_get(SB_VEL + 5u, slot));
            let x = quat_exp_map(quat_mul(exp_map_quat(op), quat_conj(exp_map_quat(on))));
            let v = vp - ang;
            for (var c = 0u; c < 3u; c++) {
                seam_set(SB_OFF + 3u + c, slot, x[c]);
                seam_set(SB_VEL + 3u + c, slot, v[c]);
            }
            seam_set(SB_OFF + 6u, slot, 0.0);
            seam_set(SB_VEL + 6u, slot, 0.0);
        } else {
            let r0 = 7u + 3u * (u - 1u);
            let rest = vec3<f32>(md[REST_ROWS + r0], md[REST_ROWS + r0 + 1u], md[REST_ROWS + r0 + 2u]);
            var np = vec3<f32>(0.0, 0.0, 0.0);
            var nv = vec3<f32>(0.0, 0.0, 0.0);
            var pp = vec3<f32>(0.0, 0.0, 0.0);
            var pv = vec3<f32>(0.0, 0.0, 0.0);
            if (r0 < captured) {
                pp = vec3<f32>(seam_get(SB_OFF + r0, slot), seam_get(SB_OFF + r0 + 1u, slot), seam_get(SB_OFF + r0 + 2u, slot));
                pv = vec3<f32>(seam_get(SB_VEL + r0, slot), seam_get(SB_VEL + r0 + 1u, slot), seam_get(SB_VEL + r0 + 2u, slot));
            }
            if (r0 < rows) {
                let a = vec3<f32>(sample_row(slot, r0, rt, 0u), sample_row(slot, r0 + 1u, rt, 0u), sample_row(slot, r0 + 2u, rt, 0u));
                let b = vec3<f32>(sample_row(slot, r0, rt, 1u), sample_row(slot, r0 + 1u, rt, 1u), sample_row(slot, r0 + 2u, rt, 1u));
                np = select(a, b, later);
                nv = vec3<f32>(finite_difference(a.x, b.x, h), finite_difference(a.y, b.y, h), finite_difference(a.z, b.z, h));
            } else {
                // A joint the incoming clip drops: it fades out to its rest rotation.
                np = nearest_branch(rest, pp);
            }
            if (r0 >= captured) {
                // A joint the incoming clip adds: it fades in from its rest rotation.
                pp = nearest_branch(rest, np);
            }
            let x = pp - np;
            let v = pv - nv;
            for (var c = 0u; c < 3u; c++) {
                seam_set(SB_OFF + r0 + c, slot, x[c]);
                seam_set(SB_VEL + r0 + c, slot, v[c]);
                seam_set(SB_BASE + r0 + c, slot, np[c]);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Foot lock (lod_policy::FootLock, as crowd_sim's walker runs it through the model source's
// plant_feet): for a visible walker at one of the first LOCK_LEVELS levels with joints, per foot
// the pivot (the lower of ankle and toe) placed in the world by the double-float cycle frame,
// contact (low and slow), the horizontal correction and the lowering onto the floor with the
// onset's easing, the release's easing after lift-off, the clearance lift in the air and the
// ground's soft floor, then two-bone IK that writes the thigh, knee and ankle rows of the pose.
// Its state lives in the walker's joint slot after the clip (and after the seam state when seams
// are on), FOOT_FLOATS floats a foot from LOCK_OFF: the previous frame's ground points (world x
// and z of ankle and toe, double-floats), flags, the contact's clock and lowest height, the
// correction and its rate, both at lift-off, the clock since lift-off, the lift, the lift at
// touchdown and the clock since touchdown. FS_HELD (foot 0's flags) marks a slot whose state is
// not the released one (the CPU walker's lock borrowed); a walker that is not near lets go at once
// (the state returns to zeros), and so does a slot given back. With LOCK_LEVELS = 0 none of it
// runs and the host allocates no lock state.

struct FootState {
    // World x, z of the ankle, then of the toe, as double-floats (FootState::prev).
    prev: array<vec2<f32>, 4>,
    flags: u32,
    since_contact: f32,
    contact_low: f32,
    offset: vec3<f32>,
    velocity: vec3<f32>,
    lo_off: vec3<f32>,
    lo_vel: vec3<f32>,
    since_lift: f32,
    lift: f32,
    landing_lift: f32,
    since_landing: f32,
}

const FS_PREV: u32 = 1u;
const FS_PLANTED: u32 = 2u;
const FS_AIR: u32 = 4u;
const FS_HELD: u32 = 8u;
const FOOT_FLOATS: u32 = 27u;
const ONE_MINUS_2EPS: f32 = 0.99999976;
const HALF_PI: f32 = 1.5707964;

fn foot_base(foot: u32) -> u32 {
    return LOCK_OFF + FOOT_FLOATS * foot;
}

fn foot_vec3(slot: u32, k: u32) -> vec3<f32> {
    return vec3<f32>(seam_get(k, slot), seam_get(k + 1u, slot), seam_get(k + 2u, slot));
}

fn foot_set3(slot: u32, k: u32, v: vec3<f32>) {
    seam_set(k, slot, v.x);
    seam_set(k + 1u, slot, v.y);
    seam_set(k + 2u, slot, v.z);
}

fn foot_load(slot: u32, foot: u32) -> FootState {
    let b = foot_base(foot);
    var s: FootState;
    for (var k = 0u; k < 4u; k++) {
        s.prev[k] = vec2<f32>(seam_get(b + 2u * k, slot), seam_get(b + 2u * k + 1u, slot));
    }
    s.flags = u32(seam_get(b + 8u, slot));
    s.since_contact = seam_get(b + 9u, slot);
    s.contact_low = seam_get(b + 10u, slot);
    s.offset = foot_vec3(slot, b + 11u);
    s.velocity = foot_vec3(slot, b + 14u);
    s.lo_off = foot_vec3(slot, b + 17u);
    s.lo_vel = foot_vec3(slot, b + 20u);
    s.since_lift = seam_get(b + 23u, slot);
    s.lift = seam_get(b + 24u, slot);
    s.landing_lift = seam_get(b + 25u, slot);
    s.since_landing = seam_get(b + 26u, slot);
    return s;
}

fn foot_store(slot: u32, foot: u32, s: FootState) {
    let b = foot_base(foot);
    for (var k = 0u; k < 4u; k++) {
        seam_set(b + 2u * k, slot, s.prev[k].x);
        seam_set(b + 2u * k + 1u, slot, s.prev[k].y);
    }
    seam_set(b + 8u, slot, f32(s.flags));
    seam_set(b + 9u, slot, s.since_contact);
    seam_set(b + 10u, slot, s.contact_low);
    foot_set3(slot, b + 11u, s.offset);
    foot_set3(slot, b + 14u, s.velocity);
    foot_set3(slot, b + 17u, s.lo_off);
    foot_set3(slot, b + 20u, s.lo_vel);
    seam_set(b + 23u, slot, s.since_lift);
    seam_set(b + 24u, slot, s.lift);
    seam_set(b + 25u, slot, s.landing_lift);
    seam_set(b + 26u, slot, s.since_landing);
}

// Lets go of both feet at once (FootLock::release, the lock given back): the slot's lock state
// returns to zeros, when it holds any.
fn lock_clear(slot: u32) {
    if (LOCK_LEVELS > 0u && (u32(seam_get(LOCK_OFF + 8u, slot)) & FS_HELD) != 0u) {
        for (var k = 0u; k < 2u * FOOT_FLOATS; k++) {
            seam_set(LOCK_OFF + k, slot, 0.0);
        }
    }
}

// lod_policy::ease_in_out.
fn ease_in_out(u: f32) -> f32 {
    let v = clamp(u, 0.0, 1.0);
    return v * v * (3.0 - 2.0 * v);
}

fn is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

fn is_finite_f(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// footlock's `released`: the correction `t` seconds after lift-off.
fn foot_released(x0: vec3<f32>, v0: vec3<f32>, t: f32) -> vec3<f32> {
    if (t >= LOCK_RELEASE) {
        return vec3<f32>(0.0);
    }
    let g = LOCK_RELEASE_G;
    return (x0 + (v0 + g * x0) * t) * exp(-g * t) * ease_in_out(1.0 - t / LOCK_RELEASE);
}

fn soft_max(h: f32, level: f32, m: f32) -> f32 {
    if (h >= level + m) {
        return h;
    } else if (h <= level - m) {
        return level;
    }
    let u = h - level + m;
    return level + u * u / (4.0 * m);
}

fn foot_release(s: ptr<function, FootState>, dt: f32) {
    if (((*s).flags & FS_PLANTED) != 0u) {
        (*s).flags &= ~FS_PLANTED;
        (*s).lo_off = (*s).offset;
        (*s).lo_vel = (*s).velocity;
        (*s).since_lift = 0.0;
    }
    (*s).since_lift += dt;
    (*s).offset = foot_released((*s).lo_off, (*s).lo_vel, (*s).since_lift);
}

fn foot_land(s: ptr<function, FootState>) {
    if (((*s).flags & FS_AIR) != 0u) {
        (*s).flags &= ~FS_AIR;
        (*s).landing_lift = (*s).lift;
        (*s).since_landing = 0.0;
    }
}

fn foot_ease_lift(s: ptr<function, FootState>, dt: f32) {
    (*s).since_landing += dt;
    if ((*s).since_landing >= LOCK_RELEASE) {
        (*s).lift = 0.0;
    } else {
        (*s).lift = (*s).landing_lift * ease_in_out(1.0 - (*s).since_landing / LOCK_RELEASE);
    }
}

fn foot_clear(s: ptr<function, FootState>, height: f32, shown: f32, contact: bool, dt: f32) {
    if (contact) {
        foot_land(s);
    } else if (height >= LOCK_HEIGHT) {
        (*s).flags |= FS_AIR;
    }
    if (((*s).flags & FS_AIR) != 0u) {
        (*s).lift = soft_max(shown, LOCK_HEIGHT, 0.5 * LOCK_HEIGHT) - shown;
    } else {
        foot_ease_lift(s, dt);
        (*s).lift = max((*s).lift, soft_max(shown, 0.0, LOCK_GROUND_MARGIN) - shown);
    }
}

// FootState::let_go.
fn foot_let_go(s: ptr<function, FootState>, dt: f32) {
    (*s).flags &= ~FS_PREV;
    foot_land(s);
    foot_ease_lift(s, dt);
    let before = (*s).offset;
    foot_release(s, dt);
    (*s).velocity = ((*s).offset - before) / dt;
}

// FootState::step with the foot's world points: ground (x, z double-floats of ankle then toe) and
// heights `ys` (ankle, toe); returns the world correction.
fn foot_step(s: ptr<function, FootState>, ground: array<vec2<f32>, 4>, ys: vec2<f32>, dt: f32) -> vec3<f32> {
    var pivot = 0u;
    if (ys.y < ys.x) {
        pivot = 1u;
    }
    let had = ((*s).flags & FS_PREV) != 0u;
    var moved = vec3<f32>(0.0);
    if (had) {
        let mx = df_add(ground[2u * pivot], -(*s).prev[2u * pivot]);
        let mz = df_add(ground[2u * pivot + 1u], -(*s).prev[2u * pivot + 1u]);
        moved = vec3<f32>(mx.x + mx.y, 0.0, mz.x + mz.y);
    }
    (*s).prev = ground;
    (*s).flags |= FS_PREV;
    let speed = length(moved) / dt;
    if (had && (is_nan(speed) || speed >= LOCK_TELEPORT)) {
        let held = (*s).flags & FS_HELD;
        var fresh: FootState;
        fresh.prev = ground;
        fresh.flags = FS_PREV | held;
        *s = fresh;
        return vec3<f32>(0.0);
    }
    let height = select(ys.x, ys.y, pivot == 1u) - LOCK_FLOOR;
    let contact = height < LOCK_HEIGHT && had && speed < LOCK_SPEED;
    let before = (*s).offset;
    if (contact) {
        if (((*s).flags & FS_PLANTED) == 0u) {
            (*s).flags |= FS_PLANTED;
            (*s).since_contact = 0.0;
            (*s).contact_low = height;
        }
        (*s).since_contact += dt;
        (*s).contact_low = min((*s).contact_low, height);
        let w = ease_in_out(min((*s).since_contact / LOCK_ONSET, 1.0));
        (*s).offset = (*s).offset - w * moved;
        (*s).offset.y = (*s).offset.y + w * (-max((*s).contact_low, 0.0) - (*s).offset.y);
    } else {
        foot_release(s, dt);
    }
    (*s).velocity = ((*s).offset - before) / dt;
    foot_clear(s, height, height + (*s).offset.y, contact, dt);
    return (*s).offset + vec3<f32>(0.0, (*s).lift, 0.0);
}

// glam's Vec3::normalize_or: `v` times its length's reciprocal, `fallback` when that is not finite
// and positive.
fn normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / length(v);
    if (is_finite_f(rcp) && rcp > 0.0) {
        return v * rcp;
    }
    return fallback;
}

// glam's Quat::normalize (SSE2: divided by the length).
fn quat_normalize(q: vec4<f32>) -> vec4<f32> {
    return q / length(q);
}

// glam's Quat::from_rotation_arc(a, b) for unit vectors.
fn rotation_arc(a: vec3<f32>, b: vec3<f32>) -> vec4<f32> {
    let d = dot(a, b);
    if (d > ONE_MINUS_2EPS) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    if (d < -ONE_MINUS_2EPS) {
        // Half a turn about any vector orthogonal to `a` (Vec3::any_orthonormal_vector).
        let sg = select(-1.0, 1.0, a.z >= 0.0);
        let k = -1.0 / (sg + a.z);
        let m = a.x * a.y * k;
        let axis = vec3<f32>(m, sg + a.y * a.y * k, -a.y);
        let sc = sincos_f32(HALF_PI);
        return vec4<f32>(axis * sc.x, sc.y);
    }
    let c = cross(a, b);
    return quat_normalize(vec4<f32>(c, 1.0 + d));
}

// lod_policy's soft_reach.
fn soft_reach(reach: f32, current: f32, len: f32) -> f32 {
    let start = max(LOCK_SOFT_REACH * len, current);
    if (reach <= start) {
        return reach;
    }
    let span = len - start;
    if (span <= 0.0) {
        return start;
    }
    return min(start + span * (1.0 - exp(-(reach - start) / span)), max(LOCK_MAX_REACH * len, current));
}

struct TwoBone {
    thigh: vec4<f32>,
    knee: vec4<f32>,
}

// lod_policy's two_bone: the world rotations of thigh (about the hip) and shin (about the moved
// knee) that bring the ankle to `target` at the soft reach.
fn two_bone(hip: vec3<f32>, knee: vec3<f32>, ankle: vec3<f32>, goal_at: vec3<f32>, pole: vec3<f32>) -> TwoBone {
    let id = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    let l1 = length(knee - hip);
    let l2 = length(ankle - knee);
    let to_target = goal_at - hip;
    let reach = length(to_target);
    if (l1 < 1e-5 || l2 < 1e-5 || reach < 1e-5) {
        return TwoBone(id, id);
    }
    let d = max(soft_reach(reach, length(ankle - hip), l1 + l2), abs(l1 - l2) + 1e-4);
    let u = to_target / reach;
    let kh = knee - hip;
    let side = kh + LOCK_POLE_WEIGHT * l1 * pole;
    var w = side - dot(side, u) * u;
    if (dot(w, w) < 1e-10) {
        w = cross(cross(ankle - hip, vec3<f32>(0.0, 1.0, 0.0)), u);
    }
    w = normalize_or(w, vec3<f32>(0.0));
    let cos_a = clamp((l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d), -1.0, 1.0);
    let new_knee = hip + l1 * (cos_a * u + sqrt(max(1.0 - cos_a * cos_a, 0.0)) * w);
    let r_thigh = rotation_arc(kh / l1, (new_knee - hip) / l1);
    let shin = quat_rotate(r_thigh, ankle - knee);
    let goal = hip + d * u - new_knee;
    let r_knee = rotation_arc(normalize_or(shin, vec3<f32>(0.0)), normalize_or(goal, vec3<f32>(0.0)));
    return TwoBone(r_thigh, r_knee);
}

// Writes rotation `q` as rotating joint `k`'s rows of `pose`, on the branch nearest the rows there.
fn write_joint_rows(pose: ptr<function, array<f32, P>>, k: u32, q: vec4<f32>) {
    let r = 7u + 3u * k;
    let old = vec3<f32>((*pose)[r], (*pose)[r + 1u], (*pose)[r + 2u]);
    let v = nearest_branch(quat_exp_map(quat_normalize(q)), old);
    (*pose)[r] = v.x;
    (*pose)[r + 1u] = v.y;
    (*pose)[r + 2u] = v.z;
}

// Plants the feet of the pose of a walker at a lock level (FootLock::apply with the clip's
// `joints` active joints, body scale `scale`, the cycle frame's origin `bx`, `bz` and heading `h`);
// returns whether a leg was corrected.
fn foot_lock(pose: ptr<function, array<f32, P>>, slot: u32, joints: u32, scale: f32, bx: vec2<f32>, bz: vec2<f32>, h: f32) -> bool {
    let dt = frame.dt;
    if (!(dt > 0.0)) {
        return false;
    }
    var legs = LOCK_LEGS;
    var ks = LOCK_LEG_ROWS;
    var any_leg = false;
    var evaluated: array<bool, 2>;
    for (var f = 0u; f < 2u; f++) {
        evaluated[f] = ks[f].x < joints && ks[f].y < joints && ks[f].z < joints;
        any_leg = any_leg || evaluated[f];
    }
    var corrected = false;
    // Forward kinematics of the joints up to the legs' last (Rig::joint_transforms_of: the clip's
    // active joints, the body scale), when a leg is evaluated.
    var pos: array<vec3<f32>, NJ>;
    var rot: array<vec4<f32>, NJ>;
    if (any_leg) {
        rig_fk(pose, LOCK_NJ, joints, scale, &pos, &rot);
    }
    // CycleFrame::rotation (single precision) and to_world (the origin added in double).
    let hf = 0.5 * h;
    let fsc = sincos_f32(hf);
    let fq = vec4<f32>(0.0, fsc.x, 0.0, fsc.y);
    for (var f = 0u; f < 2u; f++) {
        var state = foot_load(slot, f);
        if (f == 0u) {
            state.flags |= FS_HELD;
        }
        if (!evaluated[f]) {
            foot_let_go(&state, dt);
            foot_store(slot, f, state);
            continue;
        }
        let leg = legs[f];
        let ankle = quat_rotate(fq, pos[leg.z]);
        let toe = quat_rotate(fq, pos[leg.w]);
        var pts: array<vec2<f32>, 4>;
        pts[0] = df_add(bx, vec2<f32>(ankle.x, 0.0));
        pts[1] = df_add(bz, vec2<f32>(ankle.z, 0.0));
        pts[2] = df_add(bx, vec2<f32>(toe.x, 0.0));
        pts[3] = df_add(bz, vec2<f32>(toe.z, 0.0));
        let corr = foot_step(&state, pts, vec2<f32>(ankle.y, toe.y), dt);
        foot_store(slot, f, state);
        let d = quat_rotate(quat_conj(fq), corr);
        if (dot(d, d) < 1e-12) {
            continue;
        }
        corrected = true;
        // bend_leg: the ankle moved by `d` with the hip fixed and the foot's orientation kept.
        let th = leg.x;
        let kn = leg.y;
        let an = leg.z;
        var parent_rot = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        if (ks[f].w != NONE) {
            parent_rot = rot[ks[f].w];
        }
        let rz = quat_rotate(rot[ROOT_JOINT], vec3<f32>(0.0, 0.0, 1.0));
        let pole = normalize_or(vec3<f32>(rz.x, 0.0, rz.z), vec3<f32>(0.0, 0.0, 1.0));
        let tb = two_bone(pos[th], pos[kn], pos[an], pos[an] + d, pole);
        let thigh_rot = quat_normalize(quat_mul(tb.thigh, rot[th]));
        let knee_rot = quat_normalize(quat_mul(quat_mul(tb.knee, tb.thigh), rot[kn]));
        write_joint_rows(pose, ks[f].x, quat_mul(quat_conj(parent_rot), thigh_rot));
        write_joint_rows(pose, ks[f].y, quat_mul(quat_conj(thigh_rot), knee_rot));
        write_joint_rows(pose, ks[f].z, quat_mul(quat_conj(knee_rot), rot[an]));
    }
    return corrected;
}
