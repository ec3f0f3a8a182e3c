//! `motion-lod crowd --gpu`: the crowd on the GPU (crate `gpu-crowd`), timed frame by frame.
//! Compiled in with the feature `gpu`; without it, `--gpu` says how to build with it.

use super::crowd::CrowdArgs;

/// Runs `crowd --gpu` (see [`CrowdArgs::gpu`]).
#[cfg(not(feature = "gpu"))]
pub fn run(_args: &CrowdArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "--gpu: this motion-lod was built without the GPU crowd; build it with the feature `gpu`: \
         cargo run --release -p motion-lod --features gpu -- crowd MODEL --gpu"
    )
}

/// Runs `crowd --gpu` (see [`CrowdArgs::gpu`]).
#[cfg(feature = "gpu")]
pub fn run(args: &CrowdArgs) -> anyhow::Result<()> {
    use anyhow::Context as _;
    use crowd_sim::render::{Recorder, RenderStyle};
    use crowd_sim::{CrowdConfig, Scene};
    use gpu_crowd::{Gpu, GpuCrowd, GpuOptions, Preview};
    use lod_policy::{DistancePolicy, FullDetail, LevelPolicy, ScreenSpacePolicy};

    use super::crowd::PolicyArg;

    // The adapter first: a machine without one fails at once, before the model is built.
    let gpu = Gpu::new().context("crowd --gpu")?;
    let (model, _) = super::crowd::model_and_analysis(args.model.as_ref(), false, args.json)?;
    let config = CrowdConfig {
        seed: args.seed,
        fps: args.fps,
        // Seams and the foot lock as the CPU crowd's (its defaults: at every level).
        style: super::crowd::crowd_style(&model, args.style.as_deref())?,
        // A crowd that is watched starts mid-stride (the CPU crowd's `prime`): every walker
        // takes its detail at the first frame instead of over its first cycle.
        spread_first_builds: args.render.is_none(),
        ..CrowdConfig::with_density(args.walkers, args.density)
    };
    let lod = model.lod();
    let policy: Box<dyn LevelPolicy + Sync> = if args.no_lod {
        Box::new(FullDetail::for_model(lod))
    } else {
        match args.policy {
            PolicyArg::Distance => Box::new(DistancePolicy::for_model(lod)),
            PolicyArg::Screen => {
                Box::new(ScreenSpacePolicy::for_model(lod).context("screen-space policy")?)
            }
        }
    };
    let started = std::time::Instant::now();
    let options = GpuOptions {
        joint_slots: args.joint_slots.map(|s| s.of(args.walkers)),
        ..GpuOptions::default()
    };
    let mut crowd =
        GpuCrowd::new(&gpu, model.runtime(), config, options).context("starting the GPU crowd")?;
    let slots = options.joint_slots.unwrap_or(args.walkers);
    let setup = started.elapsed();
    let field = crowd.config().field_size_m;
    let scene: Scene = args.camera.into();
    let lens = scene.lens(super::crowd::view_lens(), field);
    let path = scene.path(field);
    let frames = ((args.seconds * args.fps).round() as usize).max(1);
    let dt = 1.0 / args.fps;
    // `--render`: frames drawn on the GPU from the crowd's buffers, written as the CPU crowd's.
    let mut render = match &args.render {
        Some(dir) => {
            let style = RenderStyle {
                gif_every: 1,
                ..RenderStyle::default()
            };
            let bones = crowd_sim::ClipSource::bones(&motion_lod::LodSource::new(&model)).to_vec();
            let preview = Preview::new(
                &crowd,
                &bones,
                lod.levels().len(),
                &style,
                lens.image_width,
                lens.image_height,
            )
            .context("--render on the GPU")?;
            let recorder = Recorder::new(dir, style)
                .with_context(|| format!("render folder {}", dir.display()))?;
            Some((preview, recorder))
        }
        None => None,
    };
    let mut times = Vec::with_capacity(frames);
    let mut last = None;
    let mut rendered = 0;
    for f in 0..frames {
        let camera = path.camera_at(f as f32 * dt, &lens);
        let stats = crowd.step(policy.as_ref(), &camera, dt)?;
        times.push(stats.wall.as_secs_f64() * 1e3);
        last = Some(stats);
        if let Some((preview, recorder)) = render.as_mut()
            && f % args.render_every.max(1) == 0
        {
            let img = preview.render(&crowd, &camera)?;
            recorder.record_image(img)?;
            rendered += 1;
        }
    }
    let finished = match render {
        Some((_, recorder)) => Some(recorder.finish()?),
        None => None,
    };
    let last = last.expect("at least one frame");
    let warmup = ((f64::from(args.fps)).round() as usize).min(frames.saturating_sub(1));
    let mut after: Vec<f64> = times[warmup..].to_vec();
    after.sort_by(f64::total_cmp);
    let pct = |q: f64| after[((after.len() - 1) as f64 * q).round() as usize];
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    if args.json {
        out!(
            "{{\"gpu\":{:?},\"walkers\":{},\"frames\":{},\"ms_mean\":{mean:.4},\"ms_p50\":{:.4},\"ms_p99\":{:.4},\"ms_worst\":{:.4},\"gpu_bytes\":{},\"joint_slots\":{slots},\"slot_faults\":{},\"levels\":{:?}}}",
            crowd.adapter_name(),
            args.walkers,
            frames,
            pct(0.5),
            pct(0.99),
            after.last().copied().unwrap_or(0.0),
            crowd.gpu_bytes(),
            last.slot_faults,
            last.level_histogram
        );
        return Ok(());
    }
    out!(
        "{} walkers on the GPU ({}), {} s at {} fps ({frames} frames), field {field:.0} m, {} policy",
        args.walkers,
        crowd.adapter_name(),
        args.seconds,
        args.fps,
        args.policy_name()
    );
    if gpu.is_software() {
        out!("note: a software adapter (it runs on the CPU): its timings say nothing about a GPU");
    }
    out!("seams inertialized and feet locked as the CPU crowd's");
    out!(
        "set-up {:.0} ms (walkers placed, first clips built); GPU memory {:.1} MB ({:.0} bytes a walker)",
        setup.as_secs_f64() * 1e3,
        crowd.gpu_bytes() as f64 / 1e6,
        crowd.gpu_bytes() as f64 / args.walkers as f64
    );
    out!(
        "frame times (step: upload, compute, read-back of the counters) after the first {warmup} frames: \
         median {:.2} ms, p99 {:.2} ms, worst {:.2} ms; mean over all frames {mean:.2} ms ({:.1} fps)",
        pct(0.5),
        pct(0.99),
        after.last().copied().unwrap_or(0.0),
        1e3 / mean.max(1e-9)
    );
    out!(
        "last frame: {} in view, {} clips built; levels (accuracy 0.., then root only): {:?}",
        last.visible,
        last.kernels_built,
        last.level_histogram
    );
    if slots < args.walkers {
        out!(
            "joint slots: {slots} ({:.1}% of the walkers, nearest in view first); last frame: {} \
             walkers wanting joints shown root only for want of a slot",
            100.0 * slots as f64 / args.walkers as f64,
            last.slot_faults
        );
    }
    if let (Some(dir), Some(done)) = (&args.render, finished) {
        out!(
            "{}",
            super::crowd::rendered_line(
                &format!(
                    "rendered {rendered} frames on the GPU from the crowd's buffers into {}",
                    dir.display()
                ),
                "frame_*.png",
                done.gif.as_deref(),
                done.stale_removed
            )
        );
    }
    Ok(())
}
