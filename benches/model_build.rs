//! The offline build (`MotionModel::build`) on the embedded data set (61 x 135 x 60, ten key levels
//! from (40, 40, 60) down to (7, 7, 9)), and the clip kernel and pose of the real model built from it at
//! the first and last accuracy levels.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use lod_policy::{ClipKernel, Detail, KernelScratch};
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, MotionModel};

fn build(c: &mut Criterion) {
    let loaded = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("embedded data loads");
    let config = BuildConfig::default();
    let mut group = c.benchmark_group("build");
    group.sample_size(10);
    group.bench_function("embedded fixtures", |b| {
        b.iter(|| MotionModel::build(black_box(&loaded.training), &config, &NoProgress).unwrap())
    });
    group.finish();

    let model = MotionModel::build(&loaded.training, &config, &NoProgress).unwrap();
    let lod = model.lod();
    let controls = lod_policy::Controls::from_array([0.0, 1.3, 0.1, 1.75]);
    let mut scratch = KernelScratch::new(lod);
    let mut kernel = ClipKernel::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let last = lod.levels().len() - 1;
    let mut group = c.benchmark_group("fixture model");
    for (name, detail) in [
        ("first level", lod.full_detail()),
        ("last level", Detail::new(last, lod.joints())),
        ("root only", lod.root_only()),
    ] {
        group.bench_function(format!("kernel, {name}"), |b| {
            b.iter(|| {
                lod.build_kernel(black_box(&controls), detail, &mut scratch, &mut kernel)
                    .unwrap()
            })
        });
        lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)
            .unwrap();
        group.bench_function(format!("pose, {name}"), |b| {
            b.iter(|| lod.pose(&kernel, black_box(37.5), &mut pose).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
