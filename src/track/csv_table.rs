//! Numeric CSV tables (`measurements.csv`, `frames.csv`, `scan.csv`) with errors that name
//! `file:line` and the column.

use std::path::{Path, PathBuf};

use super::profile::TrackError;

/// One data row and the 1-based line it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericRow {
    pub line: u64,
    pub values: Vec<f64>,
}

/// A CSV file whose every field is a number.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericCsv {
    pub path: PathBuf,
    pub headers: Vec<String>,
    pub rows: Vec<NumericRow>,
}

impl NumericCsv {
    /// Reads a file; `#` starts a comment line.
    pub fn read(path: &Path) -> Result<NumericCsv, TrackError> {
        let bytes = std::fs::read(path).map_err(|error| TrackError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        NumericCsv::parse(path, &bytes)
    }

    /// Parses bytes; `path` is for messages only.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<NumericCsv, TrackError> {
        let err = |line: u64, column: &str, message: String| TrackError::Csv {
            path: path.to_path_buf(),
            line,
            column: column.to_string(),
            message,
        };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(bytes);
        let headers: Vec<String> = reader
            .headers()
            .map_err(|e| err(1, "", e.to_string()))?
            .iter()
            .map(|h| h.trim_start_matches('\u{feff}').to_ascii_lowercase())
            .collect();
        if headers.iter().all(|h| h.is_empty()) {
            return Err(err(1, "", "the file has no header line".to_string()));
        }
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = match record {
                Ok(r) => r,
                Err(e) => {
                    let line = e.position().map(|p| p.line()).unwrap_or(0);
                    let message = match e.kind() {
                        csv::ErrorKind::UnequalLengths {
                            expected_len, len, ..
                        } => format!(
                            "{len} field(s), the header has {expected_len}; every row needs one value per column"
                        ),
                        _ => e.to_string(),
                    };
                    return Err(err(line, "", message));
                }
            };
            let line = record.position().map(|p| p.line()).unwrap_or(0);
            let mut values = Vec::with_capacity(record.len());
            for (field, name) in record.iter().zip(&headers) {
                let v: f64 = field.parse().map_err(|_| {
                    err(
                        line,
                        name,
                        format!("`{field}` is not a number (mm or degrees)"),
                    )
                })?;
                if !v.is_finite() {
                    return Err(err(line, name, format!("`{field}` is not a finite number")));
                }
                values.push(v);
            }
            rows.push(NumericRow { line, values });
        }
        Ok(NumericCsv {
            path: path.to_path_buf(),
            headers,
            rows,
        })
    }

    /// Index of a required column.
    pub fn column(&self, name: &str) -> Result<usize, TrackError> {
        self.headers.iter().position(|h| h == name).ok_or_else(|| {
            self.error(
                1,
                name,
                format!("missing column; the header is `{}`", self.headers.join(",")),
            )
        })
    }

    /// Indices of `names`, refusing columns that are not among them (a misspelt header
    /// should not be ignored silently).
    pub fn columns(&self, names: &[&str]) -> Result<Vec<usize>, TrackError> {
        if let Some(extra) = self.headers.iter().find(|h| !names.contains(&h.as_str())) {
            return Err(self.error(
                1,
                extra,
                format!("unknown column; expected `{}`", names.join(",")),
            ));
        }
        names.iter().map(|n| self.column(n)).collect()
    }

    /// Each row's values in the order of `names` (all the file's columns, see
    /// [`NumericCsv::columns`]) with the row's line.
    pub fn select<const N: usize>(
        &self,
        names: &[&str; N],
    ) -> Result<Vec<(u64, [f64; N])>, TrackError> {
        let idx = self.columns(names)?;
        Ok(self
            .rows
            .iter()
            .map(|row| {
                let mut v = [f64::NAN; N];
                for (slot, &i) in v.iter_mut().zip(&idx) {
                    *slot = NumericCsv::get(row, i);
                }
                (row.line, v)
            })
            .collect())
    }

    /// An error at `line` of this file, in `column`.
    pub fn error(&self, line: u64, column: &str, message: String) -> TrackError {
        TrackError::Csv {
            path: self.path.clone(),
            line,
            column: column.to_string(),
            message,
        }
    }

    /// The value at `index` (validated by [`NumericCsv::columns`]).
    pub fn get(row: &NumericRow, index: usize) -> f64 {
        row.values.get(index).copied().unwrap_or(f64::NAN)
    }
}
