//! Reading and writing numpy's `.npy` format (versions 1.0, 2.0, 3.0) for exchange with numpy.
//!
//! Format (numpy `lib/format.py`): the magic `\x93NUMPY`, a major and minor version byte, the
//! header length (`u16` little-endian for 1.0, `u32` for 2.0/3.0), then an ASCII (UTF-8 for 3.0)
//! Python dict literal `{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }` padded with
//! spaces and ending in `\n`, then the raw element bytes.
//!
//! Read: dtypes `<f8`, `<f4` (also big-endian `>f8`, `>f4` and native `=f8`, `=f4`), C or
//! Fortran order, up to 64 dimensions (numpy's own limit). Values are widened to f64 and kept in file order
//! (see [`NpyArray::fortran_order`]); NaN/inf are kept here and rejected when converting to a
//! [`Tensor3`]. Write: f64 (`<f8`) or f32 (`<f4`), format 1.0 (2.0 if the header needs it),
//! header padded to a multiple of 64 bytes as numpy does.
//!
//! Hostile files: the header is at most 1 MiB, tuples nest at most 8 deep, the shape's product
//! must not overflow and must match the data bytes present exactly, so nothing is allocated
//! beyond what the file holds (see `tests/hostile_npy.rs`).
//!
//! A [`Tensor3`] goes to numpy as a Fortran-ordered `(I, J, K)` array, so `a[i, j, k]` in numpy
//! is `X(i, j, k)` here, with no copy or transpose of the data.

use crate::{Tensor3, TensorError};
use faer::{Mat, MatRef};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 6] = b"\x93NUMPY";
/// Largest header accepted on read (numpy itself caps untrusted headers at 10 000 bytes by
/// default; this is generous but bounded).
const MAX_HEADER: usize = 1 << 20;
/// Most dimensions accepted on read (numpy 2's `NPY_MAXDIMS`).
const MAX_DIMS: usize = 64;
/// Deepest nesting of tuples/lists accepted in a header (a shape needs one level); bounds the
/// recursion of the header parser on hostile input.
const MAX_NESTING: usize = 8;

/// Element type written to (or found in) an NPY file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NpyDtype {
    /// 8-byte IEEE float, `<f8`.
    F64,
    /// 4-byte IEEE float, `<f4`.
    F32,
}

impl NpyDtype {
    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            NpyDtype::F64 => 8,
            NpyDtype::F32 => 4,
        }
    }

    fn descr(self) -> &'static str {
        match self {
            NpyDtype::F64 => "<f8",
            NpyDtype::F32 => "<f4",
        }
    }
}

/// An n-dimensional float array as stored in an NPY file.
///
/// The fields are public; `data.len()` must be the product of `shape` (as [`NpyArray::new`] and
/// the readers guarantee). The conversions returning `Result` check it ([`NpyArray::check`]);
/// [`NpyArray::get`] returns `None` for a position outside `data`; [`NpyArray::to_order`] panics
/// when it has to transpose inconsistent fields.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// numpy's shape (empty for a 0-d scalar).
    pub shape: Vec<usize>,
    /// The elements in file order: C order (last index fastest) unless `fortran_order`.
    pub data: Vec<f64>,
    /// True when the first index runs fastest (numpy's Fortran order).
    pub fortran_order: bool,
    /// The element type found in the file (`F64` for arrays built in memory).
    pub dtype: NpyDtype,
}

fn shape_len(shape: &[usize]) -> Option<usize> {
    shape.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d))
}

impl NpyArray {
    /// An f64 array of `shape` with `data` in C order (`fortran_order = false`) or Fortran order.
    ///
    /// Errors: [`TensorError::ShapeMismatch`] if `data.len()` is not the product of `shape`.
    pub fn new(
        shape: Vec<usize>,
        data: Vec<f64>,
        fortran_order: bool,
    ) -> Result<Self, TensorError> {
        let expected = shape_len(&shape).ok_or(TensorError::ShapeMismatch {
            what: "NpyArray::new: shape product overflows",
            expected: usize::MAX,
            found: data.len(),
        })?;
        if expected != data.len() {
            return Err(TensorError::ShapeMismatch {
                what: "NpyArray::new: data length (product of shape)",
                expected,
                found: data.len(),
            });
        }
        Ok(Self {
            shape,
            data,
            fortran_order,
            dtype: NpyDtype::F64,
        })
    }

