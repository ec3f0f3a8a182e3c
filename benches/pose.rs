//! Runtime pose synthesis (lod-policy): clip-kernel build and per-frame pose at the first and last
//! accuracy levels, on a random model of the paper's size (P = 94, T = 100, S = 186, d = 3,
//! ranks 40 x 40 x 60 down to 7 x 7 x 9).

use criterion::{Criterion, criterion_group, criterion_main};
use lod_policy::{AccuracyLevel, KeyTensor, ModelParts, Ranks};
use lod_policy::{ClipKernel, Detail, KernelScratch, LodModel, Variogram, VariogramModel};
use std::hint::black_box;

const P: usize = 94;
const T: usize = 100;
const S: usize = 186;
const D: usize = 3;

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
    fn vec(&mut self, n: usize, scale: f32) -> Vec<f32> {
        (0..n).map(|_| scale * self.next()).collect()
    }
}

fn paper_model() -> LodModel {
    let mut rng = Lcg(7);
    let key = |rng: &mut Lcg, r: Ranks| KeyTensor {
        ranks: r,
        core: rng.vec(r.core_len(), 1.0),
        u_p: rng.vec(P * r.p, 0.2),
        u_t: rng.vec(T * r.t, 0.2),
        projection: rng.vec(r.s * (S + 1), 0.1),
        trend: rng.vec(r.s * (D + 1), 0.1),
    };
    let (big, small) = (Ranks::new(40, 40, 60), Ranks::new(7, 7, 9));
    let keys = vec![key(&mut rng, big), key(&mut rng, small)];
    let levels = vec![
        AccuracyLevel { key: 0, ranks: big },
        AccuracyLevel {
            key: 1,
            ranks: small,
        },
    ];
    let raw = rng.vec(S * D, 1.0);
    let variogram = Variogram::new(VariogramModel::Exponential, 0.05, 1.0, 1.5, 1.0).unwrap();
    let mut controls =
        motion_lod::projection::control_space(variogram, &raw, S, vec![0.0; D], vec![1.0; D])
            .unwrap();
    controls.projection = rng.vec((D + 1) * (S + 1), 0.1);
    LodModel::new(ModelParts {
        p: P,
        t: T,
        s: S,
        d: D,
        always_rows: 7,
        rows_per_joint: 3,
        keys,
        levels,
        controls,
        time_scale: 1.0,
        mean_pose: vec![0.0; P],
        level_errors: vec![],
        joint_errors: vec![],
    })
    .unwrap()
}

fn bench_pose(c: &mut Criterion) {
    let model = paper_model();
    let mut scratch = KernelScratch::new(&model);
    let mut kernel = ClipKernel::new(&model);
    let mut out = vec![0.0f32; P];
    let controls = [0.1f32, -0.3, 0.2];
    let cases = [
        ("first_level_all_joints", Detail::new(0, model.joints())),
        ("last_level_all_joints", Detail::new(1, model.joints())),
        ("root_only", model.root_only()),
    ];
    let mut group = c.benchmark_group("pose");
    for (name, detail) in cases {
        group.bench_function(format!("build_kernel/{name}"), |b| {
            b.iter(|| {
                model
                    .build_kernel_values(black_box(&controls), detail, &mut scratch, &mut kernel)
                    .unwrap();
            })
        });
        model
            .build_kernel_values(&controls, detail, &mut scratch, &mut kernel)
            .unwrap();
        let mut phase = 0.0f32;
        group.bench_function(format!("pose/{name}"), |b| {
            b.iter(|| {
                phase = (phase + 0.37) % (T - 1) as f32;
                model.pose(&kernel, black_box(phase), &mut out).unwrap();
                black_box(&out);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_pose);
criterion_main!(benches);
