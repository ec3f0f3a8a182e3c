//! Reading every BVH file of a folder, keeping going past bad files.

use std::path::{Path, PathBuf};

use crate::bvh::{BvhError, read_bvh};
use crate::motion::Motion;

/// The result of [`read_folder`]: the motions that loaded and the files that did not, both sorted
/// by file name.
#[derive(Debug, Default)]
pub struct FolderReport {
    /// Successfully read files.
    pub motions: Vec<(PathBuf, Motion)>,
    /// Files that failed, with their error (which names the line).
    pub failed: Vec<(PathBuf, BvhError)>,
}

/// Reads every `*.bvh` file (case-insensitive extension, not recursive) of `dir`, in file-name
/// order, in parallel. A file that fails is reported in `failed` and the others still load.
/// Fails only when the folder itself cannot be listed.
pub fn read_folder(dir: impl AsRef<Path>) -> Result<FolderReport, BvhError> {
    use rayon::prelude::*;
    let dir = dir.as_ref();
    let io = |source| BvhError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut paths = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let p = entry.map_err(io)?.path();
        if p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bvh")) {
            paths.push(p);
        }
    }
    paths.sort();
    let results: Vec<(PathBuf, Result<Motion, BvhError>)> = paths
        .into_par_iter()
        .map(|p| {
            let r = read_bvh(&p);
            (p, r)
        })
        .collect();
    let mut report = FolderReport::default();
    for (p, r) in results {
        match r {
            Ok(m) => report.motions.push((p, m)),
            Err(e) => report.failed.push((p, e)),
        }
    }
    Ok(report)
}
