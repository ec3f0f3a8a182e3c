//! NPY exchange: byte-level format, orders, dtypes and malformed input.

use tensor_ops::npy::{
    NpyArray, NpyDtype, parse_npy, read_npy, read_tensor, to_npy_bytes, write_npy, write_npy_f32,
    write_tensor,
};
use tensor_ops::{Tensor3, TensorError};

/// Builds NPY bytes the way numpy does (header padded to 64 bytes, ending in '\n').
fn npy_bytes(major: u8, dict: &str, body: &[u8]) -> Vec<u8> {
    let prefix = if major == 1 { 10 } else { 12 };
    let total = (prefix + dict.len() + 1).div_ceil(64) * 64;
    let mut h = dict.to_string();
    while prefix + h.len() + 1 < total {
        h.push(' ');
    }
    h.push('\n');
    let mut out = b"\x93NUMPY".to_vec();
    out.push(major);
    out.push(0);
    if major == 1 {
        out.extend_from_slice(&(h.len() as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(h.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(h.as_bytes());
    out.extend_from_slice(body);
    out
}

fn f8(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("tensor-ops-npy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn reads_c_order_like_numpy() {
    // numpy: np.arange(24.).reshape(2, 3, 4) saved with np.save (C order).
    let data: Vec<f64> = (0..24).map(|v| v as f64).collect();
    let b = npy_bytes(
        1,
        "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3, 4), }",
        &f8(&data),
    );
    let a = parse_npy(&b).unwrap();
    assert_eq!(a.shape, vec![2, 3, 4]);
    assert_eq!(a.get(&[1, 2, 3]), Some(23.0));
    assert_eq!(a.get(&[1, 0, 2]), Some(14.0));
    let t = a.to_tensor().unwrap();
    for i in 0..2 {
        for j in 0..3 {
            for k in 0..4 {
                assert_eq!(t.get(i, j, k), (i * 12 + j * 4 + k) as f64);
            }
        }
    }
}

#[test]
fn reads_fortran_f4_and_v2_v3_headers() {
    // Fortran order: first index fastest, i.e. exactly Tensor3's layout.
    let vals: Vec<f32> = (0..6).map(|v| v as f32 * 0.5).collect();
    let body: Vec<u8> = vals.iter().flat_map(|x| x.to_le_bytes()).collect();
    for major in [1u8, 2, 3] {
        let b = npy_bytes(
            major,
            "{'descr': '<f4', 'fortran_order': True, 'shape': (2, 3, 1), }",
            &body,
        );
        let a = parse_npy(&b).unwrap();
        assert_eq!(a.dtype, NpyDtype::F32);
        let t = a.to_tensor().unwrap();
        assert_eq!(t.get(1, 2, 0), 2.5);
        assert_eq!(t.get(0, 1, 0), 1.0);
    }
    // 1-D and 0-D arrays.
    let a = parse_npy(&npy_bytes(
        1,
        "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }",
        &f8(&[1.0, 2.0, 3.0]),
    ))
    .unwrap();
    assert_eq!(a.shape, vec![3]);
    let a = parse_npy(&npy_bytes(
        1,
        "{'descr': '<f8', 'fortran_order': False, 'shape': (), }",
        &f8(&[7.0]),
    ))
    .unwrap();
    assert_eq!((a.shape.len(), a.data[0]), (0, 7.0));
}

#[test]
fn write_then_read_round_trips_tensors_and_orders() {
    let x = Tensor3::from_fn([3, 4, 5], |i, j, k| {
        (i as f64 - 1.5) * 0.25 + j as f64 * 10.0 - k as f64 / 3.0
    })
    .unwrap();
    let p = tmp("x.npy");
    write_tensor(&p, &x, NpyDtype::F64).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + hlen) % 64, 0);
    assert!(
        std::str::from_utf8(&bytes[10..10 + hlen])
            .unwrap()
            .contains("'fortran_order': True, 'shape': (3, 4, 5)")
    );
    assert_eq!(read_tensor(&p).unwrap(), x);
    // C order on disk, same logical array.
    let c = NpyArray::from_tensor(&x).to_order(false);
    assert_eq!(c.get(&[2, 3, 4]), Some(x.get(2, 3, 4)));
    write_npy(&p, &c).unwrap();
    let back = read_npy(&p).unwrap();
    assert!(!back.fortran_order);
    assert_eq!(back.to_tensor().unwrap(), x);
    // f32 write rounds each value.
    write_npy_f32(&p, &c).unwrap();
    let t32 = read_tensor(&p).unwrap();
    for (a, b) in t32.as_slice().iter().zip(x.as_slice()) {
        assert_eq!(*a, *b as f32 as f64);
    }
    // Matrices.
    let m = faer::Mat::<f64>::from_fn(2, 3, |i, j| (i * 3 + j) as f64);
    assert_eq!(
        NpyArray::from_matrix(m.as_ref())
            .to_order(false)
            .to_matrix()
            .unwrap(),
        m
    );
    std::fs::remove_file(&p).ok();
}

#[test]
fn malformed_and_unsupported_files_are_typed_errors() {
    let good = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }";
    let body = f8(&[1.0, 2.0, 3.0, 4.0]);
    // Bad magic.
    let mut b = npy_bytes(1, good, &body);
    b[1] = b'X';
    assert!(matches!(
        parse_npy(&b),
        Err(TensorError::NpyMalformed { offset: 0, .. })
    ));
    // Truncated data.
    let b = npy_bytes(1, good, &body[..30]);
    let e = parse_npy(&b).unwrap_err();
    assert!(matches!(e, TensorError::NpyMalformed { .. }), "{e}");
    assert!(
        e.to_string().contains("needs 32 data bytes, found 30"),
        "{e}"
    );
    // Header past the end.
    let b = npy_bytes(1, good, &body);
    assert!(parse_npy(&b[..20]).is_err());
    assert!(parse_npy(&b[..5]).is_err());
    // Unsupported dtypes and versions.
    let b = npy_bytes(
        1,
        "{'descr': '<i8', 'fortran_order': False, 'shape': (2, 2), }",
        &body,
    );
    let e = parse_npy(&b).unwrap_err();
    assert!(
        matches!(e, TensorError::NpyUnsupported { .. }) && e.to_string().contains("<i8"),
        "{e}"
    );
    let b = npy_bytes(
        1,
        "{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (2,), }",
        &body[..16],
    );
    assert!(matches!(
        parse_npy(&b),
        Err(TensorError::NpyUnsupported { .. })
    ));
    let mut b = npy_bytes(1, good, &body);
    b[6] = 9;
    assert!(matches!(
        parse_npy(&b),
        Err(TensorError::NpyUnsupported { offset: 6, .. })
    ));
    // Garbage headers.
    for dict in [
        "{'descr': '<f8', 'fortran_order': False}",
        "{'descr': '<f8', 'fortran_order': maybe, 'shape': (2, 2), }",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (2, -2), }",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999999999999, 2), }",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296, 4294967296), }",
        "not a dict",
        "{'descr: '<f8'",
    ] {
        let e = parse_npy(&npy_bytes(1, dict, &body)).unwrap_err();
        assert!(matches!(e, TensorError::NpyMalformed { .. }), "{dict}: {e}");
    }
    // Wrong rank and non-finite values for a tensor.
    assert!(matches!(
        parse_npy(&npy_bytes(1, good, &body)).unwrap().to_tensor(),
        Err(TensorError::NpyRank { expected: 3, .. })
    ));
    let nan = npy_bytes(
        1,
        "{'descr': '<f8', 'fortran_order': True, 'shape': (2, 1, 1), }",
        &f8(&[0.0, f64::INFINITY]),
    );
    assert!(matches!(
        parse_npy(&nan).unwrap().to_tensor(),
        Err(TensorError::NonFinite {
            i: 1,
            j: 0,
            k: 0,
            ..
        })
    ));
    // Missing file names the path.
    let e = read_npy("/nonexistent/dir/x.npy").unwrap_err();
    assert!(e.to_string().contains("/nonexistent/dir/x.npy"));
    // Size mismatch on write.
    let bad = NpyArray {
        shape: vec![3],
        data: vec![1.0],
        fortran_order: false,
        dtype: NpyDtype::F64,
    };
    assert!(to_npy_bytes(&bad, NpyDtype::F64).is_err());
}

