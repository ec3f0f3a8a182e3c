//! End-to-end tests of the crowd with the procedural source.

use crate::altered::Altered;
use crowd_sim::testing::{ProceduralClip, ProceduralSource, paper_distance_policy};
use crowd_sim::{
    Camera, CameraPath, ClipError, ClipSource, Crowd, CrowdConfig, CrowdError, Culling, Frustum,
    LevelTable,
};
use glam::{Vec2, Vec3};
use lod_policy::{ControlRange, Controls, CycleFrame, Detail, RootMotion, ViewParams};

const DT: f32 = 1.0 / 30.0;

fn config(walkers: usize, field: f32) -> CrowdConfig {
    CrowdConfig {
        walkers,
        field_size_m: field,
        seed: 42,
        ..CrowdConfig::default()
    }
}

fn orbit() -> CameraPath {
    CameraPath::Orbit {
        centre: Vec3::ZERO,
        radius: 25.0,
        height: 6.0,
        period_s: 12.0,
    }
}

fn check_on_paths<S: ClipSource<Clip = ProceduralClip>>(source: &S) {
    let policy = paper_distance_policy(source.levels());
    let cfg = config(150, 60.0);
    let mut crowd = Crowd::new(source, cfg).unwrap();
    let lens = Camera::default();
    let half = 0.5 * cfg.field_size_m;
    let mut worst = 0.0f32;
    for f in 0..600 {
        let cam = orbit().camera_at(f as f32 * DT, &lens);
        crowd.step(source, &policy, &cam, DT).unwrap();
        if f % 10 == 0 {
            for i in 0..crowd.len() {
                let r = crowd.root_position(i);
                assert!(
                    r.x.abs() < half && r.z.abs() < half,
                    "walker {i} left the field at {r}"
                );
                worst = worst.max(crowd.path(i).distance_to(Vec2::new(r.x, r.z)));
            }
        }
    }
    assert!(worst < 0.6, "a walker strayed {worst} m from its path");
}

#[test]
fn walkers_stay_on_their_paths_and_inside_the_field() {
    check_on_paths(&ProceduralSource::new());
}

#[test]
fn path_controller_absorbs_a_biased_source() {
    // A source whose clips move 8 % less than asked and veer slightly right.
    check_on_paths(&Altered {
        controls: |c| Controls {
            dz: 0.92 * c.dz,
            turn: c.turn - 0.03,
            dx: c.dx - 0.02,
            ..*c
        },
        ..Altered::new(ProceduralSource::new())
    });
}

#[test]
fn root_motion_is_continuous_across_cycle_boundaries() {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let mut crowd = Crowd::new(&source, config(120, 50.0)).unwrap();
    let lens = Camera::default();
    let cam = orbit().camera_at(0.0, &lens);
    crowd.step(&source, &policy, &cam, DT).unwrap();
    let mut prev: Vec<Vec3> = (0..crowd.len()).map(|i| crowd.root_position(i)).collect();
    let mut prev_step = vec![f32::NAN; crowd.len()];
    let mut bases: Vec<CycleFrame> = (0..crowd.len()).map(|i| crowd.cycle_frame(i)).collect();
    let mut boundaries = 0;
    for f in 1..240 {
        let cam = orbit().camera_at(f as f32 * DT, &lens);
        crowd.step(&source, &policy, &cam, DT).unwrap();
        for i in 0..crowd.len() {
            let r = crowd.root_position(i);
            let step = r.distance(prev[i]);
            // At most ~1.7 m/s plus sway and bob: 7 cm per frame at 30 fps.
            assert!(step < 0.08, "walker {i} jumped {step} m at frame {f}");
            let base = crowd.cycle_frame(i);
            if base != bases[i] {
                boundaries += 1;
                // The step over a boundary is like its neighbours' (no jump beyond speed changes).
                if prev_step[i].is_finite() {
                    assert!(
                        (step - prev_step[i]).abs() < 0.02,
                        "walker {i}: {step} vs {}",
                        prev_step[i]
                    );
                }
                bases[i] = base;
            }
            prev_step[i] = step;
            prev[i] = r;
        }
    }
    assert!(
        boundaries > 500,
        "only {boundaries} cycle boundaries were crossed"
    );
}

