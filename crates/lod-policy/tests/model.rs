//! Shape and value validation, serde round trip and storage accounting.
// Index loops mirror the formulas' subscripts.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use lod_policy::{
    ClipKernel, Detail, KernelScratch, LevelError, LodModel, ModelError, Precision, Ranks,
};

fn parts() -> lod_policy::ModelParts {
    build_model(&random_truth(21, 0.01)).into_parts()
}

fn err(p: lod_policy::ModelParts) -> ModelError {
    LodModel::new(p).expect_err("invalid parts were accepted")
}

#[test]
fn valid_parts_are_accepted() {
    let model = LodModel::new(parts()).unwrap();
    assert_eq!((model.p(), model.t(), model.s(), model.d()), (P, T, S, D));
    assert_eq!(model.joints(), JOINTS);
    assert_eq!(model.max_ranks(), Ranks::new(6, 5, 8));
    assert_eq!(model.active_rows(2), 13);
    assert_eq!(model.active_rows(99), P);
}

#[test]
fn wrong_lengths_name_the_array_and_key() {
    let mut p = parts();
    p.keys[1].core.pop();
    match err(p) {
        ModelError::Length {
            what,
            expected,
            found,
        } => {
            assert_eq!(what, "key 1 core");
            assert_eq!((expected, found), (4 * 4 * 5, 4 * 4 * 5 - 1));
        }
        e => panic!("unexpected {e:?}"),
    }
    let mut p = parts();
    p.keys[0].projection.push(0.0);
    assert!(matches!(err(p), ModelError::Length { what, .. } if what == "key 0 projection"));
    let mut p = parts();
    p.mean_pose.truncate(3);
    assert!(matches!(err(p), ModelError::Length { what, .. } if what == "mean_pose"));
    let mut p = parts();
    p.controls.samples.pop();
    assert!(matches!(err(p), ModelError::Length { what, .. } if what == "controls samples"));
}

#[test]
fn non_finite_values_are_located() {
    let mut p = parts();
    p.keys[0].u_t[7] = f32::NAN;
    assert_eq!(
        err(p),
        ModelError::NonFinite {
            what: "key 0 u_t".into(),
            index: 7
        }
    );
    let mut p = parts();
    p.keys[1].trend[2] = f32::INFINITY;
    assert_eq!(
        err(p),
        ModelError::NonFinite {
            what: "key 1 trend".into(),
            index: 2
        }
    );
    let mut p = parts();
    p.controls.offset[1] = f32::NAN;
    assert_eq!(
        err(p),
        ModelError::NonFinite {
            what: "controls offset".into(),
            index: 1
        }
    );
}

#[test]
fn ranks_and_levels_are_checked() {
    let mut p = parts();
    p.levels[1].ranks.t = 6; // key 0 has R_T = 5
    assert_eq!(
        err(p),
        ModelError::Rank {
            what: "level 1 r_T".into(),
            rank: 6,
            limit: 5
        }
    );
    let mut p = parts();
    p.levels[3].key = 2;
    assert_eq!(
        err(p),
        ModelError::KeyIndex {
            level: 3,
            key: 2,
            keys: 2
        }
    );
    let mut p = parts();
    p.levels[0].ranks.s = 0;
    assert!(matches!(err(p), ModelError::ZeroSize { .. }));
    let mut p = parts();
    p.keys[0].ranks.p = P + 1;
    assert!(matches!(err(p), ModelError::Rank { what, .. } if what == "key 0 R_P"));
    let mut p = parts();
    p.levels.clear();
    assert!(matches!(err(p), ModelError::ZeroSize { .. }));
    let mut p = parts();
    p.keys.clear();
    assert!(matches!(err(p), ModelError::ZeroSize { .. }));
}

