// The GPU crowd's compute shaders (crate `gpu-crowd`). The host prepends the model's sizes as
// constants (see `shader.rs`); every array index below is bounded by them.
//
// Passes per frame: `advance` (cull, detail from the tabulated policy, clock, cycle ends with the
// path controller, clip builds scheduled), `build_args` (indirect dispatch size), `build` (one
// workgroup per scheduled clip: kriging weights, core, G(c), time table, root motion), `fix_free`
// (the joint-slot stack after its pops), `pose_fk` (pose at the clip's phase, forward kinematics,
// placement in the world).

struct Walker {
    t: f32, cur_dur: f32, hold_s: f32, pend_u: f32,
    root_x: f32, root_y: f32, root_z: f32, height: f32,
    base_x: f32, base_z: f32, heading: f32, sin_h: f32,
    cos_h: f32, s: f32, stride: f32, body_scale: f32,
    path_cx: f32, path_cz: f32, path_a: f32, path_b: f32,
    path_rot: f32, path_dir: f32, c_dx: f32, c_dz: f32,
    c_turn: f32, c_height: f32, m_dx: f32, m_dz: f32,
    m_turn: f32, init_phase: f32, init_hold: f32, pad0: f32,
    cur_acc: u32, cur_joints: u32, pend_acc: u32, pend_joints: u32,
    style: u32, slot: u32, mode: u32, flags: u32,
}

struct Frame {
    planes: array<vec4<f32>, 6>,
    eye: vec4<f32>,
    dt: f32, margin: f32, n: u32, n_slots: u32,
    vis_entries: u32, hid_entries: u32, pad1: u32, pad2: u32,
    // Policy table: (start distance bits, accuracy, joints, 0); visible entries first.
    policy: array<vec4<u32>, POLICY_MAX>,
}

// Counters: [0..3] indirect build dispatch, then the frame's counts, the free-stack top and the
// level histogram.
const C_BUILDS: u32 = 3u;
const C_VISIBLE: u32 = 4u;
const C_SLOT_FAULTS: u32 = 5u;
const C_FREE_TOP: u32 = 6u;
const C_HIST: u32 = 8u;

const NONE: u32 = 0xffffffffu;
const MODE_CYCLE: u32 = 0u;
const MODE_REFINE: u32 = 1u;
const MODE_INIT: u32 = 2u;
const PI: f32 = 3.14159265358979323846;
const TAU: f32 = 6.28318530717958647692;
const WG: u32 = 64u;
const MAX_X: u32 = 65535u;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> mtab: array<vec4<u32>, META_VEC4>;
@group(0) @binding(2) var<storage, read_write> walkers: array<Walker>;
@group(0) @binding(3) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> build_list: array<u32>;
@group(0) @binding(5) var<storage, read_write> free_stack: array<u32>;
@group(0) @binding(6) var<storage, read> md: array<f32>;
@group(0) @binding(7) var<storage, read_write> small_clips: array<f32>;
@group(0) @binding(8) var<storage, read_write> big_clips: array<f32>;
@group(0) @binding(9) var<storage, read_write> joints_out: array<f32>;

fn mi(k: u32) -> u32 {
    return mtab[k / 4u][k % 4u];
}

// Rust's f32::round (half away from zero).
fn round_away(x: f32) -> f32 {
    let r = trunc(x);
    if (abs(x - r) >= 0.5) {
        return r + sign(x);
    }
    return r;
}

fn wrap_angle(a: f32) -> f32 {
    let w = a - TAU * round_away(a / TAU);
    if (w <= -PI) {
        return w + TAU;
    }
    return w;
}

// ---------------------------------------------------------------------------------------------
// Paths (crowd_sim::path).

fn rotate_by(sr: f32, cr: f32, v: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(cr * v.x - sr * v.y, sr * v.x + cr * v.y);
}

