//! The measurement tables of the accuracy analysis: CSV with a header, text labels (`P1`) next
//! to numbers, and the exports of tracker software (one pose per row, `;` between fields and a
//! decimal comma, extra columns, the point named in a column of its own).
//!
//! `track::csv_table` reads all-numeric tables; this reader keeps text fields and each field's
//! place in the line, so every error points at the field (`file:line:col`).

use std::path::{Path, PathBuf};

use super::error::{AccuracyError, Located};
use crate::syntax::Encoding;

/// Which file column holds a role (`point`, `cycle`, `x`, …): `point=Name,cycle=Run`. Columns
/// a map names are matched case-insensitively; with a map, the file's other columns are ignored
/// (a tracker export has many), without one an unknown column is an error.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ColumnMap {
    pairs: Vec<(String, String)>,
}

impl ColumnMap {
    /// Parses `role=COLUMN,role=COLUMN`; `Err` says what is wrong with the text.
    pub fn parse(text: &str) -> Result<ColumnMap, String> {
        let mut pairs: Vec<(String, String)> = Vec::new();
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let Some((role, column)) = part.split_once('=') else {
                return Err(format!("`{part}` is not role=COLUMN"));
            };
            let (role, column) = (role.trim().to_ascii_lowercase(), column.trim());
            if role.is_empty() || column.is_empty() {
                return Err(format!("`{part}` is not role=COLUMN"));
            }
            if pairs.iter().any(|(r, _)| *r == role) {
                return Err(format!("role `{role}` is mapped twice"));
            }
            pairs.push((role, column.to_ascii_lowercase()));
        }
        Ok(ColumnMap { pairs })
    }

    /// Whether the map names no column (every column is then matched by its role's name).
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The file column (lower case) that holds `role`.
    fn column_for(&self, role: &str) -> String {
        self.pairs
            .iter()
            .find(|(r, _)| r == role)
            .map_or_else(|| role.to_owned(), |(_, c)| c.clone())
    }
}

/// One data row: its 1-based line and the byte range of each field in that line.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    pub line: u64,
    /// The line's bytes within the file.
    start: usize,
    end: usize,
    fields: Vec<(usize, usize)>,
}

/// A read table.
#[derive(Clone, Debug)]
pub(crate) struct Table {
    path: PathBuf,
    /// Header names, lower case, trimmed, unquoted.
    headers: Vec<String>,
    header: Row,
    pub rows: Vec<Row>,
    source: Vec<u8>,
    /// How the file's bytes are text: a tracker's software writes UTF-8 or a Windows code page.
    encoding: Encoding,
    delimiter: u8,
    map: ColumnMap,
}

/// Splits one line at `delimiter` outside double quotes; byte ranges relative to the file.
fn split_fields(src: &[u8], start: usize, end: usize, delimiter: u8) -> Vec<(usize, usize)> {
    let mut fields = Vec::new();
    let mut field_start = start;
    let mut quoted = false;
    for (i, &byte) in src.iter().enumerate().take(end).skip(start) {
        match byte {
            b'"' => quoted = !quoted,
            b if b == delimiter && !quoted => {
                fields.push((field_start, i));
                field_start = i + 1;
            }
            _ => {}
        }
    }
    fields.push((field_start, end));
    fields
}

/// The field's text without surrounding blanks and quotes.
fn clean(bytes: &[u8], encoding: Encoding) -> String {
    let text = encoding.text(bytes);
    let text = text.trim();
    let text = text
        .strip_prefix('"')
        .and_then(|t| t.strip_suffix('"'))
        .unwrap_or(text);
    text.trim().to_owned()
}

