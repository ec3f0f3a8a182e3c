//! Per-frame timings and level histograms, and their aggregate over a run.

use crate::error::ClipError;
use std::time::Duration;

/// Clips a source could not build during one frame ([`ClipSource::build_clip`] errors): each such
/// walker kept its previous clip.
///
/// [`ClipSource::build_clip`]: crate::ClipSource::build_clip
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ClipFaults {
    /// Failed builds.
    pub count: usize,
    /// The failing walker with the lowest index, and the source's error.
    pub first: Option<(usize, ClipError)>,
}

impl ClipFaults {
    /// Counts `count` failed builds of `walker`'s clips, the first of which gave `error`.
    pub fn record(&mut self, walker: usize, count: usize, error: ClipError) {
        self.count += count;
        if self.first.as_ref().is_none_or(|(w, _)| walker < *w) {
            self.first = Some((walker, error));
        }
    }

    /// The faults of two sets of walkers together.
    pub fn merge(a: ClipFaults, b: ClipFaults) -> ClipFaults {
        let first = match (a.first, b.first) {
            (Some(x), Some(y)) => Some(if x.0 <= y.0 { x } else { y }),
            (x, y) => x.or(y),
        };
        ClipFaults {
            count: a.count + b.count,
            first,
        }
    }
}

/// Wall-clock time of each stage of one crowd frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimings {
    /// Culling: the frustum test of every walker box ([`Culling::Scan`](crate::Culling)), or the
    /// culling tree refit or rebuild and its query ([`Culling::Tree`](crate::Culling)).
    pub cull: Duration,
    /// Detail choice, cycle scheduling and clip kernels (`ClipSource::build_clip`).
    pub kernels: Duration,
    /// Pose vectors (`ClipSource::pose`) and seam transitions.
    pub poses: Duration,
    /// Forward kinematics (`ClipSource::joints`) and placement in the world.
    pub fk: Duration,
}

impl StageTimings {
    /// Sum of all stages: the simulation and synthesis cost of the frame (no rendering).
    pub fn total(&self) -> Duration {
        self.cull + self.kernels + self.poses + self.fk
    }

    fn add(&mut self, o: &StageTimings) {
        self.cull += o.cull;
        self.kernels += o.kernels;
        self.poses += o.poses;
        self.fk += o.fk;
    }
}

/// What one `Crowd::step` did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameStats {
    /// Time per stage.
    pub timings: StageTimings,
    /// Walkers per histogram bin: bin `l < accuracy_levels` counts walkers whose clip is at
    /// accuracy `l` with joints; the last bin counts root-only walkers. Sums to the walker count.
    pub level_histogram: Vec<u32>,
    /// Walkers whose bounds intersect the view frustum.
    pub visible: usize,
    /// Clip kernels built during the frame (cycle changes and detail upgrades).
    pub kernels_built: usize,
    /// Walkers inside a seam transition (`lod_policy::SeamTransition`).
    pub in_transition: usize,
    /// Clips the source failed to build (those walkers kept their previous clips).
    pub clip_faults: ClipFaults,
    /// Buffers the frame allocated or freed for its walkers: clips, seam transitions and foot locks
    /// the crowd's stock made because it had none to lend, or freed because its queue was full.
    /// Zero once the stock holds as many of each as its walkers ever needed at once (the frame
    /// loop allocates nothing else, but for a culling tree's rebuild).
    pub allocations: usize,
}

/// Aggregate of many frames: frames per second worst/mean/best and summed histograms.
///
/// The frame rate counts simulation, synthesis and forward kinematics (the stage timings), not
/// rendering; the mean is `frames / total time` (the harmonic mean of per-frame rates).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CrowdReport {
    /// Frames added.
    pub frames: usize,
    /// Lowest per-frame rate (1 / slowest frame).
    pub fps_worst: f64,
    /// `frames / total time`.
    pub fps_mean: f64,
    /// Highest per-frame rate (1 / fastest frame).
    pub fps_best: f64,
    /// Summed stage timings.
    pub total: StageTimings,
    /// Level histogram summed over frames (walker-frames per bin).
    pub level_histogram: Vec<u64>,
    /// Summed visible walker counts.
    pub visible_sum: u64,
    /// Summed kernel builds.
    pub kernels_built: u64,
    /// Summed failed clip builds ([`FrameStats::clip_faults`]).
    pub clip_faults: u64,
    /// The first failed clip build of the run: frame index (from 0), walker and error.
    pub first_clip_fault: Option<(usize, usize, ClipError)>,
    /// Every frame's time (simulation, synthesis, forward kinematics), seconds, in frame order:
    /// what [`CrowdReport::frame_times`] takes its percentiles from.
    pub frame_s: Vec<f64>,
    /// Every frame's [`FrameStats::allocations`], in frame order.
    pub frame_allocations: Vec<usize>,
}

