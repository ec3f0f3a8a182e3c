//! The model file's sections keep their layout within a version: the serialised shape of the
//! runtime section (the runtime's parts), the report section (pose layout and build report) and the
//! style section is fingerprinted and recorded with the section's version, so a change to what they hold fails here until the version
//! is raised (files of the old layout are then refused with a request to rebuild, instead of
//! failing to decode). It happened once: the quality reference's `take_steps` became
//! `step_trends` inside report version 4 (commit 5c54240), and the files written before it
//! stopped loading with a bare bincode error.
//!
//! The shape is traced through serde (struct and field names, enum variants, element shapes of
//! sequences and maps, primitive types), not the values: a new number leaves it alone, a new field
//! does not. Options are traced as they are in the traced model (`None` hides its inner type).

use std::collections::BTreeSet;
use std::fmt;

use motion_lod::lod_policy::RuntimeModel;
use motion_lod::model_file::{REPORT_VERSION, STYLE_VERSION};
use serde::Serialize;
use serde::ser::{self, Serializer};

use crate::common;

/// Runtime section: (version, fingerprint of the embedded model's runtime parts).
const RUNTIME_LAYOUT: (u32, u64) = (3, 0xc523_66c7_1503_e847);
/// Report section: (version, fingerprint of `(PoseLayout, BuildReport)` of the embedded model).
const REPORT_LAYOUT: (u32, u64) = (4, 0x0604_3490_18e0_54be);
/// Style section: (version, fingerprint of the style report of the embedded data with the
/// performers as styles).
const STYLE_LAYOUT: (u32, u64) = (3, 0x2ed1_a4dd_2f75_d1c0);

#[test]
fn sections_keep_their_layout_within_their_version() {
    let (model, _) = common::built();
    let runtime = model
        .runtime()
        .serialize_section(Shape)
        .expect("every value has a shape");
    let report = trace(&(&model.layout, &model.report));
    let styled = crate::style::styled();
    let style = trace(styled.style.as_ref().expect("a style report"));
    const RUNTIME_FILE: &str = "crates/lod-policy/src/runtime.rs, SECTION_VERSION";
    const OFFLINE_FILE: &str = "crates/motion-lod/src/model_file.rs";
    for (what, version, recorded, shape, file) in [
        (
            "runtime (RTIM)",
            RuntimeModel::SECTION_VERSION,
            RUNTIME_LAYOUT,
            &runtime,
            RUNTIME_FILE,
        ),
        (
            "report (RPRT)",
            REPORT_VERSION,
            REPORT_LAYOUT,
            &report,
            OFFLINE_FILE,
        ),
        (
            "style (STYL)",
            STYLE_VERSION,
            STYLE_LAYOUT,
            &style,
            OFFLINE_FILE,
        ),
    ] {
        let found = fnv1a(shape);
        assert!(
            recorded == (version, found),
            "the {what} section's layout fingerprint is {found:#018x} at version {version}; \
             recorded: ({}, {:#018x}). When what the section holds changed, raise its version \
             ({file}, with a line in its history) and record \
             ({version}, {found:#018x}) here; when only the version changed, record the new pair. \
             Shape: {shape}",
            recorded.0,
            recorded.1
        );
    }
}

/// The shape trace is blind to values and sees fields, variants and types.
#[test]
fn the_trace_sees_fields_and_types_not_values() {
    #[derive(Serialize)]
    struct A {
        x: f64,
        steps: Vec<(f64, u32)>,
    }
    #[derive(Serialize)]
    #[serde(rename = "A")]
    struct B {
        x: f64,
        trends: Option<u8>,
    }
    let a1 = trace(&A {
        x: 1.0,
        steps: vec![(1.0, 2)],
    });
    let a2 = trace(&A {
        x: -7.5,
        steps: vec![(3.0, 4), (5.0, 6)],
    });
    assert_eq!(a1, a2);
    assert_eq!(a1, "A{x:f64,steps:[(f64,u32)]}");
    assert_ne!(
        a1,
        trace(&B {
            x: 1.0,
            trends: Some(1)
        })
    );
}

/// FNV-1a, 64 bits: a fingerprint that is the same on every platform and toolchain.
fn fnv1a(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The serialised shape of `value` ([`Shape`]).
fn trace<T: Serialize + ?Sized>(value: &T) -> String {
    value.serialize(Shape).expect("every value has a shape")
}

#[derive(Debug)]
struct ShapeError(String);

impl fmt::Display for ShapeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ShapeError {}

impl ser::Error for ShapeError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        ShapeError(msg.to_string())
    }
}

/// A serde serializer that writes the shape of what it is given.
struct Shape;

/// A compound in progress: its opening, closing and parts, either in order (tuples, structs) or as
/// a set of distinct shapes (sequences and maps, whose length is a value).
struct Parts {
    open: String,
    close: &'static str,
    ordered: Vec<String>,
    distinct: BTreeSet<String>,
    set: bool,
    key: Option<String>,
}

impl Parts {
    fn new(open: String, close: &'static str, set: bool) -> Parts {
        Parts {
            open,
            close,
            ordered: Vec::new(),
            distinct: BTreeSet::new(),
            set,
            key: None,
        }
    }

