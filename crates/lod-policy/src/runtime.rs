//! [`RuntimeModel`]: the one model type of the runtime, and its section of the model file.
//!
//! A runtime model holds everything playback needs and nothing of the workshop: the skeleton
//! ([`Rig`]: joint names, parents, rest transforms, what drives each joint), the multilinear model
//! at every accuracy level ([`LodModel`]), the feet for the foot lock ([`FootRig`]), the rig's
//! stature for the body scale, and the names of the controls (their ranges are the model's
//! [`ControlSpace`](crate::ControlSpace)). It writes and reads its own section of the model file
//! ([`RuntimeModel::SECTION`], versioned by [`RuntimeModel::SECTION_VERSION`] and checksummed, see
//! [`crate::file`]); the offline build writes this section first and appends its report after
//! it, which this reader skips.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::controls::{Controls, MAX_STYLES};
use crate::file::{self, FileError, InvalidModel, Section};
use crate::footlock::FootRig;
use crate::model::{ALWAYS_ROWS, LodModel, ROWS_PER_JOINT};
use crate::rig::{Rig, RigJoint};

/// The runtime form of a model file: the skeleton with its forward kinematics, the
/// multilinear model at every accuracy level, the feet for the foot lock, and the rig's stature
/// for the body scale of each character.
#[derive(Debug, Clone, PartialEq)]
pub struct RuntimeModel {
    rig: Rig,
    lod: LodModel,
    styles: Vec<String>,
    feet: Option<FootRig>,
    stature_m: Option<f32>,
}

/// The prefix of a style's control name in the runtime section: style `elderly` is the control
/// `style:elderly`, after the walk's four ([`Controls::NAMES`]).
pub const STYLE_PREFIX: &str = "style:";

impl RuntimeModel {
    /// A runtime model from its parts, checking that they fit: the rig drives the model's pose
    /// rows (`7 + 3 n` rows for its `n` rotating joints, the model's `P`, with the model's 7 always
    /// evaluated rows and 3 rows per joint).
    ///
    /// The model's controls are the walk's four, [`Controls::NAMES`]; for a model that also
    /// conditions on style, see [`RuntimeModel::with_styles`].
    pub fn new(rig: Rig, lod: LodModel) -> Result<RuntimeModel, InvalidModel> {
        Self::with_styles(rig, lod, Vec::new())
    }

    /// [`RuntimeModel::new`] for a model whose control space has a dimension per style after the
    /// walk's four ([`crate::StyleMix`]): `styles` names them in order (at most [`MAX_STYLES`],
    /// distinct, not empty, printable, no `=` or `,`, which the command line's blends use).
    pub fn with_styles(
        rig: Rig,
        lod: LodModel,
        styles: Vec<String>,
    ) -> Result<RuntimeModel, InvalidModel> {
        if styles.len() > MAX_STYLES {
            return Err(InvalidModel(format!(
                "the runtime model has {} styles; at most {MAX_STYLES} are supported",
                styles.len()
            )));
        }
        for (j, name) in styles.iter().enumerate() {
            if let Some(why) = style_name_problem(name) {
                return Err(InvalidModel(format!("style {j} {name:?}: {why}")));
            }
            if styles[..j].contains(name) {
                return Err(InvalidModel(format!("style {name:?} is named twice")));
            }
        }
        if lod.d() != Controls::COUNT + styles.len() {
            return Err(InvalidModel(format!(
                "the runtime model has {} controls; a walk model with {} styles has {} ({}{})",
                lod.d(),
                styles.len(),
                Controls::COUNT + styles.len(),
                Controls::NAMES.join(", "),
                styles
                    .iter()
                    .map(|s| format!(", {STYLE_PREFIX}{s}"))
                    .collect::<String>()
            )));
        }
        if lod.always_rows() != ALWAYS_ROWS || lod.rows_per_joint() != ROWS_PER_JOINT {
            return Err(InvalidModel(format!(
                "the runtime model has {} root rows and {} rows per joint; pose vectors have {ALWAYS_ROWS} and {ROWS_PER_JOINT}",
                lod.always_rows(),
                lod.rows_per_joint(),
            )));
        }
        if rig.dof() != lod.p() {
            return Err(InvalidModel(format!(
                "the pose layout has {} DOF rows, the runtime model {}",
                rig.dof(),
                lod.p()
            )));
        }
        Ok(RuntimeModel {
            rig,
            lod,
            styles,
            feet: None,
            stature_m: None,
        })
    }

    /// The model with its rig's stature: the standing height (m) of the rig's skeleton, measured as
    /// the height control measures the data's performers ([`crate::ControlSpace::body_scale`]). Must be
    /// finite and positive; `None` draws every character at the rig's size.
    pub fn with_stature(mut self, stature_m: Option<f32>) -> Result<RuntimeModel, InvalidModel> {
        if let Some(h) = stature_m {
            check_stature(h).map_err(InvalidModel)?;
        }
        self.stature_m = stature_m;
        Ok(self)
    }

