//! Crowds of walkers driven by the model: [`run_crowd`] steps a crowd under any of `lod-policy`'s
//! policies ([`LevelPolicy`]: the crowd speaks the runtime's [`Detail`](lod_policy::Detail) and
//! resolves it once against the source's level table), times it and optionally renders it.

use std::path::Path;

use crowd_sim::render::{Recorder, RenderStyle};
use crowd_sim::{
    Camera, ClipSource, Crowd, CrowdConfig, CrowdError, CrowdReport, FrameStats, RenderError, Scene,
};
use lod_policy::LevelPolicy;

use crate::model::MotionModel;
use crate::quality::MotionQuality;

/// How to run a crowd.
#[derive(Debug, Clone)]
pub struct CrowdRun {
    /// Walkers, field, seed, frame rate.
    pub config: CrowdConfig,
    /// Simulated seconds.
    pub seconds: f32,
    /// The camera's lens (its position follows the scene's camera path, [`Scene::path`]; its far
    /// plane is the scene's, [`Scene::lens`]).
    pub lens: Camera,
    /// Where the camera is: walking inside the crowd or circling above it.
    pub scene: Scene,
    /// Render every n-th frame into this folder (PNG frames, maps, GIF), if set.
    pub render: Option<(std::path::PathBuf, usize)>,
}

