//! Every misuse of the C ABI is a status code with a message naming what was wrong, never a crash.

use std::ffi::CStr;
use std::ptr::{null, null_mut};

use motion_lod_ffi::*;

fn message() -> String {
    // SAFETY: mlod_last_error returns a valid NUL-terminated string for this thread.
    unsafe { CStr::from_ptr(mlod_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// The model bytes of a model built from the checkout's fixtures (small settings).
fn model_bytes() -> Vec<u8> {
    use motion_lod::BuildConfig;
    use motion_lod::dataset::DataSpec;
    let spec = DataSpec {
        samples: Some(12),
        ..DataSpec::default()
    };
    let data = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("fixtures load");
    let config = BuildConfig {
        key_levels: 3,
        accuracy_levels: 4,
        ..BuildConfig::default()
    };
    let model =
        motion_lod::MotionModel::build(&data.training, &config, &motion_lod::progress::NoProgress)
            .expect("builds");
    motion_lod::model_file::encode(&model, std::path::Path::new("m")).expect("encodes")
}

#[test]
fn misuse_is_a_status_with_a_message() {
    let bytes = model_bytes();
    unsafe {
        let mut model: *mut MlodModel = null_mut();
        assert_eq!(
            mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model),
            MlodStatus::Ok
        );
        assert!(!model.is_null());
        assert_eq!(message(), "");

        // Null pointers.
        assert_eq!(
            mlod_model_from_bytes(null(), 10, &mut model as *mut _),
            MlodStatus::NullPointer
        );
        assert!(model.is_null(), "the output is cleared on failure");
        assert!(message().contains("bytes is null"), "{}", message());
        assert_eq!(
            mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model),
            MlodStatus::Ok
        );
        assert_eq!(
            mlod_model_sizes(null(), null_mut(), null_mut(), null_mut(), null_mut()),
            MlodStatus::NullPointer
        );

        // Damaged bytes: every truncation is refused.
        for cut in [0, 10, 24, bytes.len() / 2, bytes.len() - 1] {
            let mut other: *mut MlodModel = null_mut();
            assert_eq!(
                mlod_model_from_bytes(bytes.as_ptr(), cut, &mut other),
                MlodStatus::InvalidModel,
                "cut at {cut}"
            );
            assert!(other.is_null());
        }
        let path = c"/no/such/model.mlod";
        let mut other: *mut MlodModel = null_mut();
        assert_eq!(mlod_model_load(path.as_ptr(), &mut other), MlodStatus::Io);
        assert!(message().contains("/no/such/model.mlod"), "{}", message());

        let (mut levels, mut joints, mut animated, mut pose_len) = (0, 0, 0, 0);
        assert_eq!(
            mlod_model_sizes(
                model,
                &mut levels,
                &mut joints,
                &mut animated,
                &mut pose_len
            ),
            MlodStatus::Ok
        );
        assert_eq!(pose_len, 7 + 3 * animated);
        assert!(levels >= 3 && joints > animated && animated > 0);

        // Joint names: truncated to the buffer, length reported, out of range refused.
        let mut name = [0 as std::ffi::c_char; 4];
        let (mut len, mut parent) = (0usize, 0i32);
        assert_eq!(
            mlod_model_joint(model, 1, name.as_mut_ptr(), 4, &mut len, &mut parent),
            MlodStatus::Ok
        );
        assert_eq!(CStr::from_ptr(name.as_ptr()).to_bytes().len(), len.min(3));
        assert!(parent >= 0);
        assert_eq!(
            mlod_model_joint(model, joints, null_mut(), 0, null_mut(), null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("out of range"), "{}", message());

        // A walker: not prepared, bad controls and levels, short buffers, another model.
        let mut walker: *mut MlodWalker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        let mut pose = vec![0.0f32; pose_len];
        assert_eq!(
            mlod_walker_pose(walker, model, 0.0, pose.as_mut_ptr(), pose.len()),
            MlodStatus::NotPrepared
        );
        let mut lo = MlodControls::default();
        let mut hi = MlodControls::default();
        assert_eq!(
            mlod_model_control_range(model, &mut lo, &mut hi),
            MlodStatus::Ok
        );
        let nan = MlodControls {
            turn: f32::NAN,
            ..lo
        };
        let detail = MlodDetail {
            level: 0,
            joints: animated as u32,
        };
        assert_eq!(
            mlod_walker_prepare(walker, model, &nan, detail, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("turn"), "{}", message());
        let far = MlodDetail {
            level: levels as u32,
            joints: 0,
        };
        assert_eq!(
            mlod_walker_prepare(walker, model, &lo, far, null_mut()),
            MlodStatus::InvalidArgument
        );
        let mut cycle = MlodCycle::default();
        assert_eq!(
            mlod_walker_prepare(walker, model, &hi, detail, &mut cycle),
            MlodStatus::Ok
        );
        assert!(cycle.duration_s > 0.3 && cycle.dz > 0.5, "{cycle:?}");
        assert_eq!(
            mlod_walker_pose(walker, model, f64::NAN, pose.as_mut_ptr(), pose.len()),
            MlodStatus::InvalidArgument
        );
        assert_eq!(
            mlod_walker_pose(walker, model, 0.1, pose.as_mut_ptr(), pose.len() - 1),
            MlodStatus::BufferTooSmall
        );
        assert!(
            message().contains(&format!("{pose_len} are needed")),
            "{}",
            message()
        );
        assert_eq!(
            mlod_walker_pose(walker, model, 0.1, pose.as_mut_ptr(), pose.len()),
            MlodStatus::Ok
        );
        assert!(pose.iter().all(|v| v.is_finite()));
        let mut transforms = vec![MlodJointTransform::default(); joints];
        assert_eq!(
            mlod_walker_joint_transforms(walker, model, transforms.as_mut_ptr(), joints - 1),
            MlodStatus::BufferTooSmall
        );
        assert_eq!(
            mlod_walker_joint_transforms(walker, model, transforms.as_mut_ptr(), joints),
            MlodStatus::Ok
        );
        let q = transforms[1].rotation;
        let norm = q.iter().map(|v| v * v).sum::<f32>().sqrt();
        assert!((norm - 1.0).abs() < 1e-4, "unit rotations: {q:?}");

        let mut second: *mut MlodModel = null_mut();
        assert_eq!(
            mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut second),
            MlodStatus::Ok
        );
        assert_eq!(
            mlod_walker_prepare(walker, second, &lo, detail, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("another model"), "{}", message());

        // The policy: near is full detail, far is root only; a bad distance is refused.
        let mut near = MlodDetail::default();
        let mut distant = MlodDetail::default();
        assert_eq!(mlod_model_detail_at(model, 2.0, &mut near), MlodStatus::Ok);
        assert_eq!(
            mlod_model_detail_at(model, 1e5, &mut distant),
            MlodStatus::Ok
        );
        assert_eq!(near.level, 0);
        assert!(distant.joints < near.joints, "{near:?} {distant:?}");
        assert_eq!(
            mlod_model_detail_at(model, -1.0, &mut near),
            MlodStatus::InvalidArgument
        );

        mlod_walker_free(walker);
        mlod_walker_free(null_mut());
        mlod_model_free(second);
        mlod_model_free(model);
        mlod_model_free(null_mut());
    }
}