    /// Checks that `data.len()` is the product of `shape` (the invariant of the type, which the
    /// public fields let a caller break).
    ///
    /// Errors: [`TensorError::ShapeMismatch`] naming both lengths (`usize::MAX` as expected when
    /// the product overflows).
    pub fn check(&self) -> Result<(), TensorError> {
        let expected = shape_len(&self.shape).unwrap_or(usize::MAX);
        if expected != self.data.len() {
            return Err(TensorError::ShapeMismatch {
                what: "NpyArray: data length (product of shape)",
                expected,
                found: self.data.len(),
            });
        }
        Ok(())
    }

    /// Number of dimensions.
    pub fn ndim(&self) -> usize {
        self.shape.len()
    }

    /// Linear position of a multi-index in `data`, or `None` if it is out of range.
    pub fn position(&self, index: &[usize]) -> Option<usize> {
        if index.len() != self.shape.len() || index.iter().zip(&self.shape).any(|(i, d)| i >= d) {
            return None;
        }
        let mut pos = 0;
        if self.fortran_order {
            for (i, d) in index.iter().zip(&self.shape).rev() {
                pos = pos * d + i;
            }
        } else {
            for (i, d) in index.iter().zip(&self.shape) {
                pos = pos * d + i;
            }
        }
        Some(pos)
    }

    /// Element at a multi-index (numpy's `a[i, j, ...]`), or `None` if out of range (of the
    /// shape, or of `data` when the fields are inconsistent).
    pub fn get(&self, index: &[usize]) -> Option<f64> {
        self.position(index).and_then(|p| self.data.get(p).copied())
    }

    /// The same logical array with data in the requested order.
    ///
    /// # Panics
    /// If the data must be transposed (the order changes and there are at least two dimensions)
    /// and `data.len()` is not the product of `shape` (see [`NpyArray::check`]; arrays from
    /// [`NpyArray::new`] and the readers are always consistent).
    pub fn to_order(&self, fortran_order: bool) -> NpyArray {
        if fortran_order == self.fortran_order || self.shape.len() < 2 {
            let mut a = self.clone();
            a.fortran_order = fortran_order;
            return a;
        }
        if let Err(e) = self.check() {
            panic!("NpyArray::to_order: {e}");
        }
        // Reversing the axes turns C order into Fortran order of the same data; transpose by
        // walking the destination in its own order.
        let n = self.data.len();
        let nd = self.shape.len();
        let mut data = Vec::with_capacity(n);
        let mut idx = vec![0usize; nd];
        for _ in 0..n {
            data.push(self.data[self.position(&idx).unwrap_or(0)]);
            // Increment idx in the destination order.
            if fortran_order {
                for (a, i) in idx.iter_mut().enumerate() {
                    *i += 1;
                    if *i < self.shape[a] {
                        break;
                    }
                    *i = 0;
                }
            } else {
                for a in (0..nd).rev() {
                    idx[a] += 1;
                    if idx[a] < self.shape[a] {
                        break;
                    }
                    idx[a] = 0;
                }
            }
        }
        NpyArray {
            shape: self.shape.clone(),
            data,
            fortran_order,
            dtype: self.dtype,
        }
    }

    /// A Fortran-ordered `(I, J, K)` array holding `x` (numpy's `a[i, j, k] = X(i, j, k)`).
    pub fn from_tensor(x: &Tensor3) -> NpyArray {
        NpyArray {
            shape: x.dims().to_vec(),
            data: x.as_slice().to_vec(),
            fortran_order: true,
            dtype: NpyDtype::F64,
        }
    }

