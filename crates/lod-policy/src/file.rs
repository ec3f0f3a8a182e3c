//! The model file's framing and sections, and the reader an engine loads models with.
//!
//! Layout (all integers little-endian):
//!
//! | offset | size | content |
//! |---|---|---|
//! | 0 | 8 | magic `b"MLOD\r\n\x1a\n"` (catches text-mode transfers, like PNG's) |
//! | 8 | 4 | format version (`u32`, [`FORMAT_VERSION`]) |
//! | 12 | 8 | payload length in bytes (`u64`) |
//! | 20 | 4 | CRC-32 (IEEE) of the payload |
//! | 24 | n | payload: one or more sections |
//!
//! Each section ([`Section`]) is a header of [`SECTION_HEADER_LEN`] bytes, then its bytes:
//!
//! | offset | size | content |
//! |---|---|---|
//! | 0 | 4 | tag (four ASCII bytes) |
//! | 4 | 4 | the section's own version (`u32`) |
//! | 8 | 8 | length of its bytes (`u64`) |
//! | 16 | 4 | CRC-32 (IEEE) of its bytes |
//! | 20 | n | its bytes: `bincode` 2 (standard configuration) of a serde value |
//!
//! The runtime owns the first section, [`RuntimeModel::SECTION`](crate::RuntimeModel::SECTION)
//! (`RTIM`): everything playback needs ([`crate::RuntimeModel`]). The offline builder
//! (`motion_lod::model_file`) appends its build report as a section of its own (`RPRT`); the
//! runtime reader skips every section that is not its own, so an engine never decodes the
//! workshop's types, and a file holding the runtime section alone
//! ([`RuntimeModel::to_bytes`](crate::RuntimeModel::to_bytes)) plays the same.
//!
//! Every reader goes through [`unframe`] and [`sections`]: a wrong magic, another version, a
//! length that disagrees with the file, a checksum mismatch, a section that runs past the payload
//! or fails its own checksum, a missing or outdated section, or a section that does not decode is
//! a [`FileError`] naming the path and the offset. Nothing panics, and the decoder never allocates
//! more than a small multiple of the file ([`decode_payload`]).

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// The eight bytes every model file starts with.
pub const MAGIC: [u8; 8] = *b"MLOD\r\n\x1a\n";
/// The format version this build writes and the only one it reads.
pub const FORMAT_VERSION: u32 = 8;

// Version history: 1 (first release); 2 (the build report records the DOF row weights and the build
// settings their choice); 3 (the kriging rows of the controls, `C A^-1`, are stored once in the control
// space instead of in every key's projection); 4 (no build time in the report, so that the same build
// writes the same bytes; ALS convergence per key; the pose layout stores only what it is built from
// and is validated on load; the motion-quality reference measured on the training takes; static
// joints leave the pose vector, and the build report records them, the control selection and the
// joint-order note); 5 (every level and joint-count error records the foot slide, for the policies'
// screen check; the recorded data folders are relative to the model file, and the data
// specification records the units, up axis and joint map); 6 (the feet and floor for the runtime foot
// lock, `FootRig`, after the runtime model); 7 (the rig's stature after the feet, for the body
// scale of each character, and the data's takes measured with their own body scale); 8 (the payload
// is sections: the runtime's own `RTIM` (rig, multilinear model, feet, stature, control names)
// first, the offline build report `RPRT` after it). Files of an
// older version are refused
// with a request to rebuild: a model is
// rebuilt from its data in seconds, and a converter would carry guesses.
/// Bytes before the payload: magic, version, length, checksum.
pub const HEADER_LEN: usize = 24;
/// Bytes of a section's header: tag, version, length, checksum.
pub const SECTION_HEADER_LEN: usize = 20;

/// One section of a model file's payload (see the module documentation): a tag, the section's
/// own format version and its bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Section<'a> {
    /// Four ASCII bytes naming what the section holds (`RTIM`: the runtime model).
    pub tag: [u8; 4],
    /// The section's own format version.
    pub version: u32,
    /// Its bytes (bincode of a serde value).
    pub bytes: &'a [u8],
    /// Offset of its bytes in the file (for error messages; ignored by [`frame`]).
    pub offset: usize,
}