/// An array whose public fields disagree (data shorter or longer than the shape's product) gives
/// errors from the conversions, `None` from `get`, and a named panic (not an index panic) from
/// `to_order` when it must transpose.
#[test]
fn inconsistent_fields_are_errors_not_index_panics() {
    for (shape, len, fortran) in [
        (vec![2, 3], 2, false),
        (vec![2, 3], 2, true),
        (vec![2, 3], 9, false),
        (vec![2, 3, 4], 2, false),
        (vec![2, 3, 4], 2, true),
        (vec![2, 3, 4], 0, false),
    ] {
        let bad = NpyArray {
            shape: shape.clone(),
            data: vec![1.0; len],
            fortran_order: fortran,
            dtype: NpyDtype::F64,
        };
        assert!(
            matches!(bad.check(), Err(TensorError::ShapeMismatch { expected, found, .. })
                if expected == shape.iter().product::<usize>() && found == len),
            "{shape:?} {len}"
        );
        let conv = if shape.len() == 2 {
            bad.to_matrix().map(|_| ())
        } else {
            bad.to_tensor().map(|_| ())
        };
        assert!(
            matches!(conv, Err(TensorError::ShapeMismatch { .. })),
            "{shape:?} {len}: {conv:?}"
        );
        let last: Vec<usize> = shape.iter().map(|d| d - 1).collect();
        // The last element sits at position `product - 1` in either order.
        let present = len >= shape.iter().product::<usize>();
        assert_eq!(bad.get(&last), present.then_some(1.0));
        let transposed = std::panic::catch_unwind(|| bad.to_order(!fortran));
        let msg = transposed.unwrap_err();
        let msg = msg
            .downcast_ref::<String>()
            .map(String::as_str)
            .unwrap_or("");
        assert!(msg.contains("NpyArray::to_order"), "{msg}");
        // No transposition needed: the flag alone changes.
        assert_eq!(bad.to_order(fortran).data.len(), len);
    }
    let good = NpyArray::new(vec![2, 3], (0..6).map(f64::from).collect(), false).unwrap();
    assert!(good.check().is_ok());
    assert_eq!(good.get(&[1, 2]), Some(5.0));
    assert_eq!(good.to_order(true).get(&[1, 2]), Some(5.0));
}