#[test]
fn seams_happen_only_at_the_first_levels_and_are_smooth() {
    let source = ProceduralSource::new();
    let lv = source.levels();
    // Near walkers at level 0, the rest at level 6, all with every joint, all visible or not.
    let policy = |d: f32, _vis: bool, _c: &ViewParams| Detail {
        accuracy: if d < 38.0 { 0 } else { 6 },
        active_joints: lv.joints,
    };
    let cfg = CrowdConfig {
        seam_levels: 2,
        ..config(150, 60.0)
    };
    let mut crowd = Crowd::new(&source, cfg).unwrap();
    let cam = Camera {
        position: Vec3::new(0.0, 30.0, -1.0),
        target: Vec3::ZERO,
        ..Camera::default()
    };
    crowd.step(&source, &policy, &cam, DT).unwrap();
    let mut prev: Vec<Vec<Vec3>> = (0..crowd.len())
        .map(|i| crowd.joint_positions(i).to_vec())
        .collect();
    let (mut blended_frames, mut coarse_frames) = (0, 0);
    let (mut worst_blend, mut worst_steady) = (0.0f32, 0.0f32);
    // 60 fps: limbs move ~5 cm per frame, so a pop between clips would stand out.
    for f in 1..400 {
        let stats = crowd.step(&source, &policy, &cam, 0.5 * DT).unwrap();
        assert_eq!(
            stats.in_transition,
            (0..crowd.len()).filter(|&i| crowd.in_transition(i)).count()
        );
        for (i, prev_i) in prev.iter_mut().enumerate() {
            let d = crowd.detail(i);
            let cur = crowd.joint_positions(i);
            let root_step = cur[0] - prev_i[0];
            // Largest joint motion relative to the root motion.
            let rel = cur
                .iter()
                .zip(prev_i.iter())
                .map(|(a, b)| ((*a - *b) - root_step).length())
                .fold(0.0, f32::max);
            if crowd.in_transition(i) {
                assert!(
                    d.accuracy < 2,
                    "walker {i} blends at level {} in frame {f}",
                    d.accuracy
                );
                blended_frames += 1;
                worst_blend = worst_blend.max(rel);
            } else if d.accuracy >= 2 {
                coarse_frames += 1;
            } else {
                worst_steady = worst_steady.max(rel);
            }
            *prev_i = cur.to_vec();
        }
    }
    assert!(
        blended_frames > 100 && coarse_frames > 100,
        "{blended_frames} {coarse_frames}"
    );
    // Limbs move no faster relative to the root while blending than in steady walking.
    assert!(worst_steady > 0.0);
    assert!(
        worst_blend < 1.2 * worst_steady,
        "blending limb step {worst_blend} vs steady {worst_steady}"
    );
}

#[test]
fn culled_walkers_are_exactly_those_whose_bounds_miss_the_frustum() {
    for culling in [Culling::Scan, Culling::Tree] {
        culled_walkers_are_exact(culling);
    }
}

fn culled_walkers_are_exact(culling: Culling) {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let cfg = CrowdConfig {
        culling,
        tree_rebuild_interval: 7,
        ..config(800, 80.0)
    };
    let mut crowd = Crowd::new(&source, cfg).unwrap();
    let lens = Camera::default();
    let path = CameraPath::inside_crowd(cfg.field_size_m);
    for f in 0..60 {
        let cam = path.camera_at(f as f32 * 0.5, &lens);
        let stats = crowd.step(&source, &policy, &cam, DT).unwrap();
        let fr = Frustum::from_camera(&cam).unwrap();
        let brute: Vec<bool> = crowd.bounds().iter().map(|b| fr.intersects(b)).collect();
        assert_eq!(crowd.visible_flags(), &brute[..], "{culling:?} frame {f}");
        let n = brute.iter().filter(|v| **v).count();
        assert_eq!(stats.visible, n);
        assert!(n > 0 && n < crowd.len(), "frame {f}: {n} visible");
        // Culled walkers are root only under the paper policy.
        for i in (0..crowd.len()).filter(|&i| !brute[i]) {
            if crowd.detail(i).active_joints == 0 {
                assert_eq!(crowd.joint_positions(i).len(), 1);
            }
        }
    }
}