/// Why a crowd run failed.
#[derive(Debug, thiserror::Error)]
pub enum CrowdRunError {
    /// The crowd rejected its settings or a frame.
    #[error("crowd: {0}")]
    Crowd(#[from] CrowdError),
    /// A frame could not be rendered or written.
    #[error("rendering: {0}")]
    Render(#[from] RenderError),
    /// The duration is not a positive number.
    #[error("simulated time {0} s is not a positive number")]
    Seconds(f32),
}

/// What a run measured.
#[derive(Debug, Clone)]
pub struct CrowdOutcome {
    /// Frame rates and summed stage timings over the run (rendering excluded).
    pub report: CrowdReport,
    /// The last frame's statistics (its level histogram sums to the walker count).
    pub last: FrameStats,
    /// Frames rendered (each a perspective PNG and a top-down map PNG).
    pub rendered: usize,
    /// The animated GIF written at the end, if any.
    pub gif: Option<std::path::PathBuf>,
    /// Files an earlier recording into the render folder had left under the recorder's names
    /// (frames past this run's last, its GIF), removed ([`crowd_sim::render::Recorder::finish`]).
    pub stale_removed: usize,
    /// The field size used, metres.
    pub field_m: f32,
    /// The field size asked for, when the source's turn range needed a larger one
    /// ([`Crowd::field_enlarged_from`]).
    pub field_enlarged_from: Option<f32>,
}

/// Steps a crowd of `source` under `policy` for `run.seconds`, timing every frame; renders every n-th
/// frame when asked (rendering time is not counted; a rendered crowd is primed first,
/// [`Crowd::prime`], so that its first frame shows every walker mid-stride at its detail).
pub fn run_crowd<S, P>(
    source: &S,
    policy: &P,
    run: &CrowdRun,
) -> Result<CrowdOutcome, CrowdRunError>
where
    S: ClipSource,
    P: LevelPolicy + Sync,
{
    if !(run.seconds.is_finite() && run.seconds > 0.0) {
        return Err(CrowdRunError::Seconds(run.seconds));
    }
    let mut crowd = Crowd::new(source, run.config)?;
    // The field the crowd uses (enlarged when the source's turn range needs larger paths).
    let field = crowd.config().field_size_m;
    let path = run.scene.path(field);
    let lens = run.scene.lens(run.lens, field);
    let frames = ((run.seconds * run.config.fps).round() as usize).max(1);
    let dt = 1.0 / run.config.fps;
    let mut recorder = match &run.render {
        Some((dir, _)) => Some(Recorder::new(dir, render_style(source))?),
        None => None,
    };
    if recorder.is_some() {
        // A crowd that is watched starts mid-stride: every walker's clip at its detail before the
        // first frame (timed runs keep the spread of first builds over the first cycle).
        crowd.prime(source, policy, &path.camera_at(0.0, &lens))?;
    }
    let mut report = CrowdReport::with_frames(frames);
    let mut last = FrameStats::default();
    let mut rendered = 0;
    for f in 0..frames {
        let camera = path.camera_at(f as f32 * dt, &lens);
        crowd.step_into(source, policy, &camera, dt, &mut last)?;
        report.add(&last);
        if let (Some(rec), Some((_, every))) = (recorder.as_mut(), &run.render)
            && f % (*every).max(1) == 0
        {
            rec.record(&crowd, &camera)?;
            rendered += 1;
        }
    }
    let (gif, stale_removed) = match recorder {
        Some(rec) => {
            let done = rec.finish()?;
            (done.gif, done.stale_removed)
        }
        None => (None, 0),
    };
    Ok(CrowdOutcome {
        report,
        last,
        rendered,
        gif,
        stale_removed,
        field_m: crowd.config().field_size_m,
        field_enlarged_from: crowd.field_enlarged_from(),
    })
}

fn render_style<S: ClipSource>(_source: &S) -> RenderStyle {
    RenderStyle {
        map: true,
        gif_every: 1,
        ..RenderStyle::default()
    }
}

/// Whether `dir` can be written (created when missing): checked before a long run starts.
pub fn check_render_dir(dir: &Path) -> Result<(), RenderError> {
    Recorder::new(dir, RenderStyle::default()).map(|_| ())
}

/// What one crowd walker showed, frame by frame: the motion-quality meter's input
/// ([`measure_track`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WalkerTrack {
    /// The walker's index in the crowd.
    pub walker: usize,
    /// World-frame pose vectors, `frames x P` (metres, y up; rows the clip did not write hold the
    /// layout's rest rotations, as the runtime's forward kinematics uses them).
    pub poses: Vec<f64>,
    /// Frames at which a new cycle started (the walker's cycle frame moved).
    pub seams: Vec<usize>,
    /// Accuracy level shown at every frame.
    pub levels: Vec<usize>,
    /// Active joints shown at every frame.
    pub joints: Vec<usize>,
    /// The walker's body scale ([`MotionModel::body_scale`] of its height): its bones are
    /// the skeleton's times this.
    pub body_scale: f64,
    /// Whether the walker was in the camera's view at every frame.
    pub visible: Vec<bool>,
}

/// Runs a crowd of the model for `frames` frames of `1 / config.fps` s under `policy`, the camera
/// on `scene`'s path, and records what `walkers` showed, as the crowd plays it: seams between
/// cycles of changing controls, levels that change with distance, planted feet near the camera.
/// The crowd is primed ([`Crowd::prime`]) with the first frame's camera, as an exported crowd is:
/// every walker starts at its own phase of its first cycle with a clip at the detail the policy
/// gives it there, so frame 0 looks like frame 100 (no walker starts root-only and snaps into
/// walking). The same tracks for any thread count. Walker indices beyond the crowd are ignored.
///
/// # Errors
/// The crowd's errors ([`Crowd::new`], a frame's step); [`CrowdError::OutOfMemory`] (`what`:
/// `"recorded tracks"`) when the tracks of `frames` frames do not fit in memory (their size past
/// the address space, or the system refuses it), before any frame is run.
pub fn record_walkers<P: LevelPolicy + Sync + ?Sized>(
    model: &MotionModel,
    config: CrowdConfig,
    scene: Scene,
    policy: &P,
    frames: usize,
    walkers: &[usize],
) -> Result<Vec<WalkerTrack>, CrowdError> {
    let source = crate::LodSource::new(model);
    let mut crowd = Crowd::new(&source, config)?;
    let field = crowd.config().field_size_m;
    let (path, lens) = (scene.path(field), scene.lens(Camera::default(), field));
    let dt = 1.0 / config.fps;
    // Every walker starts mid-stride at the detail the policy gives it from the first frame's
    // camera, as an exported crowd does (`Crowd::prime`): frame 0 looks like frame 100.
    crowd.prime(&source, policy, &path.camera_at(0.0, &lens))?;
    let p = model.lod().p();
    let rest = model.layout.rest_pose();
    let mut placed = vec![0.0f32; p];
    let recorded: Vec<usize> = walkers
        .iter()
        .copied()
        .filter(|&i| i < crowd.len())
        .collect();
    let out_of_memory = || CrowdError::OutOfMemory {
        what: "recorded tracks",
        walkers: recorded.len(),
    };
    let mut tracks: Vec<WalkerTrack> = Vec::new();
    tracks
        .try_reserve_exact(recorded.len())
        .map_err(|_| out_of_memory())?;
    for &i in &recorded {
        // The whole recording's buffers, reserved up front: a size past the address space or
        // refused by the system is an error here, not an abort frames later.
        let mut track = WalkerTrack {
            walker: i,
            poses: Vec::new(),
            seams: Vec::new(),
            levels: Vec::new(),
            joints: Vec::new(),
            body_scale: f64::from(model.body_scale(&crowd.controls(i))),
            visible: Vec::new(),
        };
        let values = frames.checked_mul(p).ok_or_else(out_of_memory)?;
        let reserved = track.poses.try_reserve_exact(values).is_ok()
            && track.levels.try_reserve_exact(frames).is_ok()
            && track.joints.try_reserve_exact(frames).is_ok()
            && track.visible.try_reserve_exact(frames).is_ok();
        if !reserved {
            return Err(out_of_memory());
        }
        tracks.push(track);
    }
    let mut frames_of: Vec<Option<lod_policy::CycleFrame>> = vec![None; tracks.len()];
    let mut stats = FrameStats::default();
    for f in 0..frames {
        let camera = path.camera_at(f as f32 * dt, &lens);
        crowd.step_into(&source, policy, &camera, dt, &mut stats)?;
        for (track, last) in tracks.iter_mut().zip(&mut frames_of) {
            let i = track.walker;
            let frame = crowd.cycle_frame(i);
            if last.is_some_and(|l| l != frame) {
                track.seams.push(f);
            }
            *last = Some(frame);
            let shown = crowd.pose(i);
            if shown.len() >= 6 {
                // The rows the clip wrote, the root placed in the world; the rest at rest.
                let placed = &mut placed[..shown.len()];
                placed.copy_from_slice(shown);
                frame.place_root(placed);
                let tail = &rest[placed.len().min(rest.len())..];
                track.poses.extend(
                    placed
                        .iter()
                        .map(|&v| f64::from(v))
                        .chain(tail.iter().copied()),
                );
            } else {
                // No pose this frame (a clip fault): the last one stays on screen.
                match track.poses.len().checked_sub(p) {
                    Some(last) => track.poses.extend_from_within(last..),
                    None => track.poses.extend_from_slice(&rest),
                }
            }
            let d = crowd.detail(i);
            track.levels.push(d.accuracy);
            track.joints.push(d.active_joints);
            track.visible.push(crowd.is_visible(i));
        }
    }
    Ok(tracks)
}

/// One crowd walker measured by the motion-quality meter as the crowd played it
/// ([`crowd_quality`]).
#[derive(Debug, Clone, serde::Serialize)]
pub struct WalkerQuality {
    /// The walker's index in the crowd.
    pub walker: usize,
    /// Frames measured: the walker's longest stretch drawn (in view, with joints) after its first
    /// seam.
    pub frames: usize,
    /// Smallest and largest accuracy level shown in that stretch.
    pub levels: (usize, usize),
    /// Fewest and most joints shown in that stretch.
    pub joints: (usize, usize),
    /// Cycle seams in that stretch.
    pub seams: usize,
    /// The meter's figures.
    pub quality: MotionQuality,
}

/// Why [`crowd_quality`] failed.
#[derive(Debug, thiserror::Error)]
pub enum CrowdQualityError {
    /// The crowd refused its settings or a frame.
    #[error("crowd: {0}")]
    Crowd(#[from] CrowdError),
    /// The simulated time is not a positive number of seconds.
    #[error("simulated time {0} s is not a positive number")]
    Seconds(f32),
    /// The simulated time at the crowd's frame rate is more than
    /// [`MAX_WALK_FRAMES`](crate::synth::MAX_WALK_FRAMES) frames (refused before anything is
    /// allocated).
    #[error(
        "simulated time {seconds} s at {fps} fps is more than {} frames, the most a crowd's \
         walkers are recorded for",
        crate::synth::MAX_WALK_FRAMES
    )]
    TooLong {
        /// The simulated seconds asked for.
        seconds: f32,
        /// The crowd's frame rate.
        fps: f32,
    },
    /// The meter refused a track.
    #[error("walker {walker}: {source}")]
    Quality {
        /// The walker measured.
        walker: usize,
        /// The meter's error.
        source: crate::quality::QualityError,
    },
}

