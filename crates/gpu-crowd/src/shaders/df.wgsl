// Double-float arithmetic for the crowd shaders (crate `gpu-crowd`, `df.rs`): a value is hi + lo,
// two f32 with |lo| <= ulp(hi) / 2, about 48 bits. The CPU runtime computes these quantities in
// f64 where their sums cancel or grow: the kriging weights and the time table of a clip build,
// and what steers a walker (its cycle frame's origin and heading, `lod_policy::CycleFrame`, and
// `crowd_sim::path`'s points, closest-point search and controller). Products are exact through a split of each factor into 12-bit halves by
// masking (no reliance on fused multiply-add, which the CPU does not use either).
//
// Shader compilers may simplify float expressions as if they were real numbers (Mesa's NIR turns
// `(a + b) - a` into `b`, and factors and cancels products, for any arithmetic not marked exact,
// and WGSL cannot mark any), which makes the error terms below zero. So every value whose rounding
// error is taken passes through `keep`: its bits XORed with `df_zero()`, 0 read from a buffer (the
// file that includes this one defines it), which no float rule can see through.
//
// This file needs no constants from the host; the crowd shaders are appended after it.

fn keep(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) ^ df_zero());
}

fn two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = keep(a + b);
    let bb = keep(s - a);
    return vec2<f32>(s, (a - (s - bb)) + (b - bb));
}

fn quick_two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = keep(a + b);
    return vec2<f32>(s, b - (s - a));
}

fn split(a: f32) -> vec2<f32> {
    let hi = bitcast<f32>(bitcast<u32>(a) & 0xfffff000u);
    return vec2<f32>(hi, keep(a - hi));
}