    /// The model with the feet of its rig for the foot lock ([`FootRig::check`]ed against the rig).
    pub fn with_feet(mut self, feet: Option<FootRig>) -> Result<RuntimeModel, InvalidModel> {
        if let Some(f) = &feet {
            f.check(&self.rig).map_err(InvalidModel)?;
        }
        self.feet = feet;
        Ok(self)
    }

    /// The model with measured error tables per accuracy level and per joint count
    /// ([`LodModel::set_errors`], validated there): the offline build measures them once the model
    /// exists.
    pub fn with_errors(
        mut self,
        level_errors: Vec<crate::LevelError>,
        joint_errors: Vec<crate::LevelError>,
    ) -> Result<RuntimeModel, crate::ModelError> {
        self.lod.set_errors(level_errors, joint_errors)?;
        Ok(self)
    }

    /// The tag of the runtime's section of a model file.
    pub const SECTION: [u8; 4] = *b"RTIM";
    /// The format version of the runtime's section; a section of another version is refused with
    /// a request to rebuild the model.
    ///
    /// History: 1 (the first sectioned file, format 8: control names, rig joints, the multilinear
    /// model, feet, stature; a model with styles names them among the controls, [`STYLE_PREFIX`]);
    /// 2 (each accuracy level's error records its motion quality, `pop_x`, `skate_x` and `floor_cm`, and its
    /// foot slide is measured with the foot lock on); 3 (each accuracy level's error also records
    /// `facing_out_deg`, and its pop and skate are ratios to the data at each walk's step).
    /// motion-lod's `tests/section_layout.rs` records the fingerprint of the section's serialised
    /// shape ([`RuntimeModel::serialize_section`]) with this version and fails when the shape
    /// changes under it.
    pub const SECTION_VERSION: u32 = 3;

    /// Decodes the runtime model from the bytes of a model file: the framing and checksums
    /// ([`file::unframe`], [`file::sections`]), then the runtime's own section
    /// ([`RuntimeModel::SECTION`]), then the checks of [`RuntimeModel::new`], the feet and the
    /// stature. Every other section (the offline build report) is skipped unread.
    pub fn from_bytes(bytes: &[u8]) -> Result<RuntimeModel, FileError> {
        Self::decode(bytes, Path::new("<model bytes>"))
    }

    /// Reads a model file (see [`RuntimeModel::from_bytes`]); errors name the path.
    pub fn load(path: &Path) -> Result<RuntimeModel, FileError> {
        Self::decode(&file::read(path)?, path)
    }

    /// Decodes the runtime section's bytes alone (what [`RuntimeModel::section_bytes`] wrote) and
    /// checks the model; `path` only labels errors. For a reader that has already split the file
    /// into its sections ([`file::sections`]).
    pub fn from_section_bytes(section: &[u8], path: &Path) -> Result<RuntimeModel, FileError> {
        file::decode_payload::<Parts>(section, path)?.into_model_at(path)
    }

    /// [`RuntimeModel::from_bytes`] with errors naming `path` (which only labels them).
    pub fn decode(bytes: &[u8], path: &Path) -> Result<RuntimeModel, FileError> {
        let parts: Parts = file::decode_section(
            bytes,
            Self::SECTION,
            Self::SECTION_VERSION,
            "the runtime model",
            path,
        )?;
        parts.into_model_at(path)
    }

    /// The bytes of the runtime's section (bincode of the control names, the rig's joints, the
    /// multilinear model, the feet and the stature), what [`RuntimeModel::from_section_bytes`]
    /// reads back. The same model gives the same bytes.
    pub fn section_bytes(&self) -> Vec<u8> {
        // Encoding plain data into a Vec cannot fail (no map keys, no I/O).
        self.with_parts(|parts| {
            bincode::serde::encode_to_vec(parts, bincode::config::standard())
                .expect("a runtime model encodes")
        })
    }

    /// The runtime section's parts, as [`RuntimeModel::section_bytes`] encodes them, handed to any
    /// serde serializer: for tests that fingerprint the section's layout against its
    /// [`RuntimeModel::SECTION_VERSION`] (motion-lod's `tests/section_layout.rs`).
    #[doc(hidden)]
    pub fn serialize_section<S: serde::Serializer>(
        &self,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        self.with_parts(|parts| serde::Serialize::serialize(parts, serializer))
    }

