//! Bad and extreme input to the GPU crowd's public API (the audit of the crate's API): clear
//! errors, no panic, no abort, no unbounded memory, no NaN in an `Ok`; each test fails without its
//! fix. Ordinary input keeps its bits (checked by the audit against a fingerprint of the crowd's
//! joints and statistics before and after the fixes). Without a GPU adapter the tests print
//! `skipped: no GPU adapter (...)`, or fail when `MOTION_LOD_REQUIRE_GPU=1` (CI, lavapipe).

use std::cell::Cell;

use crowd_sim::{Camera, CrowdConfig, Scene};
use gpu_crowd::{Gpu, GpuCrowd, GpuError, GpuOptions, PolicyTable};
use lod_policy::{Detail, FullDetail, LevelPolicy, LodModel, RuntimeModel, ViewParams};

mod common;
use common::{gpu, model};

const DT: f32 = 1.0 / 30.0;

fn config(walkers: usize) -> CrowdConfig {
    CrowdConfig {
        seam_levels: 0,
        foot_lock_levels: 0,
        ..CrowdConfig::with_density(walkers, 0.2)
    }
}

/// The camera of `scene` at frame `f` over `crowd`'s field.
fn camera(crowd: &GpuCrowd, scene: Scene, f: usize) -> Camera {
    let field = crowd.config().field_size_m;
    scene
        .path(field)
        .camera_at(f as f32 * DT, &scene.lens(Camera::default(), field))
}

/// `model` with its parts changed by `edit` (through the runtime's public constructors, which
/// take numbers that are huge but finite: only a model read from a file is played first).
fn edited(model: &RuntimeModel, edit: impl Fn(&mut lod_policy::ModelParts)) -> RuntimeModel {
    let styles = model.styles().to_vec();
    let stature = model.stature_m();
    let (rig, lod, _feet) = model.clone().into_parts();
    let mut parts = lod.into_parts();
    edit(&mut parts);
    let lod = LodModel::new(parts).expect("passes the model's validation");
    RuntimeModel::with_styles(rig, lod, styles)
        .and_then(|m| m.with_stature(stature))
        .expect("runtime model")
}

/// A policy that answers differently each time it is asked (full detail, then root only, ...):
/// tabulating it pushed a run per answer without end, until the process aborted on a failed
/// allocation of 12 GB. Now an error once the table is full. (It panics after a million answers,
/// so that the unfixed search fails this test instead of exhausting memory.)
#[test]
fn a_policy_answering_differently_each_time_is_an_error_in_bounded_time() {
    struct Toggle {
        asked: Cell<u64>,
        joints: usize,
    }
    impl LevelPolicy for Toggle {
        fn detail(&self, _distance_m: f32, _visible: bool, _view: &ViewParams) -> Detail {
            let n = self.asked.get();
            assert!(n < 1_000_000, "the policy was asked {n} times");
            self.asked.set(n + 1);
            Detail::new(0, (n % 2) as usize * self.joints)
        }
    }
    let toggle = Toggle {
        asked: Cell::new(0),
        joints: 10,
    };
    let e = PolicyTable::new(&toggle, &ViewParams::default(), 4, 10).unwrap_err();
    assert!(
        matches!(&e, GpuError::Config(m) if m.contains("more than 256 times")),
        "{e}"
    );
    // A policy whose detail changes every metre, for good, likewise (before: the whole sweep,
    // 221,624 runs here, then the error).
    let changing = |d: f32, _: bool, _: &ViewParams| Detail::new(0, (d as usize) % 11);
    let e = PolicyTable::new(&changing, &ViewParams::default(), 4, 10).unwrap_err();
    assert!(
        matches!(&e, GpuError::Config(m) if m.contains("more than 256 times")),
        "{e}"
    );
    // 255 visible runs and one hidden fit; one more does not.
    for (changes, fits) in [(255, true), (256, false)] {
        let steps = move |d: f32, visible: bool, _: &ViewParams| {
            let k = if visible {
                (d as usize).min(changes - 1)
            } else {
                0
            };
            Detail::new(0, k % 2)
        };
        let r = PolicyTable::new(&steps, &ViewParams::default(), 4, 10);
        assert_eq!(r.is_ok(), fits, "{changes} runs: {r:?}");
        if let Ok(t) = r {
            assert_eq!((t.visible().len(), t.hidden().len()), (changes, 1));
        }
    }
}

