//! The posture meter ([`motion_lod::posture`]) on the real Bandai walks in `../shared/mocap` (prints
//! `skipped: ../shared/mocap not found` and passes when it is absent, and fails when
//! `MOTION_LOD_REQUIRE_DATA` is set, as CI sets it), with what the data say:
//!
//! - the elderly and exhausted styles' median knee extension is larger than normal's by more than 10
//!   degrees (their knees never get as straight);
//! - the elderly walk with the head forward (median head pitch more than 5 degrees above normal's),
//!   but the exhausted takes do not: their head is more upright than normal's;
//! - the nearest style ([`motion_lod::posture::nearest_style`]) of more than 90% of the elderly
//!   cycles is elderly, and of no normal cycle elderly or exhausted.

use motion_lod::dataset::DataSpec;
use motion_lod::posture::{PostureJoints, StylePosture, measure_posture, nearest_style};
use motion_lod::style::StyleSpec;

#[test]
fn slow_styles_bend_the_knees_and_the_elderly_lean_the_head_forward() {
    let Some(dir) =
        motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), "bandai-namco-2-walk")
    else {
        return;
    };
    let data = DataSpec {
        dirs: vec![dir],
        ..Default::default()
    }
    .load(&|_, _| {})
    .expect("the Bandai walks load");
    let set = data
        .training
        .with_styles(Some(&StyleSpec::Name(r"_([a-z]+)_\d+\.bvh$".into())))
        .expect("styles from the file names");
    let styles = set
        .style_postures()
        .expect("the Bandai skeleton has knees and a head");
    println!(
        "style       cycles  knee extension deg (p10 / median / p90)  head pitch deg (p10 / median / p90)"
    );
    for s in &styles {
        let (k, h) = (&s.knee_extension_deg, &s.head_pitch_deg);
        println!(
            "{:<10} {:>6}   {:>6.1} / {:>6.1} / {:>6.1}                    {:>6.1} / {:>6.1} / {:>6.1}",
            s.style, s.cycles, k.p10, k.median, k.p90, h.p10, h.median, h.p90
        );
    }
    assert_eq!(styles.len(), 7, "the seven Bandai styles");
    let total: usize = styles.iter().map(|s| s.cycles).sum();
    assert_eq!(total, set.tensor.dims()[2], "every cycle is measured");
    let of = |name: &str| -> &StylePosture {
        styles
            .iter()
            .find(|s| s.style == name)
            .unwrap_or_else(|| panic!("style {name}"))
    };
    let normal = of("normal");
    // The slow styles' knees never get as straight as normal's.
    for slow in ["elderly", "exhausted"] {
        let s = of(slow);
        assert!(
            s.knee_extension_deg.median > normal.knee_extension_deg.median + 10.0,
            "{slow}'s knees get nearly as straight as normal's: {:?} vs {:?}",
            s.knee_extension_deg,
            normal.knee_extension_deg
        );
    }
    // The elderly walk with the head forward; the exhausted takes do not: they walk with the head
    // more upright than normal's (on the neck bone, and on the head's own rotation too).
    let (elderly, exhausted) = (of("elderly"), of("exhausted"));
    assert!(
        elderly.head_pitch_deg.median > normal.head_pitch_deg.median + 5.0,
        "elderly head pitch {:?} vs normal {:?}",
        elderly.head_pitch_deg,
        normal.head_pitch_deg
    );
    assert!(
        exhausted.head_pitch_deg.median < normal.head_pitch_deg.median,
        "exhausted head pitch {:?} vs normal {:?}",
        exhausted.head_pitch_deg,
        normal.head_pitch_deg
    );
    // Which style each cycle's own posture is nearest to (columns in the order above).
    let labels = set.styles.as_ref().expect("labelled");
    let joints = PostureJoints::find(&set.layout).expect("knees and head");
    let mut confusion = vec![vec![0usize; styles.len()]; styles.len()];
    for (i, &s) in labels.of_sample.iter().enumerate() {
        let p = measure_posture(&set.layout, set.tensor.sample(i), &joints).expect("measured");
        let row = styles
            .iter()
            .position(|x| x.style == labels.names[s])
            .unwrap();
        confusion[row][nearest_style(&p, &styles).expect("nearest")] += 1;
    }
    for (s, row) in styles.iter().zip(&confusion) {
        println!("{:<10} nearest {:?}", s.style, row);
    }
    let share = |row: &str, col: &str| {
        let r = styles.iter().position(|s| s.style == row).unwrap();
        let c = styles.iter().position(|s| s.style == col).unwrap();
        confusion[r][c] as f64 / styles[r].cycles as f64
    };
    // An elderly cycle reads as elderly; no normal cycle reads as elderly or exhausted.
    assert!(share("elderly", "elderly") > 0.9, "{confusion:?}");
    assert_eq!(
        share("normal", "elderly") + share("normal", "exhausted"),
        0.0,
        "{confusion:?}"
    );
}
