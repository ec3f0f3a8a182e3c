//! The model file: a framed, checksummed bincode payload, written atomically.
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
//! A wrong magic, a newer version, a length that disagrees with the file, a checksum mismatch or a payload
//! that does not decode is a [`ModelFileError`] naming the path and the offset; nothing panics and the
//! decoder never allocates more than a small multiple of the file (see [`decode_payload`]).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// The eight bytes every model file starts with.
pub const MAGIC: [u8; 8] = *b"MLOD\r\n\x1a\n";
/// The format version this build writes and the newest it reads.
pub const FORMAT_VERSION: u32 = 5;

// Version history: 1 (first release); 2 (the build report records the DOF row weights and the build
// settings their choice); 3 (the kriging rows of the controls, `C A^-1`, are stored once in the control
// space instead of in every key's projection); 4 (no build time in the report, so that the same build
// writes the same bytes; ALS convergence per key; the pose layout stores only what it is built from
// and is validated on load; the motion-quality reference measured on the training takes; static
// joints leave the pose vector, and the build report records them, the control selection and the
// joint-order note); 5 (every level and joint-count error records the foot slide, for the policies'
// screen check; the recorded data folders are relative to the model file, and the data
// specification records the units, up axis and joint map). Files of an older version are refused
// with a request to rebuild: a model is
// rebuilt from its data in seconds, and a converter would carry guesses.
/// Bytes before the payload: magic, version, length, checksum.
pub const HEADER_LEN: usize = 24;

/// Why a model file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
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
        source: crate::model::InvalidModel,
    },
    /// The value could not be encoded.
    #[error("{path}: cannot encode model: {message}")]
    Encode {
        /// The file concerned.
        path: PathBuf,
        /// What bincode reported.
        message: String,
    },
}

/// Encodes `value` into the framed byte layout described in the module documentation.
///
/// `path` only labels errors.
pub fn encode<T: Serialize>(value: &T, path: &Path) -> Result<Vec<u8>, ModelFileError> {
    let payload =
        bincode::serde::encode_to_vec(value, bincode::config::standard()).map_err(|e| {
            ModelFileError::Encode {
                path: path.to_path_buf(),
                message: e.to_string(),
            }
        })?;
    let mut bytes = Vec::with_capacity(HEADER_LEN + payload.len());
    bytes.extend_from_slice(&MAGIC);
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
    bytes.extend_from_slice(&payload);
    Ok(bytes)
}

/// Decodes a value from bytes in the framed layout, checking magic, version, length and checksum.
///
/// `path` only labels errors.
pub fn decode<T: DeserializeOwned>(bytes: &[u8], path: &Path) -> Result<T, ModelFileError> {
    let path_buf = || path.to_path_buf();
    if bytes.len() < HEADER_LEN {
        return Err(ModelFileError::TooShort {
            path: path_buf(),
            len: bytes.len(),
        });
    }
    if bytes[..8] != MAGIC {
        return Err(ModelFileError::BadMagic { path: path_buf() });
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version == 0 {
        return Err(ModelFileError::BadVersion {
            path: path_buf(),
            found: version,
        });
    }
    if version > FORMAT_VERSION {
        return Err(ModelFileError::FutureVersion {
            path: path_buf(),
            found: version,
        });
    }
    if version < FORMAT_VERSION {
        return Err(ModelFileError::OldVersion {
            path: path_buf(),
            found: version,
        });
    }
    let expected_len = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER_LEN..];
    if expected_len != payload.len() as u64 {
        return Err(ModelFileError::LengthMismatch {
            path: path_buf(),
            expected: expected_len,
            found: payload.len() as u64,
        });
    }
    let expected_crc = u32::from_le_bytes(bytes[20..24].try_into().expect("4 bytes"));
    let found_crc = crc32fast::hash(payload);
    if expected_crc != found_crc {
        return Err(ModelFileError::Checksum {
            path: path_buf(),
            expected: expected_crc,
            found: found_crc,
        });
    }
    decode_payload(payload, path)
}

/// Decoded bytes (as bincode counts them: the in-memory size of every primitive, and the full
/// length of a string or byte buffer before it is read) allowed per payload byte. A `u128` or an
/// enum tag can claim 16 bytes for one varint byte; nothing claims more.
const CLAIMS_PER_BYTE: usize = 16;