/// Runs a crowd of the model (`config`, camera on `scene`'s path, `policy`) for `seconds` and
/// measures each walker as it was drawn: its longest stretch in view with joints after its first seam
/// (a walker culled or beyond the last level is root-only, drawn by nobody), when that stretch
/// holds at least two cycles' worth of frames (`2 x` the model's longest mean cycle, 1.2 s at 30
/// fps for a 0.6 s cycle); shorter ones are left out. Walkers at the first `config.seam_levels`
/// levels change clips with inertialized seams, those at the first `config.foot_lock_levels` plant
/// their feet (by default every walker with joints), so the figures are the crowd's transitions as
/// a viewer sees them.
///
/// # Errors
/// [`CrowdQualityError::Seconds`] for a time that is not finite and positive,
/// [`CrowdQualityError::TooLong`] for more than [`MAX_WALK_FRAMES`](crate::synth::MAX_WALK_FRAMES)
/// frames, the crowd's errors ([`record_walkers`]) and the meter's for a walker.
pub fn crowd_quality<P: LevelPolicy + Sync + ?Sized>(
    model: &MotionModel,
    config: CrowdConfig,
    scene: Scene,
    policy: &P,
    seconds: f32,
) -> Result<Vec<WalkerQuality>, CrowdQualityError> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(CrowdQualityError::Seconds(seconds));
    }
    // A frame rate that is not finite is the crowd's to refuse (`Crowd::new`).
    if config.fps.is_finite()
        && f64::from(seconds) * f64::from(config.fps) > crate::synth::MAX_WALK_FRAMES as f64
    {
        return Err(CrowdQualityError::TooLong {
            seconds,
            fps: config.fps,
        });
    }
    let frames = (seconds * config.fps).round().max(1.0) as usize;
    let all: Vec<usize> = (0..config.walkers).collect();
    let tracks = record_walkers(model, config, scene, policy, frames, &all)?;
    let dt = 1.0 / f64::from(config.fps);
    let cycle_frames = model
        .report
        .quality
        .as_ref()
        .and_then(|q| q.cycle_steps.iter().map(|s| s.1).reduce(f64::max))
        .unwrap_or(1.0)
        / dt;
    let min_frames = (2.0 * cycle_frames).ceil() as usize;
    let mut out = Vec::new();
    for t in &tracks {
        let first = t.seams.first().copied().unwrap_or(t.joints.len());
        // The longest run of frames drawn (in view, with joints), from the first seam on: a culled
        // walker still evaluated with joints until its cycle ends is seen by nobody.
        let (mut best, mut run_start) = (0..0, None);
        for f in first..=t.joints.len() {
            let drawn = f < t.joints.len() && t.joints[f] > 0 && t.visible[f];
            match (drawn, run_start) {
                (true, None) => run_start = Some(f),
                (false, Some(s)) => {
                    if f - s > best.len() {
                        best = s..f;
                    }
                    run_start = None;
                }
                _ => {}
            }
        }
        if best.len() < min_frames {
            continue;
        }
        let quality = measure_track_range(model, t, dt, best.clone()).map_err(|source| {
            CrowdQualityError::Quality {
                walker: t.walker,
                source,
            }
        })?;
        let span = |v: &[usize]| {
            let v = &v[best.clone()];
            (
                v.iter().copied().min().unwrap_or(0),
                v.iter().copied().max().unwrap_or(0),
            )
        };
        out.push(WalkerQuality {
            walker: t.walker,
            frames: best.len(),
            levels: span(&t.levels),
            joints: span(&t.joints),
            seams: t.seams.iter().filter(|s| best.contains(s)).count(),
            quality,
        });
    }
    Ok(out)
}

