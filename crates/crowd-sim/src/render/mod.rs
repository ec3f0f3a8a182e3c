//! Software rendering of a crowd: perspective stick figures coloured by level (paper Figure 6),
//! a top-down map with culled walkers and the frustum, PNG frames written atomically and a small
//! animated GIF.
//!
//! ```no_run
//! # use crowd_sim::testing::{ProceduralSource, paper_distance_policy};
//! # use crowd_sim::{Camera, ClipSource, Crowd, CrowdConfig};
//! # use crowd_sim::render::{Recorder, RenderStyle};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let source = ProceduralSource::new();
//! let policy = paper_distance_policy(source.levels());
//! let mut crowd = Crowd::new(&source, CrowdConfig::default())?;
//! let mut rec = Recorder::new("out/crowd", RenderStyle::default())?;
//! let cam = Camera::default();
//! for _ in 0..30 {
//!     crowd.step(&source, &policy, &cam, 1.0 / 30.0)?;
//!     rec.record(&crowd, &cam)?;
//! }
//! rec.finish()?;
//! # Ok(()) }
//! ```

mod image;
mod map;
mod output;
mod perspective;

pub use image::{Image, Rgb};
pub use map::render_map;
pub use output::{Finished, Recorder, write_gif_atomic, write_png_atomic};
pub use perspective::render_frame;

/// Colours and options of the renderers.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderStyle {
    /// Background colour.
    pub background: Rgb,
    /// Ground grid colour.
    pub grid: Rgb,
    /// Ground grid spacing (m); 0 disables the grid.
    pub grid_step_m: f32,
    /// Colour of each accuracy level (cycled when there are more levels).
    pub level_colors: Vec<Rgb>,
    /// Colour of root-only and culled walkers.
    pub root_only: Rgb,
    /// Walkers nearer than this are drawn with 2-pixel lines (m).
    pub thick_within_m: f32,
    /// Also write a top-down map per frame (`map_NNNN.png`).
    pub map: bool,
    /// Side of the map image (pixels).
    pub map_size_px: u32,
    /// Record every n-th frame into the GIF (0 = no GIF).
    pub gif_every: u32,
    /// Downscaling factor of GIF frames.
    pub gif_downscale: u32,
    /// At most this many GIF frames.
    pub gif_max_frames: usize,
}

impl Default for RenderStyle {
    fn default() -> Self {
        Self {
            background: [236, 236, 230],
            grid: [200, 200, 192],
            grid_step_m: 5.0,
            level_colors: vec![
                [220, 30, 30],
                [240, 120, 20],
                [210, 180, 0],
                [60, 170, 40],
                [0, 170, 170],
                [30, 90, 220],
                [110, 50, 200],
                [200, 40, 170],
                [140, 90, 40],
                [90, 90, 90],
            ],
            root_only: [150, 150, 150],
            thick_within_m: 20.0,
            map: true,
            map_size_px: 400,
            gif_every: 2,
            gif_downscale: 2,
            gif_max_frames: 60,
        }
    }
}

impl RenderStyle {
    /// Colour of a level histogram bin (the last bin, root only, uses `root_only`).
    pub fn color_of_bin(&self, bin: usize, accuracy_levels: usize) -> Rgb {
        if bin >= accuracy_levels || self.level_colors.is_empty() {
            self.root_only
        } else {
            self.level_colors[bin % self.level_colors.len()]
        }
    }
}