fn two_prod(a: f32, b: f32) -> vec2<f32> {
    let p = keep(a * b);
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

// pi and 2 pi as double-floats.
const DF_PI: vec2<f32> = vec2<f32>(3.1415927410125732, -8.742277657347586e-08);
const DF_TAU: vec2<f32> = vec2<f32>(6.2831854820251465, -1.7484555314695172e-07);
// pi / 2 = PIO2_1 + PIO2_2 + PIO2_3 + PIO2_4 (+ 8e-20): the first three have 12 significant
// bits, so that k PIO2_1, k PIO2_2 and k PIO2_3 are exact for |k| < 2^12 (arguments up to
// 6,400 rad).
const PIO2_1: f32 = 1.5703125;
const PIO2_2: f32 = 0.0004837512969970703;
const PIO2_3: f32 = 7.549533620476723e-08;
const PIO2_4: f32 = 2.5633440682570896e-12;
const TWO_OVER_PI: f32 = 0.6366197466850281;
// 1 / n! for the Taylor series below: double-floats where they carry the sum, f32 in the tails.
const INV_F3: vec2<f32> = vec2<f32>(0.1666666716337204, -4.967053879312289e-09);
const INV_F4: vec2<f32> = vec2<f32>(0.0416666679084301, -1.2417634698280722e-09);
const INV_F5: vec2<f32> = vec2<f32>(0.008333333767950535, -4.34617203337595e-10);
const INV_F6: vec2<f32> = vec2<f32>(0.0013888889225199819, -3.3631094437103215e-11);
const INV_F7: vec2<f32> = vec2<f32>(0.00019841270113829523, -2.725596874933456e-12);
const INV_F8: vec2<f32> = vec2<f32>(2.4801587642286904e-05, -3.40699609366682e-13);
const INV_F9: f32 = 2.7557318844628753e-06;
const INV_F10: f32 = 2.755731998149713e-07;
const INV_F11: f32 = 2.5052107943679403e-08;
const INV_F12: f32 = 2.0876755879584152e-09;
const INV_F13: f32 = 1.6059044372074283e-10;
const INV_F14: f32 = 1.147074536050896e-11;
const INV_F15: f32 = 7.647163609812713e-13;
const INV_F16: f32 = 4.7794772561329454e-14;

// a - k pi / 2 for a whole number k (|k| < 2^12) near a.x / (pi / 2) (within a factor of two, or
// 0), to about 1e-15 absolute: a.x - k PIO2_1 is then exact (Sterbenz), so are the products
// k PIO2_2 and k PIO2_3, and two_prod takes k PIO2_4 exactly.
fn df_minus_pio2s(a: vec2<f32>, k: f32) -> vec2<f32> {
    var r = two_sum(a.x - k * PIO2_1, -(k * PIO2_2));
    r = df_add(r, vec2<f32>(-(k * PIO2_3), 0.0));
    r = df_add(r, -two_prod(k, PIO2_4));
    return df_add(r, vec2<f32>(a.y, 0.0));
}

// sin and cos of the double-float a as (sin hi, sin lo, cos hi, cos lo), to about 1e-14
// absolute for |a| up to a few thousand radians: a = k pi / 2 + r with |r| <= pi / 4 (Cody and
// Waite's reduction in four parts), then the Taylor series of sin r to r^15 and
// of cos r to r^16 (remainders below 5e-17), the terms beyond r^7 summed in f32 (each at most
// 3e-7, so their rounding stays below 1e-13).
fn df_sincos(a: vec2<f32>) -> vec4<f32> {
    let k = round(a.x * TWO_OVER_PI);
    let r = df_minus_pio2s(a, k);
    let r2 = df_mul(r, r);
    let z = r2.x;
    let ts = INV_F9 - z * (INV_F11 - z * (INV_F13 - z * INV_F15));
    var ps = df_add(INV_F7, -df_mul_f(r2, ts));
    ps = df_add(INV_F5, -df_mul(r2, ps));
    ps = df_add(INV_F3, -df_mul(r2, ps));
    let s = df_add(r, -df_mul(r, df_mul(r2, ps)));
    let tc = INV_F10 - z * (INV_F12 - z * (INV_F14 - z * INV_F16));
    var pc = df_add(INV_F8, -df_mul_f(r2, tc));
    pc = df_add(INV_F6, -df_mul(r2, pc));
    pc = df_add(INV_F4, -df_mul(r2, pc));
    let c = df_add(df_add(vec2<f32>(1.0, 0.0), -df_mul_f(r2, 0.5)), df_mul(df_mul(r2, r2), pc));
    let q = ((i32(k) % 4) + 4) % 4;
    switch (q) {
        case 1: { return vec4<f32>(c, -s); }
        case 2: { return vec4<f32>(-s, -c); }
        case 3: { return vec4<f32>(-c, s); }
        default: { return vec4<f32>(s, c); }
    }
}

// Rust's f64::round (half away from zero) of a double-float's value, as an f32 (for whole
// numbers below 2^24).
fn df_round_away(a: vec2<f32>) -> f32 {
    let r = trunc(a.x);
    let f = df_add(a, vec2<f32>(-r, 0.0));
    if (f.x > 0.5 || (f.x == 0.5 && f.y >= 0.0)) {
        return r + 1.0;
    }
    if (f.x < -0.5 || (f.x == -0.5 && f.y <= 0.0)) {
        return r - 1.0;
    }
    return r;
}

// lod_policy::wrap_angle_f64 in double-float: a - 2 pi round(a / (2 pi)), moved into (-pi, pi].
fn df_wrap_angle(a: vec2<f32>) -> vec2<f32> {
    let q = df_round_away(df_div(a, DF_TAU));
    var w = df_minus_pio2s(a, 4.0 * q);
    let v = df_add(w, DF_PI);
    if (v.x < 0.0 || (v.x == 0.0 && v.y <= 0.0)) {
        w = df_add(w, DF_TAU);
    }
    return w;
}

// ---------------------------------------------------------------------------------------------
// Single precision, within a few ulps on any WGSL implementation (WGSL's own `sin`, `cos` and
// `atan2` may err by 2^-11 absolute and 4096 ulps).

// (sin x, cos x) to about one unit in the last place wherever the shaders run. WGSL lets `sin`
// and `cos` err by 2^-11 absolute, and SwiftShader's WebGPU does: its joints came out millimetres
// away from lavapipe's. Cody-Waite reduction by pi/2 (in three parts), then Cephes' sinf and cosf
// polynomials on [-pi/4, pi/4].
fn sincos_f32(x: f32) -> vec2<f32> {
    let q = round(x * 0.636619772);
    let r = ((x - q * 1.5703125) - q * 4.837512969970703e-4) - q * 7.549789954891882e-8;
    let z = r * r;
    let s = r + r * z * (-1.6666654611e-1 + z * (8.3321608736e-3 + z * -1.9515295891e-4));
    let c = 1.0 - 0.5 * z
        + z * z * (4.166664568298827e-2 + z * (-1.388731625493765e-3 + z * 2.443315711809948e-5));
    let k = ((i32(q) % 4) + 4) % 4;
    switch (k) {
        case 0: { return vec2<f32>(s, c); }
        case 1: { return vec2<f32>(c, -s); }
        case 2: { return vec2<f32>(-s, -c); }
        default: { return vec2<f32>(-c, s); }
    }
}

// atan2(y, x) to two or three ulps wherever the shaders run (WGSL lets `atan2` err by 4096 ulps):
// Cephes' atanf polynomial on min / max of |x| and |y| reduced below tan(pi/8), then the octant.
// Not both zero (the caller's).
fn atan2_f32(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    var t = min(ax, ay) / max(ax, ay);
    var r0 = 0.0;
    if (t > 0.41421356) {
        r0 = 0.78539816;
        t = (t - 1.0) / (t + 1.0);
    }
    let z = t * t;
    var r = r0
        + ((((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z
            - 3.33329491539e-1) * z * t + t);
    if (ay > ax) {
        r = 1.5707964 - r;
    }
    if (x < 0.0) {
        r = 3.1415927 - r;
    }
    if (y < 0.0) {
        r = -r;
    }
    return r;
}