/// A policy passed to `step` with the same view as the frame before was ignored: the crowd kept
/// the table of the policy it tabulated first (every walker root only here, for good). Now
/// another policy, or the same one changed in place, is tabulated anew.
#[test]
fn another_policy_under_the_same_view_is_followed() {
    let Some(gpu) = gpu() else {
        return;
    };
    let model = model();
    let lod = model.lod();
    let full = FullDetail::for_model(lod);
    let root_only = |_: f32, _: bool, _: &ViewParams| lod.root_only();
    // The same policy object, changed in place between frames.
    struct Switch<'a> {
        full: Cell<bool>,
        lod: &'a LodModel,
    }
    impl LevelPolicy for Switch<'_> {
        fn detail(&self, _distance_m: f32, _visible: bool, _view: &ViewParams) -> Detail {
            if self.full.get() {
                self.lod.full_detail()
            } else {
                self.lod.root_only()
            }
        }
    }
    let switch = Switch {
        full: Cell::new(false),
        lod,
    };
    let new = || GpuCrowd::new(gpu, model, config(60), GpuOptions::default()).expect("crowd");
    let (mut always, mut switched, mut in_place) = (new(), new(), new());
    let cam = camera(&always, Scene::Overview, 0);
    always.step(&full, &cam, DT).unwrap();
    switched.step(&root_only, &cam, DT).unwrap();
    in_place.step(&switch, &cam, DT).unwrap();
    switch.full.set(true);
    // Two seconds: every walker in view has refined (a frame later than in the crowd that had
    // full detail from the start, or at its cycle's end).
    let (mut want, mut got, mut got_in_place) = (vec![], vec![], vec![]);
    for _ in 0..60 {
        want = always.step(&full, &cam, DT).unwrap().level_histogram;
        got = switched.step(&full, &cam, DT).unwrap().level_histogram;
        got_in_place = in_place.step(&switch, &cam, DT).unwrap().level_histogram;
    }
    assert!(want[0] > 0, "walkers with joints to compare: {want:?}");
    assert_eq!(got, want, "another policy");
    assert_eq!(got_in_place, want, "the policy changed in place");
    let details = |c: &GpuCrowd| -> Vec<Detail> {
        c.read_walkers().unwrap().iter().map(|w| w.detail).collect()
    };
    assert_eq!(details(&switched), details(&always));
    assert_eq!(details(&in_place), details(&always));
}

/// A model whose numbers are huge but finite (every core entry 3e38: the CPU runtime's
/// `build_kernel` refuses it with `KernelError::Overflow`): `step` and `read_walkers` returned
/// `Ok` with NaN and infinite joint positions (3,745 of 3,782 after one frame). Now both are
/// `GpuError::NonFinite`, naming the frame, the walkers and the first of them.
#[test]
fn an_overflowing_model_gives_an_error_not_nan() {
    let Some(gpu) = gpu() else {
        return;
    };
    let model = model();
    let bad = edited(model, |p| {
        p.keys
            .iter_mut()
            .for_each(|k| k.core.iter_mut().for_each(|v| *v = 3e38))
    });
    let full = FullDetail::for_model(bad.lod());
    let mut crowd = GpuCrowd::new(gpu, &bad, config(40), GpuOptions::default()).expect("crowd");
    let cam = camera(&crowd, Scene::Overview, 0);
    for f in 1..=2u64 {
        let e = crowd.step(&full, &cam, DT).unwrap_err();
        let GpuError::NonFinite {
            frame,
            walkers,
            first,
        } = e
        else {
            panic!("frame {f}: {e}")
        };
        assert_eq!(frame, f);
        assert!(walkers > 0 && walkers <= 40 && first < 40, "{e}");
        let e = crowd.read_walkers().unwrap_err();
        assert!(
            matches!(e, GpuError::NonFinite { frame, first: w, .. } if frame == f && w == first),
            "{e}"
        );
    }
    // The model itself, unchanged, stays finite and Ok.
    let mut ok = GpuCrowd::new(gpu, model, config(40), GpuOptions::default()).expect("crowd");
    let full = FullDetail::for_model(model.lod());
    for _ in 0..3 {
        ok.step(&full, &cam, DT).unwrap();
    }
    let walkers = ok.read_walkers().unwrap();
    assert!(
        walkers
            .iter()
            .all(|w| w.positions.iter().all(|p| p.is_finite()))
    );
}