fn path_point(w: Walker, s: f32) -> vec2<f32> {
    return vec2<f32>(w.path_cx, w.path_cz)
        + rotate_by(sin(w.path_rot), cos(w.path_rot), vec2<f32>(w.path_a * cos(s), w.path_b * sin(s)));
}

fn path_velocity(w: Walker, s: f32) -> vec2<f32> {
    return w.path_dir
        * rotate_by(sin(w.path_rot), cos(w.path_rot), vec2<f32>(-w.path_a * sin(s), w.path_b * cos(s)));
}

fn dist2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    let d = a - b;
    return d.x * d.x + d.y * d.y;
}

fn closest_param_sampled(w: Walker, p: vec2<f32>, s_guess: f32) -> f32 {
    let stp = 0.1;
    var best = s_guess;
    var best_d = dist2(path_point(w, s_guess), p);
    for (var k = -8; k <= 8; k++) {
        let s = s_guess + f32(k) * stp;
        let d = dist2(path_point(w, s), p);
        if (d < best_d) {
            best_d = d;
            best = s;
        }
    }
    var lo = best - stp;
    var hi = best + stp;
    let g = 0.618034;
    for (var k = 0; k < 16; k++) {
        let m1 = hi - g * (hi - lo);
        let m2 = lo + g * (hi - lo);
        if (dist2(path_point(w, m1), p) < dist2(path_point(w, m2), p)) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    return 0.5 * (lo + hi);
}

// EllipsePath::closest_param_near, Newton's iteration in f32 (the CPU runs it in f64; its answer
// agrees to about 1e-7 rad).
fn closest_param_near(w: Walker, p: vec2<f32>, s_guess: f32) -> f32 {
    let a = w.path_a;
    let b = w.path_b;
    let sr = sin(w.path_rot);
    let cr = cos(w.path_rot);
    let vx = p.x - w.path_cx;
    let vy = p.y - w.path_cz;
    let x = cr * vx + sr * vy;
    let y = -sr * vx + cr * vy;
    let k = b * b - a * a;
    var theta = atan2(a * y, b * x);
    var converged = false;
    for (var it = 0; it < 8; it++) {
        let s = sin(theta);
        let c = cos(theta);
        let g = k * s * c + a * x * s - b * y * c;
        let dg = k * (c * c - s * s) + a * x * c + b * y * s;
        if (!(dg > 0.0)) {
            break;
        }
        let stp = g / dg;
        theta -= stp;
        if (abs(stp) <= 2e-6) {
            converged = true;
            break;
        }
    }
    let delta = wrap_angle(theta - s_guess);
    if (converged && abs(delta) <= 0.9) {
        return s_guess + delta;
    }
    return closest_param_sampled(w, p, s_guess);
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

@compute @workgroup_size(64)
fn advance(@builtin(global_invocation_id) gid: vec3<u32>,
           @builtin(num_workgroups) nw: vec3<u32>,
           @builtin(local_invocation_index) lid: u32) {
    if (lid == 0u) {
        atomicStore(&wg_visible, 0u);
    }
    workgroupBarrier();
    let i = walker_index(gid, nw);
    if (i < frame.n) {
        var w = walkers[i];
        let vis = visible_of(w);
        let eye = frame.eye.xyz;
        let dist = length(vec3<f32>(w.root_x, w.root_y, w.root_z) - eye);
        let d = policy_detail(dist, vis);
        let dt = frame.dt;
        w.t += dt;
        var build = false;
        if (w.t >= w.cur_dur) {
            let end = w.cur_dur;
            w.t -= end;
            let h = w.heading;
            w.base_x += cos(h) * w.m_dx + sin(h) * w.m_dz;
            w.base_z += -sin(h) * w.m_dx + cos(h) * w.m_dz;
            w.heading = wrap_angle(h + w.m_turn);
            w.sin_h = sin(w.heading);
            w.cos_h = cos(w.heading);
            let base = vec2<f32>(w.base_x, w.base_z);
            w.s = closest_param_near(w, base, w.s);
            // path_controls: pure pursuit one stride ahead, clamped into the model's range.
            let speed = max(length(path_velocity(w, w.s)), 1e-3);
            let s_t = w.s + w.path_dir * w.stride / speed;
            let tgt = path_point(w, s_t);
            let dd = tgt - base;
            let vt = path_velocity(w, s_t);
            let turn = wrap_angle(atan2(vt.x, vt.y) - w.heading);
            let hh = w.heading;
            let lft = vec2<f32>(cos(hh), -sin(hh));
            let fwd = vec2<f32>(sin(hh), cos(hh));
            w.c_dx = clamp_control(dot(dd, lft), md[RANGE_OFF + 0u], md[RANGE_OFF + 4u]);
            w.c_dz = clamp_control(dot(dd, fwd), md[RANGE_OFF + 1u], md[RANGE_OFF + 5u]);
            w.c_turn = clamp_control(turn, md[RANGE_OFF + 2u], md[RANGE_OFF + 6u]);
            w.c_height = clamp_control(w.height, md[RANGE_OFF + 3u], md[RANGE_OFF + 7u]);
            w.mode = MODE_CYCLE;
            build = true;
            w.hold_s = 0.0;
        }
        if (w.hold_s > 0.0) {
            w.hold_s -= dt;
        }
        let finer = d.x < w.cur_acc || d.y > w.cur_joints;
        if (!build && w.hold_s <= 0.0 && finer) {
            w.hold_s = 0.0;
            w.pend_u = w.t / w.cur_dur;
            w.mode = MODE_REFINE;
            build = true;
        }
        if (build) {
            w.pend_acc = d.x;
            w.pend_joints = d.y;
            if (d.y == 0u && w.slot != NONE) {
                // A root-only clip lives in the walker's own small clip: give the slot back.
                let top = atomicAdd(&counters[C_FREE_TOP], 1u);
                free_stack[top] = w.slot;
                w.slot = NONE;
            }
            let k = atomicAdd(&counters[C_BUILDS], 1u);
            build_list[k] = i;
        }
        w.flags = select(0u, 1u, vis);
        walkers[i] = w;
        if (vis) {
            atomicAdd(&wg_visible, 1u);
        }
    }
    workgroupBarrier();
    if (lid == 0u) {
        let v = atomicLoad(&wg_visible);
        if (v > 0u) {
            atomicAdd(&counters[C_VISIBLE], v);
        }
    }
}

@compute @workgroup_size(1)
fn build_args() {
    let n = atomicLoad(&counters[C_BUILDS]);
    atomicStore(&counters[0], min(n, MAX_X));
    atomicStore(&counters[1], (n + MAX_X - 1u) / MAX_X);
    atomicStore(&counters[2], 1u);
}

@compute @workgroup_size(1)
fn fix_free() {
    let top = bitcast<i32>(atomicLoad(&counters[C_FREE_TOP]));
    if (top < 0) {
        atomicStore(&counters[C_FREE_TOP], 0u);
    }
}


// ---------------------------------------------------------------------------------------------
// Double-float arithmetic (a value is hi + lo, two f32): the kriging weights and the time table,
// which the CPU runtime computes in f64 and whose sums cancel. Products are exact through a split
// of each factor into 12-bit halves by masking (no reliance on fused multiply-add).

fn two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = a + b;
    let bb = s - a;
    return vec2<f32>(s, (a - (s - bb)) + (b - bb));
}

fn quick_two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = a + b;
    return vec2<f32>(s, b - (s - a));
}

