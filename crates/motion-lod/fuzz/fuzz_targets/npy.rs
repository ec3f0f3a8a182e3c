//! NPY reader: any bytes go to `parse_npy`; an array that parses must convert to a matrix or a
//! tensor without panicking (errors are fine) and write back as bytes that parse to the same
//! array.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tensor_ops::npy::{parse_npy, to_npy_bytes};

fuzz_target!(|data: &[u8]| {
    let Ok(array) = parse_npy(data) else {
        return;
    };
    assert_eq!(
        array
            .shape
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d)),
        Some(array.data.len())
    );
    match array.ndim() {
        2 => drop(array.to_matrix()),
        3 => drop(array.to_tensor()),
        _ => {}
    }
    let bytes = to_npy_bytes(&array, array.dtype).expect("a parsed array encodes");
    let again = parse_npy(&bytes).expect("encoded bytes parse");
    assert_eq!(again.shape, array.shape);
    assert_eq!(again.fortran_order, array.fortran_order);
    assert_eq!(again.dtype, array.dtype);
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    assert!(
        again
            .data
            .iter()
            .zip(&array.data)
            .all(|(&a, &b)| same(a, b))
    );
});