/// Decodes the bincode payload (the bytes after the header) exactly as [`decode`] does after its
/// checks, without them: the entry point for fuzzing the decoder itself.
///
/// The decode limit grows with the payload (at most `64 x` its length, at least 64 KiB), so
/// a corrupted length prefix cannot make the decoder allocate a buffer much larger than the
/// file: bincode allocates a string's bytes before reading them, up to the limit.
#[doc(hidden)]
pub fn decode_payload<T: DeserializeOwned>(
    payload: &[u8],
    path: &Path,
) -> Result<T, ModelFileError> {
    let decode_error = |message: String| ModelFileError::Decode {
        path: path.to_path_buf(),
        message,
    };
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
                _ => return Err(decode_error(format!(
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
    let (value, used) = decoded.map_err(|e| match e {
        // A part that validates itself on decoding (a `try_from` in its serde form) refused its
        // values: its message says what is wrong, without bincode's debug wrapping.
        bincode::error::DecodeError::OtherString(message) => decode_error(format!(
            "invalid model (rebuild it with `motion-lod build`): {message}"
        )),
        other => decode_error(other.to_string()),
    })?;
    if used != payload.len() {
        return Err(decode_error(format!(
            "{} trailing bytes after the model",
            payload.len() - used
        )));
    }
    Ok(value)
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed to disk, then renamed
/// over `path`. An interrupted run leaves either the old file or the new one, never half of one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ModelFileError> {
    let io = |source| ModelFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".to_owned());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut file = fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
}

/// Encodes `value` and writes it to `path` atomically.
pub fn save<T: Serialize>(value: &T, path: &Path) -> Result<(), ModelFileError> {
    let bytes = encode(value, path)?;
    write_atomic(path, &bytes)
}

/// Reads and decodes a model file.
pub fn load<T: DeserializeOwned>(path: &Path) -> Result<T, ModelFileError> {
    let bytes = fs::read(path).map_err(|source| ModelFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    decode(&bytes, path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

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

    fn p() -> &'static Path {
        Path::new("test.mlod")
    }

    #[test]
    fn round_trip() {
        let bytes = encode(&sample(), p()).unwrap();
        assert_eq!(&bytes[..8], &MAGIC);
        let back: Sample = decode(&bytes, p()).unwrap();
        assert_eq!(back, sample());
    }

    #[test]
    fn every_truncation_is_an_error() {
        let bytes = encode(&sample(), p()).unwrap();
        for len in 0..bytes.len() {
            let err = decode::<Sample>(&bytes[..len], p()).unwrap_err();
            let ok = matches!(
                err,
                ModelFileError::TooShort { .. } | ModelFileError::LengthMismatch { .. }
            );
            assert!(ok, "truncation at {len} gave {err}");
        }
    }

    #[test]
    fn every_flipped_byte_is_an_error() {
        let bytes = encode(&sample(), p()).unwrap();
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
        let mut bytes = encode(&sample(), p()).unwrap();
        bytes[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
        let err = decode::<Sample>(&bytes, p()).unwrap_err();
        assert!(
            matches!(err, ModelFileError::FutureVersion { found, .. } if found == FORMAT_VERSION + 1)
        );
        assert!(err.to_string().contains("newer"));
    }

    #[test]
    fn old_version_asks_for_a_rebuild() {
        let mut bytes = encode(&sample(), p()).unwrap();
        bytes[8..12].copy_from_slice(&(FORMAT_VERSION - 1).to_le_bytes());
        let err = decode::<Sample>(&bytes, p()).unwrap_err();
        assert!(
            matches!(err, ModelFileError::OldVersion { found, .. } if found == FORMAT_VERSION - 1)
        );
        assert!(err.to_string().contains("rebuild"));
    }

    #[test]
    fn wrong_type_is_a_decode_error() {
        let bytes = encode(&42u8, p()).unwrap();
        let err = decode::<Sample>(&bytes, p()).unwrap_err();
        assert!(matches!(err, ModelFileError::Decode { .. }), "{err}");
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("mlod-file-test-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.mlod");
        save(&sample(), &path).unwrap();
        save(&sample(), &path).unwrap();
        let back: Sample = load(&path).unwrap();
        assert_eq!(back, sample());
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
        let err = save(&sample(), &path).unwrap_err();
        assert!(matches!(err, ModelFileError::Io { .. }));
    }
}