/// Percentiles of frame times after a warm-up ([`CrowdReport::frame_times`]), milliseconds:
/// what a game drops frames at, beside the mean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameTimes {
    /// Frames counted (after the warm-up).
    pub frames: usize,
    /// Median frame time (nearest rank).
    pub p50_ms: f64,
    /// 99th percentile (nearest rank: the frame below which 99 % of frames fall).
    pub p99_ms: f64,
    /// The slowest frame.
    pub worst_ms: f64,
}

impl FrameTimes {
    /// Median, 99th percentile and worst of `seconds` (frame times in seconds, any order;
    /// nearest-rank percentiles: the value at rank `ceil(q n)` of the `n` sorted times); `None` when
    /// `seconds` is empty or holds a time that is not one (NaN, infinite or negative): such a
    /// slice is refused whole, not filtered, so that the figures never come from some of the
    /// frames only. [`CrowdReport::frame_times`] takes its figures from here.
    pub fn of_seconds(seconds: &[f64]) -> Option<FrameTimes> {
        if seconds.is_empty() || !seconds.iter().all(|s| s.is_finite() && *s >= 0.0) {
            return None;
        }
        let mut v = seconds.to_vec();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let rank = |q: f64| v[((q * n as f64).ceil() as usize).clamp(1, n) - 1] * 1e3;
        Some(FrameTimes {
            frames: n,
            p50_ms: rank(0.5),
            p99_ms: rank(0.99),
            worst_ms: v[n - 1] * 1e3,
        })
    }

    /// The slowest frame over the median (1 for perfectly even frames).
    pub fn worst_over_median(&self) -> f64 {
        self.worst_ms / self.p50_ms.max(1e-12)
    }
}

impl CrowdReport {
    /// An empty report.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty report with room for `frames` frame times, so that adding that many frames does
    /// not allocate inside a frame loop. The room is a hint: at most
    /// [`CrowdReport::MAX_RESERVED_FRAMES`] frames, and none when the system refuses the memory
    /// (frames beyond it are still added, growing the report as they come).
    pub fn with_frames(frames: usize) -> Self {
        let room = frames.min(Self::MAX_RESERVED_FRAMES);
        let mut report = Self::default();
        if report.frame_s.try_reserve_exact(room).is_ok()
            && report.frame_allocations.try_reserve_exact(room).is_err()
        {
            report.frame_s = Vec::new();
        }
        report
    }

    /// Most frames [`CrowdReport::with_frames`] makes room for up front: 2^24 (155 hours at
    /// 30 fps; 256 MiB of frame times and allocation counts).
    pub const MAX_RESERVED_FRAMES: usize = 1 << 24;

    /// Adds one frame.
    pub fn add(&mut self, f: &FrameStats) {
        let secs = f.timings.total().as_secs_f64().max(1e-9);
        let fps = 1.0 / secs;
        if self.frames == 0 {
            self.fps_worst = fps;
            self.fps_best = fps;
        } else {
            self.fps_worst = self.fps_worst.min(fps);
            self.fps_best = self.fps_best.max(fps);
        }
        if let (None, Some((walker, e))) = (&self.first_clip_fault, &f.clip_faults.first) {
            self.first_clip_fault = Some((self.frames, *walker, e.clone()));
        }
        self.clip_faults += f.clip_faults.count as u64;
        self.frames += 1;
        self.total.add(&f.timings);
        self.fps_mean = self.frames as f64 / self.total.total().as_secs_f64().max(1e-9);
        if self.level_histogram.len() < f.level_histogram.len() {
            self.level_histogram.resize(f.level_histogram.len(), 0);
        }
        for (a, b) in self.level_histogram.iter_mut().zip(&f.level_histogram) {
            *a += u64::from(*b);
        }
        self.visible_sum += f.visible as u64;
        self.kernels_built += f.kernels_built as u64;
        self.frame_s.push(secs);
        self.frame_allocations.push(f.allocations);
    }

    /// Buffers allocated by the frames after the first `warmup` ([`FrameStats::allocations`]),
    /// and how many of those frames allocated.
    pub fn allocations(&self, warmup: usize) -> (usize, usize) {
        let after = self.frame_allocations.get(warmup..).unwrap_or(&[]);
        (after.iter().sum(), after.iter().filter(|&&a| a > 0).count())
    }

    /// Median, 99th percentile and worst frame time of the frames after the first `warmup`
    /// (nearest-rank percentiles: the value at rank `ceil(q n)` of the `n` sorted times); `None`
    /// when no frame is left.
    pub fn frame_times(&self, warmup: usize) -> Option<FrameTimes> {
        FrameTimes::of_seconds(self.frame_s.get(warmup..)?)
    }

