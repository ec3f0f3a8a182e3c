//! Structured mutation of a decoded model, shared by the `model_mutated` fuzz target and the
//! `mutated_models_never_panic` test of `tests/hostile_model.rs` (which includes this file with
//! `#[path]`).
//!
//! Byte-level fuzzing of a model file mostly stops at the checksum or the decoder. Here the fuzzer
//! edits the model's *parts* instead: the seed model is turned into a JSON tree of its serde layout
//! (the same fields the file's two sections store, before any validation: [`RawModel`]), the input bytes are read as a list of
//! edits on that tree (set a number, make it NaN or infinite, remove, duplicate, swap or truncate an
//! array's elements), the tree is read back into the unvalidated parts, written as a model file with
//! a valid checksum, and then every consumer a user can reach runs on it: loading, `info`'s report,
//! a few crowd frames and a synthesized walk. Each may refuse the model with an error; none may
//! panic.

use std::path::Path;

use motion_lod::crowd::{CrowdRun, run_crowd};
use motion_lod::crowd_sim::{Camera, CrowdConfig, Scene};
use motion_lod::lod_policy::{Controls, Detail, DistancePolicy};
use motion_lod::lod_policy::{FootRig, ModelParts, RigJoint, RuntimeModel, file};
use motion_lod::motion_io::PoseLayoutParts;
use motion_lod::synth::WalkRequest;
use motion_lod::{BuildReport, LodSource, MotionModel, info};
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The runtime section's parts in its serde layout (`lod_policy::RuntimeModel`'s), unvalidated.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RawRuntime {
    /// The control names.
    pub control_names: Vec<String>,
    /// The rig's joints.
    pub joints: Vec<RigJoint>,
    /// The multilinear model's parts.
    pub lod: ModelParts,
    /// The feet for the foot lock.
    pub feet: Option<FootRig>,
    /// The rig's stature.
    pub stature_m: Option<f32>,
}

/// A model's parts in the file's serde layout (the runtime section, then the report section's
/// pose layout and build report), unvalidated.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RawModel {
    /// The runtime section.
    pub runtime: RawRuntime,
    /// The report section's pose layout.
    pub layout: PoseLayoutParts,
    /// The report section's build report.
    pub report: BuildReport,
}

impl RawModel {
    /// The parts of `model`.
    pub fn new(model: &MotionModel) -> RawModel {
        RawModel {
            runtime: RawRuntime {
                control_names: motion_lod::lod_policy::Controls::NAMES
                    .map(String::from)
                    .to_vec(),
                joints: model.rig().joints().to_vec(),
                lod: model.lod().clone().into_parts(),
                feet: model.feet().copied(),
                stature_m: model.stature_m(),
            },
            layout: model.layout.clone().into(),
            report: model.report.clone(),
        }
    }

    /// The bytes of the runtime and report sections.
    pub fn section_bytes(&self) -> (Vec<u8>, Vec<u8>) {
        let cfg = bincode::config::standard();
        let runtime = bincode::serde::encode_to_vec(&self.runtime, cfg).expect("encodes");
        let report =
            bincode::serde::encode_to_vec((&self.layout, &self.report), cfg).expect("encodes");
        (runtime, report)
    }

    /// A model file of these parts, with valid checksums (used by `tests/hostile_model.rs`; the
    /// fuzz targets frame edited section bytes with [`frame`]).
    #[cfg_attr(not(test), allow(dead_code))]
    pub fn file(&self) -> Vec<u8> {
        let (runtime, report) = self.section_bytes();
        frame(&runtime, &report)
    }
}

/// A model file of the two sections' bytes, with valid checksums.
pub fn frame(runtime: &[u8], report: &[u8]) -> Vec<u8> {
    file::frame(&[
        RuntimeModel::section(runtime),
        motion_lod::model_file::report_section(report),
    ])
}

/// A float no real model holds, exact in f32 and f64: written into the tree where an edit asks for
/// NaN (JSON has no NaN), then replaced by NaN in the encoded bytes.
const NAN_MARK: f64 = 12345.5;
/// As [`NAN_MARK`], for +infinity.
const INF_MARK: f64 = 23456.25;

/// The seed model as an editable tree.
pub struct Seed {
    tree: Value,
}

impl Seed {
    /// The tree of `model`'s parts. JSON writes NaN as `null`: the NaN a model legitimately holds
    /// (the leave-one-out statistics of control decisions made without selection) become
    /// [`NAN_MARK`] again, so that the unedited tree reads back into the parts.
    pub fn new(model: &MotionModel) -> Seed {
        let mut tree =
            serde_json::to_value(RawModel::new(model)).expect("a model serialises to JSON");
        if let Some(decisions) = tree.pointer_mut("/report/control_decisions") {
            nulls_to_nan_mark(decisions);
        }
        if let Err(e) = serde_json::from_value::<RawModel>(tree.clone()) {
            panic!("the seed model's JSON tree does not read back into its parts: {e}");
        }
        Seed { tree }
    }
}