impl Section<'_> {
    /// The tag as text, for messages (`RTIM`).
    pub fn tag_name(&self) -> String {
        tag_name(self.tag)
    }
}

/// A tag as text, for messages (bytes outside printable ASCII as `\xNN`).
pub fn tag_name(tag: [u8; 4]) -> String {
    tag.iter()
        .flat_map(|&b| std::ascii::escape_default(b))
        .map(char::from)
        .collect()
}

/// What is wrong with a decoded model whose parts do not fit together.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidModel(pub String);

/// Why a model file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file system refused a read, write or rename.
    #[error("{path}: {source}")]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file is shorter than the fixed header.
    #[error(
        "{path}: not a motion-lod model: {len} bytes, shorter than the {HEADER_LEN}-byte header"
    )]
    TooShort {
        /// The file concerned.
        path: PathBuf,
        /// Its length in bytes.
        len: usize,
    },
    /// The first eight bytes are not [`MAGIC`].
    #[error("{path}: not a motion-lod model (bad magic number at offset 0)")]
    BadMagic {
        /// The file concerned.
        path: PathBuf,
    },
    /// The file was written by a newer format version than this build reads.
    #[error(
        "{path}: model format version {found} is newer than this build reads (version {FORMAT_VERSION}); \
         rebuild the model or update motion-lod"
    )]
    FutureVersion {
        /// The file concerned.
        path: PathBuf,
        /// The version found at offset 8.
        found: u32,
    },
    /// The file was written by an older format version, which this build no longer reads.
    #[error(
        "{path}: model format version {found} is older than this build reads (version {FORMAT_VERSION}); \
         rebuild the model with `motion-lod build`"
    )]
    OldVersion {
        /// The file concerned.
        path: PathBuf,
        /// The version found at offset 8.
        found: u32,
    },
    /// The version field is zero, which no build ever wrote.
    #[error("{path}: invalid model format version {found} at offset 8")]
    BadVersion {
        /// The file concerned.
        path: PathBuf,
        /// The version found.
        found: u32,
    },
    /// The payload is shorter or longer than the header says: the file was truncated or appended to.
    #[error(
        "{path}: truncated or padded model file: header at offset 12 announces {expected} payload bytes, \
         the file holds {found}"
    )]
    LengthMismatch {
        /// The file concerned.
        path: PathBuf,
        /// Payload bytes announced by the header.
        expected: u64,
        /// Payload bytes present.
        found: u64,
    },
    /// The payload does not match its checksum: the file is corrupted.
    #[error(
        "{path}: corrupted model file: payload checksum {found:08x} differs from {expected:08x} stored at offset 20"
    )]
    Checksum {
        /// The file concerned.
        path: PathBuf,
        /// Checksum stored in the header.
        expected: u32,
        /// Checksum of the payload as read.
        found: u32,
    },
    /// The payload passed its checksum but does not decode as a model of this version.
    #[error("{path}: model payload does not decode (offset {HEADER_LEN}..): {message}")]
    Decode {
        /// The file concerned.
        path: PathBuf,
        /// What bincode reported.
        message: String,
    },
    /// The payload decoded, but the model's parts do not fit together (a hand-made or damaged
    /// file with a valid checksum).
    #[error("{path}: invalid model (rebuild it with `motion-lod build`): {source}")]
    Invalid {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong.
        source: InvalidModel,
    },
    /// The section table is malformed: a section header or its bytes run past the payload.
    #[error("{path}: malformed model file: {message} (offset {offset})")]
    Section {
        /// The file concerned.
        path: PathBuf,
        /// Offset in the file of the section header concerned.
        offset: usize,
        /// What is wrong.
        message: String,
    },
    /// A section's bytes do not match its own checksum.
    #[error(
        "{path}: corrupted model file: section {tag} checksum {found:08x} differs from {expected:08x} stored at offset {offset}"
    )]
    SectionChecksum {
        /// The file concerned.
        path: PathBuf,
        /// The section's tag.
        tag: String,
        /// Offset in the file of the stored checksum.
        offset: usize,
        /// Checksum stored in the section header.
        expected: u32,
        /// Checksum of the bytes as read.
        found: u32,
    },
    /// A section the reader needs is not in the file.
    #[error(
        "{path}: not a complete model: it has no {tag} section ({what}); rebuild it with `motion-lod build`"
    )]
    MissingSection {
        /// The file concerned.
        path: PathBuf,
        /// The tag looked for.
        tag: String,
        /// What that section holds.
        what: &'static str,
    },
    /// A section was written in another version of its format than this build reads.
    #[error(
        "{path}: section {tag} has version {found}, this build reads version {expected}; rebuild the model with `motion-lod build`{hint}"
    )]
    SectionVersion {
        /// The file concerned.
        path: PathBuf,
        /// The section's tag.
        tag: String,
        /// The version found.
        found: u32,
        /// The version this build reads.
        expected: u32,
        /// `" or update motion-lod"` for a newer section, empty otherwise.
        hint: &'static str,
    },
    /// The value could not be encoded (writing a model, offline).
    #[error("{path}: cannot encode model: {message}")]
    Encode {
        /// The file concerned.
        path: PathBuf,
        /// What bincode reported.
        message: String,
    },
}

