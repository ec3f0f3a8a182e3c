//! Walks recorded from the live page (`motion-lod view MODEL.mlod`, the walker's "record" button,
//! `viewer/live.js`), read back for the motion-quality meter (`motion-lod quality MODEL
//! --recorded walk-recording.json`).
//!
//! The page steps its walker by a fixed `frameTime` while recording and saves every frame as the
//! runtime showed it: the pose vector in the cycle frame (`mlod_walker_shown_pose`, the foot lock
//! applied), the cycle frame (origin and heading), the cycle's index, detail and body scale. Read
//! back, each pose is placed in the world by its cycle frame ([`lod_policy::CycleFrame::place_root`])
//! and the cycle changes are the seams: the same track a crowd walker records
//! ([`crate::crowd::WalkerTrack`]), measured by the same code ([`crate::crowd::measure_track`]).
//!
//! The file is JSON:
//! ```json
//! { "format": "motion-lod recorded walk", "version": 1, "frameTime": 0.016666666666666666,
//!   "poseLen": 60, "joints": 19,
//!   "frames": [ { "cycle": 0, "cycleX": 0, "cycleZ": 0, "heading": 0, "level": 0, "joints": 18,
//!                 "bodyScale": 1, "pose": [0.01, 0.93, ...] }, ... ] }
//! ```

use serde::Deserialize;

use crate::MotionModel;
use crate::crowd::WalkerTrack;

/// The `format` a recording names.
pub const RECORDING_FORMAT: &str = "motion-lod recorded walk";
/// The version of the recording format this reads.
pub const RECORDING_VERSION: u32 = 1;

/// A walk recorded from the live page.
#[derive(Debug, Clone, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Recording {
    /// Always [`RECORDING_FORMAT`].
    pub format: String,
    /// [`RECORDING_VERSION`].
    pub version: u32,
    /// Seconds between frames.
    pub frame_time: f64,
    /// Floats of each pose (the model's pose length).
    pub pose_len: usize,
    /// Joints of the model's skeleton.
    pub joints: usize,
    /// The frames, in order.
    pub frames: Vec<RecordedFrame>,
}

/// One frame of a [`Recording`], as the runtime showed it.
#[derive(Debug, Clone, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RecordedFrame {
    /// Index of the cycle the frame is in (0 for the walk's first).
    pub cycle: u64,
    /// The cycle frame's origin on the ground, metres (world x).
    pub cycle_x: f64,
    /// The cycle frame's origin on the ground, metres (world z).
    pub cycle_z: f64,
    /// The cycle frame's heading, radians about +y.
    pub heading: f64,
    /// Accuracy level of the cycle.
    pub level: usize,
    /// Animated joints of the cycle.
    pub joints: usize,
    /// The cycle's body scale.
    pub body_scale: f32,
    /// The pose vector in the cycle frame.
    pub pose: Vec<f32>,
}

/// Why a recording cannot be read or measured.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// Not JSON of the recording's shape.
    #[error("not a recorded walk: {0}")]
    Json(#[from] serde_json::Error),
    /// Another format or version.
    #[error(
        "format {format:?} version {version}: this reads {RECORDING_FORMAT:?} version {RECORDING_VERSION}"
    )]
    Format {
        /// The file's format.
        format: String,
        /// The file's version.
        version: u32,
    },
    /// Recorded from another model (pose length or joints differ).
    #[error(
        "recorded from a model with {pose_len} pose floats and {joints} joints; this model has {model_pose_len} and {model_joints}"
    )]
    OtherModel {
        /// The recording's pose length.
        pose_len: usize,
        /// The recording's joints.
        joints: usize,
        /// The model's pose length.
        model_pose_len: usize,
        /// The model's joints.
        model_joints: usize,
    },
    /// A frame's pose has another length.
    #[error("frame {frame}: {len} pose floats, the recording says {expected}")]
    PoseLength {
        /// The frame.
        frame: usize,
        /// Its pose's length.
        len: usize,
        /// The recording's pose length.
        expected: usize,
    },
    /// A number that is not finite (or a frame time that is not positive).
    #[error("{what} is {value} (must be finite{})", if *what == "frameTime" { " and > 0" } else { "" })]
    NotFinite {
        /// What holds it.
        what: String,
        /// The value.
        value: f64,
    },
    /// Too few frames or cycles to measure.
    #[error("{frames} frames over {cycles} cycles: record at least two whole cycles")]
    TooShort {
        /// Frames recorded.
        frames: usize,
        /// Cycles begun in them.
        cycles: usize,
    },
}