fn split(a: f32) -> vec2<f32> {
    let hi = bitcast<f32>(bitcast<u32>(a) & 0xfffff000u);
    return vec2<f32>(hi, a - hi);
}

fn two_prod(a: f32, b: f32) -> vec2<f32> {
    let p = a * b;
    let sa = split(a);
    let sb = split(b);
    let err = ((sa.x * sb.x - p) + sa.x * sb.y + sa.y * sb.x) + sa.y * sb.y;
    return vec2<f32>(p, err);
}

fn df_add(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    var s = two_sum(a.x, b.x);
    let t = two_sum(a.y, b.y);
    s.y += t.x;
    s = quick_two_sum(s.x, s.y);
    s.y += t.y;
    return quick_two_sum(s.x, s.y);
}

fn df_mul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    var p = two_prod(a.x, b.x);
    p.y += a.x * b.y + a.y * b.x;
    return quick_two_sum(p.x, p.y);
}

fn df_mul_f(a: vec2<f32>, b: f32) -> vec2<f32> {
    var p = two_prod(a.x, b);
    p.y += a.y * b;
    return quick_two_sum(p.x, p.y);
}

fn df_div(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let q1 = a.x / b.x;
    var r = df_add(a, -df_mul(b, vec2<f32>(q1, 0.0)));
    let q2 = r.x / b.x;
    r = df_add(r, -df_mul(b, vec2<f32>(q2, 0.0)));
    let q3 = r.x / b.x;
    return df_add(quick_two_sum(q1, q2), vec2<f32>(q3, 0.0));
}

