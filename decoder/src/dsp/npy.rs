//! A small reader for NumPy `.npy` files (format 1.0/2.0/3.0, little-endian, C order), enough
//! for the recordings in `../shared/data` (int16) and for reference files written by numpy
//! (float64). Values are converted to f64.

use std::path::Path;

/// A numeric array read from a `.npy` file.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    /// Shape, outermost first.
    pub shape: Vec<usize>,
    /// Values in C (row-major) order.
    pub data: Vec<f64>,
}

/// Why a `.npy` file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    /// The file could not be read.
    #[error("reading {path}: {source}")]
    Io {
        /// File path.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// Not an NPY file or a header this reader does not understand.
    #[error("{0}")]
    Format(String),
}

fn format_err(msg: impl Into<String>) -> NpyError {
    NpyError::Format(msg.into())
}

/// Reads a whole `.npy` file.
pub fn read_npy(path: impl AsRef<Path>) -> Result<NpyArray, NpyError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| NpyError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse_npy(&bytes).map_err(|e| match e {
        NpyError::Format(m) => NpyError::Format(format!("{}: {m}", path.display())),
        other => other,
    })
}

/// Parses the bytes of a `.npy` file.
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, NpyError> {
    let (header, data_start) = header_text(bytes)?;
    let descr = dict_value(header, "descr")?;
    let descr = descr.trim().trim_matches(|c| c == '\'' || c == '"');
    let fortran = dict_value(header, "fortran_order")?;
    if fortran.trim() != "False" {
        return Err(format_err("Fortran-order arrays are not supported"));
    }
    let shape = parse_shape(dict_value(header, "shape")?)?;
    let payload = &bytes[data_start..];
    let (size, convert) = dtype(descr)?;
    // Checked: a corrupt shape such as (2**40, 2**40) must not overflow the count.
    let needed = shape
        .iter()
        .try_fold(size, |n, &d| n.checked_mul(d))
        .ok_or_else(|| format_err(format!("shape {shape:?} is too large")))?;
    if payload.len() < needed {
        return Err(format_err(format!(
            "data holds {} bytes, shape {shape:?} of {descr} needs {needed}",
            payload.len()
        )));
    }
    let data = payload[..needed].chunks_exact(size).map(convert).collect();
    Ok(NpyArray { shape, data })
}

/// The header's text (a Python dict literal) and where the data starts, after checking the
/// magic and the format version.
fn header_text(bytes: &[u8]) -> Result<(&str, usize), NpyError> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(format_err("not an NPY file (bad magic)"));
    }
    let major = bytes[6];
    let (header_len, header_start) = match major {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 => {
            if bytes.len() < 12 {
                return Err(format_err("truncated NPY header"));
            }
            (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            )
        }
        v => return Err(format_err(format!("unsupported NPY version {v}"))),
    };
    let data_start = header_start + header_len;
    let header = bytes
        .get(header_start..data_start)
        .ok_or_else(|| format_err("truncated NPY header"))?;
    let header = std::str::from_utf8(header).map_err(|_| format_err("NPY header is not text"))?;
    Ok((header, data_start))
}

/// The shape tuple's text, e.g. `(3, 2)` or `(4,)`, as sizes.
fn parse_shape(text: &str) -> Result<Vec<usize>, NpyError> {
    text.trim()
        .trim_start_matches('(')
        .trim_end_matches(')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format_err(format!("bad shape entry {s:?}")))
        })
        .collect()
}

/// Converts one little-endian element to f64.
type Convert = fn(&[u8]) -> f64;

/// Bytes per element and the conversion to f64 of a supported dtype.
fn dtype(descr: &str) -> Result<(usize, Convert), NpyError> {
    let found: (usize, Convert) = match descr {
        "<i2" => (2, |b| i16::from_le_bytes([b[0], b[1]]) as f64),
        "<i4" => (4, |b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64),
        "<f4" => (4, |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64),
        "<f8" => (8, |b| {
            f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
        }),
        other => {
            return Err(format_err(format!(
                "dtype {other:?} is not supported (only <i2, <i4, <f4, <f8)"
            )))
        }
    };
    Ok(found)
}

/// The raw text of `key`'s value in the header's Python dict literal.
fn dict_value<'a>(header: &'a str, key: &str) -> Result<&'a str, NpyError> {
    let pat_single = format!("'{key}':");
    let pat_double = format!("\"{key}\":");
    let start = header
        .find(&pat_single)
        .map(|i| i + pat_single.len())
        .or_else(|| header.find(&pat_double).map(|i| i + pat_double.len()))
        .ok_or_else(|| format_err(format!("NPY header has no {key:?}")))?;
    let rest = &header[start..];
    let rest_trim = rest.trim_start();
    let end = if rest_trim.starts_with('(') {
        rest.find(')').map(|i| i + 1)
    } else {
        rest.find(',').or_else(|| rest.find('}'))
    }
    .ok_or_else(|| format_err(format!("NPY header value of {key:?} is not terminated")))?;
    Ok(&rest[..end])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(descr: &str, shape: &str, payload: &[u8]) -> Vec<u8> {
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(payload);
        out
    }

    #[test]
    fn reads_int16_matrix() {
        let payload: Vec<u8> = [1i16, -2, 3, -32768, 32767, 0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let a = parse_npy(&npy("<i2", "(3, 2)", &payload)).expect("valid npy");
        assert_eq!(a.shape, vec![3, 2]);
        assert_eq!(a.data, vec![1.0, -2.0, 3.0, -32768.0, 32767.0, 0.0]);
    }

    #[test]
    fn reads_1d_f8() {
        let payload: Vec<u8> = [0.5f64, -1.25]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let a = parse_npy(&npy("<f8", "(2,)", &payload)).expect("valid npy");
        assert_eq!(a.shape, vec![2]);
        assert_eq!(a.data, vec![0.5, -1.25]);
    }

    #[test]
    fn refuses_bad_input() {
        assert!(parse_npy(b"hello world").is_err());
        let short = npy("<f8", "(4,)", &[0u8; 8]);
        let err = parse_npy(&short).expect_err("too short").to_string();
        assert!(err.contains("needs 32"), "{err}");
        assert!(parse_npy(&npy(">f8", "(0,)", &[])).is_err());
    }

    // Regression: the element count was an unchecked product (a panic in debug builds).
    #[test]
    fn a_shape_whose_size_overflows_is_refused() {
        let huge = npy("<f8", "(4294967296, 4294967296, 2)", &[0u8; 8]);
        let err = parse_npy(&huge).expect_err("overflowing shape").to_string();
        assert!(
            err.contains("shape [4294967296, 4294967296, 2] is too large"),
            "{err}"
        );
        let big = npy("<i2", "(1099511627776, 12)", &[0u8; 24]);
        let err = parse_npy(&big).expect_err("claims 2**40 rows").to_string();
        assert!(err.contains("needs 26388279066624"), "{err}");
    }
}
