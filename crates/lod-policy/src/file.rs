//! The model file's framing, and the reader an engine loads models with.
//!
//! Layout (all integers little-endian):
//!
//! | offset | size | content |
//! |---|---|---|
//! | 0 | 8 | magic `b"MLOD\r\n\x1a\n"` (catches text-mode transfers, like PNG's) |
//! | 8 | 4 | format version (`u32`) |
//! | 12 | 8 | payload length in bytes (`u64`) |
//! | 20 | 4 | CRC-32 (IEEE) of the payload |
//! | 24 | n | payload: `bincode` 2 (standard configuration) of the serde value |
//!
//! The offline builder (`motion_lod::model_file`) writes files with [`frame`]; every reader goes
//! through [`unframe`]: a wrong magic, another version, a length that disagrees with the file or a
//! checksum mismatch is a [`FileError`] naming the path and the offset, and a payload that does
//! not decode is one too. Nothing panics, and the decoder never allocates more than a small
//! multiple of the file ([`decode_payload`]).
//!
//! The payload of a motion model is `(PoseLayout, LodModel, BuildReport)` in that order; the runtime
//! reads the first two ([`crate::RuntimeModel::from_bytes`]) and ignores the report.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// The eight bytes every model file starts with.
pub const MAGIC: [u8; 8] = *b"MLOD\r\n\x1a\n";
/// The format version this build writes and the only one it reads.
pub const FORMAT_VERSION: u32 = 7;

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
// scale of each character, and the data's takes measured with their own body scale). Files of an
// older version are refused
// with a request to rebuild: a model is
// rebuilt from its data in seconds, and a converter would carry guesses.
/// Bytes before the payload: magic, version, length, checksum.
pub const HEADER_LEN: usize = 24;

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
    /// The value could not be encoded (writing a model, offline).
    #[error("{path}: cannot encode model: {message}")]
    Encode {
        /// The file concerned.
        path: PathBuf,
        /// What bincode reported.
        message: String,
    },
}

/// The framed file bytes for an encoded `payload`: the header (magic, [`FORMAT_VERSION`], payload
/// length, CRC-32 of the payload), then the payload.
pub fn frame(payload: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER_LEN + payload.len());
    bytes.extend_from_slice(&MAGIC);
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    bytes.extend_from_slice(payload);
    bytes
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

/// Decodes a value from framed file bytes: [`unframe`], then [`decode_payload`].
///
/// `path` only labels errors.
pub fn decode<T: DeserializeOwned>(bytes: &[u8], path: &Path) -> Result<T, FileError> {
    decode_payload(unframe(bytes, path)?, path)
}

/// Reads a file's bytes, naming the path on failure.
pub fn read(path: &Path) -> Result<Vec<u8>, FileError> {
    std::fs::read(path).map_err(|source| FileError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Decoded bytes (as bincode counts them: the in-memory size of every primitive, and the full
/// length of a string or byte buffer before it is read) allowed per payload byte. A `u128` or an
/// enum tag can claim 16 bytes for one varint byte; nothing claims more.
const CLAIMS_PER_BYTE: usize = 16;

/// Decodes the bincode payload (the bytes after the header) exactly as [`decode`] does after its
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
/// and returns it with the number of bytes it used (later bytes are not read: bincode is
/// sequential, so the first fields of a larger value decode alone).
pub fn decode_prefix<T: DeserializeOwned>(
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

    fn encode(s: &Sample) -> Vec<u8> {
        frame(&bincode::serde::encode_to_vec(s, bincode::config::standard()).unwrap())
    }

    fn p() -> &'static Path {
        Path::new("test.mlod")
    }

    #[test]
    fn round_trip() {
        let bytes = encode(&sample());
        assert_eq!(&bytes[..8], &MAGIC);
        let back: Sample = decode(&bytes, p()).unwrap();
        assert_eq!(back, sample());
    }

    #[test]
    fn every_truncation_is_an_error() {
        let bytes = encode(&sample());
        for len in 0..bytes.len() {
            let err = decode::<Sample>(&bytes[..len], p()).unwrap_err();
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
            assert!(
                decode::<Sample>(&bad, p()).is_err(),
                "flip at {i} went unnoticed"
            );
        }
    }

    #[test]
    fn future_version_is_named() {
        let mut bytes = encode(&sample());
        bytes[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
        let err = decode::<Sample>(&bytes, p()).unwrap_err();
        assert!(
            matches!(err, FileError::FutureVersion { found, .. } if found == FORMAT_VERSION + 1)
        );
        assert!(err.to_string().contains("newer"));
    }

    #[test]
    fn old_version_asks_for_a_rebuild() {
        let mut bytes = encode(&sample());
        bytes[8..12].copy_from_slice(&(FORMAT_VERSION - 1).to_le_bytes());
        let err = decode::<Sample>(&bytes, p()).unwrap_err();
        assert!(matches!(err, FileError::OldVersion { found, .. } if found == FORMAT_VERSION - 1));
        assert!(err.to_string().contains("rebuild"));
    }

    #[test]
    fn wrong_type_is_a_decode_error_and_a_prefix_decodes_alone() {
        let bytes =
            frame(&bincode::serde::encode_to_vec(42u8, bincode::config::standard()).unwrap());
        let err = decode::<Sample>(&bytes, p()).unwrap_err();
        assert!(matches!(err, FileError::Decode { .. }), "{err}");
        let payload = unframe(&encode(&sample()), p()).unwrap().to_vec();
        let (name, used): (String, usize) = decode_prefix(&payload, p()).unwrap();
        assert_eq!((name.as_str(), used), ("walk", 5));
        let err = decode_payload::<String>(&payload, p()).unwrap_err();
        assert!(err.to_string().contains("trailing"), "{err}");
    }
}