/// A model number that single precision cannot hold (a variogram sill of 1e300, a time scale of
/// 1e-300) became `inf` in the shaders' source: `GpuCrowd::new` failed with a WGSL parse error
/// as a "GPU device error". Now `GpuError::Model` names the number.
#[test]
fn model_numbers_beyond_single_precision_are_model_errors() {
    let Some(gpu) = gpu() else {
        return;
    };
    let model = model();
    type Edit = Box<dyn Fn(&mut lod_policy::ModelParts)>;
    let cases: [(&str, Edit); 2] = [
        (
            "the variogram's sill is 1e300",
            Box::new(|p| p.controls.variogram.sill = 1e300),
        ),
        ("1 / the time scale is", Box::new(|p| p.time_scale = 1e-300)),
    ];
    for (what, edit) in cases {
        let bad = edited(model, edit);
        let e = GpuCrowd::new(gpu, &bad, config(10), GpuOptions::default()).unwrap_err();
        assert!(
            matches!(&e, GpuError::Model(m) if m.contains(what) && m.contains("single precision")),
            "{what}: {e}"
        );
    }
}

/// `GpuOptions::page_walkers = Some(0)` was taken as one walker a page: a page (ten buffers, a
/// dispatch chain) per walker, 17 s for five frames of 3,000 walkers on lavapipe. Now an error.
#[test]
fn zero_walkers_a_page_is_an_error() {
    let Some(gpu) = gpu() else {
        return;
    };
    let options = GpuOptions {
        page_walkers: Some(0),
        ..GpuOptions::default()
    };
    let e = GpuCrowd::new(gpu, model(), config(10), options).unwrap_err();
    assert!(
        matches!(&e, GpuError::Config(m) if m.contains("page_walkers = Some(0)")),
        "{e}"
    );
    // One walker a page, and no joint slot at all, still run.
    let options = GpuOptions {
        page_walkers: Some(1),
        joint_slots: Some(0),
    };
    let mut crowd = GpuCrowd::new(gpu, model(), config(3), options).expect("crowd");
    assert_eq!(crowd.pages(), 3);
    let full = FullDetail::for_model(model().lod());
    let cam = camera(&crowd, Scene::Overview, 0);
    let stats = crowd.step(&full, &cam, DT).unwrap();
    assert_eq!(*stats.level_histogram.last().unwrap(), 3);
}

/// The environment variable under which a test of this file runs its case in a child process:
/// the test's name (see [`in_child`]).
const CHILD_ENV: &str = "GPU_CROWD_ROBUSTNESS_CHILD";

/// Whether this process is the child running `test`.
fn is_child(test: &str) -> bool {
    std::env::var(CHILD_ENV).is_ok_and(|v| v == test)
}

/// Runs `test` alone in a child process of this test binary, with `envs` set and its address
/// space limited to `limit_kb` (through `sh`'s `ulimit -v`), and asserts that it passed. `None`
/// where there is no `sh` (not Unix).
fn in_child(test: &str, envs: &[(&str, &str)], limit_kb: u64) -> Option<()> {
    if !cfg!(unix) {
        return None;
    }
    let exe = std::env::current_exe().expect("test binary");
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {limit_kb} && exec \"$0\" --exact {test} --nocapture --test-threads 1"
        ))
        .arg(exe)
        .env(CHILD_ENV, test)
        .envs(envs.iter().copied())
        .output()
        .expect("sh");
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{test} failed in its child: {text}");
    assert!(
        text.contains("1 passed"),
        "{test} did not run in its child: {text}"
    );
    Some(())
}

