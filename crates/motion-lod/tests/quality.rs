//! Issue 12's motion-quality acceptance: walks measured by the one motion-quality meter
//! (`motion_lod::quality`) against the data's own takes.
//!
//! On Bandai (a 240-cycle subset; skipped with `skipped: ../shared/mocap not found` when the data is
//! absent), every walk of the quality grid (straight, turns of 30 degrees both ways, sidesteps, slow,
//! fast and the corners of the control hull), 4 cycles at full detail: largest joint acceleration at
//! most 1.25x the data's median, foot skate at most 1.5x, floor offset within 1 cm, facing against
//! travel within the data's range. On the embedded data (always present): the inertialized seams
//! and the foot lock each measurably beat the plain switch and the sliding feet.

mod common;

use std::path::{Path, PathBuf};

use lod_policy::Detail;
use motion_lod::MotionModel;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::quality::{self, MotionQuality};
use motion_lod::synth::WalkRequest;

const MOCAP: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/mocap");

fn mocap(name: &str) -> Option<PathBuf> {
    let dir = Path::new(MOCAP).join(name);
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipped: ../shared/mocap not found ({name})");
        None
    }
}

fn walk(model: &MotionModel, controls: [f32; 4], blend: bool, plant_feet: bool) -> MotionQuality {
    let req = WalkRequest {
        controls,
        detail: Detail::full(),
        cycles: 4,
        fps: 30.0,
        blend,
        plant_feet,
    };
    let w = model.synthesize_walk(&req).expect("walk synthesizes");
    quality::measure_walk(model, &w).expect("walk measures")
}

#[test]
fn bandai_walks_look_like_the_data() {
    let Some(dir) = mocap("bandai-namco-2-walk") else {
        return;
    };
    let spec = DataSpec {
        dirs: vec![dir],
        samples: Some(240),
        ..DataSpec::default()
    };
    let loaded = spec.load(&|_, _| {}).expect("data loads");
    let model = MotionModel::build(&loaded.training, &Default::default(), &NoProgress)
        .expect("model builds");
    let reference = model.report.quality.clone().expect("the feet are found");
    let data = reference.median;
    assert!(reference.takes >= 100, "{} takes measured", reference.takes);
    for g in quality::walk_grid(&model) {
        let q = walk(&model, g.controls, true, true);
        let name = &g.name;
        assert!(
            q.pop_cm <= 1.25 * data.pop_cm,
            "{name}: pop {:.2} cm/frame^2 > 1.25 x the data's {:.2}",
            q.pop_cm,
            data.pop_cm
        );
        assert!(
            q.skate_cm_s <= 1.5 * data.skate_cm_s,
            "{name}: skate {:.2} cm/s > 1.5 x the data's {:.2}",
            q.skate_cm_s,
            data.skate_cm_s
        );
        assert!(
            q.floor_offset_cm.abs() <= 1.0,
            "{name}: floor offset {:.2} cm",
            q.floor_offset_cm
        );
        let (lo, hi) = reference.facing_range_deg;
        assert!(
            (lo..=hi).contains(&q.facing_deg),
            "{name}: facing {:.1} deg outside the data's {lo:.1}..{hi:.1}",
            q.facing_deg
        );
    }
}

#[test]
fn seams_and_feet_are_better_than_switching_and_sliding() {
    let (model, _) = common::built();
    let reference = model.report.quality.as_ref().expect("reference measured");
    assert!(reference.takes > 0 && reference.median.pop_cm > 0.0);
    let grid = quality::walk_grid(model);
    let (mut seam_switch, mut seam_inert, mut skate_free, mut skate_locked) = (0.0, 0.0, 0.0, 0.0);
    for g in &grid {
        let switched = walk(model, g.controls, false, false);
        let inert = walk(model, g.controls, true, false);
        let locked = walk(model, g.controls, true, true);
        seam_switch += switched.seam_pop_cm;
        seam_inert += inert.seam_pop_cm;
        skate_free += inert.skate_cm_s;
        skate_locked += locked.skate_cm_s;
    }
    assert!(
        seam_inert < 0.8 * seam_switch,
        "inertialized seams pop {seam_inert:.2} against {seam_switch:.2} switched"
    );
    assert!(
        skate_locked < 0.5 * skate_free,
        "locked feet skate {skate_locked:.2} against {skate_free:.2} free"
    );
}
