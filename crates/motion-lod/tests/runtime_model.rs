//! The runtime reads what the offline pipeline writes: a model built from the embedded data set loads
//! through `lod_policy::RuntimeModel` (the runtime's own section of the file) and gives the same
//! poses and joint positions as the offline `MotionModel` and `PoseLayout`, bit for bit. Damaged
//! files are errors that say what is wrong, never panics.

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use lod_policy::{ClipKernel, Detail, FileError, JointTransform, KernelScratch, RuntimeModel};
use motion_io::PoseLayout;
use motion_lod::model_file::{self, FORMAT_VERSION, HEADER_LEN, SECTION_HEADER_LEN};

use crate::common;

use common::built;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motion-lod-runtime-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn file_bytes() -> Vec<u8> {
    model_file::encode(&built().0, Path::new("m.mlod")).unwrap()
}

/// The f32 forward kinematics of motion-io as it was before the runtime took it over, written out
/// from the layout's public parts (skeleton, template frame, rest rotations, joint rows): the
/// reference the runtime's rig must reproduce bit for bit.
fn reference_fk(layout: &PoseLayout, pose: &[f32], active: usize, out: &mut [(Quat, Vec3)]) {
    let sk = layout.skeleton();
    let starts = sk.channel_starts();
    let template = layout.template_frame();
    let root_pos = Vec3::from_slice(&pose[0..3]);
    let root_rot = motion_io::expmap::exp_to_quat_f32(Vec3::from_slice(&pose[3..6]));
    let ground = Vec3::new(root_pos.x, 0.0, root_pos.z);
    for (j, joint) in sk.joints.iter().enumerate() {
        if j == layout.root() {
            out[j] = (root_rot, root_pos);
        } else if !sk.is_ancestor_or_self(layout.root(), j) {
            out[j] = (Quat::IDENTITY, ground);
        } else {
            let p = joint.parent.unwrap();
            let local = match layout.joint_rows(j) {
                Some(r) if (r.start - 7) / 3 < active => motion_io::expmap::exp_to_quat_f32(
                    Vec3::new(pose[r.start], pose[r.start + 1], pose[r.start + 2]),
                ),
                _ => layout.rest_rotation(j).as_quat(),
            };
            let values = &template[starts[j]..starts[j] + joint.channels.len()];
            let offset =
                (sk.local_transform(j, values).position / layout.units_per_metre()).as_vec3();
            let (pr, pp) = out[p];
            out[j] = (pr * local, pp + pr * offset);
        }
    }
}

