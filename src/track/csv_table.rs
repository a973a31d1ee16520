//! Numeric CSV tables (`measurements.csv`, `frames.csv`, `scan.csv`) with errors that name
//! `file:line:col`, show the line with a caret under the field, and say what to do.
//!
//! Besides `,`-separated files, a spreadsheet's export in a German (or other continental)
//! locale is read: `;` between the fields and `,` as the decimal point, told as a note. Tab
//! separated tables are read too. A file whose header names none of the expected columns is
//! something else (`/etc/passwd` given as a table): the error does not quote it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::error::{LocatedError, TrackError};
use crate::syntax::{LineIndex, Span};

/// One data row and the 1-based line it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericRow {
    /// 1-based line of the file.
    pub line: u64,
    /// The row's numbers, one per header column.
    pub values: Vec<f64>,
}

/// A CSV file whose every field is a number.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericCsv {
    /// The file, as named.
    pub path: PathBuf,
    /// The column names, as written.
    pub headers: Vec<String>,
    /// The data rows, in file order.
    pub rows: Vec<NumericRow>,
    /// The 1-based line of the header (comment lines may come first).
    pub header_line: u64,
    /// How the file was read when that is not plain `,`-separated CSV (for the user to check).
    pub notes: Vec<String>,
    /// The field separator found in the header.
    delimiter: u8,
    /// The file's bytes, for messages that show the line.
    source: Arc<[u8]>,
}

/// The span of field `field` (0-based) of `line`, or of the whole line when there is no such
/// field. Numeric CSV has no quoted separators, so splitting the line is enough.
fn field_span(src: &[u8], delimiter: u8, line: u64, field: Option<usize>) -> Span {
    let index = LineIndex::new(src);
    let whole = index.line_span(src, usize::try_from(line).unwrap_or(usize::MAX));
    let Some(field) = field else { return whole };
    let text = whole.slice(src);
    let mut start = 0;
    for (i, part) in text.split(|&b| b == delimiter).enumerate() {
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

/// The first line that is neither blank nor a `#` comment: the header.
fn header_text(bytes: &[u8]) -> &[u8] {
    bytes
        .split(|&b| b == b'\n')
        .find(|l| {
            let t = l.trim_ascii();
            !t.is_empty() && !t.starts_with(b"#")
        })
        .unwrap_or_default()
}

/// `,` unless the header has none and has `;` (a continental spreadsheet) or tabs.
fn detect_delimiter(header: &[u8]) -> u8 {
    let count = |d: u8| header.iter().filter(|&&b| b == d).count();
    if count(b',') > 0 {
        b','
    } else if count(b';') > 0 {
        b';'
    } else if count(b'\t') > 0 {
        b'\t'
    } else {
        b','
    }
}

struct Source<'a> {
    path: &'a Path,
    bytes: &'a Arc<[u8]>,
    delimiter: u8,
}

impl Source<'_> {
    /// The error of a CSV file: where, in which column, what, and what to do.
    fn error(
        &self,
        (line, field): (u64, Option<usize>),
        column: &str,
        message: String,
        hint: &str,
    ) -> TrackError {
        let span = field_span(self.bytes, self.delimiter, line, field);
        // The csv reader takes UTF-8 only: a file it reads this far is UTF-8.
        let mut e = LocatedError::new(self.path, self.bytes.clone(), span, message, hint).in_utf8();
        if !column.is_empty() {
            e = e.in_column(column);
        }
        e.into()
    }
}