#[test]
fn level_histogram_sums_to_walkers_and_matches_details() {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let mut crowd = Crowd::new(&source, config(500, 300.0)).unwrap();
    let lens = Camera {
        far: 1000.0,
        ..Camera::default()
    };
    let mut report = crowd_sim::CrowdReport::new();
    for f in 0..40 {
        let cam = orbit().camera_at(f as f32, &lens);
        let s = crowd.step(&source, &policy, &cam, DT).unwrap();
        assert_eq!(s.level_histogram.len(), source.levels().accuracy_levels + 1);
        assert_eq!(s.level_histogram.iter().sum::<u32>() as usize, crowd.len());
        for (bin, &count) in s.level_histogram.iter().enumerate() {
            assert_eq!(
                count as usize,
                (0..crowd.len())
                    .filter(|&i| crowd.level_bin(i) == bin)
                    .count()
            );
        }
        report.add(&s);
    }
    let used = report.level_histogram.iter().filter(|&&c| c > 0).count();
    assert!(used >= 4, "levels used: {:?}", report.level_histogram);
    assert!(report.fps_worst <= report.fps_mean && report.fps_mean <= report.fps_best);
}

#[test]
fn bad_input_gives_clear_errors() {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    assert!(matches!(
        Crowd::new(&source, config(0, 50.0)),
        Err(CrowdError::NoWalkers)
    ));
    assert!(matches!(
        Crowd::new(
            &Altered::with_levels(
                source.clone(),
                LevelTable {
                    accuracy_levels: 0,
                    ..source.levels()
                }
            ),
            config(5, 50.0)
        ),
        Err(CrowdError::NoLevels { .. })
    ));
    // A field too small for the source's turn range is enlarged to fit the paths, and says so.
    let small = Crowd::new(&source, config(5, 4.0)).expect("field enlarged");
    assert_eq!(small.field_enlarged_from(), Some(4.0));
    assert!(small.config().field_size_m > 4.0);
    let fits = Crowd::new(&source, config(5, 50.0)).expect("field fits");
    assert_eq!(fits.field_enlarged_from(), None);
    assert_eq!(fits.config().field_size_m, 50.0);
    assert!(matches!(
        Crowd::new(&source, config(5, f32::NAN)),
        Err(CrowdError::BadConfig { .. })
    ));
    let mut crowd = Crowd::new(&source, config(10, 50.0)).unwrap();
    let nan_cam = Camera {
        position: Vec3::new(f32::NAN, 1.0, 0.0),
        ..Camera::default()
    };
    let e = crowd.step(&source, &policy, &nan_cam, DT).unwrap_err();
    assert!(matches!(e, CrowdError::BadCamera { .. }));
    assert!(e.to_string().contains("NaN"));
    assert!(matches!(
        crowd.step(&source, &policy, &Camera::default(), f32::NAN),
        Err(CrowdError::BadTimeStep { .. })
    ));
    // A finite step longer than the crowd takes says the range it is outside, not "not finite".
    let e = crowd
        .step(&source, &policy, &Camera::default(), 100.0)
        .unwrap_err();
    assert_eq!(e.to_string(), "time step dt = 100 s is not in [0, 10] s");
    // A frame rate whose step is longer than that is refused by the config, before any walker.
    for fps in [0.0, 0.05, f32::MIN_POSITIVE] {
        let cfg = CrowdConfig {
            fps,
            ..config(5, 50.0)
        };
        assert!(
            matches!(
                Crowd::new(&source, cfg),
                Err(CrowdError::BadConfig { field: "fps", .. })
            ),
            "{fps}"
        );
    }
    let slow = CrowdConfig {
        fps: 1.0 / crowd_sim::MAX_DT,
        ..config(5, 50.0)
    };
    assert!(Crowd::new(&source, slow).is_ok());
    let greedy = |_: f32, _: bool, _: &ViewParams| Detail {
        accuracy: 99,
        active_joints: 3,
    };
    let e = crowd
        .step(&source, &greedy, &Camera::default(), DT)
        .unwrap_err();
    assert_eq!(
        e,
        CrowdError::BadLevel {
            walker: 0,
            level: 99,
            levels: 10
        }
    );
    // After errors the crowd still steps normally.
    crowd
        .step(&source, &policy, &Camera::default(), DT)
        .unwrap();
}