/// The framed file bytes for `sections`, in order: the header (magic, [`FORMAT_VERSION`], payload
/// length, CRC-32 of the payload), then each section's header (tag, version, length, CRC-32 of
/// its bytes) and bytes.
pub fn frame(sections: &[Section<'_>]) -> Vec<u8> {
    let len: usize = sections
        .iter()
        .map(|s| SECTION_HEADER_LEN + s.bytes.len())
        .sum();
    let mut payload = Vec::with_capacity(len);
    for s in sections {
        payload.extend_from_slice(&s.tag);
        payload.extend_from_slice(&s.version.to_le_bytes());
        payload.extend_from_slice(&(s.bytes.len() as u64).to_le_bytes());
        payload.extend_from_slice(&crc32fast::hash(s.bytes).to_le_bytes());
        payload.extend_from_slice(s.bytes);
    }
    frame_payload(&payload)
}

/// The framed file bytes for a raw `payload` (the header, then the payload as given): what
/// [`frame`] does after laying out its sections. For tests of the framing and hand-made files.
pub fn frame_payload(payload: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER_LEN + payload.len());
    bytes.extend_from_slice(&MAGIC);
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    bytes.extend_from_slice(payload);
    bytes
}

/// The sections of framed file bytes, in file order, after [`unframe`]'s checks and each
/// section's own: its header and bytes lie inside the payload and its bytes match its checksum.
///
/// `path` only labels errors.
pub fn sections<'a>(bytes: &'a [u8], path: &Path) -> Result<Vec<Section<'a>>, FileError> {
    let payload = unframe(bytes, path)?;
    let mut out = Vec::new();
    let mut at = 0usize;
    while at < payload.len() {
        let offset = HEADER_LEN + at;
        let malformed = |message: String| FileError::Section {
            path: path.to_path_buf(),
            offset,
            message,
        };
        let rest = &payload[at..];
        if rest.len() < SECTION_HEADER_LEN {
            return Err(malformed(format!(
                "{} bytes left, fewer than a {SECTION_HEADER_LEN}-byte section header",
                rest.len()
            )));
        }
        let tag: [u8; 4] = field(rest, 0);
        let version = u32::from_le_bytes(field(rest, 4));
        let len = u64::from_le_bytes(field(rest, 8));
        let stored_crc = u32::from_le_bytes(field(rest, 16));
        let available = (rest.len() - SECTION_HEADER_LEN) as u64;
        if len > available {
            return Err(malformed(format!(
                "section {} announces {len} bytes, {available} remain",
                tag_name(tag)
            )));
        }
        let body = &rest[SECTION_HEADER_LEN..SECTION_HEADER_LEN + len as usize];
        let found = crc32fast::hash(body);
        if found != stored_crc {
            return Err(FileError::SectionChecksum {
                path: path.to_path_buf(),
                tag: tag_name(tag),
                offset: offset + 16,
                expected: stored_crc,
                found,
            });
        }
        out.push(Section {
            tag,
            version,
            bytes: body,
            offset: offset + SECTION_HEADER_LEN,
        });
        at += SECTION_HEADER_LEN + len as usize;
    }
    Ok(out)
}

