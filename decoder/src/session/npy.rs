//! Writing NumPy `.npy` files (v1.0, little-endian float64), for imported sessions. Reading
//! reuses [`crate::dsp::npy`].

use std::path::Path;

use super::error::SessionError;
use crate::fsio::write_atomic;

/// Encodes a row-major `rows x cols` float64 matrix as NPY v1.0 bytes.
pub fn npy_f64_bytes(rows: usize, cols: usize, data: &[f64]) -> Vec<u8> {
    debug_assert_eq!(rows * cols, data.len());
    let mut header =
        format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is padded to a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + data.len() * 8);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Writes a row-major `rows x cols` float64 matrix to `path` atomically.
pub fn write_npy_f64(
    path: &Path,
    rows: usize,
    cols: usize,
    data: &[f64],
) -> Result<(), SessionError> {
    if rows * cols != data.len() {
        return Err(SessionError::recording(
            path,
            format!("{} values is not {rows} x {cols}", data.len()),
        ));
    }
    Ok(write_atomic(path, &npy_f64_bytes(rows, cols, data))?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dsp::npy::parse_npy;

    #[test]
    fn round_trips_through_the_reader() {
        let data = [1.0, -2.5, 3.25, 1e-300, f64::MAX, 0.0];
        let bytes = npy_f64_bytes(3, 2, &data);
        assert_eq!((bytes.len() - data.len() * 8) % 64, 0);
        let a = parse_npy(&bytes).unwrap();
        assert_eq!(a.shape, vec![3, 2]);
        assert_eq!(a.data, data.to_vec());
    }
}