/// 90 frames of 700 walkers seen from inside the crowd, on `threads` threads, primed with the first
/// frame's camera (`Crowd::prime`) when asked: every joint position, the last visibility flags and
/// every frame's level histogram.
fn run_in_pool(threads: usize, culling: Culling, prime: bool) -> (Vec<Vec3>, Vec<bool>, Vec<u32>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let source = ProceduralSource::new();
        let policy = paper_distance_policy(source.levels());
        let cfg = CrowdConfig {
            culling,
            tree_rebuild_interval: 5,
            ..config(700, 70.0)
        };
        let mut crowd = Crowd::new(&source, cfg).unwrap();
        let lens = Camera::default();
        let path = CameraPath::inside_crowd(cfg.field_size_m);
        let mut hist = Vec::new();
        let mut all = Vec::new();
        if prime {
            let (built, faults) = crowd
                .prime(&source, &policy, &path.camera_at(0.0, &lens))
                .unwrap();
            assert!(built > 0 && faults.count == 0);
        }
        for f in 0..90 {
            let cam = path.camera_at(f as f32 * DT * 4.0, &lens);
            let s = crowd.step(&source, &policy, &cam, DT).unwrap();
            hist.extend(s.level_histogram);
            for i in 0..crowd.len() {
                all.extend_from_slice(crowd.joint_positions(i));
            }
        }
        (all, crowd.visible_flags().to_vec(), hist)
    })
}

#[test]
fn results_are_identical_for_one_and_four_threads_and_both_cullings() {
    let (a, va, ha) = run_in_pool(1, Culling::Scan, false);
    let bits = |v: &[Vec3]| {
        v.iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<u32>>()
    };
    assert!(va.iter().any(|&v| v) && !va.iter().all(|&v| v));
    for (threads, culling) in [(4, Culling::Scan), (1, Culling::Tree), (4, Culling::Tree)] {
        let (b, vb, hb) = run_in_pool(threads, culling, false);
        assert_eq!(a.len(), b.len());
        assert!(
            bits(&a) == bits(&b),
            "joint positions differ: {threads} threads, {culling:?}"
        );
        assert_eq!(va, vb);
        assert_eq!(ha, hb);
    }
}

/// A primed crowd (`Crowd::prime`) is the same for any thread count, and not the unprimed crowd.
#[test]
fn a_primed_crowd_is_the_same_for_one_and_four_threads() {
    let (a, va, ha) = run_in_pool(1, Culling::Scan, true);
    let (b, vb, hb) = run_in_pool(4, Culling::Scan, true);
    let bits = |v: &[Vec3]| {
        v.iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<u32>>()
    };
    assert!(bits(&a) == bits(&b), "joint positions differ");
    assert_eq!((va, ha), (vb, hb));
    let (unprimed, _, _) = run_in_pool(1, Culling::Scan, false);
    assert!(bits(&a) != bits(&unprimed));
}