/// The bytes of the first section tagged `tag` in framed file bytes ([`sections`]), checked to be
/// of `version`; `what` names its content in the error when it is missing. Other sections are
/// skipped unread.
pub fn find_section<'a>(
    bytes: &'a [u8],
    tag: [u8; 4],
    version: u32,
    what: &'static str,
    path: &Path,
) -> Result<Section<'a>, FileError> {
    let section = sections(bytes, path)?
        .into_iter()
        .find(|s| s.tag == tag)
        .ok_or_else(|| FileError::MissingSection {
            path: path.to_path_buf(),
            tag: tag_name(tag),
            what,
        })?;
    if section.version != version {
        return Err(FileError::SectionVersion {
            path: path.to_path_buf(),
            tag: tag_name(tag),
            found: section.version,
            expected: version,
            hint: if section.version > version {
                " or update motion-lod"
            } else {
                ""
            },
        });
    }
    Ok(section)
}

/// Little-endian integer of `N` bytes at `offset` (the caller has checked the header's length).
fn field<const N: usize>(bytes: &[u8], offset: usize) -> [u8; N] {
    let mut out = [0u8; N];
    out.copy_from_slice(&bytes[offset..offset + N]);
    out
}

/// The payload of framed file bytes, after checking magic, version, length and checksum.
///
/// `path` only labels errors.
pub fn unframe<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a [u8], FileError> {
    let path_buf = || path.to_path_buf();
    if bytes.len() < HEADER_LEN {
        return Err(FileError::TooShort {
            path: path_buf(),
            len: bytes.len(),
        });
    }
    if bytes[..8] != MAGIC {
        return Err(FileError::BadMagic { path: path_buf() });
    }
    let version = u32::from_le_bytes(field(bytes, 8));
    if version == 0 {
        return Err(FileError::BadVersion {
            path: path_buf(),
            found: version,
        });
    }
    if version > FORMAT_VERSION {
        return Err(FileError::FutureVersion {
            path: path_buf(),
            found: version,
        });
    }
    if version < FORMAT_VERSION {
        return Err(FileError::OldVersion {
            path: path_buf(),
            found: version,
        });
    }
    let expected_len = u64::from_le_bytes(field(bytes, 12));
    let payload = &bytes[HEADER_LEN..];
    if expected_len != payload.len() as u64 {
        return Err(FileError::LengthMismatch {
            path: path_buf(),
            expected: expected_len,
            found: payload.len() as u64,
        });
    }
    let expected_crc = u32::from_le_bytes(field(bytes, 20));
    let found_crc = crc32fast::hash(payload);
    if expected_crc != found_crc {
        return Err(FileError::Checksum {
            path: path_buf(),
            expected: expected_crc,
            found: found_crc,
        });
    }
    Ok(payload)
}

/// Decodes the value of the section tagged `tag` (of `version`) from framed file bytes:
/// [`find_section`], then [`decode_payload`] of its bytes (errors give the section's offset).
///
/// `path` only labels errors.
pub fn decode_section<T: DeserializeOwned>(
    bytes: &[u8],
    tag: [u8; 4],
    version: u32,
    what: &'static str,
    path: &Path,
) -> Result<T, FileError> {
    let section = find_section(bytes, tag, version, what, path)?;
    // The framing and both checksums held, and the version is this build's: the bytes were
    // written by a build whose layout of this version differs (a format change without a version
    // change), or made by hand. Either way the cure is a rebuild.
    decode_payload(section.bytes, path).map_err(|e| match e {
        FileError::Decode { path, message } => FileError::Decode {
            path,
            message: format!(
                "section {} (offset {}..), {what} of version {version}, passed its checksum but \
                 does not decode with this build's layout of that version (a file written by \
                 another build of the same version); rebuild the model with `motion-lod build` \
                 ({message})",
                section.tag_name(),
                section.offset
            ),
        },
        other => other,
    })
}