    /// Runs `f` on the parts the section holds, borrowed from the model.
    fn with_parts<R>(&self, f: impl FnOnce(&PartsRef<'_>) -> R) -> R {
        let control_names: Vec<String> = Controls::NAMES
            .iter()
            .map(|n| n.to_string())
            .chain(self.styles.iter().map(|s| format!("{STYLE_PREFIX}{s}")))
            .collect();
        f(&PartsRef {
            control_names: &control_names,
            joints: self.rig.joints(),
            lod: &self.lod,
            feet: &self.feet,
            stature_m: self.stature_m,
        })
    }

    /// The runtime's section of a model file, to frame with others ([`file::frame`]):
    /// `bytes` must be [`RuntimeModel::section_bytes`].
    pub fn section(bytes: &[u8]) -> Section<'_> {
        Section {
            tag: Self::SECTION,
            version: Self::SECTION_VERSION,
            bytes,
            offset: 0,
        }
    }

    /// A complete model file holding the runtime section alone: what an engine or a browser
    /// needs to ship (the build report left out), read back by [`RuntimeModel::from_bytes`].
    pub fn to_bytes(&self) -> Vec<u8> {
        file::frame(&[Self::section(&self.section_bytes())])
    }

    /// The skeleton and its forward kinematics.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// The multilinear model at every accuracy level.
    pub fn lod(&self) -> &LodModel {
        &self.lod
    }

    /// The feet and floor the foot lock needs ([`crate::FootLock`]); `None` when the model's build
    /// found no feet.
    pub fn feet(&self) -> Option<&FootRig> {
        self.feet.as_ref()
    }

    /// The standing height (m) of the rig's skeleton, as the height control measures it; `None`
    /// when the build could not measure it (no feet or head found).
    pub fn stature_m(&self) -> Option<f32> {
        self.stature_m
    }

    /// The body scale of a character with `controls`: its height over the rig's stature
    /// ([`crate::ControlSpace::body_scale`]); what [`Rig::joint_positions_scaled`],
    /// [`Rig::joint_transforms_scaled`] and [`crate::FootLock::apply`] take, and what an engine
    /// scales the skeleton's bone translations by. 1 when the data hold one height.
    pub fn body_scale(&self, controls: &Controls) -> f32 {
        // The kernel's conversion, with the data's mix the model cached when it loaded (a clip
        // build calls this per character); a style the kernel refuses reads as the data's mix.
        let mut values = [0.0f32; crate::CONTROL_VALUES];
        match self.lod.control_vector(controls, &mut values) {
            Ok(d) => self
                .lod
                .controls()
                .body_scale_of(self.stature_m, &values[..d]),
            Err(_) => self.lod.controls().body_scale(self.stature_m, controls),
        }
    }

    /// The names of the styles the model conditions on, in the order of [`crate::StyleMix`]'s
    /// weights; empty for a model built without style labels.
    pub fn styles(&self) -> &[String] {
        &self.styles
    }

    /// The index of the style named `name` (exact match), if the model has it.
    pub fn style_index(&self, name: &str) -> Option<usize> {
        self.styles.iter().position(|s| s == name)
    }

    /// The data's mix of styles: each style's share of the training cycles, in style order (what
    /// [`crate::StyleMix::DATA_MIX`] asks for); empty without styles.
    pub fn data_style_mix(&self) -> &[f32] {
        self.lod.data_style_mix()
    }

    /// The parts.
    pub fn into_parts(self) -> (Rig, LodModel, Option<FootRig>) {
        (self.rig, self.lod, self.feet)
    }
}

/// The runtime section as written: borrowed parts, in the order [`Parts`] reads them.
#[derive(Serialize)]
struct PartsRef<'a> {
    control_names: &'a [String],
    joints: &'a [RigJoint],
    lod: &'a LodModel,
    feet: &'a Option<FootRig>,
    stature_m: Option<f32>,
}

/// The runtime section as read, before the checks that make it a [`RuntimeModel`].
#[derive(Deserialize)]
struct Parts {
    control_names: Vec<String>,
    joints: Vec<RigJoint>,
    lod: LodModel,
    feet: Option<FootRig>,
    stature_m: Option<f32>,
}

impl Parts {
    /// [`Parts::into_model`], its error naming the file.
    fn into_model_at(self, path: &Path) -> Result<RuntimeModel, FileError> {
        self.into_model().map_err(|source| FileError::Invalid {
            path: path.to_path_buf(),
            source,
        })
    }

    fn into_model(self) -> Result<RuntimeModel, InvalidModel> {
        let n = Controls::COUNT;
        let styles: Option<Vec<String>> = self.control_names.get(n..).and_then(|rest| {
            rest.iter()
                .map(|name| name.strip_prefix(STYLE_PREFIX).map(str::to_string))
                .collect()
        });
        let (Some(styles), true) = (
            styles,
            self.control_names.get(..n) == Some(&Controls::NAMES.map(String::from)[..]),
        ) else {
            return Err(InvalidModel(format!(
                "the model's controls are {:?}; this build plays walks with {:?} and styles named {STYLE_PREFIX}NAME",
                self.control_names,
                Controls::NAMES
            )));
        };
        let rig = Rig::new(self.joints).map_err(|e| InvalidModel(format!("rig: {e}")))?;
        let model = RuntimeModel::with_styles(rig, self.lod, styles)?
            .with_feet(self.feet)?
            .with_stature(self.stature_m)?;
        model.check_played()?;
        Ok(model)
    }
}