impl Recording {
    /// Reads a recording from its JSON text and checks it: the format and version, a positive
    /// frame time, every pose of the stated length and every number finite.
    pub fn parse(text: &str) -> Result<Recording, RecordingError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let r: Recording = serde_json::from_str(text)?;
        if r.format != RECORDING_FORMAT || r.version != RECORDING_VERSION {
            return Err(RecordingError::Format {
                format: r.format,
                version: r.version,
            });
        }
        if !(r.frame_time.is_finite() && r.frame_time > 0.0) {
            return Err(RecordingError::NotFinite {
                what: "frameTime".into(),
                value: r.frame_time,
            });
        }
        for (f, frame) in r.frames.iter().enumerate() {
            if frame.pose.len() != r.pose_len {
                return Err(RecordingError::PoseLength {
                    frame: f,
                    len: frame.pose.len(),
                    expected: r.pose_len,
                });
            }
            let scalars = [
                ("cycleX", frame.cycle_x),
                ("cycleZ", frame.cycle_z),
                ("heading", frame.heading),
                ("bodyScale", f64::from(frame.body_scale)),
            ];
            let bad = scalars
                .into_iter()
                .find(|(_, v)| !v.is_finite())
                .map(|(name, v)| (name.to_string(), v))
                .or_else(|| {
                    frame
                        .pose
                        .iter()
                        .position(|v| !v.is_finite())
                        .map(|k| (format!("pose value {k}"), f64::from(frame.pose[k])))
                });
            if let Some((what, value)) = bad {
                return Err(RecordingError::NotFinite {
                    what: format!("frame {f}: {what}"),
                    value,
                });
            }
        }
        Ok(r)
    }

    /// The recording as a crowd walker's track of `model` ([`crate::crowd::measure_track`]
    /// measures it): world-frame poses (each placed by its cycle frame, the joints the runtime
    /// leaves out at the model's rest), seams where the cycle changes, the median body scale.
    pub fn track(&self, model: &MotionModel) -> Result<WalkerTrack, RecordingError> {
        let p = model.lod().p();
        let joints = model.runtime().rig().joint_count();
        if self.pose_len != p || self.joints != joints {
            return Err(RecordingError::OtherModel {
                pose_len: self.pose_len,
                joints: self.joints,
                model_pose_len: p,
                model_joints: joints,
            });
        }
        let cycles = self
            .frames
            .windows(2)
            .filter(|w| w[0].cycle != w[1].cycle)
            .count();
        if cycles < 2 {
            return Err(RecordingError::TooShort {
                frames: self.frames.len(),
                cycles,
            });
        }
        let rest = model.layout.rest_pose();
        let mut poses = Vec::with_capacity(self.frames.len() * rest.len().max(p));
        let mut seams = Vec::new();
        let mut placed = vec![0.0f32; p];
        for (f, frame) in self.frames.iter().enumerate() {
            if f > 0 && self.frames[f - 1].cycle != frame.cycle {
                seams.push(f);
            }
            placed.copy_from_slice(&frame.pose);
            lod_policy::CycleFrame {
                x: frame.cycle_x,
                z: frame.cycle_z,
                heading: frame.heading,
            }
            .place_root(&mut placed);
            poses.extend(placed.iter().map(|&v| f64::from(v)));
            poses.extend_from_slice(rest.get(p..).unwrap_or(&[]));
        }
        let mut scales: Vec<f64> = self
            .frames
            .iter()
            .map(|f| f64::from(f.body_scale))
            .collect();
        let body_scale = crate::quality::median(&mut scales);
        Ok(WalkerTrack {
            walker: 0,
            poses,
            seams,
            levels: self.frames.iter().map(|f| f.level).collect(),
            joints: self.frames.iter().map(|f| f.joints).collect(),
            body_scale,
            visible: vec![true; self.frames.len()],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(frames: &str) -> String {
        format!(
            r#"{{"format":"{RECORDING_FORMAT}","version":1,"frameTime":0.0166,"poseLen":2,"joints":3,"frames":[{frames}]}}"#
        )
    }

    const FRAME: &str = r#"{"cycle":0,"cycleX":0,"cycleZ":0,"heading":0,"level":0,"joints":2,"bodyScale":1,"pose":[1,2]}"#;

    #[test]
    fn a_recording_is_read_and_bad_ones_say_what_and_where() {
        let r = Recording::parse(&text(FRAME)).unwrap();
        assert_eq!((r.frames.len(), r.pose_len), (1, 2));
        let err = Recording::parse("{").unwrap_err().to_string();
        assert!(err.contains("not a recorded walk"), "{err}");
        let other = text(FRAME).replace("\"version\":1", "\"version\":7");
        let err = Recording::parse(&other).unwrap_err().to_string();
        assert!(err.contains("version 7"), "{err}");
        let short = text(&FRAME.replace("[1,2]", "[1]"));
        let err = Recording::parse(&short).unwrap_err().to_string();
        assert!(err.contains("frame 0: 1 pose floats"), "{err}");
        let zero = text(FRAME).replace("0.0166", "0");
        let err = Recording::parse(&zero).unwrap_err().to_string();
        assert!(err.contains("frameTime is 0"), "{err}");
        // JSON has no NaN: a number beyond f32 in a float field is refused, either by the JSON
        // reader (out of range, with serde_json's float_roundtrip feature on, as the workspace has
        // it) or as infinite; the cycle frame's fields are doubles, and beyond f64 is refused too.
        let huge = text(&FRAME.replace("\"bodyScale\":1", "\"bodyScale\":1e60"));
        let err = Recording::parse(&huge).unwrap_err().to_string();
        assert!(
            err.contains("frame 0: bodyScale is inf") || err.contains("number out of range"),
            "{err}"
        );
        let far = text(&FRAME.replace("\"heading\":0", "\"heading\":1e400"));
        let err = Recording::parse(&far).unwrap_err().to_string();
        assert!(err.contains("number out of range"), "{err}");
        // A walk far from the origin keeps its frame to the double.
        let km = text(&FRAME.replace("\"cycleX\":0", "\"cycleX\":1000.000001"));
        assert_eq!(
            Recording::parse(&km).unwrap().frames[0].cycle_x,
            1000.000001
        );
    }
}
