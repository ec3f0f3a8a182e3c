//! Issue 33: style as a control.
//!
//! On the embedded data (always present; the three performers `p160`, `p175`, `p190` named in the
//! file names serve as styles): labels from file names, the style section of the model file, the
//! runtime's styles and data mix, the kernel at one style, a blend and the data's mix, refused
//! weights, a crowd of the data's mix, a track of controls over time, and a model without labels
//! that has no style anywhere.
//!
//! On Bandai (seven styles in the file names; skipped with `skipped: ../shared/mocap not found`
//! when the data is absent, failed under `MOTION_LOD_REQUIRE_DATA`): every style and every 50/50
//! blend of two styles, walking straight at its styles' median step, stays within the
//! motion-quality thresholds of its (heaviest) style's own takes, a blend lies
//! between its two styles, and 5-fold cross-validation by take (the whole pipeline refitted on
//! each fold) keeps level 0 at most 3.0 cm.

use std::path::PathBuf;
use std::sync::OnceLock;

use crowd_sim::{Crowd, CrowdConfig, CrowdStyle};
use lod_policy::{
    ClipKernel, Controls, KernelError, KernelScratch, RuntimeModel, StyleMix, file::sections,
};
use motion_lod::dataset::DataSpec;
use motion_lod::eval::{EvalConfig, FoldBy, k_fold};
use motion_lod::model_file::{STYLE_SECTION, encode};
use motion_lod::progress::NoProgress;
use motion_lod::source::LodSource;
use motion_lod::style::StyleSpec;
use motion_lod::synth::WalkRequest;
use motion_lod::{BuildConfig, MotionModel, TrainingSet, walk_quality};

/// The embedded data's performers as styles.
const PERFORMER: &str = r"walk_(p\d+)_";
/// Bandai's styles in its file names (`dataset-2_walk-turn-left_elderly_001.bvh`).
const BANDAI_STYLE: &str = r"_([a-z]+)_\d+\.bvh$";

fn fixture_training() -> TrainingSet {
    DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("fixtures load")
        .training
}

fn small() -> BuildConfig {
    BuildConfig {
        key_levels: 3,
        accuracy_levels: 4,
        ..BuildConfig::default()
    }
}

/// The embedded data built with the performers as styles, once per test binary.
pub(crate) fn styled() -> &'static MotionModel {
    static MODEL: OnceLock<MotionModel> = OnceLock::new();
    MODEL.get_or_init(|| {
        let set = fixture_training()
            .with_styles(Some(&StyleSpec::Name(PERFORMER.into())))
            .expect("labels");
        MotionModel::build(&set, &small(), &NoProgress).expect("builds")
    })
}

fn middle(model: &MotionModel) -> Controls {
    let r = model.control_range();
    Controls::from_array(r.map(|(lo, hi)| 0.5 * (lo + hi)))
}

/// Joint positions (cycle frame) at a few phases of the level-0 clip for `c`.
fn joints_of(model: &MotionModel, c: &Controls) -> Vec<glam::Vec3> {
    let (lod, rig) = (model.lod(), model.rig());
    let (mut scratch, mut kernel) = (KernelScratch::new(lod), ClipKernel::new(lod));
    lod.build_kernel(c, lod.full_detail(), &mut scratch, &mut kernel)
        .expect("kernel");
    let mut pose = vec![0.0f32; lod.p()];
    let mut out = Vec::new();
    for phase in [0.0, 0.2, 0.4, 0.6, 0.8] {
        lod.pose(
            &kernel,
            kernel.phase_at(phase * kernel.duration()),
            &mut pose,
        )
        .expect("pose");
        let mut j = vec![glam::Vec3::ZERO; rig.joint_count()];
        rig.joint_positions(&pose, lod.joints(), &mut j)
            .expect("joints");
        out.extend(j);
    }
    out
}

/// Mean distance (m) between two sets of joint positions.
fn apart(a: &[glam::Vec3], b: &[glam::Vec3]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x.distance(*y)).sum::<f32>() / a.len() as f32
}