    /// Mean stage timings per frame: the sums divided by `frames` (at least 1), in integer
    /// nanoseconds below 2^32 frames and in floating point beyond (a `Duration` divides by a `u32`).
    pub fn mean_timings(&self) -> StageTimings {
        let n = self.frames.max(1);
        let mean = |d: Duration| match u32::try_from(n) {
            Ok(n) => d / n,
            Err(_) => d.div_f64(n as f64),
        };
        StageTimings {
            cull: mean(self.total.cull),
            kernels: mean(self.total.kernels),
            poses: mean(self.total.poses),
            fk: mean(self.total.fk),
        }
    }

    /// Mean number of visible walkers per frame.
    pub fn mean_visible(&self) -> f64 {
        self.visible_sum as f64 / self.frames.max(1) as f64
    }
}

impl std::fmt::Display for CrowdReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = self.mean_timings();
        writeln!(
            f,
            "{} frames: fps worst {:.1} / mean {:.1} / best {:.1}",
            self.frames, self.fps_worst, self.fps_mean, self.fps_best
        )?;
        writeln!(
            f,
            "mean per frame: cull {:?}, kernels {:?}, poses {:?}, fk {:?}; visible {:.0}",
            m.cull,
            m.kernels,
            m.poses,
            m.fk,
            self.mean_visible()
        )?;
        writeln!(
            f,
            "clip kernels built per frame: {:.0}",
            self.kernels_built as f64 / self.frames.max(1) as f64
        )?;
        write!(
            f,
            "level histogram (walker-frames, last = root only): {:?}",
            self.level_histogram
        )?;
        if let Some((frame, walker, e)) = &self.first_clip_fault {
            write!(
                f,
                "\nclip faults: {} (walkers kept their previous clips); first: frame {frame}, \
                 walker {walker}: {e}",
                self.clip_faults
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_aggregates_fps_and_histograms() {
        let mut r = CrowdReport::new();
        let frame = |ms: u64, h: Vec<u32>| FrameStats {
            timings: StageTimings {
                kernels: Duration::from_millis(ms),
                ..Default::default()
            },
            level_histogram: h,
            visible: 3,
            ..Default::default()
        };
        r.add(&frame(10, vec![1, 2]));
        r.add(&frame(40, vec![3, 0]));
        assert_eq!(r.frames, 2);
        assert!((r.fps_best - 100.0).abs() < 1e-6);
        assert!((r.fps_worst - 25.0).abs() < 1e-6);
        assert!((r.fps_mean - 40.0).abs() < 1e-6);
        assert_eq!(r.level_histogram, vec![4, 2]);
        assert_eq!(r.mean_visible(), 3.0);
        assert!(r.to_string().contains("fps worst 25.0"));
        assert!(!r.to_string().contains("clip faults"));
    }

    #[test]
    fn frame_times_are_nearest_rank_percentiles_after_the_warm_up() {
        let mut r = CrowdReport::new();
        let frame = |ms: u64| FrameStats {
            timings: StageTimings {
                poses: Duration::from_millis(ms),
                ..Default::default()
            },
            ..Default::default()
        };
        // A slow first frame (the warm-up), then 1..=100 ms in shuffled order.
        r.add(&frame(5000));
        for i in 0..100u64 {
            r.add(&frame((i * 37) % 100 + 1));
        }
        let t = r.frame_times(1).unwrap();
        assert_eq!(t.frames, 100);
        assert!((t.p50_ms - 50.0).abs() < 1e-9, "{t:?}");
        assert!((t.p99_ms - 99.0).abs() < 1e-9, "{t:?}");
        assert!((t.worst_ms - 100.0).abs() < 1e-9, "{t:?}");
        assert!((t.worst_over_median() - 2.0).abs() < 1e-9);
        // Counting the warm-up frame makes it the worst.
        assert!((r.frame_times(0).unwrap().worst_ms - 5000.0).abs() < 1e-9);
        assert_eq!(r.frame_times(101), None);
        assert_eq!(r.frame_times(500), None);
    }

    #[test]
    fn clip_faults_keep_the_lowest_walker_and_are_reported() {
        let mut a = ClipFaults::default();
        a.record(9, 1, ClipError("late".into()));
        a.record(4, 1, ClipError("early".into()));
        let mut b = ClipFaults::default();
        b.record(6, 1, ClipError("middle".into()));
        let m = ClipFaults::merge(b, a);
        assert_eq!(m.count, 3);
        assert_eq!(m.first, Some((4, ClipError("early".into()))));
        let mut r = CrowdReport::new();
        r.add(&FrameStats::default());
        r.add(&FrameStats {
            clip_faults: m,
            ..Default::default()
        });
        assert_eq!(r.clip_faults, 3);
        let text = r.to_string();
        assert!(text.contains("clip faults: 3"), "{text}");
        assert!(text.contains("frame 1, walker 4: early"), "{text}");
    }
}
