//! Clip kernels and poses of a model FILE (`MOTION_LOD_BENCH_MODEL=path.mlod`, for example a model
//! built from the Bandai data with `motion-lod build`): root-only, the last accuracy level and full
//! detail, so the runtime's costs are measured at a real sample count (S = 800 for Bandai) rather
//! than the embedded fixtures'. Without the variable it prints how to set it and measures nothing.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use lod_policy::{ClipKernel, Detail, KernelScratch};
use motion_lod::MotionModel;

fn bench(c: &mut Criterion) {
    let Some(path) = std::env::var_os("MOTION_LOD_BENCH_MODEL").map(PathBuf::from) else {
        eprintln!(
            "model_file: set MOTION_LOD_BENCH_MODEL to a model file (motion-lod build --output \
             FILE DIR) to measure it; nothing measured"
        );
        return;
    };
    let model = MotionModel::load(&path).expect("MOTION_LOD_BENCH_MODEL loads");
    let lod = &model.lod;
    let cs = lod.controls();
    // Controls spread over the data's range (a fixed low-discrepancy walk, so every run is the same).
    let controls: Vec<Vec<f32>> = (0..64)
        .map(|i| {
            (0..lod.d())
                .map(|k| {
                    let u = ((i as f32 + 0.5) * (0.618_034 + 0.1 * k as f32)).fract();
                    cs.min[k] + u * (cs.max[k] - cs.min[k])
                })
                .collect()
        })
        .collect();
    let mut scratch = KernelScratch::new(lod);
    let mut kernel = ClipKernel::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let last = lod.levels().len() - 1;
    let name = path
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().into_owned());
    let mut g = c.benchmark_group(format!("model_file/{name}"));
    for (case, detail) in [
        ("root_only", Detail::root_only()),
        ("last_level_all_joints", Detail::new(last, usize::MAX)),
        ("level0_all_joints", Detail::full()),
    ] {
        let mut i = 0;
        g.bench_function(BenchmarkId::new("build_kernel", case), |b| {
            b.iter(|| {
                i = (i + 1) % controls.len();
                lod.build_kernel(black_box(&controls[i]), detail, &mut scratch, &mut kernel)
                    .unwrap();
                black_box(kernel.duration())
            })
        });
        let mut i = 0;
        g.bench_function(BenchmarkId::new("kriging_weights", case), |b| {
            let level = detail.level_in(lod).unwrap();
            let lv = lod.levels()[level];
            b.iter(|| {
                i = (i + 1) % controls.len();
                let w = lod
                    .kriging_weights(black_box(&controls[i]), lv.key, lv.ranks.s, &mut scratch)
                    .unwrap();
                black_box(w[0])
            })
        });
        lod.build_kernel(&controls[0], detail, &mut scratch, &mut kernel)
            .unwrap();
        let rows = if detail.active_joints == 0 {
            7
        } else {
            lod.p()
        };
        let mut phase = 0.0f32;
        g.bench_function(BenchmarkId::new("pose", case), |b| {
            b.iter(|| {
                phase = (phase + 0.37) % (lod.t() - 1) as f32;
                lod.pose_rows(&kernel, black_box(phase), &mut pose[..rows])
                    .unwrap();
                black_box(pose[0])
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