    /// The 3-D array as a [`Tensor3`] with `X(i, j, k) = a[i, j, k]`, whatever the file order.
    ///
    /// Errors: [`TensorError::NpyRank`] unless `ndim() == 3`; [`TensorError::ShapeMismatch`] when
    /// `data.len()` is not the product of `shape` ([`NpyArray::check`]); [`TensorError::NpyEmpty`]
    /// for an array without elements; [`TensorError::NonFinite`] for NaN/inf.
    pub fn to_tensor(&self) -> Result<Tensor3, TensorError> {
        if self.shape.len() != 3 {
            return Err(TensorError::NpyRank {
                shape: self.shape.clone(),
                expected: 3,
            });
        }
        self.check()?;
        if self.data.is_empty() {
            return Err(TensorError::NpyEmpty {
                shape: self.shape.clone(),
            });
        }
        let dims = [self.shape[0], self.shape[1], self.shape[2]];
        let f = self.to_order(true);
        Tensor3::from_vec(dims, f.data)
    }

    /// A Fortran-ordered `(rows, cols)` array holding the matrix `m`.
    pub fn from_matrix(m: MatRef<'_, f64>) -> NpyArray {
        let mut data = Vec::with_capacity(m.nrows() * m.ncols());
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                data.push(m[(i, j)]);
            }
        }
        NpyArray {
            shape: vec![m.nrows(), m.ncols()],
            data,
            fortran_order: true,
            dtype: NpyDtype::F64,
        }
    }

    /// The 2-D array as a matrix `M(i, j) = a[i, j]`.
    ///
    /// Errors: [`TensorError::NpyRank`] unless `ndim() == 2`; [`TensorError::ShapeMismatch`] when
    /// `data.len()` is not the product of `shape` ([`NpyArray::check`]); [`TensorError::NpyEmpty`]
    /// for an array without elements.
    pub fn to_matrix(&self) -> Result<Mat<f64>, TensorError> {
        if self.shape.len() != 2 {
            return Err(TensorError::NpyRank {
                shape: self.shape.clone(),
                expected: 2,
            });
        }
        self.check()?;
        if self.data.is_empty() {
            return Err(TensorError::NpyEmpty {
                shape: self.shape.clone(),
            });
        }
        let f = self.to_order(true);
        let r = self.shape[0];
        Ok(Mat::from_fn(self.shape[0], self.shape[1], |i, j| {
            f.data[i + r * j]
        }))
    }
}

/// Reads an NPY file (see the module docs for what is supported).
///
/// Errors: [`TensorError::Io`], [`TensorError::NpyMalformed`] (bad magic, header, shape or data
/// length, with the byte offset), [`TensorError::NpyUnsupported`] (dtype other than f8/f4, version).
pub fn read_npy(path: impl AsRef<Path>) -> Result<NpyArray, TensorError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| TensorError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&bytes, Some(path))
}

/// Parses NPY bytes held in memory (errors carry no file name).
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, TensorError> {
    parse(bytes, None)
}

/// Reads a 3-D NPY file as a [`Tensor3`] (`X(i, j, k) = a[i, j, k]`).
pub fn read_tensor(path: impl AsRef<Path>) -> Result<Tensor3, TensorError> {
    read_npy(path)?.to_tensor()
}

/// Writes `array` as f64 (`<f8`), keeping its order flag.
pub fn write_npy(path: impl AsRef<Path>, array: &NpyArray) -> Result<(), TensorError> {
    write_npy_as(path, array, NpyDtype::F64)
}

/// Writes `array` as f32 (`<f4`), rounding each value to nearest.
pub fn write_npy_f32(path: impl AsRef<Path>, array: &NpyArray) -> Result<(), TensorError> {
    write_npy_as(path, array, NpyDtype::F32)
}