/// Issue 34: a primed crowd starts mid-stride. Its first frame shows every walker at the detail
/// the policy gives it from the first camera, at its own phase: the frame a crowd that builds every
/// first clip in its first step shows (`spread_first_builds` off), with no clip left to build in
/// that step; a crowd whose first builds are spread shows most of the walkers in view root-only.
#[test]
fn a_primed_crowd_starts_mid_stride_at_its_details() {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let lens = Camera::default();
    let n = 700;
    let start = |prime: bool, spread: bool| {
        let cfg = CrowdConfig {
            spread_first_builds: spread,
            ..config(n, 70.0)
        };
        let mut crowd = Crowd::new(&source, cfg).unwrap();
        let cam = CameraPath::inside_crowd(cfg.field_size_m).camera_at(0.0, &lens);
        let built = if prime {
            crowd.prime(&source, &policy, &cam).unwrap().0
        } else {
            0
        };
        let stats = crowd.step(&source, &policy, &cam, DT).unwrap();
        (crowd, built, stats)
    };
    let (primed, built, first) = start(true, true);
    let (at_once, _, at_once_first) = start(false, false);
    let (spread, _, _) = start(false, true);
    let with_joints = |c: &Crowd<ProceduralClip>| {
        (0..n)
            .filter(|&i| c.is_visible(i) && c.detail(i).active_joints > 0)
            .count()
    };
    let (p, a, s) = (
        with_joints(&primed),
        with_joints(&at_once),
        with_joints(&spread),
    );
    println!(
        "walkers in view with joints at frame 0: primed {p}, built at once {a}, spread {s}; \
         clips built by prime {built}, then in the first step {} (at once: {})",
        first.kernels_built, at_once_first.kernels_built
    );
    assert!(p > 50, "{p} walkers in view with joints");
    assert!(s * 4 < p, "spread {s} against primed {p}");
    assert!(built >= p);
    // The first step builds what any step does: the next clips of the walkers whose cycle ends
    // (about one in 30 at 30 fps), not a clip for every walker in view.
    assert!(first.kernels_built * 10 <= n, "{}", first.kernels_built);
    assert!(first.kernels_built * 10 <= at_once_first.kernels_built);
    // The same poses, up to the phase kept: prime keeps the phase of the root-only clip when it
    // was asked, the other crowd one frame later (clips of other durations map it a little apart).
    let (mut same, mut farthest) = (0, 0.0f32);
    for i in 0..n {
        if primed.detail(i) != at_once.detail(i) {
            continue;
        }
        same += 1;
        let (x, y) = (primed.joint_positions(i), at_once.joint_positions(i));
        assert_eq!(x.len(), y.len(), "walker {i}");
        let far = x
            .iter()
            .zip(y)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f32::max);
        farthest = farthest.max(far);
    }
    println!("frame 0 against the crowd built at once: joints at most {farthest} m apart");
    assert!(farthest < 0.02, "joints {farthest} m apart");
    assert!(
        same * 100 >= 99 * n,
        "{same} of {n} walkers at the same detail"
    );
}

#[test]
fn first_clip_builds_are_spread_over_the_first_cycle() {
    let source = ProceduralSource::new();
    // Every walker wants full detail: without spreading, all of them rebuild in the first frame.
    let full = |_d: f32, _v: bool, _c: &ViewParams| Detail {
        accuracy: 0,
        active_joints: source.levels().joints,
    };
    let built = |spread: bool| -> Vec<usize> {
        let cfg = CrowdConfig {
            spread_first_builds: spread,
            ..config(400, 60.0)
        };
        let mut crowd = Crowd::new(&source, cfg).unwrap();
        (0..60)
            .map(|_| {
                crowd
                    .step(&source, &full, &Camera::default(), DT)
                    .unwrap()
                    .kernels_built
            })
            .collect()
    };
    let at_once = built(false);
    let spread = built(true);
    assert_eq!(at_once[0], 400, "{at_once:?}");
    let most = *spread.iter().max().unwrap();
    assert!(most < 400 / 4, "largest frame built {most}: {spread:?}");
    // By the end of the first cycle every walker holds full detail either way.
    let cfg = CrowdConfig {
        spread_first_builds: true,
        ..config(400, 60.0)
    };
    let mut crowd = Crowd::new(&source, cfg).unwrap();
    let mut last = None;
    for _ in 0..60 {
        last = Some(crowd.step(&source, &full, &Camera::default(), DT).unwrap());
    }
    assert_eq!(last.unwrap().level_histogram[0], 400);
}