/// The largest magnitude a pose row (metres, radians, seconds) of a model read from a file may
/// take in [`RuntimeModel::check_played`]: far above any walk's, far below where `f32` sums of
/// products overflow.
const PLAYED_LIMIT: f32 = 1e6;

impl RuntimeModel {
    /// Plays the model once as it is read: at every accuracy level, in full detail, at the middle
    /// of its controls (the data's mix of styles) and at every aligned frame, every pose row must
    /// be finite and at most [`PLAYED_LIMIT`] in magnitude, and the cycle's duration finite and
    /// positive. The checksums and the array checks pass a file with one huge finite number (a
    /// core entry of `3.4e38` with its CRC-32s fixed), which then animated with infinite joints
    /// (483 of 9,000 such mutations, found 2026-11-28); every array of the clip's arithmetic is
    /// read here. About a tenth of reading the Bandai model (2.46 against 2.22 ms, README,
    /// "Reliability").
    fn check_played(&self) -> Result<(), InvalidModel> {
        let lod = &self.lod;
        let Some(range) = lod.controls().range() else {
            return Ok(());
        };
        let (lo, hi) = (range.min.to_array(), range.max.to_array());
        let middle = Controls::from_array(std::array::from_fn(|k| 0.5 * lo[k] + 0.5 * hi[k]));
        let mut scratch = crate::KernelScratch::new(lod);
        let mut kernel = crate::ClipKernel::new(lod);
        let mut pose = vec![0.0f32; lod.p()];
        let corrupt = |what: String| {
            InvalidModel(format!(
                "{what}: a number in the model is corrupt (its checksums hold, so it was written \
                 so); rebuild it with `motion-lod build`"
            ))
        };
        for level in 0..lod.levels().len() {
            let detail = crate::Detail::new(level, lod.joints());
            lod.build_kernel(&middle, detail, &mut scratch, &mut kernel)
                .map_err(|e| corrupt(format!("playing accuracy level {level}: {e}")))?;
            let duration = kernel.duration();
            if !(duration.is_finite() && duration > 0.0) {
                return Err(corrupt(format!(
                    "accuracy level {level} plays a cycle of {duration} s at the middle of its \
                     controls"
                )));
            }
            for frame in 0..lod.t() {
                lod.pose(&kernel, frame as f32, &mut pose)
                    .map_err(|e| corrupt(format!("playing accuracy level {level}: {e}")))?;
                if let Some((row, v)) = pose
                    .iter()
                    .enumerate()
                    .find(|(_, v)| v.is_nan() || v.abs() > PLAYED_LIMIT)
                {
                    return Err(corrupt(format!(
                        "accuracy level {level} at the middle of its controls gives {v} in pose \
                         row {row} at aligned frame {frame} (at most {PLAYED_LIMIT:e} in \
                         magnitude)"
                    )));
                }
            }
        }
        Ok(())
    }
}

/// Why `name` cannot name a style, if it cannot: empty, longer than 64 bytes, a control character,
/// leading or trailing white space, or one of `=` and `,` (the command line's blend syntax,
/// `elderly=0.5,youthful=0.5`).
pub fn style_name_problem(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("a style name is not empty")
    } else if name.len() > 64 {
        Some("a style name has at most 64 bytes")
    } else if name.chars().any(char::is_control) {
        Some("a style name has no control characters")
    } else if name.trim() != name {
        Some("a style name has no leading or trailing white space")
    } else if name.contains(['=', ',']) {
        Some("a style name has no '=' or ','")
    } else {
        None
    }
}

/// Checks a stature (the standing height of a model's skeleton, m): a finite height between 1 cm and
/// 100 m. The one check the runtime and the offline model use.
pub fn check_stature(h: f32) -> Result<(), String> {
    if h.is_finite() && (0.01..=100.0).contains(&h) {
        Ok(())
    } else {
        Err(format!(
            "stature {h} m is not a standing height (finite, 0.01 to 100 m)"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn style_names_are_printable_and_free_of_the_blend_syntax() {
        assert_eq!(style_name_problem("elderly"), None);
        assert_eq!(style_name_problem("p160"), None);
        for bad in [
            "",
            " old",
            "old ",
            "a=b",
            "a,b",
            "tab\there",
            &"x".repeat(65),
        ] {
            assert!(style_name_problem(bad).is_some(), "{bad:?}");
        }
    }
}