/// A crowd whose buffers the device cannot allocate (a million walkers, 12.5 GB, in an address
/// space of 8 GB: lavapipe's device memory is the process's): wgpu panicked ("Buffer with
/// 'walkers' label is invalid", mapping a buffer made with its contents). Now
/// `GpuError::Memory`, with the bytes asked for. Runs in a child process under `ulimit -v`
/// (Unix, software adapters; skipped elsewhere).
#[test]
fn buffers_the_device_cannot_hold_are_an_error() {
    const TEST: &str = "buffers_the_device_cannot_hold_are_an_error";
    if !is_child(TEST) {
        // Only where the device's memory is the process's (a software adapter): a GPU driver
        // may need more address space than the limit just to open the device.
        match gpu() {
            Some(g) if g.is_software() => {
                in_child(TEST, &[], 8_000_000);
            }
            Some(g) => println!("skipped: {} is not a software adapter", g.adapter_name()),
            None => {}
        }
        return;
    }
    let Some(gpu) = gpu() else {
        return;
    };
    let walkers = 1_000_000;
    match GpuCrowd::new(gpu, model(), config(walkers), GpuOptions::default()) {
        Err(GpuError::Memory {
            what,
            bytes,
            walkers: w,
            ..
        }) => {
            assert_eq!((what, w), ("the crowd's buffers", walkers));
            assert!(bytes > 8_000_000_000, "{bytes}");
        }
        Err(e) => panic!("{e}"),
        // A device whose memory is not the process's (a GPU): nothing to check.
        Ok(crowd) => println!("a crowd of {} bytes fits", crowd.gpu_bytes()),
    }
}

/// `WGPU_BACKEND` naming no backend compiled in (`dx12` in a Vulkan build, or a misspelling):
/// `GpuError::NoAdapter` said "No Vulkan driver was found" and how to install one, though
/// Vulkan was never tried. Now it says that no backend compiled in was allowed. (In a child
/// process: the variable would change the adapter of the other tests.)
#[test]
fn a_backend_restriction_excluding_every_backend_says_so() {
    const TEST: &str = "a_backend_restriction_excluding_every_backend_says_so";
    if !is_child(TEST) {
        for backend in ["dx12", "vulkn"] {
            if cfg!(feature = "vulkan") && !cfg!(feature = "dx12") {
                in_child(TEST, &[("WGPU_BACKEND", backend)], 8_000_000);
            }
        }
        return;
    }
    let e = Gpu::new().unwrap_err();
    let GpuError::NoAdapter { what } = &e else {
        panic!("{e}")
    };
    assert!(
        what.contains("None of the backends compiled in was allowed")
            && what.contains("WGPU_BACKEND=")
            && !what.contains("No Vulkan driver"),
        "{e}"
    );
}

/// A model without feet (one rebuilt from its parts without a `FootRig`) with the foot lock asked:
/// the CPU source locks nothing there, and so does the GPU crowd. It runs, its joint slots hold no
/// lock state (the bytes of a crowd with the lock off), and no frame reports a locked leg, where
/// the same crowd over the model with feet locks legs and pays for the state.
#[test]
fn a_model_without_feet_runs_with_the_lock_asked_and_locks_nothing() {
    let Some(gpu) = gpu() else {
        return;
    };
    let feetless = edited(model(), |_| {});
    assert!(feetless.feet().is_none() && model().feet().is_some());
    let lock = CrowdConfig {
        foot_lock_levels: usize::MAX,
        ..config(300)
    };
    let slot_bytes = |m: &RuntimeModel, c: CrowdConfig| {
        GpuCrowd::new(gpu, m, c, GpuOptions::default())
            .expect("crowd")
            .bytes_per_joint_slot()
    };
    assert_eq!(
        slot_bytes(&feetless, lock),
        slot_bytes(&feetless, config(300))
    );
    assert!(slot_bytes(model(), lock) > slot_bytes(model(), config(300)));
    let locked = |m: &RuntimeModel| {
        let mut crowd = GpuCrowd::new(gpu, m, lock, GpuOptions::default()).expect("crowd");
        let policy = FullDetail::for_model(m.lod());
        (0..30)
            .map(|f| {
                let camera = camera(&crowd, Scene::Ground, f);
                crowd.step(&policy, &camera, DT).expect("step").feet_locked
            })
            .sum::<u64>()
    };
    assert_eq!(locked(&feetless), 0);
    assert!(locked(model()) > 0);
}
