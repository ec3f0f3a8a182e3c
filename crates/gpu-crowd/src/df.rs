//! The shaders' double-float library (`shaders/df.wgsl`, with the single-precision `sincos_f32` and
//! `atan2_f32` that do not lean on WGSL's loose `sin`, `cos` and `atan2`), placed before the crowd
//! shaders, and its check against the CPU's f64 and f32 functions on whatever adapter there is.

/// Double-float arithmetic, sine and cosine, and angle wrapping in WGSL (no host constants).
pub(crate) const DF_WGSL: &str = include_str!("shaders/df.wgsl");

#[cfg(test)]
mod tests {
    use super::DF_WGSL;
    use crate::Gpu;
    use lod_policy::{SplitMix64, wrap_angle_f64};
    use wgpu::util::DeviceExt;

    /// What every test kernel binds: double-float arguments, four `vec4` of results per argument,
    /// and the zero `df_zero()` reads.
    const BINDINGS: &str = r#"
@group(0) @binding(0) var<storage, read> args: array<vec2<f32>>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(2) var<uniform> zero: vec4<u32>;

fn df_zero() -> u32 {
    return zero.x;
}
"#;

    /// For each argument `a` (and `b`, another argument): `df_sincos(a)`, `df_wrap_angle(a)`,
    /// `df_sqrt(|a|)`, `df_exp(a / 4)`, `df_log(|a|)`, `df_mul(a, b)` and `df_div(a, b)`.
    const KERNEL: &str = r#"
@compute @workgroup_size(64)
fn check(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&args)) {
        return;
    }
    let a = args[i];
    let b = args[(i * 7919u + 1u) % arrayLength(&args)];
    let m = select(a, -a, a.x < 0.0);
    out[4u * i] = df_sincos(a);
    out[4u * i + 1u] = vec4<f32>(df_wrap_angle(a), df_sqrt(m));
    out[4u * i + 2u] = vec4<f32>(df_exp(df_mul_f(a, 0.25)), df_log(m));
    out[4u * i + 3u] = vec4<f32>(df_mul(a, b), df_div(a, b));
}
"#;

    /// Runs `kernel` (entry point `check`, after the library and [`BINDINGS`]) over `args`
    /// (hi, lo) and returns its 16 floats for each argument.
    fn run_kernel(gpu: &Gpu, kernel: &str, args: &[[f32; 2]]) -> Vec<[f32; 16]> {
        let device = &gpu.device;
        let source = format!("{DF_WGSL}\n{BINDINGS}\n{kernel}");
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("df check"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("df check"),
            layout: None,
            module: &module,
            entry_point: Some("check"),
            compilation_options: Default::default(),
            cache: None,
        });
        let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("args"),
            contents: bytemuck::cast_slice(args),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let size = (args.len() * 64) as u64;
        let output = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("out"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read-back"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let zero = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("zero"),
            contents: bytemuck::cast_slice(&[0u32; 4]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("df check"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: input.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: output.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: zero.as_entire_binding(),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(args.len().div_ceil(64) as u32, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&output, 0, &staging, 0, size);
        gpu.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |r| r.expect("map"));
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("poll");
        let floats: Vec<f32> = bytemuck::cast_slice(&slice.get_mapped_range()).to_vec();
        floats
            .chunks_exact(16)
            .map(|c| c.try_into().expect("16"))
            .collect()
    }

    /// The kernel of [`composed_double_float_expressions_keep_their_error_terms`]: per case
    /// `(a, b)`, `x`, `y`, `theta` (four arguments), the closest-point search's
    /// `g = (b^2 - a^2) sin cos + a x sin - b y cos` at `theta`, as `crowd.wgsl` computes it.
    const G_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn check(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = 4u * gid.x;
    if (i + 3u >= arrayLength(&args)) {
        return;
    }
    let a = args[i].x;
    let b = args[i].y;
    let x = args[i + 1u];
    let y = args[i + 2u];
    let sc = df_sincos(args[i + 3u]);
    let k = df_add(two_prod(b, b), -two_prod(a, a));
    let g = df_add(df_add(df_mul(df_mul(k, sc.xy), sc.zw), df_mul(df_mul_f(x, a), sc.xy)),
        -df_mul(df_mul_f(y, b), sc.zw));
    out[4u * gid.x] = vec4<f32>(g, 0.0, 0.0);
}
"#;

    /// Sums of products that cancel, inside one shader: where the closest-point search's
    /// Newton step stalled at 3e-8 rad because Mesa's compiler had folded `two_sum`'s error term
    /// to zero in this context (and not in the simpler kernel above) before `keep` was added. At
    /// the f64 root of `g` for 2,000 walkers' ellipses and places, `g` must come out within
    /// 1e-13 of the size of its terms (f32 gives 1e-7).
    #[test]
    fn composed_double_float_expressions_keep_their_error_terms() {
        let Some(gpu) = Gpu::open_or_skip() else {
            return;
        };
        let dfv = |v: f64| {
            let h = v as f32;
            [h, (v - f64::from(h)) as f32]
        };
        let mut g = SplitMix64::new(5);
        let mut args = Vec::new();
        let mut cases = Vec::new();
        for _ in 0..2000 {
            let a = g.uniform(3.0, 40.0) as f32;
            let b = (f64::from(a) * g.uniform(0.5, 1.0)) as f32;
            let (af, bf) = (f64::from(a), f64::from(b));
            let s = g.uniform(-3.0, 3.0);
            let x = af * s.cos() + g.uniform(-1.5, 1.5);
            let y = bf * s.sin() + g.uniform(-1.5, 1.5);
            let k = bf * bf - af * af;
            let mut theta = (af * y).atan2(bf * x);
            for _ in 0..8 {
                let (sn, cs) = theta.sin_cos();
                let gv = k * sn * cs + af * x * sn - bf * y * cs;
                let dg = k * (cs * cs - sn * sn) + af * x * cs + bf * y * sn;
                theta -= gv / dg;
            }
            args.extend([[a, b], dfv(x), dfv(y), dfv(theta)]);
            cases.push((af, bf, x, y, theta));
        }
        let out = run_kernel(&gpu, G_KERNEL, &args);
        let mut worst = 0.0f64;
        for (o, &(a, b, x, y, theta)) in out.iter().zip(&cases) {
            let (sn, cs) = theta.sin_cos();
            let k = b * b - a * a;
            let want = k * sn * cs + a * x * sn - b * y * cs;
            let scale = k.abs() + (a * x).abs() + (b * y).abs();
            let err = (value(o[0], o[1]) - want).abs() / scale;
            worst = worst.max(err);
        }
        println!(
            "g at the root within {worst:.2e} of its terms' size, on {}",
            gpu.adapter_name()
        );
        assert!(
            worst <= 1e-13,
            "g at the root: {worst:e} of its terms' size"
        );
    }

    /// Per argument `(a, b)`: `sincos_f32(a)` and `atan2_f32(a, b)`.
    const F32_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn check(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= arrayLength(&args)) {
        return;
    }
    let a = args[i];
    // (df_zero() binds the uniform every kernel of this module binds.)
    out[4u * i] = vec4<f32>(sincos_f32(a.x), atan2_f32(a.x, a.y), f32(df_zero()));
}
"#;

    /// `sincos_f32` and `atan2_f32` (the rotations of forward kinematics, seams and the foot lock)
    /// within 2 and 3 ulps of f64's values rounded (or 2^-24 and 3 2^-24 where those are below 1
    /// in magnitude: next to the zeros of sine and cosine), for angles up to 16 rad (the crowd's are half-angles of
    /// rotations), next to multiples of pi / 2, and for `atan2` in every octant: what WGSL's own
    /// functions do not promise (2^-11 absolute; 4096 ulps).
    #[test]
    fn single_precision_sine_cosine_and_atan2_are_within_a_few_ulps() {
        let Some(gpu) = Gpu::open_or_skip() else {
            return;
        };
        let mut g = SplitMix64::new(5);
        let mut args: Vec<[f32; 2]> = Vec::new();
        for _ in 0..100_000 {
            args.push([g.uniform(-16.0, 16.0) as f32, g.uniform(-16.0, 16.0) as f32]);
        }
        for _ in 0..20_000 {
            args.push([g.uniform(-1e-3, 1e-3) as f32, g.uniform(-1.0, 1.0) as f32]);
            args.push([g.uniform(-1.0, 1.0) as f32, g.uniform(-1e-3, 1e-3) as f32]);
        }
        for k in -10..=10 {
            let c = (f64::from(k) * std::f64::consts::FRAC_PI_2) as f32;
            let mut x = c;
            for _ in 0..20 {
                args.push([x, if k == 0 { 1.0 } else { c }]);
                x = f32::from_bits(x.to_bits() + 1);
            }
        }
        args.retain(|a| a[0] != 0.0 || a[1] != 0.0);
        let out = run_kernel(&gpu, F32_KERNEL, &args);
        let err = |got: f32, want: f64| {
            let rounded = want as f32;
            if want.abs() < 1.0 {
                ((f64::from(got) - want).abs() / 2f64.powi(-24))
                    .max(0.0)
                    .min(f64::from(ulps(got, rounded)))
            } else {
                f64::from(ulps(got, rounded))
            }
        };
        let (mut worst_sc, mut worst_at) = (0.0f64, 0.0f64);
        for (a, o) in args.iter().zip(&out) {
            let (s, c) = f64::from(a[0]).sin_cos();
            let t = f64::from(a[0]).atan2(f64::from(a[1]));
            let esc = err(o[0], s).max(err(o[1], c));
            let eat = err(o[2], t);
            assert!(
                esc <= 2.0,
                "sincos_f32({}): ({}, {}) against ({s}, {c})",
                a[0],
                o[0],
                o[1]
            );
            assert!(
                eat <= 3.0,
                "atan2_f32({}, {}): {} against {t}",
                a[0],
                a[1],
                o[2]
            );
            worst_sc = worst_sc.max(esc);
            worst_at = worst_at.max(eat);
        }
        println!(
            "{} arguments on {}: sincos_f32 within {worst_sc} and atan2_f32 within {worst_at} ulps \
             (or 2^-24 below 1)",
            args.len(),
            gpu.adapter_name()
        );
    }

    fn value(hi: f32, lo: f32) -> f64 {
        f64::from(hi) + f64::from(lo)
    }

    /// Units in the last place between two f32 of the same sign (0 when equal).
    fn ulps(a: f32, b: f32) -> u32 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs() as u32
    }

    /// `df_sincos` within 2e-14 of f64's sine and cosine, for f32 arguments (the path parameters,
    /// headings and rotations the crowd shaders pass) up to 200 rad, small ones and ones next to
    /// multiples of pi / 2, and for double-float arguments; its high parts the f64 values
    /// rounded to f32 but for at most 1 in 10,000, and within 1 ulp of the CPU's f32 `sin` and
    /// `cos` (glibc's differ from the rounded f64 values in about 1 in 80: why the CPU crowd's
    /// steering uses f64); `df_wrap_angle` as `lod_policy::wrap_angle_f64` within 1e-13 and in
    /// `(-pi, pi]`; and its square root, exponential, logarithm, product and quotient within
    /// 1e-11 of f64's (relative; the logarithm absolute).
    #[test]
    fn double_float_sine_cosine_and_wrap_match_the_cpu() {
        let Some(gpu) = Gpu::open_or_skip() else {
            return;
        };
        let mut g = SplitMix64::new(11);
        let mut args: Vec<[f32; 2]> = Vec::new();
        for _ in 0..100_000 {
            args.push([g.uniform(-200.0, 200.0) as f32, 0.0]);
        }
        for _ in 0..20_000 {
            args.push([g.uniform(-4.0, 4.0) as f32, 0.0]);
            args.push([g.uniform(-1e-3, 1e-3) as f32, 0.0]);
        }
        for k in -100..=100 {
            let c = (f64::from(k) * std::f64::consts::FRAC_PI_2) as f32;
            let mut x = c;
            for _ in 0..20 {
                args.push([x, 0.0]);
                x = f32::from_bits(x.to_bits() + 1);
            }
        }
        let f32_args = args.len();
        for _ in 0..50_000 {
            let x = f64::from(g.uniform(-30.0, 30.0) as f32) + g.uniform(-1.0, 1.0) * 1e-7;
            let hi = x as f32;
            args.push([hi, (x - f64::from(hi)) as f32]);
        }
        let out = run_kernel(&gpu, KERNEL, &args);
        let (mut worst, mut worst_wrap) = (0.0f64, 0.0f64);
        let (mut misrounded, mut off_cpu) = (0usize, 0usize);
        let n = args.len();
        let mut worst_arith = [0.0f64; 5];
        for (k, (a, o)) in args.iter().zip(&out).enumerate() {
            let (sc, wrap) = (&o[0..4], &o[4..6]);
            let x = value(a[0], a[1]);
            let b = args[(k * 7919 + 1) % n];
            let y = value(b[0], b[1]);
            // Relative errors of sqrt, exp, log, the product and the quotient.
            let rel = |got: f64, want: f64| {
                if want == 0.0 {
                    got.abs()
                } else {
                    ((got - want) / want).abs()
                }
            };
            let arith = [
                rel(value(o[6], o[7]), x.abs().sqrt()),
                rel(value(o[8], o[9]), (x * 0.25).exp()),
                if x == 0.0 {
                    0.0
                } else {
                    (value(o[10], o[11]) - x.abs().ln()).abs()
                },
                rel(value(o[12], o[13]), x * y),
                rel(value(o[14], o[15]), x / y),
            ];
            // Not near f32's smallest normal numbers, which GPUs may flush to zero (the
            // arguments next to 0 pi / 2 are subnormal).
            if x.abs() > 1e-30 && y.abs() > 1e-30 {
                for (w, e) in worst_arith.iter_mut().zip(arith) {
                    *w = w.max(e);
                }
            }
            let (s, c) = x.sin_cos();
            let err = (value(sc[0], sc[1]) - s)
                .abs()
                .max((value(sc[2], sc[3]) - c).abs());
            assert!(
                err <= 2e-14,
                "df_sincos({x}): {sc:?} against ({s}, {c}): {err:e}"
            );
            worst = worst.max(err);
            if k < f32_args {
                let (s32, c32) = a[0].sin_cos();
                for (got, rounded, cpu) in [(sc[0], s as f32, s32), (sc[2], c as f32, c32)] {
                    misrounded += usize::from(got != rounded);
                    assert!(
                        ulps(got, cpu) <= 1,
                        "df_sincos({}) rounded: {got} against the CPU's f32 {cpu}",
                        a[0]
                    );
                    off_cpu += usize::from(got != cpu);
                }
            }
            let w = value(wrap[0], wrap[1]);
            let want = wrap_angle_f64(x);
            let werr = (w - want).abs();
            assert!(
                werr <= 1e-13 && w > -std::f64::consts::PI - 1e-13,
                "df_wrap_angle({x}): {w} against {want}"
            );
            worst_wrap = worst_wrap.max(werr);
        }
        let arith = worst_arith.map(|e| format!("{e:.2e}"));
        println!("df_sqrt, df_exp, df_log (absolute), df_mul, df_div: {arith:?} of f64's");
        assert!(
            worst_arith.iter().all(|&e| e <= 1e-11),
            "df_sqrt, df_exp, df_log, df_mul, df_div: {arith:?}"
        );
        println!(
            "{} arguments on {}: df_sincos within {worst:.2e} of f64, df_wrap_angle within \
             {worst_wrap:.2e}; of {} f32 sines and cosines, {misrounded} not the f64 value rounded \
             and {off_cpu} (1 ulp) not the CPU's f32 sin and cos",
            args.len(),
            gpu.adapter_name(),
            2 * f32_args
        );
        assert!(
            misrounded * 10_000 <= 2 * f32_args,
            "{misrounded} of {} f32 sines and cosines are not the f64 values rounded",
            2 * f32_args
        );
    }
}
