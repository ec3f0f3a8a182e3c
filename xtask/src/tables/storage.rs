//! Table 1: storage of the raw samples, of every accuracy level by ALS, of the hybrid key levels and of
//! PCA (paper section 5.1: 13.34, 9.7, 1.45 and 5.7 MB at 94 x 100 x 186).

use std::path::Path;

use anyhow::{Context, Result};
use hosvd_als::storage::{all_levels_bytes, dense_bytes, key_levels_bytes, tucker_bytes};
use lod_policy::Precision;
use motion_lod::{Analysis, MotionModel};

use super::markdown::{Table, mb, mib, percent};

/// The paper's published storage figures (section 5.1), in its "MB" (mebibytes, `2^20` bytes).
pub const PAPER_MIB: [(&str, f64); 4] = [
    ("raw samples", 13.34),
    ("all levels by ALS", 9.7),
    ("hybrid key levels", 1.45),
    ("PCA", 5.7),
];

/// One row of the storage table: bytes in f64 and in f32.
#[derive(Debug, Clone, PartialEq)]
pub struct StorageRow {
    /// What is stored.
    pub what: String,
    /// Bytes with 8-byte values.
    pub f64_bytes: usize,
    /// Bytes with 4-byte values.
    pub f32_bytes: usize,
}

/// Bytes of the PCA baseline at rank `r`: the `r x T x S` projected samples and the `P x r` basis,
/// `(r T S + P r) * size` (paper section 5.1).
pub fn pca_bytes(dims: [usize; 3], r: usize, size: usize) -> usize {
    let [p, t, s] = dims;
    let r = r.clamp(1, p);
    (r * t * s + p * r) * size
}

/// The four rows of the paper, counted as it counts them (Tucker cores and factor matrices, no kriging
/// data): raw samples, every accuracy level by ALS, the hybrid key levels, PCA at `pca_rank`.
pub fn paper_rows(analysis: &Analysis, pca_rank: usize) -> Vec<StorageRow> {
    let dims = analysis.tensor.dims();
    let both = |f: &dyn Fn(Precision) -> usize| (f(Precision::F64), f(Precision::F32));
    let rows: [(String, (usize, usize)); 4] = [
        (
            format!("raw samples ({} x {} x {})", dims[0], dims[1], dims[2]),
            both(&|pr| dense_bytes(dims, pr.value_bytes())),
        ),
        (
            format!("all {} accuracy levels by ALS", analysis.levels.len()),
            both(&|pr| all_levels_bytes(dims, &analysis.levels, pr.value_bytes())),
        ),
        (
            format!("hybrid: {} key levels", analysis.keys.levels.len()),
            both(&|pr| key_levels_bytes(&analysis.keys, pr.value_bytes())),
        ),
        (
            format!("PCA (R_P = {})", pca_rank.clamp(1, dims[0])),
            both(&|pr| pca_bytes(dims, pca_rank, pr.value_bytes())),
        ),
    ];
    rows.into_iter()
        .map(|(what, (f64_bytes, f32_bytes))| StorageRow {
            what,
            f64_bytes,
            f32_bytes,
        })
        .collect()
}

/// Bytes of `model` as a model file (header and bincode payload, f32 values).
pub fn model_file_bytes(model: &MotionModel) -> Result<usize> {
    Ok(
        motion_lod::model_file::encode(model, Path::new("tables.mlod"))
            .context("encoding the model file")?
            .len(),
    )
}

/// The storage section in markdown: the paper's four rows with ours beside them, then the runtime form
/// of the hybrid model and of ALS at every level (kriging projections instead of `U_S`, model file).
pub fn section(
    analysis: &Analysis,
    hybrid: &MotionModel,
    als_every: &MotionModel,
    pca_rank: usize,
) -> Result<String> {
    let rows = paper_rows(analysis, pca_rank);
    let raw = rows[0].f64_bytes as f64;
    let paper_raw = PAPER_MIB[0].1;
    let mut t = Table::new(&[
        "stored",
        ">paper (published), 94 x 100 x 186",
        ">paper ratio to raw",
        ">ours, f64",
        ">ours, f32",
        ">ours, ratio to raw",
    ]);
    for (row, (_, paper)) in rows.iter().zip(PAPER_MIB) {
        t.row(&[
            row.what.clone(),
            format!("{paper} MB"),
            percent(paper / paper_raw),
            format!("{} ({})", mib(row.f64_bytes), mb(row.f64_bytes)),
            mib(row.f32_bytes),
            percent(row.f64_bytes as f64 / raw),
        ]);
    }
    let key0 = &analysis.keys.levels[0];
    let mut out = String::new();
    out.push_str(&format!(
        "Counted as the paper counts (section 5.1): a Tucker model is its core and its three factor \
         matrices, `(R_P R_T R_S + P R_P + T R_T + S R_S) x bytes`; the paper's \"MB\" are MiB \
         (94 x 100 x 186 x 8 bytes = 13.34). Key 0 alone ({}) is {}.\n\n",
        super::markdown::ranks(key0.ranks),
        mib(tucker_bytes(analysis.tensor.dims(), key0.ranks, Precision::F64.value_bytes()))
    ));
    out.push_str(&t.render());

    let mut rt = Table::new(&[
        "runtime model",
        ">keys",
        ">f64",
        ">f32",
        ">model file (f32)",
        ">file / raw f64",
    ]);
    for (name, m) in [
        ("hybrid (the built model)", hybrid),
        ("ALS at every level", als_every),
    ] {
        let file = model_file_bytes(m)?;
        rt.row(&[
            name.to_string(),
            m.lod().keys().len().to_string(),
            mib(m.lod().bytes(Precision::F64)),
            mib(m.lod().bytes(Precision::F32)),
            format!("{} ({file} bytes)", mib(file)),
            percent(file as f64 / raw),
        ]);
    }
    out.push_str(
        "\nWhat the runtime keeps instead (`LodModel::bytes`): per key the core, `U_P`, `U_T`, the kriging \
         projection `Q` (R_S x (S + 1)) and the trend `V` in place of `U_S`, plus the control space \
         (with the kriging rows of the controls, (d + 1) x (S + 1), stored once for all keys) and the mean \
         pose; the model file is the f32 model with the skeleton and the build report.\n\n",
    );
    out.push_str(&rt.render());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pca_bytes_at_the_papers_size_is_its_5_7_mb() {
        // 40 components of 100 frames x 186 samples plus the 94 x 40 basis, in doubles.
        let b = pca_bytes([94, 100, 186], 40, 8);
        assert_eq!(b, (40 * 100 * 186 + 94 * 40) * 8);
        assert!((b as f64 / (1u64 << 20) as f64 - 5.7).abs() < 0.05);
    }
}
