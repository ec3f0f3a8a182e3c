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

/// [`RenderError::BadSize`] unless `img` has a non-zero size and `width * height * 3` bytes (its
/// fields are public: a hand-built image may not).
fn check_buffer(img: &Image) -> Result<(), RenderError> {
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
    Ok(())
}

/// Writes `img` as an 8-bit RGB PNG at `path`, atomically (temp file + rename).
///
/// Errors: an image of zero size or whose buffer is not `width * height * 3` bytes
/// ([`RenderError::BadSize`]), the encoder's and the file system's.
pub fn write_png_atomic(path: &Path, img: &Image) -> Result<(), RenderError> {
    check_buffer(img)?;
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
///
/// Errors ([`RenderError::BadSize`]): no frame, frames of different sizes or of a side above
/// 65535, a frame of zero size or whose buffer is not `width * height * 3` bytes (as
/// [`write_png_atomic`]); the encoder's and the file system's.
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
    for f in frames {
        check_buffer(f)?;
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
        if self.style.map {
            let m = render_map(crowd, camera, &self.style, self.style.map_size_px)?;
            write_png_atomic(&self.dir.join(format!("map_{:05}.png", self.index)), &m)?;
        }
        self.record_image(img)
    }

    /// Writes a frame rendered elsewhere (a GPU renderer's, say) as the next `frame_NNNNN.png`
    /// and collects it for the GIF as [`Recorder::record`] does; draws no map (a recorder of
    /// such frames is made with [`RenderStyle::map`] off, so that [`Recorder::finish`] removes an
    /// earlier run's maps). Returns the PNG path.
    pub fn record_image(&mut self, img: Image) -> Result<PathBuf, RenderError> {
        let path = self.dir.join(format!("frame_{:05}.png", self.index));
        write_png_atomic(&path, &img)?;
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
    /// second, times `gif_every`), then removes what an earlier recording into the same folder left
    /// under this recorder's names and this one did not write: `frame_NNNNN.png` and
    /// `map_NNNNN.png` past its last frame (every `map_` when it drew no maps) and `crowd.gif` when
    /// it wrote none. Other files are not touched. Without that, a folder used before held two
    /// runs' frames under one pattern.
    pub fn finish(self) -> Result<Finished, RenderError> {
        let path = self.dir.join("crowd.gif");
        let gif = if self.gif_frames.is_empty() {
            None
        } else {
            let delay = (100 * self.style.gif_every.max(1) / 30).max(2) as u16;
            write_gif_atomic(&path, &self.gif_frames, delay)?;
            Some(path)
        };
        let stale_removed = self.remove_stale(gif.is_some())?;
        Ok(Finished { gif, stale_removed })
    }

    /// Removes the files of [`Recorder::finish`]'s rule; returns how many.
    fn remove_stale(&self, wrote_gif: bool) -> Result<usize, RenderError> {
        let derr = |source| RenderError::Dir {
            path: self.dir.clone(),
            source,
        };
        let mut removed = 0;
        for entry in std::fs::read_dir(&self.dir).map_err(derr)? {
            let entry = entry.map_err(derr)?;
            let name = entry.file_name();
            let Some(name) = name.to_str() else {
                continue;
            };
            let stale = match recorded_index(name) {
                Some(("frame", i)) => i >= self.index,
                Some(("map", i)) => !self.style.map || i >= self.index,
                _ => name == "crowd.gif" && !wrote_gif,
            };
            if stale && entry.file_type().is_ok_and(|t| t.is_file()) {
                let path = entry.path();
                std::fs::remove_file(&path).map_err(|source| RenderError::Io { path, source })?;
                removed += 1;
            }
        }
        Ok(removed)
    }
}

/// What [`Recorder::finish`] did beyond the frames.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finished {
    /// The animated GIF written, if frames were collected for one.
    pub gif: Option<PathBuf>,
    /// Files an earlier recording had left under the recorder's names, removed.
    pub stale_removed: usize,
}

/// The kind (`frame` or `map`) and index of a file named as [`Recorder`] names them
/// (`frame_00012.png`: at least five digits, nothing else).
fn recorded_index(name: &str) -> Option<(&'static str, usize)> {
    let (kind, rest) = if let Some(rest) = name.strip_prefix("frame_") {
        ("frame", rest)
    } else {
        ("map", name.strip_prefix("map_")?)
    };
    let digits = rest.strip_suffix(".png")?;
    if digits.len() < 5 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((kind, digits.parse().ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_recorders_own_names_are_read_as_frames() {
        assert_eq!(recorded_index("frame_00012.png"), Some(("frame", 12)));
        assert_eq!(recorded_index("map_123456.png"), Some(("map", 123456)));
        for other in [
            "frame_0012.png",
            "frame_00012.PNG",
            "frame_00012.png.bak",
            "my_frame_00012.png",
            "frame_0001a.png",
            "maps_00001.png",
            "crowd.gif",
        ] {
            assert_eq!(recorded_index(other), None, "{other}");
        }
    }

    /// A second, shorter recording into the folder of a first leaves only its own frames under
    /// the recorder's names, and every other file: the first run's `frame_00003.png` and later,
    /// and its maps and GIF, were left mixed with the second's (found 2026-11-28).
    #[test]
    fn a_second_recording_leaves_only_its_own_frames() {
        use crate::testing::{ProceduralSource, paper_distance_policy};
        use crate::{Camera, ClipSource, CrowdConfig};
        let source = ProceduralSource::new();
        let policy = paper_distance_policy(source.levels());
        let config = CrowdConfig {
            walkers: 20,
            ..CrowdConfig::default()
        };
        let dir = std::env::temp_dir().join(format!("crowd-sim-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let cam = Camera {
            image_width: 64,
            image_height: 48,
            ..Camera::default()
        };
        let small = RenderStyle {
            map_size_px: 32,
            ..RenderStyle::default()
        };
        let record = |frames: usize, style: RenderStyle| {
            let mut crowd = Crowd::new(&source, config).unwrap();
            let mut rec = Recorder::new(&dir, style).unwrap();
            for _ in 0..frames {
                crowd.step(&source, &policy, &cam, 1.0 / 30.0).unwrap();
                rec.record(&crowd, &cam).unwrap();
            }
            rec.finish().unwrap()
        };
        let first = record(
            5,
            RenderStyle {
                map: true,
                gif_every: 1,
                ..small.clone()
            },
        );
        assert!(first.gif.is_some());
        assert_eq!(first.stale_removed, 0);
        let keep = ["notes.txt", "frame_7.png", "frame_00001.png.bak"];
        for name in keep {
            std::fs::write(dir.join(name), b"mine").unwrap();
        }
        let second = record(
            2,
            RenderStyle {
                map: false,
                gif_every: 0,
                ..small
            },
        );
        assert_eq!(second.gif, None);
        // Frames 2..5, maps 0..5 and the GIF.
        assert_eq!(second.stale_removed, 3 + 5 + 1);
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        let mut want: Vec<String> = ["frame_00000.png", "frame_00001.png"]
            .iter()
            .chain(&keep)
            .map(|s| s.to_string())
            .collect();
        want.sort();
        assert_eq!(names, want);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
