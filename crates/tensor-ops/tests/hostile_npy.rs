//! Hostile NPY input: every case is a `NpyMalformed` or `NpyUnsupported` error naming the byte
//! offset, in bounded time and memory (nothing is allocated from a size declared in the file
//! before the file is shown to hold that many bytes), never a panic.

use tensor_ops::TensorError;
use tensor_ops::npy::{NpyArray, NpyDtype, parse_npy, read_npy, to_npy_bytes};

/// NPY bytes with `dict` as header (padded to 64 bytes as numpy does) and `body` as data.
fn npy(major: u8, dict: &str, body: &[u8]) -> Vec<u8> {
    let prefix = if major == 1 { 10 } else { 12 };
    let total = (prefix + dict.len() + 1).div_ceil(64) * 64;
    let mut out = b"\x93NUMPY".to_vec();
    out.extend_from_slice(&[major, 0]);
    let hlen = total - prefix;
    if major == 1 {
        out.extend_from_slice(&(hlen as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(hlen as u32).to_le_bytes());
    }
    out.extend_from_slice(dict.as_bytes());
    out.resize(total - 1, b' ');
    out.push(b'\n');
    out.extend_from_slice(body);
    out
}

fn dict(descr: &str, fortran: &str, shape: &str) -> String {
    format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}")
}

