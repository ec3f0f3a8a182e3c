//! The model file, offline side: the report section, encoding and atomic writing. The framing
//! (magic, version, length, checksum), the sections, their errors and the runtime's own section are
//! the runtime's ([`lod_policy::file`], [`lod_policy::RuntimeModel`]), re-exported here so that
//! there is one copy of each rule.
//!
//! A model file holds two or three sections (see [`lod_policy::file`] for the byte layout):
//!
//! | tag | version | content | read by |
//! |---|---|---|---|
//! | `RTIM` | [`RuntimeModel::SECTION_VERSION`] | the runtime model: control names, rig, multilinear model, feet, stature | every reader ([`RuntimeModel::from_bytes`]) |
//! | `RPRT` | [`REPORT_VERSION`] | the offline report: the pose layout (skeleton with its BVH channels, units, joint order) and the [`BuildReport`] | the offline side ([`MotionModel::from_bytes`]) |
//! | `STYL` | [`STYLE_VERSION`] | only in a model built with style labels: the [`StyleReport`] (where the labels came from, the styles, their counts, the weight of their code and its cross-validation) | the offline side |
//!
//! A wrong magic, a newer version, a length that disagrees with the file, a checksum mismatch or a
//! section that does not decode is a [`ModelFileError`] naming the path and the offset; nothing
//! panics and the decoder never allocates more than a small multiple of the file (see
//! [`decode_payload`]).

use std::path::Path;

use lod_policy::RuntimeModel;
use lod_policy::file::Section;
use motion_io::PoseLayout;

use crate::model::{BuildReport, MotionModel};
use crate::style::StyleReport;

/// Why a model file could not be read or written (the runtime's [`lod_policy::FileError`]).
pub use lod_policy::file::FileError as ModelFileError;
pub use lod_policy::file::{FORMAT_VERSION, HEADER_LEN, MAGIC, SECTION_HEADER_LEN};

/// The tag of the offline report's section.
pub const REPORT_SECTION: [u8; 4] = *b"RPRT";
/// The format version of the report section; another version is refused with a request to
/// rebuild. History: 1 (format 8: the pose layout, then the build report); 2 (the motion-quality
/// meter finds contacts from the feet's own motion and reports floating,
/// [`crate::quality::MotionQuality::floating_cm`]); 3 (the reference keeps the trends of the takes'
/// pop and skate by step length, [`crate::quality::QualityReference::step_trends`]); 4 (control selection by
/// cross-validation by take and its quality guard: the decisions `KeptByFolds`, `DroppedByFolds`
/// and `Overruled` of [`kriging::DimDecision`], and [`BuildReport::overruled_quality`]).
/// Version 4 files written before commit 5c54240 (09:08 on 2026-11-27; version 4 came with
/// b0a5bee) keep the quality reference's every take (`take_steps`) where later ones keep its two
/// trends: they fail to decode, and the error asks for a rebuild
/// ([`lod_policy::file::decode_section`]).
/// Since then `tests/section_layout.rs` records the fingerprint of the section's serialised shape
/// with its version (and the style section's), and fails when the shape changes under the same
/// version.
pub const REPORT_VERSION: u32 = 4;

/// The tag of the style report's section, written only for a model with styles (a model without
/// them is byte for byte what it was before styles existed).
pub const STYLE_SECTION: [u8; 4] = *b"STYL";
/// The format version of the style section. History: 1 (the first); 2 (each style's
/// motion-quality reference by the meter of [`REPORT_VERSION`] 2); 3 (the references of
/// [`REPORT_VERSION`] 3; its files from before 09:08 on 2026-11-27 hold the earlier quality
/// reference and are refused with a request to rebuild, as the report's are).
pub const STYLE_VERSION: u32 = 3;

/// The runtime's payload decoder ([`lod_policy::file::decode_payload`]): the entry point for fuzzing
/// the decoder itself.
#[doc(hidden)]
pub use lod_policy::file::decode_payload;

