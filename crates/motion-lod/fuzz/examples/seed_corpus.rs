//! Writes the seed corpus of every fuzz target under `corpus/<target>/` (git-ignored):
//!
//! - `bvh`: the BVH files of `fixtures/`, plus CRLF, tab and 1-frame variants of the first one;
//! - `npy`: small arrays written by `tensor_ops::npy` (f8/f4, C/Fortran order, 0-d to 3-d,
//!   format 2.0, big-endian);
//! - `model_file` / `model_payload`: the small real `MotionModel` of `seed_model.rs` (the whole
//!   file, and its runtime section's bytes); `model_mutated`: a few edit lists.
//!
//! Run: `cargo run --release --manifest-path crates/motion-lod/fuzz/Cargo.toml --example seed_corpus`

use std::fs;
use std::path::{Path, PathBuf};

use motion_lod::model_file::encode;
use tensor_ops::npy::{NpyArray, NpyDtype, to_npy_bytes};

#[path = "../seed_model.rs"]
mod seed_model;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn main() -> Result<()> {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let fixtures = here.join("../../../fixtures");
    let corpus = here.join("corpus");
    seed_bvh(&fixtures, &corpus.join("bvh"))?;
    seed_npy(&corpus.join("npy"))?;
    seed_models(&fixtures, &corpus)?;
    Ok(())
}

fn dir(p: &Path) -> Result<&Path> {
    fs::create_dir_all(p)?;
    Ok(p)
}

fn seed_bvh(fixtures: &Path, out: &Path) -> Result<()> {
    let out = dir(out)?;
    let mut files: Vec<PathBuf> = fs::read_dir(fixtures)?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "bvh"))
        .collect();
    files.sort();
    for f in &files {
        fs::copy(f, out.join(f.file_name().expect("a file")))?;
    }
    let first = fs::read_to_string(files.first().ok_or("no BVH in fixtures/")?)?;
    fs::write(out.join("variant_crlf.bvh"), first.replace('\n', "\r\n"))?;
    fs::write(out.join("variant_tabs.bvh"), first.replace(' ', "\t"))?;
    // Hierarchy plus one frame: small inputs mutate faster.
    let motion_at = first.find("MOTION").ok_or("no MOTION")?;
    let frame1 = first[motion_at..].lines().nth(3).ok_or("no frame")?;
    let short = format!(
        "{}MOTION\nFrames: 1\nFrame Time: 0.033333\n{frame1}\n",
        &first[..motion_at]
    );
    fs::write(out.join("variant_one_frame.bvh"), short)?;
    println!("bvh: {} files", files.len() + 3);
    Ok(())
}

fn seed_npy(out: &Path) -> Result<()> {
    let out = dir(out)?;
    let seq = |n: usize| (0..n).map(|i| i as f64 * 0.5 - 1.0).collect::<Vec<_>>();
    let arrays = [
        (
            "c_2x3_f8",
            NpyArray::new(vec![2, 3], seq(6), false)?,
            NpyDtype::F64,
        ),
        (
            "f_2x3x2_f4",
            NpyArray::new(vec![2, 3, 2], seq(12), true)?,
            NpyDtype::F32,
        ),
        (
            "scalar_f8",
            NpyArray::new(vec![], seq(1), false)?,
            NpyDtype::F64,
        ),
        (
            "empty_f8",
            NpyArray::new(vec![0], vec![], false)?,
            NpyDtype::F64,
        ),
        (
            "vec_5_f4",
            NpyArray::new(vec![5], seq(5), false)?,
            NpyDtype::F32,
        ),
    ];
    for (name, a, dtype) in &arrays {
        fs::write(out.join(format!("{name}.npy")), to_npy_bytes(a, *dtype)?)?;
    }
    // Big-endian f8 (same header length, data bytes swapped).
    let a = &arrays[0].1;
    let mut be = to_npy_bytes(a, NpyDtype::F64)?;
    let at = be.windows(3).position(|w| w == b"<f8").ok_or("descr")?;
    be[at] = b'>';
    let data_start = be.len() - 8 * a.data.len();
    for (chunk, v) in be[data_start..].chunks_exact_mut(8).zip(&a.data) {
        chunk.copy_from_slice(&v.to_be_bytes());
    }
    fs::write(out.join("c_2x3_be_f8.npy"), be)?;
    // Format 2.0: u32 header length.
    let mut v2 = vec![0x93];
    v2.extend_from_slice(b"NUMPY\x02\x00");
    let dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }";
    let hlen = (12 + dict.len() + 1).div_ceil(64) * 64 - 12;
    v2.extend_from_slice(&(hlen as u32).to_le_bytes());
    v2.extend_from_slice(dict.as_bytes());
    v2.resize(12 + hlen - 1, b' ');
    v2.push(b'\n');
    v2.extend_from_slice(&1.5f64.to_le_bytes());
    v2.extend_from_slice(&(-2.0f64).to_le_bytes());
    fs::write(out.join("v2_vec_f8.npy"), v2)?;
    println!("npy: {} files", arrays.len() + 2);
    Ok(())
}

fn seed_models(fixtures: &Path, corpus: &Path) -> Result<()> {
    let model = seed_model::build_small_model(fixtures)?;
    let bytes = encode(&model, Path::new("seed.mlod"))?;
    fs::write(dir(&corpus.join("model_file"))?.join("small.mlod"), &bytes)?;
    fs::write(
        dir(&corpus.join("model_payload"))?.join("small.bin"),
        model.runtime().section_bytes(),
    )?;
    println!("model: {} bytes", bytes.len());
    // Edit lists for `model_mutated` (see `mutate_model.rs`): an op byte, then its operands.
    let mutated = corpus.join("model_mutated");
    dir(&mutated)?;
    let edits: [&[u8]; 6] = [
        &[],
        &[0, 0, 0, 0, 3, 7],          // small integer into the 4th number
        &[2, 0, 0, 1, 0],             // NaN into the 257th number
        &[5, 0, 0, 0, 1, 0, 0, 0, 0], // remove an element of the 2nd array
        &[6, 0, 0, 0, 9, 0, 0, 0, 2], // duplicate an element
        &[8, 0, 0, 0, 3, 0, 0, 0, 1], // truncate an array
    ];
    for (i, e) in edits.iter().enumerate() {
        fs::write(mutated.join(format!("edits{i}")), e)?;
    }
    Ok(())
}