fn df_sqrt(a: vec2<f32>) -> vec2<f32> {
    if (!(a.x > 0.0)) {
        return vec2<f32>(0.0, 0.0);
    }
    let s = sqrt(a.x);
    let r = df_add(a, -two_prod(s, s));
    return two_sum(s, r.x / (2.0 * s));
}

const LN2: vec2<f32> = vec2<f32>(0.6931472, -1.9046542e-9);

fn df_exp(a: vec2<f32>) -> vec2<f32> {
    if (a.x < -87.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let k = round(a.x / LN2.x);
    // r = (a - k ln 2) / 512, |r| < 7e-4: eight Taylor terms, then squared nine times.
    let r = df_mul_f(df_add(a, -df_mul_f(LN2, k)), 1.0 / 512.0);
    var p = vec2<f32>(1.0, 0.0);
    for (var n = 9; n >= 1; n--) {
        p = df_add(vec2<f32>(1.0, 0.0), df_div(df_mul(r, p), vec2<f32>(f32(n), 0.0)));
    }
    for (var q = 0; q < 9; q++) {
        p = df_mul(p, p);
    }
    let e = i32(k);
    return vec2<f32>(ldexp(p.x, e), ldexp(p.y, e));
}

fn df_log(a: vec2<f32>) -> vec2<f32> {
    // One Newton step on exp(y) = a from the f32 logarithm.
    let y = vec2<f32>(log(a.x), 0.0);
    let t = df_mul(a, df_exp(-y));
    return df_add(y, df_add(t, vec2<f32>(-1.0, 0.0)));
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
        var acc = w.pend_acc;
        var joints = w.pend_joints;
        if (joints == 0u) {
            acc = LAST_LEVEL;
        } else if (w.slot == NONE) {
            let top = bitcast<i32>(atomicSub(&counters[C_FREE_TOP], 1u)) - 1;
            if (top >= 0) {
                w.slot = free_stack[u32(top)];
            } else {
                // No joint slot left: a root-only clip, and a retry when slots free up.
                atomicAdd(&counters[C_SLOT_FAULTS], 1u);
                acc = LAST_LEVEL;
                joints = 0u;
                w.pend_acc = LAST_LEVEL;
                w.pend_joints = 0u;
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
    workgroupBarrier();
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
    var k = 0.0;
    if (theta < 1e-3) {
        k = 0.5 - theta * theta / 48.0;
    } else {
        k = sin(hf) / theta;
    }
    return vec4<f32>(v * k, cos(hf));
}

var<workgroup> wg_hist: array<atomic<u32>, HIST_BINS>;

@compute @workgroup_size(64)
fn pose_fk(@builtin(global_invocation_id) gid: vec3<u32>,
           @builtin(num_workgroups) nw: vec3<u32>,
           @builtin(local_invocation_index) lid: u32) {
    for (var b = lid; b < HIST_BINS; b += WG) {
        atomicStore(&wg_hist[b], 0u);
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
}

fn clip_at(big: bool, e: u32) -> f32 {
    if (big) {
        return big_clips[e];
    }
    return small_clips[e];
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
    let duration = vec2<f32>(clip_at(big, (tt + T - 1u) * stride + base), clip_at(big, (tt + 2u * T - 1u) * stride + base));
    var phase = 0.0;
    if (T >= 2u && duration.x > 0.0) {
        let tq = min(max(w.t, 0.0), duration.x + duration.y);
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
    // Time weights w_T (eq. 5).
    let ph = clamp(phase, 0.0, f32(T - 1u));
    let i0 = min(u32(floor(ph)), T - 2u);
    let i1 = min(i0 + 1u, T - 1u);
    let a = ph - f32(i0);
    var wt: array<f32, RT_MAX>;
    for (var b = 0u; b < rt; b++) {
        wt[b] = (1.0 - a) * md[off_ut + i0 * big_t + b] + a * md[off_ut + i1 * big_t + b];
    }
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
    let sh = w.sin_h;
    let ch = w.cos_h;
    var root = vec3<f32>(pose[0], pose[1], pose[2]);
    if (joints > 0u) {
        // Forward kinematics over the rig (Rig::joint_positions_scaled).
        var pos: array<vec3<f32>, NJ>;
        var rot: array<vec4<f32>, NJ>;
        let ground = vec3<f32>(root.x, 0.0, root.z);
        let scale = w.body_scale;
        for (var j = 0u; j < NJ; j++) {
            let role = mi(RIG + 4u * j);
            let k = mi(RIG + 4u * j + 1u);
            let parent = mi(RIG + 4u * j + 2u);
            let rest = vec4<f32>(md[RIG_F + 7u * j + 3u], md[RIG_F + 7u * j + 4u], md[RIG_F + 7u * j + 5u], md[RIG_F + 7u * j + 6u]);
            if (role == 0u) {
                pos[j] = ground;
                rot[j] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
            } else if (role == 1u) {
                pos[j] = root;
                rot[j] = exp_to_quat(vec3<f32>(pose[3], pose[4], pose[5]));
            } else {
                var local = rest;
                if (role == 2u && k < joints) {
                    let r = 7u + 3u * k;
                    local = exp_to_quat(vec3<f32>(pose[r], pose[r + 1u], pose[r + 2u]));
                }
                let off = vec3<f32>(md[RIG_F + 7u * j], md[RIG_F + 7u * j + 1u], md[RIG_F + 7u * j + 2u]);
                let pp = pos[parent];
                let pr = rot[parent];
                pos[j] = pp + quat_rotate(pr, off * scale);
                rot[j] = quat_mul(pr, local);
            }
        }
        root = pos[ROOT_JOINT];
        for (var k = 0u; k < joints; k++) {
            let q = pos[mi(ROTATING + k)];
            let world = vec3<f32>(w.base_x + q.x * ch + q.z * sh, q.y, w.base_z - q.x * sh + q.z * ch);
            joints_out[(3u * k) * ns + slot] = world.x;
            joints_out[(3u * k + 1u) * ns + slot] = world.y;
            joints_out[(3u * k + 2u) * ns + slot] = world.z;
        }
    }
    w.root_x = w.base_x + root.x * ch + root.z * sh;
    w.root_y = root.y;
    w.root_z = w.base_z - root.x * sh + root.z * ch;
    walkers[i] = w;
    var bin = LEVEL_COUNT;
    if (joints > 0u) {
        bin = min(w.cur_acc, LEVEL_COUNT - 1u);
    }
    atomicAdd(&wg_hist[bin], 1u);
}