#[test]
fn failing_clip_builds_are_counted_and_walkers_keep_their_clips() {
    use crowd_sim::testing::FailingSource;
    let source = FailingSource {
        inner: ProceduralSource::new(),
        every: 7,
    };
    let policy = paper_distance_policy(source.levels());
    let mut crowd = Crowd::new(&source, config(300, 60.0)).unwrap();
    let lens = Camera::default();
    let path = orbit();
    let mut report = crowd_sim::CrowdReport::new();
    let mut prev: Vec<Vec3> = Vec::new();
    for f in 0..240 {
        let cam = path.camera_at(f as f32 * DT, &lens);
        let s = crowd.step(&source, &policy, &cam, DT).unwrap();
        if let Some((walker, e)) = &s.clip_faults.first {
            assert!(s.clip_faults.count >= 1);
            assert!(*walker < crowd.len());
            assert!(e.to_string().contains("test failure"), "{e}");
        } else {
            assert_eq!(s.clip_faults.count, 0);
        }
        report.add(&s);
        // Walkers never jump: a failed build keeps the clip that was playing.
        let roots: Vec<Vec3> = (0..crowd.len())
            .map(|i| crowd.joint_positions(i)[0])
            .collect();
        for (a, b) in prev.iter().zip(&roots) {
            assert!(
                a.distance(*b) < 0.2,
                "a root moved {} m in one frame",
                a.distance(*b)
            );
        }
        for i in 0..crowd.len() {
            let c = crowd.controls(i);
            let held = crowd.detail(i);
            // A walker whose current clip has joints holds one that did build.
            assert!(held.active_joints == 0 || !source.fails(&c, &held));
        }
        prev = roots;
    }
    assert!(
        report.clip_faults > 10,
        "only {} clip faults were counted",
        report.clip_faults
    );
    let text = report.to_string();
    assert!(text.contains("clip faults"), "{text}");
    // The same source without failures counts none.
    let mut clean = Crowd::new(&source.inner, config(300, 60.0)).unwrap();
    for f in 0..60 {
        let cam = path.camera_at(f as f32 * DT, &lens);
        let s = clean.step(&source.inner, &policy, &cam, DT).unwrap();
        assert_eq!(s.clip_faults.count, 0);
    }
}

/// The procedural source with clips of three size classes (the model's compact source has four):
/// root-only details, details with joints at the finest accuracy level, and coarser ones. Counts the builds of each class and
/// those into a clip of the wrong class (a crowd that lends clips from its stock never does one).
struct SizedSource {
    inner: ProceduralSource,
    wrong_size: std::sync::atomic::AtomicUsize,
    made: std::sync::atomic::AtomicUsize,
    built: [std::sync::atomic::AtomicUsize; 3],
}

/// A procedural clip and its size class.
struct SizedClip(ProceduralClip, usize);

impl SizedSource {
    fn new() -> SizedSource {
        SizedSource {
            inner: ProceduralSource::new(),
            wrong_size: 0.into(),
            made: 0.into(),
            built: Default::default(),
        }
    }
}