fn f8(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The offset and reason of a malformed-file error (panics on anything else).
fn malformed(bytes: &[u8]) -> (usize, String) {
    match parse_npy(bytes) {
        Err(TensorError::NpyMalformed {
            offset,
            reason,
            path: None,
        }) => (offset, reason),
        other => panic!("expected NpyMalformed, got {other:?}"),
    }
}

fn unsupported(bytes: &[u8]) -> (usize, String) {
    match parse_npy(bytes) {
        Err(TensorError::NpyUnsupported {
            offset,
            reason,
            path: None,
        }) => (offset, reason),
        other => panic!("expected NpyUnsupported, got {other:?}"),
    }
}

#[test]
fn reference_file_parses() {
    let a = parse_npy(&npy(1, &dict("<f8", "False", "(2, 3)"), &f8(&[1.0; 6]))).unwrap();
    assert_eq!(a.shape, vec![2, 3]);
}

#[test]
fn header_length_beyond_the_file() {
    // Version 1: u16 length 0xffff in a 20-byte file.
    let mut b = npy(1, &dict("<f8", "False", "(1,)"), &f8(&[1.0]));
    b[8..10].copy_from_slice(&u16::MAX.to_le_bytes());
    b.truncate(20);
    let (off, why) = malformed(&b);
    assert_eq!(off, 10);
    assert!(why.contains("runs past the end"), "{why}");
    // Version 2: u32 length 4 GiB - 1: refused by the header cap before anything is read.
    let mut b = npy(2, &dict("<f8", "False", "(1,)"), &f8(&[1.0]));
    b[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    let (off, why) = malformed(&b);
    assert_eq!(off, 8);
    assert!(why.contains("exceeds"), "{why}");
    // Just past the end by one byte.
    let good = npy(1, &dict("<f8", "False", "(0,)"), &[]);
    let mut b = good.clone();
    let h = u16::from_le_bytes([b[8], b[9]]) + 1;
    b[8..10].copy_from_slice(&h.to_le_bytes());
    assert!(malformed(&b).1.contains("runs past the end"));
    // Version 2 with the file ending inside the 4-byte length.
    assert_eq!(malformed(b"\x93NUMPY\x02\x00\x10\x00").0, 8);
}

#[test]
fn shape_products_that_overflow_usize() {
    let huge = usize::MAX / 2 + 1;
    for shape in [
        format!("({huge}, 2)"),
        format!("({}, {}, {})", 1u64 << 32, 1u64 << 32, 2),
        format!("({}, {})", usize::MAX, usize::MAX),
    ] {
        let (_, why) = malformed(&npy(1, &dict("<f8", "False", &shape), &[]));
        assert!(why.contains("overflows"), "{shape}: {why}");
    }
    // Product fits usize but the byte count (x 8) does not.
    let (_, why) = malformed(&npy(
        1,
        &dict("<f8", "False", &format!("({},)", usize::MAX / 4)),
        &[],
    ));
    assert!(why.contains("overflows"), "{why}");
    // A dimension beyond usize itself.
    let (off, why) = malformed(&npy(
        1,
        &dict("<f8", "False", "(99999999999999999999999,)"),
        &[],
    ));
    assert!(why.contains("out of range"), "{why}");
    assert!(off > 10);
}

#[test]
fn absurd_shapes_in_a_tiny_file() {
    // 10^12 elements declared, 16 bytes present: an error naming both, no allocation.
    let b = npy(
        1,
        &dict("<f8", "False", "(1000000, 1000000)"),
        &f8(&[1.0, 2.0]),
    );
    let (off, why) = malformed(&b);
    assert_eq!(off, b.len() - 16, "offset of the data");
    assert!(
        why.contains("8000000000000") && why.contains("found 16"),
        "{why}"
    );
    // A zero dimension next to huge ones: 0 elements, so 0 bytes are expected.
    let b = npy(
        1,
        &dict(
            "<f8",
            "False",
            &format!("(0, {}, {})", 1u64 << 40, 1u64 << 40),
        ),
        &[],
    );
    let a = parse_npy(&b).unwrap();
    assert!(a.data.is_empty());
    // It parses, but it is no tensor: every operation would walk its 2^40-long dimensions.
    assert!(a.to_tensor().is_err());
    // ... but a byte of data after it is one too many.
    let b = npy(1, &dict("<f8", "False", "(0, 5)"), &[0]);
    assert!(malformed(&b).1.contains("found 1"));
    // 65 dimensions of 1 (numpy's limit is 64).
    let shape = format!("({})", vec!["1"; 65].join(", "));
    let (_, why) = unsupported(&npy(2, &dict("<f8", "False", &shape), &f8(&[1.0])));
    assert!(why.contains("65 dimensions"), "{why}");
    // Deeply nested tuples: an error, not a stack overflow.
    let shape = format!("{}1{}", "(".repeat(100_000), ")".repeat(100_000));
    let (_, why) = malformed(&npy(2, &dict("<f8", "False", &shape), &[]));
    assert!(why.contains("nested"), "{why}");
    // Nested but shallow: the shape holds a tuple, not an integer.
    let (_, why) = malformed(&npy(1, &dict("<f8", "False", "((2, 3),)"), &[]));
    assert!(why.contains("non-integer"), "{why}");
    // Negative dimensions are not integers of the header grammar.
    let (_, why) = malformed(&npy(1, &dict("<f8", "False", "(-1, 3)"), &[]));
    assert!(why.contains("unexpected token"), "{why}");
}

#[test]
fn unsupported_dtypes_are_named() {
    for descr in [
        "<i8", "<f2", "<c16", "|b1", "<U10", "|O", "<f16", "f8", "<F8", "",
    ] {
        let (off, why) = unsupported(&npy(1, &dict(descr, "False", "(1,)"), &f8(&[1.0])));
        assert!(why.contains(&format!("'{descr}'")), "{descr}: {why}");
        assert_eq!(off, 10 + "{'descr': ".len(), "{descr}");
    }
    // Structured dtype (a list of fields).
    let d = "{'descr': [('x', '<f8')], 'fortran_order': False, 'shape': (1,), }";
    assert!(
        unsupported(&npy(1, d, &f8(&[1.0])))
            .1
            .contains("structured")
    );
    // A descr that is not a string at all.
    let d = "{'descr': 8, 'fortran_order': False, 'shape': (1,), }";
    assert!(malformed(&npy(1, d, &f8(&[1.0]))).1.contains("wrong type"));
    // Unknown format versions.
    for major in [0u8, 4, 255] {
        let mut b = npy(1, &dict("<f8", "False", "(1,)"), &f8(&[1.0]));
        b[6] = major;
        let (off, why) = unsupported(&b);
        assert_eq!(off, 6);
        assert!(why.contains("version"), "{why}");
    }
}

#[test]
fn fortran_order_as_garbage() {
    for fortran in ["0", "'False'", "false", "None", "Truth", "(True,)", "1"] {
        let b = npy(1, &dict("<f8", fortran, "(1,)"), &f8(&[1.0]));
        let r = parse_npy(&b);
        assert!(
            matches!(r, Err(TensorError::NpyMalformed { .. })),
            "{fortran}: {r:?}"
        );
    }
    // Missing key.
    let d = "{'descr': '<f8', 'shape': (1,), }";
    assert!(
        malformed(&npy(1, d, &f8(&[1.0])))
            .1
            .contains("fortran_order")
    );
}

#[test]
fn malformed_headers() {
    for d in [
        "",
        "{",
        "{'descr': '<f8'",
        "{'descr: '<f8', 'fortran_order': False, 'shape': (1,), }",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (1,) 'x': 1}",
        "['descr', '<f8']",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (1,, 2), }",
    ] {
        let r = parse_npy(&npy(1, d, &f8(&[1.0])));
        assert!(
            matches!(r, Err(TensorError::NpyMalformed { .. })),
            "{d}: {r:?}"
        );
    }
    // Non-ASCII header in a version 1 file; invalid UTF-8 in a version 3 file.
    let b = npy(
        1,
        &dict("<f8", "False", "(1,)").replace("descr", "déscr"),
        &f8(&[1.0]),
    );
    assert!(malformed(&b).1.contains("ASCII"));
    let mut b = npy(3, &dict("<f8", "False", "(1,)"), &f8(&[1.0]));
    b[13] = 0xff;
    assert_eq!(malformed(&b).0, 13);
    // Bad magic, short files.
    for b in [
        &b""[..],
        b"\x93NUMPY",
        b"\x93NUMPZ\x01\x00\x00\x00",
        b"PK\x03\x04 not npy at all",
    ] {
        assert_eq!(malformed(b).0, 0, "{b:?}");
    }
}