/// Writes `array` with element type `dtype`.
pub fn write_npy_as(
    path: impl AsRef<Path>,
    array: &NpyArray,
    dtype: NpyDtype,
) -> Result<(), TensorError> {
    let path = path.as_ref();
    let bytes = to_npy_bytes(array, dtype)?;
    std::fs::write(path, bytes).map_err(|source| TensorError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes a tensor as a Fortran-ordered `(I, J, K)` array of `dtype`.
pub fn write_tensor(
    path: impl AsRef<Path>,
    x: &Tensor3,
    dtype: NpyDtype,
) -> Result<(), TensorError> {
    write_npy_as(path, &NpyArray::from_tensor(x), dtype)
}

/// Encodes `array` as NPY bytes of `dtype` (format 1.0, or 2.0 for headers over 65535 bytes).
///
/// Errors: [`TensorError::ShapeMismatch`] if `data.len()` is not the product of `shape`.
pub fn to_npy_bytes(array: &NpyArray, dtype: NpyDtype) -> Result<Vec<u8>, TensorError> {
    let n = shape_len(&array.shape).unwrap_or(usize::MAX);
    if n != array.data.len() {
        return Err(TensorError::ShapeMismatch {
            what: "write_npy: data length (product of shape)",
            expected: n,
            found: array.data.len(),
        });
    }
    let shape = match array.shape.len() {
        0 => "()".to_string(),
        1 => format!("({},)", array.shape[0]),
        _ => format!(
            "({})",
            array
                .shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let dict = format!(
        "{{'descr': '{}', 'fortran_order': {}, 'shape': {}, }}",
        dtype.descr(),
        if array.fortran_order { "True" } else { "False" },
        shape
    );
    // Version 1.0 uses a u16 length (prefix 10 bytes); 2.0 a u32 length (prefix 12 bytes).
    let (major, prefix) = if dict.len() + 1 + 10 + 64 <= u16::MAX as usize {
        (1u8, 10usize)
    } else {
        (2u8, 12usize)
    };
    let total = (prefix + dict.len() + 1).div_ceil(64) * 64;
    let hlen = total - prefix;
    let mut out = Vec::with_capacity(total + n * dtype.size());
    out.extend_from_slice(MAGIC);
    out.push(major);
    out.push(0);
    if major == 1 {
        out.extend_from_slice(&(hlen as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(hlen as u32).to_le_bytes());
    }
    out.extend_from_slice(dict.as_bytes());
    out.resize(total - 1, b' ');
    out.push(b'\n');
    match dtype {
        NpyDtype::F64 => array
            .data
            .iter()
            .for_each(|v| out.extend_from_slice(&v.to_le_bytes())),
        NpyDtype::F32 => array
            .data
            .iter()
            .for_each(|v| out.extend_from_slice(&(*v as f32).to_le_bytes())),
    }
    Ok(out)
}

struct Ctx<'a> {
    path: Option<&'a Path>,
}

impl Ctx<'_> {
    fn malformed(&self, offset: usize, reason: impl Into<String>) -> TensorError {
        TensorError::NpyMalformed {
            path: self.path.map(PathBuf::from),
            offset,
            reason: reason.into(),
        }
    }
    fn unsupported(&self, offset: usize, reason: impl Into<String>) -> TensorError {
        TensorError::NpyUnsupported {
            path: self.path.map(PathBuf::from),
            offset,
            reason: reason.into(),
        }
    }
}

fn parse(bytes: &[u8], path: Option<&Path>) -> Result<NpyArray, TensorError> {
    let cx = Ctx { path };
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err(cx.malformed(0, "missing magic string \\x93NUMPY"));
    }
    let (major, minor) = (bytes[6], bytes[7]);
    let (hlen, start) = match major {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 => {
            if bytes.len() < 12 {
                return Err(cx.malformed(8, "file ends inside the header length"));
            }
            (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            )
        }
        _ => return Err(cx.unsupported(6, format!("format version {major}.{minor}"))),
    };
    if hlen > MAX_HEADER {
        return Err(cx.malformed(
            8,
            format!("header length {hlen} exceeds {MAX_HEADER} bytes"),
        ));
    }
    let end = start + hlen;
    if bytes.len() < end {
        return Err(cx.malformed(
            start,
            format!(
                "header of {hlen} bytes runs past the end of the file ({} bytes)",
                bytes.len()
            ),
        ));
    }
    let header = std::str::from_utf8(&bytes[start..end])
        .map_err(|e| cx.malformed(start + e.valid_up_to(), "header is not valid text"))?;
    if major < 3 && !header.is_ascii() {
        return Err(cx.malformed(start, "header of a version 1/2 file is not ASCII"));
    }
    let fields = Header::parse(header, start, &cx)?;
    let (dtype, big_endian) = match fields.descr.as_str() {
        "<f8" => (NpyDtype::F64, false),
        "<f4" => (NpyDtype::F32, false),
        ">f8" => (NpyDtype::F64, true),
        ">f4" => (NpyDtype::F32, true),
        "=f8" => (NpyDtype::F64, cfg!(target_endian = "big")),
        "=f4" => (NpyDtype::F32, cfg!(target_endian = "big")),
        other => {
            return Err(cx.unsupported(
                start + fields.descr_offset,
                format!("dtype '{other}' (only f8 and f4 floats are read)"),
            ));
        }
    };
    let n = shape_len(&fields.shape)
        .ok_or_else(|| cx.malformed(start + fields.shape_offset, "shape product overflows"))?;
    let need = n
        .checked_mul(dtype.size())
        .ok_or_else(|| cx.malformed(start + fields.shape_offset, "data size overflows"))?;
    let body = &bytes[end..];
    if body.len() != need {
        return Err(cx.malformed(
            end,
            format!(
                "shape {:?} of {} needs {need} data bytes, found {}",
                fields.shape,
                fields.descr,
                body.len()
            ),
        ));
    }
    let data: Vec<f64> = match dtype {
        NpyDtype::F64 => body
            .chunks_exact(8)
            .map(|c| {
                let a: [u8; 8] = c.try_into().unwrap_or([0; 8]);
                if big_endian {
                    f64::from_be_bytes(a)
                } else {
                    f64::from_le_bytes(a)
                }
            })
            .collect(),
        NpyDtype::F32 => body
            .chunks_exact(4)
            .map(|c| {
                let a: [u8; 4] = c.try_into().unwrap_or([0; 4]);
                (if big_endian {
                    f32::from_be_bytes(a)
                } else {
                    f32::from_le_bytes(a)
                }) as f64
            })
            .collect(),
    };
    Ok(NpyArray {
        shape: fields.shape,
        data,
        fortran_order: fields.fortran_order,
        dtype,
    })
}

/// The three fields of an NPY header dict.
struct Header {
    descr: String,
    descr_offset: usize,
    fortran_order: bool,
    shape: Vec<usize>,
    shape_offset: usize,
}

/// A value of the Python literal subset used by NPY headers.
enum Lit {
    Str(String),
    Bool(bool),
    Int(usize),
    Tuple(Vec<Lit>),
}

struct Parser<'a, 'c> {
    s: &'a [u8],
    pos: usize,
    base: usize,
    /// Open tuples/lists around the current position.
    depth: usize,
    cx: &'c Ctx<'c>,
}

impl Parser<'_, '_> {
    fn err(&self, reason: impl Into<String>) -> TensorError {
        self.cx.malformed(self.base + self.pos, reason)
    }
    fn ws(&mut self) {
        while self.pos < self.s.len() && (self.s[self.pos] as char).is_ascii_whitespace() {
            self.pos += 1;
        }
    }
    fn peek(&mut self) -> Option<u8> {
        self.ws();
        self.s.get(self.pos).copied()
    }
    fn expect(&mut self, c: u8) -> Result<(), TensorError> {
        if self.peek() == Some(c) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.err(format!("expected '{}' in header", c as char)))
        }
    }
    fn string(&mut self) -> Result<String, TensorError> {
        let q = self
            .peek()
            .ok_or_else(|| self.err("header ends where a string was expected"))?;
        if q != b'\'' && q != b'"' {
            return Err(self.err("expected a quoted string in header"));
        }
        self.pos += 1;
        let from = self.pos;
        while self.pos < self.s.len() && self.s[self.pos] != q {
            self.pos += 1;
        }
        if self.pos >= self.s.len() {
            return Err(self.err("unterminated string in header"));
        }
        let text = String::from_utf8_lossy(&self.s[from..self.pos]).into_owned();
        self.pos += 1;
        Ok(text)
    }
    fn value(&mut self) -> Result<Lit, TensorError> {
        match self.peek() {
            Some(b'\'') | Some(b'"') => self.string().map(Lit::Str),
            Some(b'(') | Some(b'[') => {
                let close = if self.s[self.pos] == b'(' { b')' } else { b']' };
                if self.depth == MAX_NESTING {
                    return Err(self.err(format!(
                        "tuples nested deeper than {MAX_NESTING} levels in header"
                    )));
                }
                self.pos += 1;
                self.depth += 1;
                let mut items = Vec::new();
                loop {
                    if self.peek() == Some(close) {
                        self.pos += 1;
                        break;
                    }
                    items.push(self.value()?);
                    match self.peek() {
                        Some(b',') => self.pos += 1,
                        Some(c) if c == close => {}
                        _ => return Err(self.err("expected ',' or a closing bracket in header")),
                    }
                }
                self.depth -= 1;
                Ok(Lit::Tuple(items))
            }
            Some(c) if c.is_ascii_digit() => {
                let from = self.pos;
                while self.pos < self.s.len() && self.s[self.pos].is_ascii_digit() {
                    self.pos += 1;
                }
                // Python 2 era files may write long integers as `3L`.
                if self.pos < self.s.len() && self.s[self.pos] == b'L' {
                    self.pos += 1;
                }
                let digits = std::str::from_utf8(&self.s[from..self.pos])
                    .unwrap_or("")
                    .trim_end_matches('L');
                digits
                    .parse::<usize>()
                    .map(Lit::Int)
                    .map_err(|_| self.err(format!("integer '{digits}' out of range")))
            }
            Some(_) => {
                for (word, v) in [("True", true), ("False", false)] {
                    if self.s[self.pos..].starts_with(word.as_bytes()) {
                        self.pos += word.len();
                        return Ok(Lit::Bool(v));
                    }
                }
                Err(self.err("unexpected token in header"))
            }
            None => Err(self.err("header ends where a value was expected")),
        }
    }
}