#[test]
fn a_styled_model_names_its_styles_in_every_reader() {
    let model = styled();
    assert_eq!(model.styles(), ["p160", "p175", "p190"]);
    assert_eq!(model.lod().d(), 4 + 3);
    let bytes = encode(model, std::path::Path::new("m")).unwrap();
    let tags: Vec<[u8; 4]> = sections(&bytes, std::path::Path::new("m"))
        .unwrap()
        .iter()
        .map(|s| s.tag)
        .collect();
    assert_eq!(tags, [*b"RTIM", *b"RPRT", STYLE_SECTION]);
    // The runtime alone reads the styles and the data's mix from its own section.
    let runtime = RuntimeModel::from_bytes(&bytes).unwrap();
    assert_eq!(runtime.styles(), model.styles());
    assert_eq!(runtime.style_index("p175"), Some(1));
    let mix = runtime.data_style_mix();
    assert_eq!(mix.len(), 3);
    assert!((mix.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{mix:?}");
    for &share in mix {
        assert!(
            (share - 1.0 / 3.0).abs() < 1e-5,
            "{mix:?}: 20 cycles per performer"
        );
    }
    // The offline reader gets the style report back.
    let back = MotionModel::from_bytes(&bytes, std::path::Path::new("m")).unwrap();
    let report = back.style.as_ref().expect("style report");
    assert_eq!(report.names, model.styles());
    assert_eq!(report.cycles, [20, 20, 20]);
    assert_eq!(report.takes, [5, 5, 5]);
    assert_eq!(report.spec, StyleSpec::Name(PERFORMER.into()));
    assert_eq!(report.trials.len(), motion_lod::build::STYLE_WEIGHTS.len());
    assert!(
        report.trials.iter().any(|t| t.weight == report.weight),
        "the weight is one of those tried"
    );
    let best = report
        .trials
        .iter()
        .map(|t| t.rmse)
        .fold(f64::INFINITY, f64::min);
    assert!(
        report
            .trials
            .iter()
            .any(|t| t.weight == report.weight && t.rmse == best)
    );
}

#[test]
fn a_model_without_labels_has_no_style_anywhere() {
    let model = MotionModel::build(&fixture_training(), &small(), &NoProgress).unwrap();
    assert!(model.styles().is_empty() && model.style.is_none());
    assert_eq!(model.lod().d(), 4);
    assert!(model.runtime().data_style_mix().is_empty());
    let bytes = encode(&model, std::path::Path::new("m")).unwrap();
    let tags: Vec<[u8; 4]> = sections(&bytes, std::path::Path::new("m"))
        .unwrap()
        .iter()
        .map(|s| s.tag)
        .collect();
    assert_eq!(tags, [*b"RTIM", *b"RPRT"], "no style section");
    // A style asked of a model without styles is ignored: the same clip bits.
    let c = middle(&model);
    assert_eq!(
        joints_of(&model, &c),
        joints_of(&model, &c.with_style(StyleMix::one(1)))
    );
}

#[test]
fn one_style_a_blend_and_the_data_mix_are_different_walks() {
    let model = styled();
    let c = middle(model);
    let [a, b, m] = [0, 2, 1].map(|j| joints_of(model, &c.with_style(StyleMix::one(j))));
    let ab = apart(&a, &b);
    // The performers differ mostly in height, which is a control of its own: at one height their
    // styles differ by millimetres.
    assert!(ab > 0.001, "p160 and p190 walk alike ({ab} m)");
    let mut half = StyleMix::DATA_MIX;
    half.weights[0] = 0.5;
    half.weights[2] = 0.5;
    let blend = joints_of(model, &c.with_style(half));
    let (to_a, to_b) = (apart(&blend, &a), apart(&blend, &b));
    assert!(
        to_a < ab && to_b < ab,
        "the 50/50 blend lies between its styles: {to_a} and {to_b} m from them, {ab} m apart"
    );
    // Weights are normalised: 3/3 is 1/1.
    let mut big = half;
    big.weights[0] = 3.0;
    big.weights[2] = 3.0;
    assert_eq!(joints_of(model, &c.with_style(big)), blend);
    // All zero is the data's mix, the same bits as the shares written out.
    let mut shares = StyleMix::DATA_MIX;
    shares.weights[..3].copy_from_slice(model.runtime().data_style_mix());
    assert_eq!(
        joints_of(model, &c),
        joints_of(model, &c.with_style(shares))
    );
    assert_ne!(
        joints_of(model, &c),
        m,
        "the mix is not the middle performer"
    );
}

#[test]
fn bad_style_weights_are_refused_before_anything_is_written() {
    let model = styled();
    let lod = model.lod();
    let (mut scratch, mut kernel) = (KernelScratch::new(lod), ClipKernel::new(lod));
    let c = middle(model);
    lod.build_kernel(&c, lod.full_detail(), &mut scratch, &mut kernel)
        .unwrap();
    let before = kernel.clone();
    for bad in [f32::NAN, -1.0, f32::INFINITY] {
        let mut style = StyleMix::one(0);
        style.weights[1] = bad;
        let e = lod
            .build_kernel(
                &c.with_style(style),
                lod.full_detail(),
                &mut scratch,
                &mut kernel,
            )
            .unwrap_err();
        assert!(
            matches!(e, KernelError::Style { index: 1, .. }),
            "{bad}: {e}"
        );
        assert!(e.to_string().contains("style weight 1"), "{e}");
        assert_eq!(kernel, before, "a refused build leaves the clip as it was");
    }
}

#[test]
fn a_crowd_walks_the_data_mix_or_one_style() {
    let model = styled();
    let source = LodSource::new(model);
    let config = CrowdConfig {
        walkers: 300,
        ..CrowdConfig::default()
    };
    let crowd = Crowd::new(&source, config).unwrap();
    let mut counts = [0usize; 3];
    for i in 0..300 {
        let style = crowd.controls(i).style;
        let j = (0..3)
            .find(|&j| style == StyleMix::one(j))
            .expect("each walker walks one style");
        counts[j] += 1;
    }
    for n in counts {
        assert!(
            (70..=130).contains(&n),
            "{counts:?}: a third each, as the data"
        );
    }
    let one = StyleMix::one(2);
    let crowd = Crowd::new(
        &source,
        CrowdConfig {
            style: CrowdStyle::Each(one),
            ..config
        },
    )
    .unwrap();
    assert!((0..300).all(|i| crowd.controls(i).style == one));
    let mut bad = one;
    bad.weights[0] = f32::NAN;
    assert!(
        Crowd::new(
            &source,
            CrowdConfig {
                style: CrowdStyle::Each(bad),
                ..config
            }
        )
        .is_err()
    );
}

#[test]
fn a_track_changes_the_walk_at_the_next_seam() {
    let model = styled();
    let (lo, hi) = model.control_range()[1];
    let slow = Controls {
        dz: lo + 0.15 * (hi - lo),
        ..middle(model)
    };
    let fast = Controls {
        dz: lo + 0.85 * (hi - lo),
        ..slow
    };
    let req = WalkRequest {
        controls: slow,
        detail: model.lod().full_detail(),
        cycles: 1,
        fps: 30.0,
        blend: true,
        plant_feet: false,
    };
    let track = [(0.0, slow), (3.0, fast)];
    let walk = model.synthesize_track(&req, &track).unwrap();
    let p = model.layout.dof();
    let frames = walk.poses.len() / p;
    let z = |f: usize| walk.poses[f * p + 2];
    let speed = |a: f64, b: f64| {
        let (fa, fb) = (
            (a / walk.frame_time) as usize,
            (b / walk.frame_time) as usize,
        );
        (z(fb) - z(fa)) / (b - a)
    };
    let end = (frames - 1) as f64 * walk.frame_time;
    assert!(end > 3.0, "the walk goes on past the last row: {end} s");
    let (before, after) = (speed(0.2, 2.6), speed(end - 1.0, end));
    assert!(
        after > 1.3 * before,
        "the walk speeds up after the row at 3 s: {before:.3} then {after:.3} m/s"
    );
    // Constant controls as a track are the same walk as the plain request up to its cycles.
    let plain = model
        .synthesize_walk(&WalkRequest { cycles: 2, ..req })
        .unwrap();
    let as_track = model
        .synthesize_track(&req, &[(0.0, slow), (plain.cycle_seconds * 1.5, slow)])
        .unwrap();
    let n = plain.poses.len().min(as_track.poses.len()) - p;
    let worst = plain.poses[..n]
        .iter()
        .zip(&as_track.poses[..n])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f64, f64::max);
    assert!(worst < 1e-9, "{worst}");
    // Bad tracks are clear errors.
    for bad in [
        vec![],
        vec![(1.0, slow)],
        vec![(0.0, slow), (0.0, fast)],
        vec![(0.0, slow), (f64::NAN, fast)],
    ] {
        assert!(model.synthesize_track(&req, &bad).is_err(), "{bad:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// Bandai: seven styles.

fn mocap(name: &str) -> Option<PathBuf> {
    motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), name)
}

/// The Bandai training set with its styles; `None` (skipped) without the data.
fn bandai_set() -> Option<&'static TrainingSet> {
    static SET: OnceLock<Option<TrainingSet>> = OnceLock::new();
    SET.get_or_init(|| {
        let spec = DataSpec {
            dirs: vec![mocap("bandai-namco-2-walk")?],
            ..DataSpec::default()
        };
        let set = spec.load(&|_, _| {}).expect("Bandai loads").training;
        Some(
            set.with_styles(Some(&StyleSpec::Name(BANDAI_STYLE.into())))
                .expect("Bandai's file names give styles"),
        )
    })
    .as_ref()
}

/// The Bandai model with styles at the weight the build chooses (1; given here to spare the
/// choice's 25 kriging fits in an unoptimised test).
fn bandai() -> Option<&'static MotionModel> {
    static MODEL: OnceLock<Option<MotionModel>> = OnceLock::new();
    MODEL
        .get_or_init(|| {
            let config = BuildConfig {
                style_weight: Some(1.0),
                ..BuildConfig::default()
            };
            Some(MotionModel::build(bandai_set()?, &config, &NoProgress).expect("builds"))
        })
        .as_ref()
}