#[test]
fn a_built_model_loads_in_the_runtime_with_the_same_poses_and_joints() {
    let (model, _) = built();
    let runtime = RuntimeModel::from_bytes(&file_bytes()).unwrap();
    assert_eq!(runtime.lod(), model.lod());
    assert_eq!(runtime.rig(), model.layout.rig());
    // The feet for the foot lock: the skeleton's ankles and toes, read back from the file.
    let feet = runtime.feet().expect("the embedded data's model has feet");
    assert_eq!(Some(feet), model.feet());
    let name = |j: usize| runtime.rig().joints()[j].name.as_str();
    assert_eq!(
        (name(feet.left.ankle), name(feet.right.ankle)),
        ("Foot_L", "Foot_R")
    );
    // The stature: the first take's performer (1.60 m in the fixtures' controls.csv, measured from
    // the skeleton's chains), and the body scale of each performer height the data hold.
    let stature = runtime
        .stature_m()
        .expect("the embedded data's model has a stature");
    assert_eq!(Some(stature), model.stature_m());
    assert!((stature - 1.60).abs() < 0.03, "stature {stature} m");
    let range = runtime.lod().controls().range().unwrap();
    for height in [range.min.height, 1.75, range.max.height] {
        let c = lod_policy::Controls {
            height,
            ..range.min
        };
        let s = runtime.body_scale(&c);
        assert_eq!(s, model.body_scale(&c));
        assert!((s - height / stature).abs() < 1e-6, "{height} m: scale {s}");
    }
    let mut report = Vec::new();
    motion_lod::info::write_report(&mut report, model).unwrap();
    let report = String::from_utf8(report).unwrap();
    assert!(
        report.contains(&format!("skeleton: stature {stature:.3} m")),
        "{report}"
    );
    assert_eq!(model.runtime(), &runtime);
    let (lod, rig) = (runtime.lod(), runtime.rig());
    assert_eq!(rig.dof(), lod.p());
    assert_eq!(rig.joint_count(), model.layout.skeleton().joints.len());

    let (mut s1, mut k1) = (KernelScratch::new(lod), ClipKernel::new(lod));
    let (mut s2, mut k2) = (
        KernelScratch::new(model.lod()),
        ClipKernel::new(model.lod()),
    );
    let (mut p1, mut p2) = (vec![0.0f32; lod.p()], vec![0.0f32; lod.p()]);
    let nj = rig.joint_count();
    let mut runtime_joints = vec![Vec3::ZERO; nj];
    let mut offline_joints = vec![Vec3::ZERO; nj];
    let mut transforms = vec![JointTransform::default(); nj];
    let mut reference = vec![(Quat::IDENTITY, Vec3::ZERO); nj];
    let levels = lod.levels().len();
    let mut compared = 0;
    for (controls, accuracy, joints) in [
        ([0.0, 1.4, 0.0, 1.7], 0, lod.joints()),
        ([0.1, 1.2, 0.3, 1.7], levels / 2, 9),
        ([-0.2, 0.9, -0.5, 1.6], levels - 1, 3),
        ([0.0, 1.0, 0.0, 1.7], levels - 1, 0),
    ] {
        let controls = lod_policy::Controls::from_array(controls);
        let detail = Detail::new(accuracy, joints);
        lod.build_kernel(&controls, detail, &mut s1, &mut k1)
            .unwrap();
        model
            .lod()
            .build_kernel(&controls, detail, &mut s2, &mut k2)
            .unwrap();
        for f in 0..=12 {
            let seconds = k1.duration() * f64::from(f) / 12.0;
            lod.pose(&k1, k1.phase_at(seconds), &mut p1).unwrap();
            model
                .lod()
                .pose(&k2, k2.phase_at(seconds), &mut p2)
                .unwrap();
            assert_eq!(p1, p2, "pose at {seconds} s, {detail:?}");
            let rows = lod.active_rows(joints);
            // The runtime reads only the evaluated rows; the offline layout the whole pose.
            rig.joint_positions(&p1[..rows], joints, &mut runtime_joints)
                .unwrap();
            model
                .layout
                .joint_positions(&p2, joints, &mut offline_joints);
            rig.joint_transforms(&p1, joints, &mut transforms).unwrap();
            reference_fk(&model.layout, &p1, joints, &mut reference);
            for j in 0..nj {
                let (r, p) = reference[j];
                assert_eq!(runtime_joints[j].to_array(), p.to_array(), "joint {j}");
                assert_eq!(offline_joints[j].to_array(), p.to_array(), "joint {j}");
                assert_eq!(transforms[j].position.to_array(), p.to_array(), "joint {j}");
                assert_eq!(transforms[j].rotation.to_array(), r.to_array(), "joint {j}");
            }
            compared += 1;
        }
    }
    assert_eq!(compared, 52);
}

#[test]
fn the_runtime_loads_a_saved_file_and_names_the_path_of_a_missing_one() {
    let (model, _) = built();
    let path = temp("walk.mlod");
    model.save(&path).unwrap();
    let runtime = RuntimeModel::load(&path).unwrap();
    assert_eq!(runtime.lod(), model.lod());
    let missing = temp("no-such-model.mlod");
    let e = RuntimeModel::load(&missing).unwrap_err();
    assert!(matches!(e, FileError::Io { .. }), "{e}");
    assert!(e.to_string().contains("no-such-model.mlod"), "{e}");
}

