//! Smoke test of the `cargo xtask tables` pipeline on a tiny configuration: every section and all
//! three figures are written, and the measured numbers are finite.

use xtask::tables::{TablesConfig, run};

#[test]
fn tables_pipeline_writes_every_section_and_figure() {
    let dir = std::env::temp_dir().join(format!("xtask-tables-smoke-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.join("tables.md");
    let figures = dir.join("figures");
    let config = TablesConfig::quick(out.clone(), figures.clone());
    run(&config).expect("tables pipeline runs");
    let doc = std::fs::read_to_string(&out).expect("tables written");
    for heading in [
        "## 1. Storage",
        "## 2. Figure 4",
        "## 3. Figure 5",
        "## 4. Crowd frame rates",
        "## 5. Accuracy",
        "### By refitting: 2-fold cross-validation by",
        "Refitted, multilinear level 0 is",
        "### Leave-one-out, factors fitted on all samples",
        "## 6. The paper's plain tensor",
        "## 7. Motion quality per accuracy level",
        "## 8. Criterion benchmarks",
        "paper (published)",
        "](figures/figure4.svg)",
        "](figures/figure5.svg)",
        "](figures/quality.svg)",
    ] {
        assert!(doc.contains(heading), "missing {heading:?} in:\n{doc}");
    }
    assert!(!doc.contains("NaN"), "a measured value is NaN:\n{doc}");
    // The quick crowds are 50 and 200 walkers in both scenes, each with LOD, naive and PCA rows under
    // the LOD policy and at full detail, the model on one and two threads, and every walker root
    // only on one thread at the largest size on the ground, and that crowd culled by the tree.
    assert!(
        doc.contains("### ground camera")
            && doc.contains("### overview camera")
            && doc.contains("| ground | 50 | lod | LOD |")
            && doc.contains("| ground | 200 | naive | LOD |")
            && doc.contains("| overview | 200 | pca | no LOD |")
            && doc.contains("| overview | 200 | LOD | 1 |")
            && doc.contains("| overview | 200 | LOD | 2 |")
            && doc.contains("| ground | 200 | root only | 1 |")
            && doc.contains("| ground | 200 | lod | LOD, tree culling |"),
        "{doc}"
    );
    // Frame times of the quick size (300 walkers) in both scenes on one and two threads.
    for row in [
        "| ground | 300 | 1 |",
        "| ground | 300 | 2 |",
        "| overview | 300 | 1 |",
        "| overview | 300 | 2 |",
    ] {
        assert!(
            doc.contains(row),
            "missing frame-time row {row:?} in:\n{doc}"
        );
    }
    assert!(
        doc.contains("| worst / median | goal | fixed work: worst / median |"),
        "{doc}"
    );
    for f in ["figure4.svg", "figure5.svg", "quality.svg"] {
        let svg = std::fs::read_to_string(figures.join(f)).expect("figure written");
        assert!(svg.starts_with("<svg") && svg.contains("<polyline"), "{f}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The online-truncation kernel (unfold the full core per clip, cut the sub-block) computes the same
/// `G(c)`, durations and poses as the runtime kernel over a model whose levels truncate key 0.
#[test]
fn online_truncation_matches_the_runtime_kernel_on_truncations_of_key_0() {
    use lod_policy::{ClipKernel, Detail, KernelScratch};
    use motion_lod::MotionModel;
    use motion_lod::dataset::DataSpec;
    use motion_lod::progress::NoProgress;
    use xtask::tables::{online::OnlineTruncation, schemes};

    let config = TablesConfig::quick("unused.md".into(), "unused".into());
    let data = DataSpec {
        samples: config.samples,
        ..DataSpec::default()
    }
    .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
    .expect("fixtures load");
    let (model, analysis) =
        MotionModel::build_with_analysis(&data.training, &config.build, &NoProgress)
            .expect("model builds");
    let trunc = schemes::truncation_only(&model).expect("truncation model");
    assert_eq!(trunc.keys().len(), 1);
    assert_eq!(trunc.levels().len(), model.lod().levels().len());
    let mut online = OnlineTruncation::new(&trunc);
    let mut scratch = KernelScratch::new(&trunc);
    let mut kernel = ClipKernel::new(&trunc);
    let (mut a, mut b) = (vec![0.0f32; trunc.p()], vec![0.0f32; trunc.p()]);
    let last = trunc.levels().len() - 1;
    for (k, c) in analysis.controls.iter().enumerate().step_by(5) {
        let c = lod_policy::Controls::from_f64(*c);
        for level in [0, last / 2, last] {
            for joints in [trunc.joints(), 2] {
                let detail = Detail::new(level, joints);
                trunc
                    .build_kernel(&c, detail, &mut scratch, &mut kernel)
                    .expect("kernel");
                online.build(&c, trunc.levels()[level].ranks, kernel.rows());
                let scale = kernel.g().iter().fold(1e-6f32, |m, v| m.max(v.abs()));
                assert_eq!(online.g().len(), kernel.g().len());
                for (x, y) in online.g().iter().zip(kernel.g()) {
                    assert!(
                        (x - y).abs() <= 1e-4 * scale,
                        "sample {k} level {level}: {x} vs {y}"
                    );
                }
                assert!((online.duration() - kernel.duration()).abs() < 1e-4);
                for phase in [0.0, 3.5, (trunc.t() - 1) as f32] {
                    trunc.pose(&kernel, phase, &mut a).expect("pose");
                    online.pose(phase, &mut b);
                    for (x, y) in a.iter().zip(&b) {
                        assert!((x - y).abs() <= 1e-4 * scale.max(1.0), "{x} vs {y}");
                    }
                }
            }
        }
    }
}

/// `cargo xtask frames` alone: a model file's frame-time rows in both scenes on each thread count,
/// in a document that names the machine (with its vector extensions) and the command.
#[test]
fn frames_writes_a_row_per_scene_and_thread_count() {
    use motion_lod::MotionModel;
    use xtask::tables::{FramesConfig, frames};

    let dir = std::env::temp_dir().join(format!("xtask-frames-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let loaded = motion_lod::dataset::DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("the embedded data loads");
    let build = TablesConfig::quick(dir.join("t.md"), dir.join("f")).build;
    let model = MotionModel::build(&loaded.training, &build, &motion_lod::progress::NoProgress)
        .expect("the quick model builds");
    let path = dir.join("quick.mlod");
    model.save(&path).unwrap();
    let doc = frames(&FramesConfig {
        model: path.clone(),
        walkers: vec![300],
        threads: vec![1, 2],
        frames: 4,
        show_progress: false,
        command: "cargo xtask frames quick.mlod".into(),
    })
    .expect("frame times measured");
    for line in [
        "# Frame times: ",
        "Written by `cargo xtask frames quick.mlod` on ",
        "- Machine: ",
        "4 timed frames after the 1.5 s warm-up",
        "| ground | 300 | 1 |",
        "| ground | 300 | 2 |",
        "| overview | 300 | 1 |",
        "| overview | 300 | 2 |",
    ] {
        assert!(doc.contains(line), "missing {line:?} in:\n{doc}");
    }
    assert!(!doc.contains("NaN"), "{doc}");
    // A model that is not there is named.
    let missing = dir.join("missing.mlod");
    let e = frames(&FramesConfig {
        model: missing,
        ..FramesConfig {
            model: path,
            walkers: vec![300],
            threads: vec![1],
            frames: 1,
            show_progress: false,
            command: String::new(),
        }
    })
    .unwrap_err();
    assert!(format!("{e:#}").contains("missing.mlod"), "{e:#}");
    let _ = std::fs::remove_dir_all(&dir);
}