/// The bytes of the report section of `model`: bincode of its pose layout and build report.
pub fn report_bytes(model: &MotionModel, path: &Path) -> Result<Vec<u8>, ModelFileError> {
    bincode::serde::encode_to_vec((&model.layout, &model.report), bincode::config::standard())
        .map_err(|e| ModelFileError::Encode {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
}

/// The report section of a model file, to frame after the runtime's: `bytes` must be
/// [`report_bytes`].
pub fn report_section(bytes: &[u8]) -> Section<'_> {
    Section {
        tag: REPORT_SECTION,
        version: REPORT_VERSION,
        bytes,
        offset: 0,
    }
}

/// Encodes `model` into the framed byte layout described in the module documentation: the
/// runtime's section ([`RuntimeModel::section_bytes`]), then the report's.
///
/// `path` only labels errors.
pub fn encode(model: &MotionModel, path: &Path) -> Result<Vec<u8>, ModelFileError> {
    let runtime = model.runtime().section_bytes();
    let report = report_bytes(model, path)?;
    let style = model
        .style
        .as_ref()
        .map(|s| {
            bincode::serde::encode_to_vec(s, bincode::config::standard()).map_err(|e| {
                ModelFileError::Encode {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                }
            })
        })
        .transpose()?;
    let mut sections = vec![RuntimeModel::section(&runtime), report_section(&report)];
    if let Some(bytes) = &style {
        sections.push(Section {
            tag: STYLE_SECTION,
            version: STYLE_VERSION,
            bytes,
            offset: 0,
        });
    }
    Ok(lod_policy::file::frame(&sections))
}

/// The style report of a model file, when it has a style section ([`STYLE_SECTION`]); the
/// framing must already have been checked ([`decode`]). `path` only labels errors.
pub fn decode_style(bytes: &[u8], path: &Path) -> Result<Option<StyleReport>, ModelFileError> {
    let has = lod_policy::file::sections(bytes, path)?
        .iter()
        .any(|s| s.tag == STYLE_SECTION);
    if !has {
        return Ok(None);
    }
    lod_policy::file::decode_section(
        bytes,
        STYLE_SECTION,
        STYLE_VERSION,
        "the style report",
        path,
    )
    .map(Some)
}

/// Decodes the parts of a model file: the runtime model ([`RuntimeModel::decode`]: framing,
/// checksums, its section and its checks) and the report section's pose layout and build
/// report. The parts are not yet checked against each other ([`MotionModel::from_bytes`] does
/// that).
///
/// `path` only labels errors.
pub fn decode(
    bytes: &[u8],
    path: &Path,
) -> Result<(RuntimeModel, PoseLayout, BuildReport), ModelFileError> {
    let runtime = RuntimeModel::decode(bytes, path)?;
    let (layout, report) = lod_policy::file::decode_section(
        bytes,
        REPORT_SECTION,
        REPORT_VERSION,
        "the build report",
        path,
    )?;
    Ok((runtime, layout, report))
}

/// Writes `bytes` to `path` atomically ([`lod_policy::file::write_atomic`]: a temporary file in
/// the same folder, flushed to disk, then renamed over `path`). An interrupted run leaves either
/// the old file or the new one, never half of one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ModelFileError> {
    lod_policy::file::write_atomic(path, bytes).map_err(|source| ModelFileError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Encodes `model` and writes it to `path` atomically.
pub fn save(model: &MotionModel, path: &Path) -> Result<(), ModelFileError> {
    let bytes = encode(model, path)?;
    write_atomic(path, &bytes)
}

impl MotionModel {
    /// Writes the model file atomically (see [`crate::model_file`]). The recorded data folders are
    /// written relative to the model file's folder (absolute ones stay absolute), so that the model
    /// and its data can move together and be used from any working directory.
    pub fn save(&self, path: &Path) -> Result<(), ModelFileError> {
        match &self.report.data {
            Some(spec) if spec.dirs.iter().any(|d| d.is_relative()) => {
                let mut model = self.clone();
                model.report.data = Some(spec.relative_to(model_folder(path)));
                save(&model, path)
            }
            _ => save(self, path),
        }
    }

    /// Reads a model file: framing, checksums and sections ([`decode`]), then the semantic
    /// validation of [`MotionModel::validate`]. Every failure names the file and what is wrong.
    pub fn load(path: &Path) -> Result<MotionModel, ModelFileError> {
        let bytes = std::fs::read(path).map_err(|source| ModelFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut model = MotionModel::from_bytes(&bytes, path)?;
        if let Some(spec) = &model.report.data {
            model.report.data = Some(spec.resolved_from(model_folder(path)));
        }
        Ok(model)
    }

    /// Decodes and validates a model from the bytes of a model file (`path` only labels errors):
    /// the runtime section ([`RuntimeModel::from_bytes`], which checks the runtime's parts), the
    /// report section ([`decode`]), then [`MotionModel::validate`].
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<MotionModel, ModelFileError> {
        let (runtime, layout, report) = decode(bytes, path)?;
        let style = decode_style(bytes, path)?;
        MotionModel::new(runtime, layout, report)
            .and_then(|m| m.with_style_report(style))
            .map_err(|source| ModelFileError::Invalid {
                path: path.to_path_buf(),
                source,
            })
    }
}

/// The folder of a model file (`.` for a bare file name).
fn model_folder(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Reads, decodes and validates a model file ([`MotionModel::load`]).
pub fn load(path: &Path) -> Result<MotionModel, ModelFileError> {
    MotionModel::load(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("mlod-file-test-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.bin");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second");
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn write_into_missing_folder_fails_cleanly() {
        let path = std::env::temp_dir().join("mlod-no-such-dir-xyz/sub/m.mlod");
        let err = write_atomic(&path, b"x").unwrap_err();
        assert!(matches!(err, ModelFileError::Io { .. }));
    }
}
