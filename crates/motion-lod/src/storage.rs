//! Storage accounting of a model, counted as the paper counts its 1.45 MB (section 5.1): everything the
//! hybrid model keeps (key cores and factors, the kriging data), against the raw aligned samples.

use lod_policy::Precision;
use serde::Serialize;

use crate::model::MotionModel;

/// Bytes of the raw samples and of the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Storage {
    /// The aligned samples in f64: `P T S x 8` (what naive interpolation keeps).
    pub raw_f64: usize,
    /// Everything the hybrid model keeps, in f64 (the analysis precision).
    pub model_f64: usize,
    /// The same in f32 (the runtime model and the model file).
    pub model_f32: usize,
}

impl Storage {
    /// Accounts `model`.
    pub fn of(model: &MotionModel) -> Storage {
        let lod = model.lod();
        Storage {
            raw_f64: lod.p() * lod.t() * lod.s() * 8,
            model_f64: lod.bytes(Precision::F64),
            model_f32: lod.bytes(Precision::F32),
        }
    }
}