impl Header {
    fn parse(text: &str, base: usize, cx: &Ctx<'_>) -> Result<Header, TensorError> {
        let mut p = Parser {
            s: text.as_bytes(),
            pos: 0,
            base,
            depth: 0,
            cx,
        };
        p.expect(b'{')?;
        let mut descr = None;
        let mut fortran = None;
        let mut shape = None;
        loop {
            if p.peek() == Some(b'}') {
                break;
            }
            let key = p.string()?;
            p.expect(b':')?;
            let at = {
                p.ws();
                p.pos
            };
            let v = p.value()?;
            match (key.as_str(), v) {
                ("descr", Lit::Str(s)) => descr = Some((s, at)),
                ("descr", Lit::Tuple(_)) => {
                    return Err(cx.unsupported(base + at, "structured dtype (a list of fields)"));
                }
                ("fortran_order", Lit::Bool(b)) => fortran = Some(b),
                ("shape", Lit::Tuple(items)) => {
                    if items.len() > MAX_DIMS {
                        return Err(cx.unsupported(
                            base + at,
                            format!("{} dimensions (at most {MAX_DIMS} are read)", items.len()),
                        ));
                    }
                    let mut dims = Vec::with_capacity(items.len());
                    for it in items {
                        match it {
                            Lit::Int(d) => dims.push(d),
                            _ => return Err(cx.malformed(base + at, "shape holds a non-integer")),
                        }
                    }
                    shape = Some((dims, at));
                }
                ("descr" | "fortran_order" | "shape", _) => {
                    return Err(
                        cx.malformed(base + at, format!("header key '{key}' has the wrong type"))
                    );
                }
                _ => {} // numpy writes no other keys; tolerate extras.
            }
            match p.peek() {
                Some(b',') => p.pos += 1,
                Some(b'}') => {}
                _ => return Err(p.err("expected ',' or '}' in header")),
            }
        }
        let (descr, descr_offset) =
            descr.ok_or_else(|| cx.malformed(base, "header has no 'descr'"))?;
        let fortran_order =
            fortran.ok_or_else(|| cx.malformed(base, "header has no 'fortran_order'"))?;
        let (shape, shape_offset) =
            shape.ok_or_else(|| cx.malformed(base, "header has no 'shape'"))?;
        Ok(Header {
            descr,
            descr_offset,
            fortran_order,
            shape,
            shape_offset,
        })
    }
}