/// What happened to one mutated model (for the test's statistics).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// The edits gave a tree that is not the parts' layout (a float in an integer field, say).
    NotParts,
    /// The file was refused on load (decoding or validation).
    Refused,
    /// The model loaded; info, the crowd and synthesis ran (each may have returned an error).
    Loaded {
        /// The crowd run returned an error.
        crowd_failed: bool,
        /// The synthesized walk returned an error.
        synth_failed: bool,
    },
}

/// Reads the input as edits on the seed, writes the model file and runs every consumer on it.
pub fn run(seed: &Seed, data: &[u8]) -> Outcome {
    let Some(bytes) = mutated_file(seed, data) else {
        return Outcome::NotParts;
    };
    exercise(&bytes)
}

/// The model file (valid header and checksum) of the seed after the edits `data` encodes, or `None`
/// when the edited tree is not the parts' layout.
pub fn mutated_file(seed: &Seed, data: &[u8]) -> Option<Vec<u8>> {
    let mut tree = seed.tree.clone();
    let mut input = Input(data);
    for _ in 0..8 {
        let Some(op) = input.byte() else { break };
        edit(&mut tree, op, &mut input);
    }
    let raw: RawModel = serde_json::from_value(tree).ok()?;
    let (mut runtime, mut report) = raw.section_bytes();
    for payload in [&mut runtime, &mut report] {
        replace_all(
            payload,
            &(NAN_MARK as f32).to_le_bytes(),
            &f32::NAN.to_le_bytes(),
        );
        replace_all(payload, &NAN_MARK.to_le_bytes(), &f64::NAN.to_le_bytes());
        replace_all(
            payload,
            &(INF_MARK as f32).to_le_bytes(),
            &f32::INFINITY.to_le_bytes(),
        );
        replace_all(
            payload,
            &INF_MARK.to_le_bytes(),
            &f64::INFINITY.to_le_bytes(),
        );
    }
    Some(frame(&runtime, &report))
}

/// Loads `bytes` as a model file and, when it loads, runs `info`'s report, a few crowd frames at
/// every level the policy picks, and a synthesized walk at the finest and coarsest levels.
pub fn exercise(bytes: &[u8]) -> Outcome {
    // The runtime reads its own section alone: whatever the offline reader accepts, it accepts.
    let runtime = RuntimeModel::from_bytes(bytes);
    let Ok(model) = MotionModel::from_bytes(bytes, Path::new("mutated.mlod")) else {
        return Outcome::Refused;
    };
    // Compared as bytes: a model may hold NaN (an unused variogram exponent), which is never
    // equal to itself.
    assert_eq!(
        runtime.as_ref().ok().map(RuntimeModel::section_bytes),
        Some(model.runtime().section_bytes()),
        "the runtime reads what the offline reader reads"
    );
    let _ = info::summary(&model);
    let _ = info::write_report(&mut std::io::sink(), &model);
    let _ = info::control_notes(&model.report);

    let lod = model.lod();
    let policy = DistancePolicy::for_model(lod);
    // A sparse field (55 m square): paths of the model's turn range fit in it.
    let run = CrowdRun {
        config: CrowdConfig {
            seed: 1,
            ..CrowdConfig::with_density(6, 0.002)
        },
        seconds: 0.1,
        lens: Camera::default(),
        scene: Scene::Ground,
        render: None,
    };
    let source = LodSource::new(&model);
    let crowd_failed = run_crowd(&source, &policy, &run).is_err();

    let mut synth_failed = false;
    let range = model.control_range();
    let controls: [f32; 4] = std::array::from_fn(|k| 0.5 * (range[k].0 + range[k].1));
    for accuracy in [0, lod.levels().len().saturating_sub(1)] {
        let req = WalkRequest {
            controls: Controls::from_array(controls),
            detail: Detail {
                accuracy,
                active_joints: lod.joints(),
            },
            cycles: 2,
            fps: 30.0,
            blend: true,
            plant_feet: true,
        };
        match model.synthesize_walk(&req) {
            Ok(walk) => {
                let _ = model.walk_motion(&walk);
            }
            Err(_) => synth_failed = true,
        }
    }
    Outcome::Loaded {
        crowd_failed,
        synth_failed,
    }
}

