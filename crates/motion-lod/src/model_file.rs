//! The model file, offline side: encoding and atomic writing. The framing (magic, version, length,
//! checksum), its errors and the reader are the runtime's ([`lod_policy::file`]), re-exported here so
//! that there is one copy of each rule.
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

/// Why a model file could not be read or written (the runtime's [`lod_policy::FileError`]).
pub use lod_policy::file::FileError as ModelFileError;
pub use lod_policy::file::{FORMAT_VERSION, HEADER_LEN, MAGIC, decode};

/// The runtime's payload decoder ([`lod_policy::file::decode_payload`]): the entry point for fuzzing
/// the decoder itself.
#[doc(hidden)]
pub use lod_policy::file::decode_payload;

/// Encodes `value` into the framed byte layout described in the module documentation
/// ([`lod_policy::file::frame`]).
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
    Ok(lod_policy::file::frame(&payload))
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
    decode(&lod_policy::file::read(path)?, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Any serde value will do: the framing's own tests are the runtime's (`lod_policy::file`).
    type Sample = (String, Vec<f32>);

    fn sample() -> Sample {
        ("walk".into(), (0..200).map(|i| i as f32 * 0.25).collect())
    }

    fn p() -> &'static Path {
        Path::new("test.mlod")
    }

    #[test]
    fn round_trip() {
        let bytes = encode(&sample(), p()).unwrap();
        assert_eq!((&bytes[..8], bytes.len() > HEADER_LEN), (&MAGIC[..], true));
        assert_eq!(decode::<Sample>(&bytes, p()).unwrap(), sample());
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
