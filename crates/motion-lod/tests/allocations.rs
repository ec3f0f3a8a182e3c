//! Issue 35, item 1: the frame loop of a crowd animated by the model allocates nothing but what its
//! stock of lent buffers counts ([`FrameStats::allocations`]: a clip of a size class, a seam
//! transition or a foot lock made when more walkers need one at once than ever before), and that
//! stops once the crowd has warmed up. Counted by a global allocator (every allocation, reallocation
//! and release of the process; this binary runs this one test). A crowd stocked while loading
//! ([`Crowd::reserve`]) for the most walkers near at once allocates nothing from its first frame.
//!
//! Before the stock, a walker's compact clip was resized whenever it gained or lost its joints and
//! its seam transition and foot lock were allocated on first use and kept: 2.5 to 4 allocations a
//! frame at 100,000 walkers, every frame.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use crowd_sim::{Camera, CameraPath, Crowd, CrowdConfig, FrameStats};
use lod_policy::DistancePolicy;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, LodSource, MotionModel};

/// The system allocator, counting every call of every thread.
struct Counting;

static CALLS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; the counter is an atomic.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        CALLS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: per GlobalAlloc's contract.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        CALLS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: per GlobalAlloc's contract.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        CALLS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: per GlobalAlloc's contract.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const DT: f32 = 1.0 / 30.0;
/// Frames run: 40 s at 30 fps.
const FRAMES: usize = 1200;
/// Frames counted as the warm-up: the first 20 s.
const WARMUP: usize = 600;

#[test]
fn the_frame_loop_allocates_only_while_the_stock_grows() {
    let loaded = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .unwrap();
    let model = MotionModel::build(&loaded.training, &BuildConfig::default(), &NoProgress).unwrap();
    let source = LodSource::new(&model);
    let policy = DistancePolicy::for_model(model.lod());
    let config = CrowdConfig {
        seed: 3,
        ..CrowdConfig::with_density(3000, 0.05)
    };
    let path = CameraPath::inside_crowd(config.field_size_m);
    let lens = Camera::default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // Per frame: allocator calls, the stock's count and the walkers with joints; with the stock
    // filled for `reserve` walkers near at once first when given.
    let run = |frames_run: usize, reserve: Option<usize>| -> Vec<(usize, usize, u32)> {
        let mut crowd = Crowd::new(&source, config).unwrap();
        crowd
            .prime(&source, &policy, &path.camera_at(0.0, &lens))
            .unwrap();
        if let Some(near) = reserve {
            assert!(crowd.reserve(&source, near) > 0);
        }
        let mut stats = FrameStats::default();
        let mut frames = Vec::with_capacity(frames_run);
        for f in 0..frames_run {
            let cam = path.camera_at(f as f32 * DT, &lens);
            let before = CALLS.load(Ordering::Relaxed);
            crowd
                .step_into(&source, &policy, &cam, DT, &mut stats)
                .unwrap();
            let calls = CALLS.load(Ordering::Relaxed) - before;
            let root_only = *stats.level_histogram.last().unwrap();
            frames.push((calls, stats.allocations, crowd.len() as u32 - root_only));
        }
        frames
    };
    let frames = pool.install(|| run(FRAMES, None));
    // The first frame sizes the statistics' histogram.
    for (f, &(calls, counted, _)) in frames.iter().enumerate().skip(1) {
        assert!(
            counted > 0 || calls == 0,
            "frame {f}: {calls} allocator calls that the stock did not count"
        );
    }
    let near_min = frames.iter().map(|f| f.2).min().unwrap();
    assert!(near_min > 50, "only {near_min} walkers with joints");
    let growing: usize = frames[1..WARMUP].iter().map(|f| f.1).sum();
    let after: usize = frames[WARMUP..].iter().map(|f| f.1).sum();
    let allocating = frames[WARMUP..].iter().filter(|f| f.0 > 0).count();
    assert!(growing > 0, "the stock never grew");
    assert!(
        allocating <= (FRAMES - WARMUP) / 100,
        "{allocating} of the {} frames after the warm-up allocated ({after} buffers; {growing} \
         during it)",
        FRAMES - WARMUP
    );

    // The same crowd stocked for twice the most walkers with joints seen above (a frame may lend a
    // clip to a walker coming near before one going far gives its back): nothing after the first
    // frame allocates.
    let peak = frames.iter().map(|f| f.2).max().unwrap() as usize;
    let reserved = pool.install(|| run(WARMUP, Some(2 * peak)));
    for (f, &(calls, counted, _)) in reserved.iter().enumerate().skip(1) {
        assert!(
            calls == 0 && counted == 0,
            "frame {f} of the stocked crowd: {calls} allocator calls, {counted} counted"
        );
    }
}