impl Table {
    /// Reads a file; lines starting with `#` and blank lines are skipped.
    pub(crate) fn read(path: &Path, map: &ColumnMap) -> Result<Table, AccuracyError> {
        let bytes = crate::output::read_input(path).map_err(|error| AccuracyError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        Table::parse(path, &bytes, map)
    }

    /// Parses bytes; `path` is for messages only.
    pub(crate) fn parse(
        path: &Path,
        bytes: &[u8],
        map: &ColumnMap,
    ) -> Result<Table, AccuracyError> {
        let mut lines = Vec::new();
        let mut start = 0;
        let mut number = 0u64;
        while start <= bytes.len() {
            let stop = bytes[start..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(bytes.len(), |p| start + p);
            number += 1;
            let mut end = stop;
            if end > start && bytes[end - 1] == b'\r' {
                end -= 1;
            }
            let mut first = start;
            if number == 1 && bytes[start..end].starts_with(b"\xEF\xBB\xBF") {
                first += 3;
            }
            let text = &bytes[first..end];
            let blank = text.iter().all(u8::is_ascii_whitespace);
            let comment = text
                .iter()
                .find(|b| !b.is_ascii_whitespace())
                .is_some_and(|&b| b == b'#');
            if !blank && !comment {
                lines.push((number, first, end));
            }
            if stop == bytes.len() {
                break;
            }
            start = stop + 1;
        }
        let Some(&(header_line, hs, he)) = lines.first() else {
            return Err(AccuracyError::Empty {
                path: path.to_path_buf(),
            });
        };
        let head = &bytes[hs..he];
        let delimiter = if head.contains(&b';') {
            b';'
        } else if head.contains(&b'\t') && !head.contains(&b',') {
            b'\t'
        } else {
            b','
        };
        let row = |(line, s, e): (u64, usize, usize)| Row {
            line,
            start: s,
            end: e,
            fields: split_fields(bytes, s, e, delimiter),
        };
        let header = row((header_line, hs, he));
        let encoding = Encoding::of_text(bytes);
        let headers: Vec<String> = header
            .fields
            .iter()
            .map(|&(a, b)| clean(&bytes[a..b], encoding).to_ascii_lowercase())
            .collect();
        let mut table = Table {
            path: path.to_path_buf(),
            headers,
            header,
            rows: Vec::new(),
            source: bytes.to_vec(),
            encoding,
            delimiter,
            map: map.clone(),
        };
        for &(line, s, e) in &lines[1..] {
            let r = row((line, s, e));
            if r.fields.len() != table.headers.len() {
                return Err(table.located(
                    &r,
                    None,
                    format!(
                        "{} field(s), the header has {}",
                        r.fields.len(),
                        table.headers.len()
                    ),
                    "write one value per column on every row".to_owned(),
                ));
            }
            table.rows.push(r);
        }
        if table.rows.is_empty() {
            return Err(table.located(
                &table.header,
                None,
                "the file has a header but no data rows".to_owned(),
                "add one row per measurement".to_owned(),
            ));
        }
        Ok(table)
    }

    /// The index of `role`'s column, if the file has it.
    pub(crate) fn optional(&self, role: &str) -> Option<usize> {
        let name = self.map.column_for(role);
        self.headers.iter().position(|h| *h == name)
    }

    /// The index of `role`'s column, or an error at the header naming it.
    pub(crate) fn column(&self, role: &str) -> Result<usize, AccuracyError> {
        self.optional(role).ok_or_else(|| {
            let name = self.map.column_for(role);
            let hint = if name == role {
                format!(
                    "the header is `{}`; add the column `{role}` (or name the column that holds it with a column map, {role}=COLUMN)",
                    self.headers.join(",")
                )
            } else {
                format!(
                    "the header is `{}`; the column map names `{name}` for `{role}`",
                    self.headers.join(",")
                )
            };
            self.located(
                &self.header,
                None,
                format!("column `{name}` ({role}) is missing"),
                hint,
            )
        })
    }

    /// `rx, ry, rz` together or not at all: one or two of them is an error.
    pub(crate) fn angle_columns(&self) -> Result<Option<[usize; 3]>, AccuracyError> {
        let found = ["rx", "ry", "rz"].map(|r| self.optional(r));
        match found {
            [Some(a), Some(b), Some(c)] => Ok(Some([a, b, c])),
            [None, None, None] => Ok(None),
            _ => {
                let missing = ["rx", "ry", "rz"]
                    .iter()
                    .zip(found)
                    .find(|(_, f)| f.is_none())
                    .map_or("rz", |(r, _)| *r);
                self.column(missing).map(|_| None)
            }
        }
    }

    /// Without a column map, a column that is not one of `roles` is an error: a misspelt header
    /// is not ignored silently. With a map, other columns are the export's own and are ignored.
    pub(crate) fn refuse_unknown(&self, roles: &[&str]) -> Result<(), AccuracyError> {
        if !self.map.is_empty() {
            return Ok(());
        }
        for (i, h) in self.headers.iter().enumerate() {
            if !roles.contains(&h.as_str()) {
                return Err(self.located(
                    &self.header,
                    Some(i),
                    format!("unknown column `{h}`"),
                    format!(
                        "this file takes the columns `{}`; to read an export with other columns, name the ones to use with a column map (e.g. point=NAME)",
                        roles.join(",")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The text of field `index` of `row`.
    pub(crate) fn text(&self, row: &Row, index: usize) -> String {
        row.fields.get(index).map_or_else(String::new, |&(a, b)| {
            clean(&self.source[a..b], self.encoding)
        })
    }

    /// The number in field `index` of `row`; with `;` between fields a decimal comma is read.
    pub(crate) fn number(&self, row: &Row, index: usize) -> Result<f64, AccuracyError> {
        let text = self.text(row, index);
        let name = self.headers.get(index).cloned().unwrap_or_default();
        let normalised = if self.delimiter != b',' {
            text.replace(',', ".")
        } else {
            text.clone()
        };
        match normalised.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.located(
                row,
                Some(index),
                format!("`{text}` in column `{name}` is not a finite number"),
                "write a plain number (mm, degrees or seconds)".to_owned(),
            )),
            Err(_) => Err(self.located(
                row,
                Some(index),
                format!("`{text}` in column `{name}` is not a number"),
                "write a plain number (mm, degrees or seconds; `.` as the decimal point, or `,` in a `;`-separated file)".to_owned(),
            )),
        }
    }

    /// An error at `row`, under field `field` (the whole line when `None`).
    pub(crate) fn located(
        &self,
        row: &Row,
        field: Option<usize>,
        message: String,
        hint: String,
    ) -> AccuracyError {
        let line_bytes = &self.source[row.start..row.end];
        let line_text = self.encoding.text(line_bytes);
        // The caret counts characters, which are bytes only in Latin-1.
        let chars = |bytes: &[u8]| self.encoding.text(bytes).chars().count();
        let (mut a, mut b) = field
            .and_then(|f| row.fields.get(f).copied())
            .unwrap_or((row.start, row.end));
        while a < b && self.source[a].is_ascii_whitespace() {
            a += 1;
        }
        while b > a && self.source[b - 1].is_ascii_whitespace() {
            b -= 1;
        }
        AccuracyError::Input(Box::new(Located {
            path: self.path.clone(),
            line: row.line,
            column: chars(&self.source[row.start..a]) + 1,
            width: chars(&self.source[a..b]).max(1),
            line_text,
            message,
            hint,
        }))
    }

    /// An error under `role`'s field of `row`.
    pub(crate) fn error_at(
        &self,
        row: &Row,
        role: &str,
        message: String,
        hint: &str,
    ) -> AccuracyError {
        self.located(row, self.optional(role), message, hint.to_owned())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_semicolon_export_with_decimal_commas_and_quotes() {
        let map = ColumnMap::parse("point=Name, cycle=Run").unwrap();
        let src = "\u{feff}\"Name\";Run;X;Y;Z;Time\r\n# comment\r\n\"P1\";1;1,5;-2,25;3;0,1\r\n";
        let t = Table::parse(Path::new("e.csv"), src.as_bytes(), &map).unwrap();
        let r = &t.rows[0];
        assert_eq!(t.text(r, t.column("point").unwrap()), "P1");
        assert_eq!(t.number(r, t.column("x").unwrap()).unwrap(), 1.5);
        assert_eq!(t.number(r, t.column("y").unwrap()).unwrap(), -2.25);
        assert!(t.refuse_unknown(&["point"]).is_ok());
    }

    #[test]
    fn errors_point_at_the_field() {
        let src = b"point,x,y,z\nP1,1,zwei,3\n";
        let t = Table::parse(Path::new("c.csv"), src, &ColumnMap::default()).unwrap();
        let e = t.number(&t.rows[0], 2).unwrap_err();
        assert_eq!(
            e.to_string(),
            "c.csv:2:6: error: `zwei` in column `y` is not a number\n  |\n2 | P1,1,zwei,3\n  |      ^^^^\n  = help: write a plain number (mm, degrees or seconds; `.` as the decimal point, or `,` in a `;`-separated file)"
        );
        let e = t.refuse_unknown(&["point", "x", "y"]).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("c.csv:1:11: error: unknown column `z`")
        );
    }

    #[test]
    fn an_error_shows_the_line_in_the_files_encoding_with_the_caret_under_its_characters() {
        // UTF-8 (`°` is two bytes): one character each, the caret under the field.
        let src = "point,x,y,z\nPunkt°1,1,zwei,3\n";
        let t = Table::parse(Path::new("c.csv"), src.as_bytes(), &ColumnMap::default()).unwrap();
        assert_eq!(t.text(&t.rows[0], 0), "Punkt°1");
        let e = t.number(&t.rows[0], 2).unwrap_err();
        assert_eq!(
            e.to_string().lines().take(4).collect::<Vec<_>>().join("\n"),
            "c.csv:2:11: error: `zwei` in column `y` is not a number\n  |\n2 | Punkt°1,1,zwei,3\n  |           ^^^^"
        );
        // Latin-1 (a Windows export): the same text from one byte each.
        let src = b"point,x,y,z\nPunkt\xb01,1,zwei,3\n";
        let t = Table::parse(Path::new("c.csv"), src, &ColumnMap::default()).unwrap();
        assert_eq!(t.text(&t.rows[0], 0), "Punkt°1");
        let e = t.number(&t.rows[0], 2).unwrap_err();
        assert!(
            e.to_string()
                .contains("2 | Punkt°1,1,zwei,3\n  |           ^^^^")
        );
    }

    proptest::proptest! {
        #[test]
        fn any_bytes_give_a_table_or_a_located_error(bytes in proptest::collection::vec(
            proptest::prop_oneof![
                proptest::strategy::Just(b','), proptest::strategy::Just(b';'),
                proptest::strategy::Just(b'\n'), proptest::strategy::Just(b'"'),
                proptest::strategy::Just(b'1'), proptest::strategy::Just(b'x'),
                proptest::num::u8::ANY,
            ],
            0..200,
        )) {
            let map = ColumnMap::parse("point=x").unwrap();
            match Table::parse(Path::new("f.csv"), &bytes, &map) {
                Ok(t) => {
                    for row in &t.rows {
                        for i in 0..row.fields.len() + 1 {
                            let _ = t.text(row, i);
                            if let Err(e) = t.number(row, i) {
                                proptest::prop_assert!(e.location().is_some());
                            }
                        }
                    }
                    let _ = t.column("point");
                    let _ = t.angle_columns();
                }
                Err(e) => {
                    let _ = e.to_string();
                }
            }
        }
    }

    #[test]
    fn column_map_syntax() {
        assert!(ColumnMap::parse("point").is_err());
        assert!(ColumnMap::parse("point=a,point=b").is_err());
        assert!(ColumnMap::parse("").unwrap().is_empty());
    }
}