    fn push(&mut self, part: String) {
        if self.set {
            self.distinct.insert(part);
        } else {
            self.ordered.push(part);
        }
    }

    fn finish(self) -> String {
        let inner = if self.set {
            self.distinct.into_iter().collect::<Vec<_>>().join("|")
        } else {
            self.ordered.join(",")
        };
        format!("{}{inner}{}", self.open, self.close)
    }
}

macro_rules! primitive {
    ($($method:ident: $ty:ty => $name:literal),* $(,)?) => {
        $(fn $method(self, _: $ty) -> Result<String, ShapeError> {
            Ok($name.into())
        })*
    };
}

impl Serializer for Shape {
    type Ok = String;
    type Error = ShapeError;
    type SerializeSeq = Parts;
    type SerializeTuple = Parts;
    type SerializeTupleStruct = Parts;
    type SerializeTupleVariant = Parts;
    type SerializeMap = Parts;
    type SerializeStruct = Parts;
    type SerializeStructVariant = Parts;

    primitive!(
        serialize_bool: bool => "bool",
        serialize_i8: i8 => "i8",
        serialize_i16: i16 => "i16",
        serialize_i32: i32 => "i32",
        serialize_i64: i64 => "i64",
        serialize_u8: u8 => "u8",
        serialize_u16: u16 => "u16",
        serialize_u32: u32 => "u32",
        serialize_u64: u64 => "u64",
        serialize_f32: f32 => "f32",
        serialize_f64: f64 => "f64",
        serialize_char: char => "char",
        serialize_str: &str => "str",
        serialize_bytes: &[u8] => "bytes",
    );

    fn serialize_none(self) -> Result<String, ShapeError> {
        Ok("none".into())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<String, ShapeError> {
        Ok(format!("some({})", value.serialize(Shape)?))
    }
    fn serialize_unit(self) -> Result<String, ShapeError> {
        Ok("()".into())
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<String, ShapeError> {
        Ok(name.into())
    }
    fn serialize_unit_variant(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
    ) -> Result<String, ShapeError> {
        Ok(format!("{name}::{variant}"))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        value: &T,
    ) -> Result<String, ShapeError> {
        Ok(format!("{name}({})", value.serialize(Shape)?))
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<String, ShapeError> {
        Ok(format!("{name}::{variant}({})", value.serialize(Shape)?))
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Parts, ShapeError> {
        Ok(Parts::new("[".into(), "]", true))
    }
    fn serialize_tuple(self, _: usize) -> Result<Parts, ShapeError> {
        Ok(Parts::new("(".into(), ")", false))
    }
    fn serialize_tuple_struct(self, name: &'static str, _: usize) -> Result<Parts, ShapeError> {
        Ok(Parts::new(format!("{name}("), ")", false))
    }
    fn serialize_tuple_variant(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Parts, ShapeError> {
        Ok(Parts::new(format!("{name}::{variant}("), ")", false))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Parts, ShapeError> {
        Ok(Parts::new("{".into(), "}", true))
    }
    fn serialize_struct(self, name: &'static str, _: usize) -> Result<Parts, ShapeError> {
        Ok(Parts::new(format!("{name}{{"), "}", false))
    }
    fn serialize_struct_variant(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Parts, ShapeError> {
        Ok(Parts::new(format!("{name}::{variant}{{"), "}", false))
    }
}

/// The compound traits whose parts come in order or as a set, each pushing one shape per call of
/// `$method` (an element or an unnamed field).
macro_rules! unnamed_parts {
    ($($trait:ident::$method:ident),* $(,)?) => {
        $(impl ser::$trait for Parts {
            type Ok = String;
            type Error = ShapeError;
            fn $method<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), ShapeError> {
                self.push(value.serialize(Shape)?);
                Ok(())
            }
            fn end(self) -> Result<String, ShapeError> {
                Ok(self.finish())
            }
        })*
    };
}

/// The compound traits whose parts are named fields, pushed as `field:shape`.
macro_rules! named_parts {
    ($($trait:ident),* $(,)?) => {
        $(impl ser::$trait for Parts {
            type Ok = String;
            type Error = ShapeError;
            fn serialize_field<T: Serialize + ?Sized>(
                &mut self,
                field: &'static str,
                value: &T,
            ) -> Result<(), ShapeError> {
                self.push(format!("{field}:{}", value.serialize(Shape)?));
                Ok(())
            }
            fn end(self) -> Result<String, ShapeError> {
                Ok(self.finish())
            }
        })*
    };
}

unnamed_parts!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field,
);
named_parts!(SerializeStruct, SerializeStructVariant);

impl ser::SerializeMap for Parts {
    type Ok = String;
    type Error = ShapeError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), ShapeError> {
        self.key = Some(key.serialize(Shape)?);
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), ShapeError> {
        let key = self.key.take().unwrap_or_default();
        self.push(format!("{key}:{}", value.serialize(Shape)?));
        Ok(())
    }
    fn end(self) -> Result<String, ShapeError> {
        Ok(self.finish())
    }
}