impl NumericCsv {
    /// Reads a file; `#` starts a comment line. `accepted` are the columns the caller can use:
    /// a header naming none of them means the file is not such a table.
    pub fn read(path: &Path, accepted: &[&str]) -> Result<NumericCsv, TrackError> {
        let bytes = crate::output::read_input(path).map_err(|error| TrackError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        NumericCsv::parse(path, &bytes, accepted)
    }

    /// Parses bytes; `path` is for messages only. See [`NumericCsv::read`].
    pub fn parse(path: &Path, bytes: &[u8], accepted: &[&str]) -> Result<NumericCsv, TrackError> {
        let shared: Arc<[u8]> = Arc::from(bytes);
        let delimiter = detect_delimiter(header_text(bytes));
        let src = Source {
            path,
            bytes: &shared,
            delimiter,
        };
        let err = |at: (u64, Option<usize>), column: &str, message: String, hint: &str| {
            src.error(at, column, message, hint)
        };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .delimiter(delimiter)
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
                "start the file with its column names (the command's help lists them)",
            ));
        }
        if !accepted.is_empty() && !headers.iter().any(|h| accepted.contains(&h.as_str())) {
            let e = LocatedError::new(
                path,
                shared.clone(),
                field_span(&shared, delimiter, header_line, None),
                format!(
                    "not a table of this kind: its first line names none of the columns `{}`",
                    accepted.join(",")
                ),
                "give a table whose header line names these columns",
            );
            return Err(e.without_quote().into());
        }
        // Decimal commas only where `,` cannot be the separator.
        let decimal_comma = delimiter != b',';
        let mut saw_decimal_comma = false;
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
                            &format!(
                                "write one value per column on every row, separated by `{}` as in the header",
                                char::from(delimiter).escape_default()
                            ),
                        ),
                        _ => err((line, None), "", e.to_string(), ""),
                    });
                }
            };
            let line = record.position().map(|p| p.line()).unwrap_or(0);
            let mut values = Vec::with_capacity(record.len());
            for (i, (field, name)) in record.iter().zip(&headers).enumerate() {
                let parsed = if decimal_comma && field.contains(',') {
                    saw_decimal_comma = true;
                    field.replacen(',', ".", 1).parse::<f64>()
                } else {
                    field.parse::<f64>()
                };
                let v: f64 = parsed.map_err(|_| {
                    err(
                        (line, Some(i)),
                        name,
                        format!("`{field}` in column `{name}` is not a number"),
                        if decimal_comma {
                            "write a plain number (mm or degrees, `,` or `.` as the decimal point)"
                        } else {
                            "write a plain number (mm or degrees, `.` as the decimal point)"
                        },
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
        let mut notes = Vec::new();
        match (delimiter, saw_decimal_comma) {
            (b',', _) => {}
            (b';', true) => notes.push(format!(
                "{}: read with `;` between the fields and `,` as the decimal point (a spreadsheet export in a continental locale)",
                path.display()
            )),
            (d, _) => notes.push(format!(
                "{}: read with `{}` between the fields",
                path.display(),
                char::from(d).escape_default()
            )),
        }
        Ok(NumericCsv {
            path: path.to_path_buf(),
            headers,
            rows,
            header_line,
            notes,
            delimiter,
            source: shared,
        })
    }

    /// Index of a required column.
    pub fn column(&self, name: &str) -> Result<usize, TrackError> {
        self.headers.iter().position(|h| h == name).ok_or_else(|| {
            self.src().error(
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
        self.src().error((line, field), column, message, hint)
    }

    fn src(&self) -> Source<'_> {
        Source {
            path: &self.path,
            bytes: &self.source,
            delimiter: self.delimiter,
        }
    }

    /// The value at `index` (validated by [`NumericCsv::columns`]).
    pub fn get(row: &NumericRow, index: usize) -> f64 {
        row.values.get(index).copied().unwrap_or(f64::NAN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_shows_the_utf8_line_it_read() {
        let src = "skid,x\n100,1.5°\n";
        let Err(e) = NumericCsv::parse(Path::new("t.csv"), src.as_bytes(), &["skid", "x"]) else {
            panic!("`1.5°` is no number");
        };
        let text = e.to_string();
        assert!(
            text.contains("2 | 100,1.5°\n"),
            "the line as written, `°` one character: {text}"
        );
        assert!(!text.contains('Â'), "{text}");
    }
}