impl ClipSource for SizedSource {
    type Clip = SizedClip;
    fn levels(&self) -> LevelTable {
        self.inner.levels()
    }
    fn control_range(&self) -> ControlRange {
        self.inner.control_range()
    }
    fn new_clip(&self) -> SizedClip {
        self.made.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        SizedClip(self.inner.new_clip(), 0)
    }
    fn clip_classes(&self) -> usize {
        3
    }
    fn clip_class(&self, d: &Detail) -> usize {
        match (d.active_joints, d.accuracy) {
            (0, _) => 0,
            (_, 0) => 1,
            _ => 2,
        }
    }
    fn new_clip_of_class(&self, class: usize) -> SizedClip {
        self.made.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        SizedClip(self.inner.new_clip(), class)
    }
    fn build_clip(&self, c: &Controls, d: Detail, clip: &mut SizedClip) -> Result<(), ClipError> {
        self.built[self.clip_class(&d)].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if self.clip_class(&d) != clip.1 {
            self.wrong_size
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        self.inner.build_clip(c, d, &mut clip.0)
    }
    fn clip_duration(&self, clip: &SizedClip) -> f32 {
        self.inner.clip_duration(&clip.0)
    }
    fn clip_root_motion(&self, clip: &SizedClip) -> RootMotion {
        self.inner.clip_root_motion(&clip.0)
    }
    fn pose(&self, clip: &SizedClip, t: f32, out: &mut [f32]) -> usize {
        self.inner.pose(&clip.0, t, out)
    }
    fn joints(&self, clip: &SizedClip, pose: &[f32], out: &mut [Vec3]) -> usize {
        self.inner.joints(&clip.0, pose, out)
    }
    fn bones(&self) -> &[(usize, usize)] {
        self.inner.bones()
    }
}

/// Every walker's joint positions after each of `frames` frames around the orbit.
fn joint_trace<S: ClipSource>(
    source: &S,
    walkers: usize,
    frames: usize,
    threads: usize,
) -> (Vec<Vec3>, crowd_sim::CrowdReport) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let policy = paper_distance_policy(source.levels());
        let mut crowd = Crowd::new(source, config(walkers, 150.0)).unwrap();
        let lens = Camera::default();
        let mut report = crowd_sim::CrowdReport::new();
        let mut trace = Vec::new();
        for f in 0..frames {
            let cam = orbit().camera_at(f as f32 * DT, &lens);
            report.add(&crowd.step(source, &policy, &cam, DT).unwrap());
            for i in 0..crowd.len() {
                trace.extend_from_slice(crowd.joint_positions(i));
            }
        }
        (trace, report)
    })
}

#[test]
fn clips_of_three_sizes_are_lent_from_the_stock_and_change_no_frame() {
    let plain = ProceduralSource::new();
    let (want, plain_report) = joint_trace(&plain, 400, 600, 2);
    // A source whose clips are all one size never exchanges clips: only seam transitions and foot
    // locks come from the stock.
    assert!(plain_report.allocations(0).0 > 0);
    for threads in [1, 2, 3] {
        let sized = SizedSource::new();
        let (got, report) = joint_trace(&sized, 400, 600, threads);
        assert!(got == want, "{threads} threads: the frames differ");
        let wrong = sized.wrong_size.load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(
            wrong, 0,
            "{threads} threads: {wrong} builds into a clip of the wrong class"
        );
        let built = sized
            .built
            .each_ref()
            .map(|b| b.load(std::sync::atomic::Ordering::Relaxed));
        assert!(
            built.iter().all(|&b| b > 0),
            "builds per class: {built:?} {:?}",
            report.level_histogram
        );
        // The stock grows while walkers first come near, then lends what it holds: the last
        // third of the run allocates less than a tenth of what the first third did.
        let (first, _) = report.allocations(0);
        let (last, _) = report.allocations(400);
        assert!(
            first > 0 && last * 10 < first,
            "{threads} threads: {first} then {last}"
        );
        // Clips made: one per walker, and the stock's, no more than the walkers ever holding a
        // class at once, for each of the two classes with joints.
        let made = sized.made.load(std::sync::atomic::Ordering::Relaxed);
        assert!(
            made > 400 && made <= 3 * 400,
            "{threads} threads: {made} clips made"
        );
    }
}

#[test]
fn a_failed_build_into_a_lent_clip_keeps_the_walkers_own() {
    use crowd_sim::testing::FailingSource;
    let plain = FailingSource {
        inner: ProceduralSource::new(),
        every: 5,
    };
    let sized = FailingSource {
        inner: SizedSource::new(),
        every: 5,
    };
    let (want, want_report) = joint_trace(&plain, 300, 300, 2);
    let (got, report) = joint_trace(&sized, 300, 300, 2);
    assert!(want_report.clip_faults > 10, "{}", want_report.clip_faults);
    assert_eq!(report.clip_faults, want_report.clip_faults);
    assert!(got == want, "the frames differ");
    assert_eq!(
        sized
            .inner
            .wrong_size
            .load(std::sync::atomic::Ordering::Relaxed),
        0
    );
}
