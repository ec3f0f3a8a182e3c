//! Crowds of walkers driven by the model: [`run_crowd`] steps a crowd under any of `lod-policy`'s
//! policies ([`LevelPolicy`]: the crowd speaks the runtime's [`Detail`](lod_policy::Detail) and
//! resolves it once against the source's level table), times it and optionally renders it.

use std::path::Path;

use crowd_sim::render::{Recorder, RenderStyle};
use crowd_sim::{
    Camera, ClipSource, Crowd, CrowdConfig, CrowdError, CrowdReport, FrameStats, RenderError, Scene,
};
use lod_policy::LevelPolicy;

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
    /// The field size used, metres.
    pub field_m: f32,
    /// The field size asked for, when the source's turn range needed a larger one
    /// ([`Crowd::field_enlarged_from`]).
    pub field_enlarged_from: Option<f32>,
}

/// Steps a crowd of `source` under `policy` for `run.seconds`, timing every frame; renders every n-th
/// frame when asked (rendering time is not counted).
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
    let mut report = CrowdReport::new();
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
    let gif = match recorder {
        Some(rec) => rec.finish()?,
        None => None,
    };
    Ok(CrowdOutcome {
        report,
        last,
        rendered,
        gif,
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