#[test]
fn damaged_files_are_clear_errors() {
    let bytes = file_bytes();
    // Truncated: every cut is an error, and a cut in the payload says so.
    for len in (0..bytes.len())
        .step_by(997)
        .chain([1, 23, 24, bytes.len() - 1])
    {
        let e = RuntimeModel::from_bytes(&bytes[..len]).unwrap_err();
        assert!(
            matches!(
                e,
                FileError::TooShort { .. } | FileError::LengthMismatch { .. }
            ),
            "cut at {len}: {e}"
        );
    }
    let e = RuntimeModel::from_bytes(&bytes[..bytes.len() - 7]).unwrap_err();
    assert!(e.to_string().contains("truncated"), "{e}");
    // A flipped payload byte fails the checksum.
    let mut bad = bytes.clone();
    let mid = HEADER_LEN + (bytes.len() - HEADER_LEN) / 2;
    bad[mid] ^= 0x40;
    let e = RuntimeModel::from_bytes(&bad).unwrap_err();
    assert!(matches!(e, FileError::Checksum { .. }), "{e}");
    assert!(e.to_string().contains("corrupted"), "{e}");
    // Another format version asks for a rebuild (older) or names the newer version.
    let mut old = bytes.clone();
    old[8..12].copy_from_slice(&(FORMAT_VERSION - 1).to_le_bytes());
    let e = RuntimeModel::from_bytes(&old).unwrap_err();
    assert!(matches!(e, FileError::OldVersion { .. }), "{e}");
    assert!(e.to_string().contains("rebuild"), "{e}");
    let mut new = bytes.clone();
    new[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    let e = RuntimeModel::from_bytes(&new).unwrap_err();
    assert!(e.to_string().contains("newer"), "{e}");
    // Not a model at all.
    let e = RuntimeModel::from_bytes(b"hello, this is not a model file").unwrap_err();
    assert!(matches!(e, FileError::BadMagic { .. }), "{e}");
    // A payload cut short but framed with a valid checksum: the section table says so.
    let payload = &bytes[HEADER_LEN..];
    for len in [1, 100, payload.len() / 3, payload.len() / 2] {
        let framed = lod_policy::file::frame_payload(&payload[..len]);
        let e = RuntimeModel::from_bytes(&framed).unwrap_err();
        assert!(
            matches!(e, FileError::Section { .. }),
            "payload cut at {len}: {e}"
        );
    }
    // No sections at all: the runtime section is missing.
    let e = RuntimeModel::from_bytes(&lod_policy::file::frame_payload(&[])).unwrap_err();
    assert!(matches!(e, FileError::MissingSection { .. }), "{e}");
    assert!(e.to_string().contains("RTIM"), "{e}");
    // A runtime section cut short behind valid checksums: a decode error naming the section.
    let runtime = RuntimeModel::from_bytes(&bytes).unwrap().section_bytes();
    for len in [0, 1, 100, runtime.len() / 2, runtime.len() - 1] {
        let framed = lod_policy::file::frame(&[RuntimeModel::section(&runtime[..len])]);
        let e = RuntimeModel::from_bytes(&framed).unwrap_err();
        assert!(
            matches!(e, FileError::Decode { .. }),
            "section cut at {len}: {e}"
        );
        assert!(e.to_string().contains("section RTIM"), "{e}");
    }
    // Another version of the runtime section asks for a rebuild.
    let mut section = RuntimeModel::section(&runtime);
    section.version += 1;
    let e = RuntimeModel::from_bytes(&lod_policy::file::frame(&[section])).unwrap_err();
    assert!(matches!(e, FileError::SectionVersion { .. }), "{e}");
    assert!(e.to_string().contains("rebuild"), "{e}");
}

/// The runtime's section alone is a complete model file for the runtime (what an engine or a page
/// ships); the offline reader asks for the report section. The runtime section starts the file,
/// and the runtime skips the report whatever it holds.
#[test]
fn the_runtime_section_alone_plays_and_the_report_is_skipped() {
    let (model, _) = built();
    let bytes = file_bytes();
    let runtime = model.runtime();
    let alone = runtime.to_bytes();
    assert!(alone.len() < bytes.len());
    assert_eq!(&RuntimeModel::from_bytes(&alone).unwrap(), runtime);
    let e = motion_lod::MotionModel::from_bytes(&alone, Path::new("m.mlod")).unwrap_err();
    assert!(
        e.to_string().contains("RPRT") && e.to_string().contains("rebuild"),
        "{e}"
    );
    // The file's first section is the runtime's, byte for byte.
    let section = runtime.section_bytes();
    let start = HEADER_LEN + SECTION_HEADER_LEN;
    assert_eq!(&bytes[HEADER_LEN..HEADER_LEN + 4], b"RTIM");
    assert_eq!(&bytes[start..start + section.len()], &section[..]);
    // A report the runtime cannot decode does not stop it.
    let framed = lod_policy::file::frame(&[
        RuntimeModel::section(&section),
        model_file::report_section(b"not a report"),
    ]);
    assert_eq!(&RuntimeModel::from_bytes(&framed).unwrap(), runtime);
    let e = motion_lod::MotionModel::from_bytes(&framed, Path::new("m.mlod")).unwrap_err();
    assert!(e.to_string().contains("section RPRT"), "{e}");
}

#[test]
fn a_layout_that_does_not_fit_the_model_is_refused() {
    let (model, _) = built();
    // The layout of a model with one joint less: the rows no longer match. The runtime never
    // reads the layout; the offline reader refuses the file.
    let mut other = model.clone();
    let last = *other.layout.joint_order().last().unwrap();
    other.layout = other.layout.clone().freeze_joints(&[last]).unwrap();
    let bytes = model_file::encode(&other, Path::new("m")).unwrap();
    assert_eq!(&RuntimeModel::from_bytes(&bytes).unwrap(), model.runtime());
    let e = motion_lod::MotionModel::from_bytes(&bytes, Path::new("m")).unwrap_err();
    assert!(matches!(e, FileError::Invalid { .. }), "{e}");
    assert!(e.to_string().contains("DOF rows"), "{e}");
    assert!(other.validate().is_err());
}