/// Reads a file's bytes, naming the path on failure.
pub fn read(path: &Path) -> Result<Vec<u8>, FileError> {
    std::fs::read(path).map_err(|source| FileError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `bytes` to `path` so that an interrupted run leaves the old file or the new one, never
/// half of one: a temporary file in the target's folder, flushed to disk, renamed over it (and
/// removed on failure). What `path` names decides where the bytes go:
/// - a symbolic link to a file: that file is replaced, and the link kept;
/// - something that is not a regular file or a folder (`/dev/null`, a named pipe, a terminal):
///   written in place, as a shell's `>` would (renaming over it replaced `/dev/null` with a
///   regular file when run as root);
/// - a folder: an error of kind [`std::io::ErrorKind::IsADirectory`], nothing written.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let target = match std::fs::metadata(path) {
        Ok(meta) if meta.is_dir() => {
            return Err(std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "it is a folder",
            ));
        }
        Ok(meta) if !meta.is_file() => {
            return std::fs::OpenOptions::new()
                .write(true)
                .truncate(true)
                .open(path)?
                .write_all(bytes);
        }
        Ok(_) if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) => {
            std::fs::canonicalize(path)?
        }
        _ => path.to_path_buf(),
    };
    let name = target
        .file_name()
        .map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
    let tmp = target.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, &target)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Decoded bytes (as bincode counts them: the in-memory size of every primitive, and the full
/// length of a string or byte buffer before it is read) allowed per payload byte. A `u128` or an
/// enum tag can claim 16 bytes for one varint byte; nothing claims more.
const CLAIMS_PER_BYTE: usize = 16;

/// Decodes the bincode payload (the bytes after the header) exactly as [`decode_section`] does after its
/// checks, without them: the entry point for fuzzing the decoder itself. Every byte must be used.
///
/// The decode limit grows with the payload (at most `64 x` its length, at least 64 KiB), so
/// a corrupted length prefix cannot make the decoder allocate a buffer much larger than the
/// file: bincode allocates a string's bytes before reading them, up to the limit.
pub fn decode_payload<T: DeserializeOwned>(payload: &[u8], path: &Path) -> Result<T, FileError> {
    let (value, used) = decode_prefix(payload, path)?;
    if used != payload.len() {
        return Err(decode_error(
            path,
            format!("{} trailing bytes after the model", payload.len() - used),
        ));
    }
    Ok(value)
}

fn decode_error(path: &Path, message: String) -> FileError {
    FileError::Decode {
        path: path.to_path_buf(),
        message,
    }
}

/// Decodes a value from the start of `payload` with [`decode_payload`]'s configuration and limit,
/// and returns it with the number of bytes it used.
fn decode_prefix<T: DeserializeOwned>(
    payload: &[u8],
    path: &Path,
) -> Result<(T, usize), FileError> {
    let budget = payload.len().saturating_mul(CLAIMS_PER_BYTE).max(1 << 16);
    // Round the budget up to an even power of two: the limit is a const generic.
    let bits = (usize::BITS - (budget - 1).leading_zeros()).next_multiple_of(2);
    macro_rules! decode_with_limit {
        ($($b:literal)*) => {
            match bits {
                $($b => bincode::serde::decode_from_slice::<T, _>(
                    payload,
                    bincode::config::standard().with_limit::<{ 1usize << $b }>(),
                ),)*
                _ => return Err(decode_error(path, format!(
                    "payload of {} bytes is larger than this build reads",
                    payload.len()
                ))),
            }
        };
    }
    #[cfg(target_pointer_width = "64")]
    let decoded = decode_with_limit!(16 18 20 22 24 26 28 30 32 34 36 38 40);
    #[cfg(not(target_pointer_width = "64"))]
    let decoded = decode_with_limit!(16 18 20 22 24 26 28 30);
    decoded.map_err(|e| match e {
        // A part that validates itself on decoding (a `try_from` in its serde form) refused its
        // values: its message says what is wrong, without bincode's debug wrapping.
        bincode::error::DecodeError::OtherString(message) => decode_error(
            path,
            format!("invalid model (rebuild it with `motion-lod build`): {message}"),
        ),
        other => decode_error(path, other.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::{Deserialize, Serialize};

    /// `write_atomic` replaces a file, writes through a link to a file (keeping the link), writes
    /// into a device in place (found 2026-11-28: `-o /dev/null` as root renamed a regular file
    /// over `/dev/null`), refuses a folder, and leaves no temporary file.
    #[test]
    fn atomic_writes_replace_files_follow_links_and_spare_devices() {
        let dir = std::env::temp_dir().join(format!("lod-policy-write-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a.bin");
        write_atomic(&file, b"first").unwrap();
        write_atomic(&file, b"second").unwrap();
        assert_eq!(std::fs::read(&file).unwrap(), b"second");
        let e = write_atomic(&dir, b"x").unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::IsADirectory);
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            let link = dir.join("link.bin");
            std::os::unix::fs::symlink(&file, &link).unwrap();
            write_atomic(&link, b"through the link").unwrap();
            assert!(
                std::fs::symlink_metadata(&link)
                    .unwrap()
                    .file_type()
                    .is_symlink()
            );
            assert_eq!(std::fs::read(&file).unwrap(), b"through the link");
            let null = Path::new("/dev/null");
            if null.exists() {
                write_atomic(null, b"discarded").unwrap();
                let kind = std::fs::symlink_metadata(null).unwrap().file_type();
                assert!(kind.is_char_device(), "{kind:?}");
            }
        }
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        let want: &[&str] = if cfg!(unix) {
            &["a.bin", "link.bin"]
        } else {
            &["a.bin"]
        };
        assert_eq!(names, want);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Sample {
        name: String,
        values: Vec<f32>,
        dims: [u32; 3],
    }

    fn sample() -> Sample {
        Sample {
            name: "walk".into(),
            values: (0..200).map(|i| i as f32 * 0.25).collect(),
            dims: [94, 100, 186],
        }
    }

    const TAG: [u8; 4] = *b"TEST";

    fn section(bytes: &[u8]) -> Section<'_> {
        Section {
            tag: TAG,
            version: 3,
            bytes,
            offset: 0,
        }
    }

    /// A file of two sections: an unknown one first, then the sample.
    fn encode(s: &Sample) -> Vec<u8> {
        let body = bincode::serde::encode_to_vec(s, bincode::config::standard()).unwrap();
        let other = Section {
            tag: *b"XTRA",
            version: 1,
            bytes: b"skipped",
            offset: 0,
        };
        frame(&[other, section(&body)])
    }

    fn decode(bytes: &[u8]) -> Result<Sample, FileError> {
        decode_section(bytes, TAG, 3, "a sample", p())
    }

    fn p() -> &'static Path {
        Path::new("test.mlod")
    }

    #[test]
    fn round_trip_skips_other_sections() {
        let bytes = encode(&sample());
        assert_eq!(&bytes[..8], &MAGIC);
        assert_eq!(decode(&bytes).unwrap(), sample());
        let all = sections(&bytes, p()).unwrap();
        let tags: Vec<String> = all.iter().map(Section::tag_name).collect();
        assert_eq!(tags, ["XTRA", "TEST"]);
        assert_eq!(all[0].bytes, b"skipped");
        assert_eq!(all[0].offset, HEADER_LEN + SECTION_HEADER_LEN);
    }

    #[test]
    fn every_truncation_is_an_error() {
        let bytes = encode(&sample());
        for len in 0..bytes.len() {
            let err = decode(&bytes[..len]).unwrap_err();
            let ok = matches!(
                err,
                FileError::TooShort { .. } | FileError::LengthMismatch { .. }
            );
            assert!(ok, "truncation at {len} gave {err}");
        }
    }

    #[test]
    fn every_flipped_byte_is_an_error() {
        let bytes = encode(&sample());
        for i in 0..bytes.len() {
            let mut bad = bytes.clone();
            bad[i] ^= 0x5a;
            assert!(decode(&bad).is_err(), "flip at {i} went unnoticed");
        }
    }

    /// A file whose outer checksum was recomputed after a section changed: the section's own
    /// checksum still catches it, and a section that runs past the payload is named.
    #[test]
    fn sections_check_their_own_checksum_and_bounds() {
        let bytes = encode(&sample());
        let payload = unframe(&bytes, p()).unwrap().to_vec();
        let mut edited = payload.clone();
        let last = edited.len() - 1;
        edited[last] ^= 1;
        let err = decode(&frame_payload(&edited)).unwrap_err();
        assert!(
            matches!(&err, FileError::SectionChecksum { tag, .. } if tag == "TEST"),
            "{err}"
        );
        let err = decode(&frame_payload(&payload[..payload.len() - 1])).unwrap_err();
        assert!(matches!(err, FileError::Section { .. }), "{err}");
        assert!(err.to_string().contains("announces"), "{err}");
        let err = decode(&frame_payload(&payload[..10])).unwrap_err();
        assert!(err.to_string().contains("section header"), "{err}");
    }

    #[test]
    fn a_missing_or_outdated_section_asks_for_a_rebuild() {
        let bytes = encode(&sample());
        let err = decode_section::<Sample>(&bytes, *b"NONE", 1, "nothing", p()).unwrap_err();
        assert!(matches!(err, FileError::MissingSection { .. }), "{err}");
        assert!(err.to_string().contains("rebuild"), "{err}");
        let err = decode_section::<Sample>(&bytes, TAG, 4, "a sample", p()).unwrap_err();
        assert!(err.to_string().contains("rebuild"), "{err}");
        let err = decode_section::<Sample>(&bytes, TAG, 2, "a sample", p()).unwrap_err();
        assert!(err.to_string().contains("update motion-lod"), "{err}");
    }

    #[test]
    fn future_version_is_named() {
        let mut bytes = encode(&sample());
        bytes[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
        let err = decode(&bytes).unwrap_err();
        assert!(
            matches!(err, FileError::FutureVersion { found, .. } if found == FORMAT_VERSION + 1)
        );
        assert!(err.to_string().contains("newer"));
    }

    #[test]
    fn old_version_asks_for_a_rebuild() {
        let mut bytes = encode(&sample());
        bytes[8..12].copy_from_slice(&(FORMAT_VERSION - 1).to_le_bytes());
        let err = decode(&bytes).unwrap_err();
        assert!(matches!(err, FileError::OldVersion { found, .. } if found == FORMAT_VERSION - 1));
        assert!(err.to_string().contains("rebuild"));
    }

    #[test]
    fn wrong_type_is_a_decode_error_naming_the_section() {
        let body = bincode::serde::encode_to_vec(42u8, bincode::config::standard()).unwrap();
        let err = decode(&frame(&[section(&body)])).unwrap_err();
        assert!(matches!(err, FileError::Decode { .. }), "{err}");
        assert!(err.to_string().contains("section TEST"), "{err}");
        let body = bincode::serde::encode_to_vec(sample(), bincode::config::standard()).unwrap();
        let mut longer = body.clone();
        longer.push(0);
        let err = decode(&frame(&[section(&longer)])).unwrap_err();
        assert!(err.to_string().contains("trailing"), "{err}");
    }

    #[test]
    fn tags_print_as_text() {
        assert_eq!(tag_name(*b"RTIM"), "RTIM");
        assert_eq!(tag_name([b'A', 0, 0xff, b'\n']), "A\\x00\\xff\\n");
    }
}
