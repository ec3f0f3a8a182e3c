//! Writing images: PNG and GIF files through a temporary file renamed into place (a failure never
//! leaves a truncated file under the final name), and a recorder for frame sequences.

use super::image::Image;
use super::{RenderStyle, map::render_map, perspective::render_frame};
use crate::camera::Camera;
use crate::crowd::Crowd;
use crate::error::RenderError;
use std::fs::File;
use std::path::{Path, PathBuf};

/// Encodes through `body` into memory, then writes the bytes to `path` atomically
/// ([`lod_policy::file::write_atomic`]: a temporary file renamed over it, removed on failure).
fn write_atomic(
    path: &Path,
    body: impl FnOnce(&mut Vec<u8>) -> Result<(), RenderError>,
) -> Result<(), RenderError> {
    let mut bytes = Vec::new();
    body(&mut bytes)?;
    lod_policy::file::write_atomic(path, &bytes).map_err(|source| RenderError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `img` as an 8-bit RGB PNG at `path`, atomically (temp file + rename).
pub fn write_png_atomic(path: &Path, img: &Image) -> Result<(), RenderError> {
    if img.rgb.len() != img.width as usize * img.height as usize * 3
        || img.width == 0
        || img.height == 0
    {
        return Err(RenderError::BadSize {
            width: img.width,
            height: img.height,
            what: "pixel buffer size mismatch",
        });
    }
    write_atomic(path, |w| {
        let png_err = |e: png::EncodingError| RenderError::Png {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut enc = png::Encoder::new(w, img.width, img.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().map_err(png_err)?;
        wr.write_image_data(&img.rgb).map_err(png_err)?;
        wr.finish().map_err(png_err)
    })
}

/// Writes `frames` (all the size of the first) as a looping animated GIF, `delay_cs`
/// hundredths of a second per frame, each frame quantised to its own 256-colour palette.
pub fn write_gif_atomic(path: &Path, frames: &[Image], delay_cs: u16) -> Result<(), RenderError> {
    let Some(first) = frames.first() else {
        return Err(RenderError::BadSize {
            width: 0,
            height: 0,
            what: "no GIF frames",
        });
    };
    let (w, h) = (first.width, first.height);
    if w > u32::from(u16::MAX)
        || h > u32::from(u16::MAX)
        || frames.iter().any(|f| (f.width, f.height) != (w, h))
    {
        return Err(RenderError::BadSize {
            width: w,
            height: h,
            what: "GIF frames must share a size below 65536",
        });
    }
    write_atomic(path, |out| {
        let gif_err = |e: gif::EncodingError| RenderError::Gif {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut enc = gif::Encoder::new(out, w as u16, h as u16, &[]).map_err(gif_err)?;
        enc.set_repeat(gif::Repeat::Infinite).map_err(gif_err)?;
        for f in frames {
            let mut fr = gif::Frame::from_rgb_speed(w as u16, h as u16, &f.rgb, 10);
            fr.delay = delay_cs;
            enc.write_frame(&fr).map_err(gif_err)?;
        }
        Ok(())
    })
}

/// Writes a rendered sequence into a directory: `frame_NNNNN.png`, optionally `map_NNNNN.png`,
/// and at `finish` an animated `crowd.gif` of downscaled frames.
#[derive(Debug)]
pub struct Recorder {
    dir: PathBuf,
    style: RenderStyle,
    index: usize,
    gif_frames: Vec<Image>,
}

impl Recorder {
    /// Creates `dir` if needed and checks it can be written (a probe file is created and removed).
    pub fn new(dir: impl AsRef<Path>, style: RenderStyle) -> Result<Self, RenderError> {
        let dir = dir.as_ref().to_path_buf();
        let derr = |source| RenderError::Dir {
            path: dir.clone(),
            source,
        };
        std::fs::create_dir_all(&dir).map_err(derr)?;
        let probe = dir.join(".crowd-sim-write-probe");
        File::create(&probe).map_err(derr)?;
        std::fs::remove_file(&probe).map_err(derr)?;
        Ok(Self {
            dir,
            style,
            index: 0,
            gif_frames: Vec::new(),
        })
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Renders and writes the current frame of `crowd` seen by `camera`; returns the PNG path.
    pub fn record<C>(&mut self, crowd: &Crowd<C>, camera: &Camera) -> Result<PathBuf, RenderError> {
        let img = render_frame(crowd, camera, &self.style)?;
        let path = self.dir.join(format!("frame_{:05}.png", self.index));
        write_png_atomic(&path, &img)?;
        if self.style.map {
            let m = render_map(crowd, camera, &self.style, self.style.map_size_px)?;
            write_png_atomic(&self.dir.join(format!("map_{:05}.png", self.index)), &m)?;
        }
        let every = self.style.gif_every as usize;
        if every > 0 && self.index % every == 0 && self.gif_frames.len() < self.style.gif_max_frames
        {
            self.gif_frames
                .push(img.downscale(self.style.gif_downscale));
        }
        self.index += 1;
        Ok(path)
    }

    /// Writes `crowd.gif` when frames were collected (frame delay assumes 30 recorded frames per
    /// second, times `gif_every`); returns its path.
    pub fn finish(self) -> Result<Option<PathBuf>, RenderError> {
        if self.gif_frames.is_empty() {
            return Ok(None);
        }
        let path = self.dir.join("crowd.gif");
        let delay = (100 * self.style.gif_every.max(1) / 30).max(2) as u16;
        write_gif_atomic(&path, &self.gif_frames, delay)?;
        Ok(Some(path))
    }
}