/// Measures what a crowd walker showed ([`record_walkers`]) against the model's
/// reference floor, with its seams; `frame_time`: the crowd's `1 / fps`. The cycle duration (the
/// facing window) is the mean time between the track's seams, the track's length with fewer than
/// two. The frames before the first seam are not measured: they are a part of a cycle (or, for a
/// walk recorded from the live page, a start from rest), too short for the stance floor's one-cycle
/// window. A recorded crowd starts mid-stride ([`record_walkers`]); its start is measured with
/// [`measure_track_range`] (the tests compare its first 30 frames with frames 100-130).
pub fn measure_track(
    model: &MotionModel,
    track: &WalkerTrack,
    frame_time: f64,
) -> Result<MotionQuality, crate::quality::QualityError> {
    let dof = model.layout.dof().max(1);
    let start = track.seams.first().copied().unwrap_or(0);
    measure_track_range(model, track, frame_time, start..track.poses.len() / dof)
}

/// [`measure_track`] over the frames `range` of the track only (its seams inside the range).
pub fn measure_track_range(
    model: &MotionModel,
    track: &WalkerTrack,
    frame_time: f64,
    range: std::ops::Range<usize>,
) -> Result<MotionQuality, crate::quality::QualityError> {
    let reference = crate::walk_quality::reference_of(model)?;
    let dof = model.layout.dof().max(1);
    let (start, end) = (range.start, range.end.min(track.poses.len() / dof));
    let poses = track.poses.get(start * dof..end * dof).unwrap_or(&[]);
    let seams: Vec<usize> = track
        .seams
        .iter()
        .filter(|&&s| s >= start && s < end)
        .map(|&s| s - start)
        .collect();
    let frames = poses.len() / dof;
    let cycle_s = match (seams.first(), seams.last()) {
        (Some(&a), Some(&b)) if b > a => (b - a) as f64 / (seams.len() - 1) as f64,
        _ => frames as f64,
    } * frame_time;
    let layout = crate::walk_quality::drawn_layout(model, track.body_scale)?;
    crate::quality::measure(
        &layout,
        &reference.feet,
        poses,
        frame_time,
        Some(reference.floor_m),
        cycle_s,
        &seams,
    )
}
