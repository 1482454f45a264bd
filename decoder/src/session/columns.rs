//! The columns of an imported samples file: the EMG channels, the reference column (a force or
//! angle recorded beside the EMG) and columns to leave out (a time stamp). A column is named by
//! its header name (CSV, case-insensitive) or by its 0-based index (CSV or NPY).

use std::path::{Path, PathBuf};

use super::error::SessionError;
use super::import::read_text;

/// A samples file read whole: `n_rows x n_cols` values, row-major, with the CSV header if any.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleTable {
    /// The file, for messages.
    pub path: PathBuf,
    /// Column names (a CSV's non-numeric first line), lower-cased; `None` without a header.
    pub header: Option<Vec<String>>,
    /// Columns per row.
    pub n_cols: usize,
    /// Row-major values.
    pub values: Vec<f64>,
}

/// A table split into what the session stores.
#[derive(Debug, Clone, PartialEq)]
pub struct SplitColumns {
    /// EMG samples, row-major `n x channels`.
    pub emg: Vec<f64>,
    /// The reference column, one value per row, with its name.
    pub reference: Option<(String, Vec<f64>)>,
}

impl SampleTable {
    /// Reads a CSV file: one row per line, a non-numeric first line is the header, every row
    /// as wide as the first.
    pub fn read_csv(path: &Path) -> Result<Self, SessionError> {
        let text = read_text(path)?;
        let mut table = SampleTable {
            path: path.to_path_buf(),
            header: None,
            n_cols: 0,
            values: Vec::new(),
        };
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let width = table.header.as_ref().map(Vec::len).unwrap_or(table.n_cols);
            if width != 0 && fields.len() != width {
                return Err(SessionError::recording(
                    path,
                    format!(
                        "line {}: {} values, the first line has {width}",
                        i + 1,
                        fields.len()
                    ),
                ));
            }
            let vals: Result<Vec<f64>, _> = fields.iter().map(|v| v.parse::<f64>()).collect();
            match vals {
                Ok(v) => {
                    table.n_cols = v.len();
                    table.values.extend(v);
                }
                Err(_) if i == 0 => {
                    table.header = Some(fields.iter().map(|f| f.to_ascii_lowercase()).collect());
                }
                Err(_) => {
                    return Err(SessionError::recording(
                        path,
                        format!("line {}: not numbers", i + 1),
                    ))
                }
            }
        }
        table.n_cols = table.header.as_ref().map(Vec::len).unwrap_or(table.n_cols);
        Ok(table)
    }

    /// Reads an NPY file `n x columns` (or `n`, one column).
    pub fn read_npy(path: &Path) -> Result<Self, SessionError> {
        let arr = crate::dsp::npy::read_npy(path).map_err(|e| match e {
            crate::dsp::npy::NpyError::Io { source, .. } => SessionError::io(path, source),
            other => SessionError::recording(path, other.to_string()),
        })?;
        let n_cols = match arr.shape.as_slice() {
            [_] => 1,
            [_, c] => *c,
            other => {
                return Err(SessionError::recording(
                    path,
                    format!("shape {other:?}: expected (n_samples, columns)"),
                ))
            }
        };
        Ok(SampleTable {
            path: path.to_path_buf(),
            header: None,
            n_cols,
            values: arr.data,
        })
    }

    /// Index of the column `spec` names: a header name, or a 0-based index.
    fn column(&self, spec: &str, role: &str) -> Result<usize, SessionError> {
        let key = spec.trim().to_ascii_lowercase();
        let by_name = self
            .header
            .as_ref()
            .and_then(|h| h.iter().position(|c| *c == key));
        let by_index = key.parse::<usize>().ok().filter(|&i| i < self.n_cols);
        by_name.or(by_index).ok_or_else(|| {
            let known = match &self.header {
                Some(h) => format!("the columns are {}", h.join(", ")),
                None => format!("no header: give a column index 0..{}", self.n_cols),
            };
            SessionError::recording(
                &self.path,
                format!("{role} column \"{spec}\" is not in the file ({known})"),
            )
        })
    }

    /// Splits the table into `channels` EMG columns (every column but the reference and the
    /// ignored ones, in file order) and the reference column.
    pub fn split(
        &self,
        reference: Option<&str>,
        ignore: &[String],
        channels: usize,
    ) -> Result<SplitColumns, SessionError> {
        let reference = match reference {
            Some(r) => Some((r.trim().to_string(), self.column(r, "reference")?)),
            None => None,
        };
        let mut dropped = Vec::new();
        for c in ignore {
            dropped.push(self.column(c, "ignored")?);
        }
        let ref_col = reference.as_ref().map(|(_, c)| *c);
        let emg_cols: Vec<usize> = (0..self.n_cols)
            .filter(|c| Some(*c) != ref_col && !dropped.contains(c))
            .collect();
        if emg_cols.len() != channels {
            return Err(SessionError::recording(
                &self.path,
                format!(
                    "{} columns less the reference ({}) and {} ignored leave {} EMG channels, not the {channels} channels asked for",
                    self.n_cols,
                    reference.as_ref().map_or("none", |(n, _)| n.as_str()),
                    dropped.len(),
                    emg_cols.len()
                ),
            ));
        }
        let rows = self.values.chunks_exact(self.n_cols.max(1));
        let emg = rows
            .clone()
            .flat_map(|row| emg_cols.iter().map(move |&c| row[c]))
            .collect();
        let reference = reference.map(|(name, c)| (name, rows.map(|row| row[c]).collect()));
        Ok(SplitColumns { emg, reference })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> SampleTable {
        SampleTable {
            path: PathBuf::from("x.csv"),
            header: Some(vec!["time_s".into(), "emg".into(), "force".into()]),
            n_cols: 3,
            values: vec![0.0, 1.0, 10.0, 0.001, 2.0, 20.0],
        }
    }

    #[test]
    fn columns_by_name_or_index() {
        let s = table().split(Some("Force"), &["0".into()], 1).unwrap();
        assert_eq!(s.emg, vec![1.0, 2.0]);
        assert_eq!(s.reference, Some(("Force".into(), vec![10.0, 20.0])));
        let s = table().split(None, &[], 3).unwrap();
        assert_eq!(s.emg.len(), 6);
    }

    #[test]
    fn unknown_columns_and_wrong_counts_are_named() {
        let e = table()
            .split(Some("angle"), &[], 2)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("\"angle\"") && e.contains("time_s, emg, force"),
            "{e}"
        );
        let e = table()
            .split(Some("force"), &[], 4)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("leave 2 EMG channels") && e.contains("4 channels"),
            "{e}"
        );
    }
}
