//! Numeric CSV tables (`measurements.csv`, `frames.csv`, `scan.csv`) with errors that name
//! `file:line:col`, show the line with a caret under the field, and say what to do.

use std::path::{Path, PathBuf};

use super::profile::TrackError;
use crate::syntax::{Diagnostic, LineIndex, Span};

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
    /// The 1-based line of the header (comment lines may come first).
    pub header_line: u64,
    /// The file's bytes, for messages that show the line.
    source: Vec<u8>,
}

/// `file:line:col: error: message`, the line, a caret under `span` and `hint`.
pub(crate) fn render_located(
    path: &Path,
    src: &[u8],
    span: Span,
    message: &str,
    hint: &str,
) -> String {
    let index = LineIndex::new(src);
    let mut d = Diagnostic::error(span, message);
    if !hint.is_empty() {
        d = d.with_hint(hint);
    }
    d.render(&path.display().to_string(), src, &index)
        .trim_end()
        .to_owned()
}

/// The span of field `field` (0-based) of `line`, or of the whole line when there is no such
/// field. Numeric CSV has no quoted commas, so splitting the line is enough.
fn field_span(src: &[u8], line: u64, field: Option<usize>) -> Span {
    let index = LineIndex::new(src);
    let whole = index.line_span(src, usize::try_from(line).unwrap_or(usize::MAX));
    let Some(field) = field else { return whole };
    let text = whole.slice(src);
    let mut start = 0;
    for (i, part) in text.split(|&b| b == b',').enumerate() {
        if i == field {
            let lead = part.iter().take_while(|b| b.is_ascii_whitespace()).count();
            let trail = part
                .iter()
                .rev()
                .take_while(|b| b.is_ascii_whitespace())
                .count();
            let end = part.len().saturating_sub(trail).max(lead);
            return Span::new(whole.start + start + lead, whole.start + start + end);
        }
        start += part.len() + 1;
    }
    whole
}

/// The error of a CSV file: where, in which column, what, and what to do.
fn csv_error(
    path: &Path,
    src: &[u8],
    (line, field): (u64, Option<usize>),
    column: &str,
    message: String,
    hint: &str,
) -> TrackError {
    let rendered = render_located(path, src, field_span(src, line, field), &message, hint);
    TrackError::Csv {
        path: path.to_path_buf(),
        line,
        column: column.to_string(),
        message,
        rendered,
    }
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
        let err = |at: (u64, Option<usize>), column: &str, message: String, hint: &str| {
            csv_error(path, bytes, at, column, message, hint)
        };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(bytes);
        let header_record = reader
            .headers()
            .map_err(|e| err((1, None), "", e.to_string(), ""))?;
        let header_line = header_record.position().map_or(1, |p| p.line());
        let headers: Vec<String> = header_record
            .iter()
            .map(|h| h.trim_start_matches('\u{feff}').to_ascii_lowercase())
            .collect();
        if headers.iter().all(|h| h.is_empty()) {
            return Err(err(
                (header_line, None),
                "",
                "the file has no header line".to_string(),
                "start the file with its column names (the command's --help lists them)",
            ));
        }
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = match record {
                Ok(r) => r,
                Err(e) => {
                    let line = e.position().map(|p| p.line()).unwrap_or(0);
                    return Err(match e.kind() {
                        csv::ErrorKind::UnequalLengths {
                            expected_len, len, ..
                        } => err(
                            (line, None),
                            "",
                            format!("{len} field(s), the header has {expected_len}"),
                            "write one value per column on every row",
                        ),
                        _ => err((line, None), "", e.to_string(), ""),
                    });
                }
            };
            let line = record.position().map(|p| p.line()).unwrap_or(0);
            let mut values = Vec::with_capacity(record.len());
            for (i, (field, name)) in record.iter().zip(&headers).enumerate() {
                let v: f64 = field.parse().map_err(|_| {
                    err(
                        (line, Some(i)),
                        name,
                        format!("`{field}` in column `{name}` is not a number"),
                        "write a plain number (mm or degrees, `.` as the decimal point)",
                    )
                })?;
                if !v.is_finite() {
                    return Err(err(
                        (line, Some(i)),
                        name,
                        format!("`{field}` in column `{name}` is not a finite number"),
                        "write a plain number (mm or degrees)",
                    ));
                }
                values.push(v);
            }
            rows.push(NumericRow { line, values });
        }
        Ok(NumericCsv {
            path: path.to_path_buf(),
            headers,
            rows,
            header_line,
            source: bytes.to_vec(),
        })
    }

    /// Index of a required column.
    pub fn column(&self, name: &str) -> Result<usize, TrackError> {
        self.headers.iter().position(|h| h == name).ok_or_else(|| {
            csv_error(
                &self.path,
                &self.source,
                (self.header_line, None),
                name,
                format!("column `{name}` is missing"),
                &format!(
                    "the header is `{}`; add the column `{name}`",
                    self.headers.join(",")
                ),
            )
        })
    }

    /// Indices of `names`, refusing columns that are not among them (a misspelt header
    /// should not be ignored silently).
    pub fn columns(&self, names: &[&str]) -> Result<Vec<usize>, TrackError> {
        if let Some(extra) = self.headers.iter().find(|h| !names.contains(&h.as_str())) {
            return Err(self.error(
                self.header_line,
                extra,
                format!("unknown column `{extra}`"),
                &format!(
                    "this file needs exactly the columns `{}` (in any order)",
                    names.join(",")
                ),
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

    /// An error at `line` of this file, under the field of `column`, with what to do.
    pub fn error(&self, line: u64, column: &str, message: String, hint: &str) -> TrackError {
        let field = self.headers.iter().position(|h| h == column);
        csv_error(
            &self.path,
            &self.source,
            (line, field),
            column,
            message,
            hint,
        )
    }

    /// The value at `index` (validated by [`NumericCsv::columns`]).
    pub fn get(row: &NumericRow, index: usize) -> f64 {
        row.values.get(index).copied().unwrap_or(f64::NAN)
    }
}