/// The fuzz input, read front to back.
struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn byte(&mut self) -> Option<u8> {
        let (&b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(b)
    }

    fn u32(&mut self) -> u32 {
        let mut v = 0u32;
        for _ in 0..4 {
            v = (v << 8) | u32::from(self.byte().unwrap_or(0));
        }
        v
    }

    fn f64(&mut self) -> f64 {
        let hi = u64::from(self.u32());
        f64::from_bits((hi << 32) | u64::from(self.u32()))
    }
}

/// Applies edit `op` (its operands read from `input`) to one node of `tree`.
fn edit(tree: &mut Value, op: u8, input: &mut Input) {
    match op % 9 {
        // Numbers: pick the n-th number leaf.
        0..=4 => {
            let n = input.u32() as usize;
            let count = count_numbers(tree);
            if count == 0 {
                return;
            }
            let Some(leaf) = nth_number(tree, n % count) else {
                return;
            };
            *leaf = match op % 9 {
                0 => Value::from(i64::from(input.byte().unwrap_or(0) as i8)),
                1 => {
                    let v = input.f64();
                    if v.is_finite() {
                        Value::from(v)
                    } else {
                        Value::from(NAN_MARK)
                    }
                }
                2 => Value::from(NAN_MARK),
                3 => Value::from(INF_MARK),
                _ => Value::from(
                    [1e30, -1.0, 0.0, 4_294_967_296.0, 1e-30]
                        [input.byte().unwrap_or(0) as usize % 5],
                ),
            };
        }
        // Arrays: pick the n-th array.
        _ => {
            let n = input.u32() as usize;
            let count = count_arrays(tree);
            if count == 0 {
                return;
            }
            let Some(array) = nth_array(tree, n % count) else {
                return;
            };
            if array.is_empty() {
                return;
            }
            let i = input.u32() as usize % array.len();
            match op % 9 {
                5 => {
                    array.remove(i);
                }
                6 => {
                    let v = array[i].clone();
                    array.insert(i, v);
                }
                7 => {
                    let j = input.u32() as usize % array.len();
                    array.swap(i, j);
                }
                _ => array.truncate(i),
            }
        }
    }
}

fn nulls_to_nan_mark(v: &mut Value) {
    match v {
        Value::Null => *v = Value::from(NAN_MARK),
        Value::Array(a) => a.iter_mut().for_each(nulls_to_nan_mark),
        Value::Object(o) => o.values_mut().for_each(nulls_to_nan_mark),
        _ => {}
    }
}

fn count_numbers(v: &Value) -> usize {
    match v {
        Value::Number(_) => 1,
        Value::Array(a) => a.iter().map(count_numbers).sum(),
        Value::Object(o) => o.values().map(count_numbers).sum(),
        _ => 0,
    }
}

fn nth_number(v: &mut Value, n: usize) -> Option<&mut Value> {
    fn walk<'a>(v: &'a mut Value, n: &mut usize) -> Option<&'a mut Value> {
        match v {
            Value::Number(_) => {
                if *n == 0 {
                    return Some(v);
                }
                *n -= 1;
                None
            }
            Value::Array(a) => a.iter_mut().find_map(|x| walk(x, n)),
            Value::Object(o) => o.values_mut().find_map(|x| walk(x, n)),
            _ => None,
        }
    }
    let mut n = n;
    walk(v, &mut n)
}

fn count_arrays(v: &Value) -> usize {
    match v {
        Value::Array(a) => 1 + a.iter().map(count_arrays).sum::<usize>(),
        Value::Object(o) => o.values().map(count_arrays).sum(),
        _ => 0,
    }
}

fn nth_array(v: &mut Value, n: usize) -> Option<&mut Vec<Value>> {
    fn walk<'a>(v: &'a mut Value, n: &mut usize) -> Option<&'a mut Vec<Value>> {
        match v {
            Value::Array(a) => {
                if *n == 0 {
                    return Some(a);
                }
                *n -= 1;
                a.iter_mut().find_map(|x| walk(x, n))
            }
            Value::Object(o) => o.values_mut().find_map(|x| walk(x, n)),
            _ => None,
        }
    }
    let mut n = n;
    walk(v, &mut n)
}

/// Replaces every occurrence of `from` in `bytes` by `to` (same length).
fn replace_all(bytes: &mut [u8], from: &[u8], to: &[u8]) {
    debug_assert_eq!(from.len(), to.len());
    let mut i = 0;
    while i + from.len() <= bytes.len() {
        if &bytes[i..i + from.len()] == from {
            bytes[i..i + from.len()].copy_from_slice(to);
            i += from.len();
        } else {
            i += 1;
        }
    }
}