#[test]
fn bandai_styles_and_their_blends_walk_like_the_data() {
    let Some(model) = bandai() else {
        return;
    };
    let styles = model.styles().to_vec();
    assert_eq!(
        styles,
        [
            "active",
            "elderly",
            "exhausted",
            "feminine",
            "masculine",
            "normal",
            "youthful"
        ]
    );
    let pooled = model.report.quality.clone().expect("feet found");
    let report = model.style.as_ref().expect("style report");
    assert_eq!(report.quality.len(), styles.len());
    assert!(
        report.quality.iter().all(Option::is_some),
        "every style's takes measured"
    );
    let straight = walk_quality::walk_grid(model)
        .into_iter()
        .find(|g| g.name == "straight")
        .expect("a straight walk")
        .controls;
    // Each style walks straight at its own median step (the active takes are brisk, the elderly
    // slow); a blend at the mean of its two styles' steps.
    let set = bandai_set().expect("the data");
    let labels = set.styles.as_ref().expect("labels");
    let step_of = |j: usize| {
        let mut dz: Vec<f64> = (0..set.controls.len())
            .filter(|&i| labels.of_sample[i] == j)
            .map(|i| set.controls[i][1])
            .collect();
        dz.sort_by(f64::total_cmp);
        dz[dz.len() / 2] as f32
    };
    let mut mixes: Vec<(String, StyleMix, f32)> = (0..styles.len())
        .map(|j| (styles[j].clone(), StyleMix::one(j), step_of(j)))
        .collect();
    for a in 0..styles.len() {
        for b in a + 1..styles.len() {
            let mut m = StyleMix::DATA_MIX;
            m.weights[a] = 0.5;
            m.weights[b] = 0.5;
            let step = 0.5 * (step_of(a) + step_of(b));
            mixes.push((format!("{}+{}", styles[a], styles[b]), m, step));
        }
    }
    let mut failures = Vec::new();
    for (name, mix, step) in &mixes {
        let controls = Controls {
            dz: *step,
            ..straight
        };
        let req = WalkRequest {
            controls: controls.with_style(*mix),
            detail: model.lod().full_detail(),
            cycles: 4,
            fps: 30.0,
            blend: true,
            plant_feet: true,
        };
        let walk = model.synthesize_walk(&req).unwrap();
        let q = walk_quality::measure_walk(model, &walk).unwrap();
        // Held to its (heaviest) style's own takes: the active takes pop 1.7x the elderly ones.
        let reference = report
            .reference_for(mix, Some(&pooled))
            .expect("a reference");
        let data = &reference.median;
        let (lo, hi) = reference.facing_range_deg;
        println!(
            "{name:22} dz {step:.3} pop {:5.2} (takes {:5.2}) skate {:5.2} (takes {:5.2}) floor {:5.2} facing {:5.1}",
            q.pop_cm, data.pop_cm, q.skate_cm_s, data.skate_cm_s, q.floor_offset_cm, q.facing_deg
        );
        if q.pop_cm > 1.25 * data.pop_cm {
            failures.push(format!(
                "{name}: pop {:.2} cm/frame^2 > 1.25 x the data's {:.2}",
                q.pop_cm, data.pop_cm
            ));
        }
        if q.skate_cm_s > 1.5 * data.skate_cm_s {
            failures.push(format!(
                "{name}: skate {:.2} cm/s > 1.5 x the data's {:.2}",
                q.skate_cm_s, data.skate_cm_s
            ));
        }
        if q.floor_offset_cm.abs() > 1.0 {
            failures.push(format!("{name}: floor offset {:.2} cm", q.floor_offset_cm));
        }
        if !(lo..=hi).contains(&q.facing_deg) {
            failures.push(format!(
                "{name}: facing {:.1} deg outside the data's {lo:.1}..{hi:.1}",
                q.facing_deg
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");

    // Speed apart from style: a normal walk as slow as the elderly takes' median step does not
    // take the elderly or exhausted posture (knees never straight, head down), which the elderly
    // style at that speed does.
    let slow = Controls {
        dz: step_of(1),
        ..straight
    };
    let postures = &report.posture;
    assert_eq!(
        postures.len(),
        styles.len(),
        "every style's posture measured"
    );
    let looks = |j: usize| {
        let req = WalkRequest {
            controls: slow.with_style(StyleMix::one(j)),
            detail: model.lod().full_detail(),
            cycles: 4,
            fps: 30.0,
            blend: true,
            plant_feet: true,
        };
        let walk = model.synthesize_walk(&req).unwrap();
        let p = walk_quality::walk_posture(model, &walk).expect("posture");
        let nearest = motion_lod::posture::nearest_style(&p, postures).expect("a style");
        println!(
            "{} at {:.2} m per cycle: knee extension {:.1} deg, head pitch {:.1} deg, looks {}",
            styles[j], slow.dz, p.knee_extension_deg, p.head_pitch_deg, postures[nearest].style
        );
        (p, postures[nearest].style.clone())
    };
    let (normal, normal_looks) = looks(5);
    let (elderly, elderly_looks) = looks(1);
    assert!(
        normal_looks != "elderly" && normal_looks != "exhausted",
        "a slow normal walk looks {normal_looks}"
    );
    assert_eq!(elderly_looks, "elderly");
    assert!(
        normal.head_pitch_deg < postures[1].head_pitch_deg.p10
            && normal.knee_extension_deg < elderly.knee_extension_deg,
        "slow normal {normal:?} against slow elderly {elderly:?}"
    );
    // A blend lies between its styles (joint positions of the level-0 clip).
    for a in 0..styles.len() {
        for b in a + 1..styles.len() {
            let ja = joints_of(model, &straight.with_style(StyleMix::one(a)));
            let jb = joints_of(model, &straight.with_style(StyleMix::one(b)));
            let mut m = StyleMix::DATA_MIX;
            m.weights[a] = 0.5;
            m.weights[b] = 0.5;
            let jm = joints_of(model, &straight.with_style(m));
            let ab = apart(&ja, &jb);
            let (to_a, to_b) = (apart(&jm, &ja), apart(&jm, &jb));
            assert!(
                to_a < ab && to_b < ab,
                "{}+{}: the blend is {to_a:.4} and {to_b:.4} m from its styles, {ab:.4} m apart",
                styles[a],
                styles[b]
            );
        }
    }
}

/// The headline figure: 5-fold cross-validation by take, every fold's model refitted, level 0 at
/// most 3.0 cm with styles (3.98 cm without them).
#[test]
fn bandai_with_styles_predicts_held_out_takes_within_3_cm() {
    let Some(set) = bandai_set() else {
        return;
    };
    let config = BuildConfig {
        style_weight: Some(1.0),
        ..BuildConfig::default()
    };
    let eval = EvalConfig {
        max_samples: Some(200),
        ..EvalConfig::default()
    };
    let report = k_fold(set, &config, 5, FoldBy::Take, &eval, &NoProgress).unwrap();
    let level0 = report
        .pooled
        .methods
        .iter()
        .find(|m| m.name == "multilinear" && m.level == Some(0))
        .expect("level 0")
        .error_cm;
    println!("Bandai with styles, 5-fold by take: level 0 {level0:.3} cm");
    assert!(level0 <= 3.0, "level 0 {level0:.3} cm > 3.0 cm");
}

#[test]
fn the_runtime_refuses_styles_that_do_not_fit_its_controls() {
    let model = styled();
    let (rig, lod, _) = model.runtime().clone().into_parts();
    let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    for (bad, says) in [
        (names(&["p160", "p175"]), "7 controls"),
        (names(&["p160", "p160", "p190"]), "named twice"),
        (names(&["p160", "a=b", "p190"]), "'='"),
        (
            names(&["a", "b", "c", "d", "e", "f", "g", "h", "i"]),
            "at most 8",
        ),
    ] {
        let e = RuntimeModel::with_styles(rig.clone(), lod.clone(), bad.clone()).unwrap_err();
        assert!(e.to_string().contains(says), "{bad:?}: {e}");
    }
    // Without style names the seven controls do not make a walk model.
    assert!(RuntimeModel::new(rig.clone(), lod.clone()).is_err());
    assert!(RuntimeModel::with_styles(rig, lod, names(&["a", "b", "c"])).is_ok());
}

/// The style section is checked like every other: a styled model without it, with it cut short
/// or of another version, and a style-less model given one, are clear errors of the offline reader,
/// never a panic; the runtime, which skips it, still plays the model.
#[test]
fn a_broken_style_section_is_a_clear_error() {
    use lod_policy::file::{Section, frame};
    let model = styled();
    let path = std::path::Path::new("styled.mlod");
    let bytes = encode(model, path).unwrap();
    let parts = sections(&bytes, path).unwrap();
    let owned: Vec<(Vec<u8>, [u8; 4], u32)> = parts
        .iter()
        .map(|s| (s.bytes.to_vec(), s.tag, s.version))
        .collect();
    // A section's new (version, bytes) from its tag and bytes, or `None` to leave it out; version
    // 0 keeps the section's own.
    type Edit<'a> = &'a dyn Fn(&[u8; 4], &[u8]) -> Option<(u32, Vec<u8>)>;
    let rebuild = |edit: Edit| {
        let kept: Vec<(u32, Vec<u8>, [u8; 4])> = owned
            .iter()
            .filter_map(|(b, tag, v)| {
                edit(tag, b).map(|(v2, b2)| (if v2 == 0 { *v } else { v2 }, b2, *tag))
            })
            .collect();
        let sections: Vec<Section> = kept
            .iter()
            .map(|(v, b, tag)| Section {
                tag: *tag,
                version: *v,
                bytes: b,
                offset: 0,
            })
            .collect();
        frame(&sections)
    };
    let is_style = |tag: &[u8; 4]| *tag == STYLE_SECTION;
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "no style section",
            rebuild(&|tag, b| (!is_style(tag)).then(|| (0, b.to_vec()))),
            "no style report",
        ),
        (
            "cut short",
            rebuild(&|tag, b| {
                Some((
                    0,
                    if is_style(tag) {
                        b[..b.len() / 2].to_vec()
                    } else {
                        b.to_vec()
                    },
                ))
            }),
            "section STYL",
        ),
        (
            "another version",
            rebuild(&|tag, b| Some((if is_style(tag) { 99 } else { 0 }, b.to_vec()))),
            "rebuild",
        ),
    ];
    for (what, file, says) in cases {
        let e = MotionModel::from_bytes(&file, path)
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{what}: {e}");
        let runtime = RuntimeModel::from_bytes(&file).expect("the runtime skips the style section");
        assert_eq!(runtime.styles(), model.styles(), "{what}");
    }
    // A style report beside a model without styles.
    let plain = MotionModel::build(&fixture_training(), &small(), &NoProgress).unwrap();
    let plain_bytes = encode(&plain, path).unwrap();
    let plain_parts = sections(&plain_bytes, path).unwrap();
    let style_bytes = &owned.iter().find(|(_, tag, _)| is_style(tag)).unwrap().0;
    let mut with_style: Vec<Section> = plain_parts.clone();
    with_style.push(Section {
        tag: STYLE_SECTION,
        version: motion_lod::model_file::STYLE_VERSION,
        bytes: style_bytes,
        offset: 0,
    });
    let e = MotionModel::from_bytes(&frame(&with_style), path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("style report names"), "{e}");
}