#[test]
fn truncated_data_at_every_length() {
    let a = NpyArray::new(vec![3, 4], (0..12).map(f64::from).collect(), false).unwrap();
    for dtype in [NpyDtype::F64, NpyDtype::F32] {
        let bytes = to_npy_bytes(&a, dtype).unwrap();
        assert_eq!(parse_npy(&bytes).unwrap().data, a.data);
        for len in 0..bytes.len() {
            let r = parse_npy(&bytes[..len]);
            assert!(
                matches!(r, Err(TensorError::NpyMalformed { .. })),
                "{dtype:?} cut at {len}: {r:?}"
            );
        }
        // One byte too many.
        let mut long = bytes.clone();
        long.push(0);
        assert!(malformed(&long).1.contains("found"));
    }
}

#[test]
fn read_npy_names_the_file() {
    let dir = std::env::temp_dir().join(format!("tensor-ops-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.npy");
    std::fs::write(
        &path,
        npy(1, &dict("<f8", "False", "(1000000, 1000000)"), &[]),
    )
    .unwrap();
    let e = read_npy(&path).unwrap_err();
    assert!(e.to_string().contains("bad.npy"), "{e}");
    assert!(e.to_string().contains("byte 128"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// SplitMix64, for deterministic mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// The plain-test counterpart of the `npy` fuzz target: seeded mutations of small valid files
/// parse or fail cleanly; what parses converts (or fails cleanly) and re-encodes to the same array.
#[test]
fn mutated_files_never_panic() {
    let seeds: Vec<Vec<u8>> = vec![
        npy(
            1,
            &dict("<f8", "False", "(2, 3)"),
            &f8(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
        ),
        npy(1, &dict("<f4", "True", "(2, 1, 2)"), &[0u8; 16]),
        npy(2, &dict(">f8", "False", "()"), &f8(&[7.0])),
        npy(3, &dict("<f8", "True", "(0, 3)"), &[]),
    ];
    let tokens: [&[u8]; 10] = [
        b"(",
        b")",
        b",",
        b"'",
        b"True",
        b"999999999999",
        b"0",
        b"<f4",
        b"}",
        b"\xff",
    ];
    let mut rng = Rng(99);
    let mut parsed = 0;
    for round in 0..20_000 {
        let mut b = seeds[round % seeds.len()].clone();
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(b.len());
            match rng.below(4) {
                0 => b[at] ^= 1 << rng.below(8),
                1 => b.truncate(at),
                2 => {
                    let t = tokens[rng.below(tokens.len())];
                    b.splice(at..at, t.iter().copied());
                }
                _ => b[at] = rng.next() as u8,
            }
            if b.is_empty() {
                break;
            }
        }
        if let Ok(a) = parse_npy(&b) {
            parsed += 1;
            let n = a.shape.iter().product::<usize>();
            assert_eq!(n, a.data.len());
            match a.ndim() {
                2 => drop(a.to_matrix()),
                3 => drop(a.to_tensor()),
                _ => {}
            }
            let again = parse_npy(&to_npy_bytes(&a, a.dtype).unwrap()).unwrap();
            assert_eq!(
                (&again.shape, again.fortran_order),
                (&a.shape, a.fortran_order)
            );
            let same = |x: f64, y: f64| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
            assert!(again.data.iter().zip(&a.data).all(|(&x, &y)| same(x, y)));
        }
    }
    assert!(parsed > 100, "only {parsed} mutants parsed");
}

/// Found by the `npy` fuzz target (10-minute run): a zero-element array with a huge other dimension
/// parsed fine and then `to_matrix` looped over 10^15 rows. Empty arrays are no matrix or tensor.
#[test]
fn empty_arrays_with_huge_dimensions_are_refused_quickly() {
    use std::time::Instant;
    use tensor_ops::TensorError;
    use tensor_ops::npy::parse_npy;
    for shape in [
        "(1000000000000000, 0)",
        "(0, 1000000000000000)",
        "(1000000000000000, 0, 7)",
    ] {
        let bytes = npy(1, &dict("<f8", "False", shape), &[]);
        let array = parse_npy(&bytes).expect("an empty array is valid NPY");
        let started = Instant::now();
        let err = if array.ndim() == 2 {
            array.to_matrix().map(|_| ()).unwrap_err()
        } else {
            array.to_tensor().map(|_| ()).unwrap_err()
        };
        assert!(
            matches!(err, TensorError::NpyEmpty { .. }),
            "{shape}: {err}"
        );
        assert!(
            started.elapsed().as_secs() < 1,
            "{shape} took {:?}",
            started.elapsed()
        );
    }
}