#[test]
fn layout_controls_and_tables_are_checked() {
    let mut p = parts();
    p.always_rows = 6;
    assert!(matches!(err(p), ModelError::RowLayout(_)));
    let mut p = parts();
    p.always_rows = 8; // P - 8 = 11 is not a multiple of 3
    assert!(matches!(err(p), ModelError::RowLayout(_)));
    let mut p = parts();
    p.p = 0;
    assert!(matches!(err(p), ModelError::ZeroSize { what } if what == "P"));
    let mut p = parts();
    p.controls.min[0] = p.controls.max[0] + 1.0;
    assert!(matches!(err(p), ModelError::Controls(_)));
    let mut p = parts();
    p.controls.scale[1] = -1.0;
    assert!(matches!(err(p), ModelError::Controls(_)));
    let mut p = parts();
    p.level_errors.pop();
    assert!(matches!(err(p), ModelError::ErrorTable(_)));
    let mut p = parts();
    p.joint_errors[0].shell_cm = -1.0;
    assert!(matches!(err(p), ModelError::ErrorTable(_)));
    // Empty tables mean "not measured" and are fine.
    let mut p = parts();
    p.level_errors.clear();
    p.joint_errors.clear();
    let mut model = LodModel::new(p).unwrap();
    assert!(
        model
            .set_errors(vec![LevelError::default(); 3], vec![])
            .is_err()
    );
    model
        .set_errors(vec![LevelError::default(); 4], vec![])
        .unwrap();
    assert_eq!(model.level_errors().len(), 4);
}

#[test]
fn serde_round_trip_keeps_model_and_poses() {
    let model = build_model(&random_truth(22, 0.01));
    let cfg = bincode::config::standard();
    let bytes = bincode::serde::encode_to_vec(&model, cfg).unwrap();
    let (back, used): (LodModel, usize) = bincode::serde::decode_from_slice(&bytes, cfg).unwrap();
    assert_eq!(used, bytes.len());
    assert_eq!(back, model);
    let pose = |m: &LodModel| {
        let mut scratch = KernelScratch::new(m);
        let mut kernel = ClipKernel::new(m);
        m.build_kernel_values(&[0.2, 1.4], Detail::new(1, 3), &mut scratch, &mut kernel)
            .unwrap();
        let mut out = vec![0.0; m.p()];
        m.pose(&kernel, 4.5, &mut out).unwrap();
        out.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    };
    assert_eq!(pose(&model), pose(&back));
}

#[test]
fn deserialising_invalid_parts_is_an_error_not_a_panic() {
    let cfg = bincode::config::standard();
    let mut p = parts();
    p.keys[0].u_p.pop();
    // Serialise the raw (invalid) parts, then read them back as a model.
    let bytes = bincode::serde::encode_to_vec(&p, cfg).unwrap();
    let res: Result<(LodModel, usize), _> = bincode::serde::decode_from_slice(&bytes, cfg);
    let msg = res.expect_err("invalid model decoded").to_string();
    assert!(msg.contains("key 0 u_p"), "message: {msg}");
    // Truncated input.
    let good = bincode::serde::encode_to_vec(build_model(&random_truth(23, 0.0)), cfg).unwrap();
    let res: Result<(LodModel, usize), _> =
        bincode::serde::decode_from_slice(&good[..good.len() / 2], cfg);
    assert!(res.is_err());
}

#[test]
fn storage_accounting_counts_every_array() {
    let model = build_model(&random_truth(24, 0.0));
    let mut values = 0usize;
    for k in model.keys() {
        let r = k.ranks;
        values += r.core_len() + P * r.p + T * r.t + r.s * (S + 1) + r.s * (D + 1);
    }
    let key_values = values;
    // Samples, offset/scale/min/max, the controls' kriging rows (stored once), mean pose.
    values += S * D + 4 * D + (D + 1) * (S + 1) + P;
    values += model.controls().implied.len(); // implied controls of a dropped turn
    values += 3 * (4 + JOINTS + 1); // error tables: 3 values per level and joint count
    let level_table = 4 * 4 * 4; // four u32 per level
    assert_eq!(model.bytes(Precision::F32), 4 * values + level_table);
    assert_eq!(model.bytes(Precision::F64), 8 * values + level_table);
    let keys_f32: usize = (0..2).map(|k| model.key_bytes(k, Precision::F32)).sum();
    assert_eq!(keys_f32, 4 * key_values);
}

#[test]
fn non_positive_time_scale_is_rejected() {
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut p = parts();
        p.time_scale = bad;
        assert!(
            matches!(err(p), ModelError::NonFinite { what, .. } if what.starts_with("time_scale"))
        );
    }
}
