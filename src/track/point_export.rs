//! Point exports of laser-tracker software: one named point per line, `name x y z`, with or
//! without a header line, separated by `;`, tabs, spaces or `,` (a `;`- or space-separated file
//! may write decimal commas). Which column holds what is found from the header (`name`/`point`/
//! `id`, `x`, `y`, `z`, any case) or given as a [`ColumnMap`] (`name=1,x=2,y=3,z=4` by
//! position, or by header: `name=Punkt,x=X [mm],…`); without either the first four columns are
//! name, x, y, z. Lines starting with `#` or `//` are comments.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use super::error::{LocatedError, TrackError};
use crate::syntax::{LineIndex, Span};

/// Where one quantity is: a 1-based column number or a header name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Column {
    /// The n-th column, 1-based.
    Position(usize),
    /// The column with this header (matched case-insensitively).
    Header(String),
}

/// Which columns hold the point name and x, y, z.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColumnMap {
    /// The point name's column.
    pub name: Column,
    /// The x coordinate's column.
    pub x: Column,
    /// The y coordinate's column.
    pub y: Column,
    /// The z coordinate's column.
    pub z: Column,
}

impl std::str::FromStr for ColumnMap {
    type Err = String;

    /// `name=1,x=2,y=3,z=4` (positions) or header names; all four keys are needed.
    fn from_str(s: &str) -> Result<ColumnMap, String> {
        let mut found: BTreeMap<&str, Column> = BTreeMap::new();
        for part in s.split(',') {
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| format!("`{part}`: write KEY=COLUMN, e.g. x=2"))?;
            let key = key.trim();
            if !["name", "x", "y", "z"].contains(&key) {
                return Err(format!("`{key}`: the keys are name, x, y and z"));
            }
            let value = value.trim();
            let column = match value.parse::<usize>() {
                Ok(0) => return Err(format!("`{part}`: columns count from 1")),
                Ok(n) => Column::Position(n),
                Err(_) if !value.is_empty() => Column::Header(value.to_owned()),
                Err(_) => return Err(format!("`{part}`: no column given")),
            };
            if found.insert(key, column).is_some() {
                return Err(format!("`{key}` is mapped twice"));
            }
        }
        let mut take = |k: &str| {
            found
                .remove(k)
                .ok_or_else(|| format!("`{k}` is not mapped: give name, x, y and z"))
        };
        Ok(ColumnMap {
            name: take("name")?,
            x: take("x")?,
            y: take("y")?,
            z: take("z")?,
        })
    }
}

/// One exported point.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedPoint {
    /// The point's name, as exported.
    pub name: String,
    /// mm, in the tracker's (or the frame it was told to report in) coordinates.
    pub xyz: [f64; 3],
    /// 1-based line in the file.
    pub line: u64,
}

/// The points of an export and how it was read.
#[derive(Clone, Debug, PartialEq)]
pub struct PointExport {
    /// The points, in file order.
    pub points: Vec<NamedPoint>,
    /// How the file was read (separator, decimal commas, header, columns), for the user to
    /// check.
    pub notes: Vec<String>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Separator {
    Char(u8),
    Whitespace,
}

impl Separator {
    fn describe(self) -> &'static str {
        match self {
            Separator::Char(b';') => "`;`",
            Separator::Char(b'\t') => "tabs",
            Separator::Char(_) => "`,`",
            Separator::Whitespace => "spaces",
        }
    }
}

/// Fields of `line` with their byte offsets in it.
fn split(line: &str, sep: Separator) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    match sep {
        Separator::Char(c) => {
            let mut start = 0;
            for part in line.split(char::from(c)) {
                let lead = part.len() - part.trim_start().len();
                out.push((start + lead, part.trim()));
                start += part.len() + 1;
            }
        }
        Separator::Whitespace => {
            let mut start = None;
            for (i, ch) in line.char_indices() {
                match (ch.is_whitespace(), start) {
                    (false, None) => start = Some(i),
                    (true, Some(s)) => {
                        out.push((s, &line[s..i]));
                        start = None;
                    }
                    _ => {}
                }
            }
            if let Some(s) = start {
                out.push((s, &line[s..]));
            }
        }
    }
    out
}

fn detect_separator(line: &str) -> Separator {
    if line.contains(';') {
        Separator::Char(b';')
    } else if line.contains('\t') {
        Separator::Char(b'\t')
    } else if line.contains(',') && !line.trim().contains(' ') {
        Separator::Char(b',')
    } else {
        Separator::Whitespace
    }
}

fn number(field: &str, decimal_comma: bool) -> Option<f64> {
    let v = if decimal_comma && field.contains(',') && !field.contains('.') {
        field.replacen(',', ".", 1).parse::<f64>().ok()?
    } else {
        field.parse::<f64>().ok()?
    };
    v.is_finite().then_some(v)
}

/// Reads an export file.
pub fn read_point_export(path: &Path, map: Option<&ColumnMap>) -> Result<PointExport, TrackError> {
    let bytes = crate::output::read_input(path).map_err(|error| TrackError::Io {
        path: path.to_path_buf(),
        error,
    })?;
    parse_point_export(path, &bytes, map)
}

/// Parses export bytes; `path` is for messages only.
pub fn parse_point_export(
    path: &Path,
    bytes: &[u8],
    map: Option<&ColumnMap>,
) -> Result<PointExport, TrackError> {
    let source: Arc<[u8]> = Arc::from(bytes);
    let index = LineIndex::new(bytes);
    let at = |line: usize, col: usize, len: usize| {
        let start = index.line_span(bytes, line).start + col;
        Span::new(start, start + len)
    };
    let err = |span: Span, message: String, hint: &str| -> TrackError {
        // Read only once it is known to be UTF-8 (below): its excerpts decode so.
        LocatedError::new(path, source.clone(), span, message, hint)
            .in_utf8()
            .into()
    };
    let Ok(text) = std::str::from_utf8(bytes) else {
        let text = String::from_utf8_lossy(bytes);
        let line = text
            .lines()
            .position(|l| l.contains('\u{fffd}'))
            .unwrap_or(0)
            + 1;
        return Err(LocatedError::new(
            path,
            source.clone(),
            at(line, 0, 0),
            "not a text export: the file is not UTF-8 text",
            "export the points as text (CSV or TXT)",
        )
        .without_quote()
        .into());
    };
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_start_matches('\u{feff}')))
        .filter(|(_, l)| {
            let t = l.trim();
            !t.is_empty() && !t.starts_with('#') && !t.starts_with("//")
        })
        .collect();
    let Some(&(first_line, first)) = lines.first() else {
        return Err(err(
            Span::default(),
            "no points: the file has no data lines".to_owned(),
            "export at least one point (name x y z)",
        ));
    };
    let sep = detect_separator(first);
    let decimal_comma = sep != Separator::Char(b',');
    // A header is a first line whose x, y, z fields (wherever they are) are not all numbers.
    let first_fields = split(first, sep);
    let numeric = first_fields
        .iter()
        .filter(|(_, f)| number(f, decimal_comma).is_some())
        .count();
    let has_header = numeric < 3;
    let headers: Vec<String> = if has_header {
        first_fields.iter().map(|(_, f)| f.to_lowercase()).collect()
    } else {
        Vec::new()
    };
    let resolve = |column: &Column, what: &str| -> Result<usize, TrackError> {
        match column {
            Column::Position(n) => Ok(n - 1),
            Column::Header(h) => headers
                .iter()
                .position(|x| *x == h.to_lowercase())
                .ok_or_else(|| {
                    err(
                        at(first_line, 0, first.len()),
                        format!("no column `{h}` for {what} in the header"),
                        &format!("the header's columns are `{}`", headers.join("`, `")),
                    )
                }),
        }
    };
    let guess = |names: &[&str], fallback: usize| {
        headers
            .iter()
            .position(|h| names.contains(&h.as_str()))
            .unwrap_or(fallback)
    };
    let known = |h: &String| {
        [
            "name",
            "point",
            "id",
            "punkt",
            "point name",
            "pointname",
            "x",
            "y",
            "z",
        ]
        .contains(&h.as_str())
    };
    // A file with a header naming nothing known, read without a map, may be anything: until one
    // point is read, its lines are not quoted.
    let claims_export = !has_header || map.is_some() || headers.iter().any(known);
    let cols = match map {
        Some(m) => [
            resolve(&m.name, "the name")?,
            resolve(&m.x, "x")?,
            resolve(&m.y, "y")?,
            resolve(&m.z, "z")?,
        ],
        None => [
            guess(
                &["name", "point", "id", "punkt", "point name", "pointname"],
                0,
            ),
            guess(&["x", "x [mm]", "x/mm"], 1),
            guess(&["y", "y [mm]", "y/mm"], 2),
            guess(&["z", "z [mm]", "z/mm"], 3),
        ],
    };
    let mut points = Vec::new();
    let mut seen: BTreeMap<String, u64> = BTreeMap::new();
    let mut saw_decimal_comma = false;
    for &(line, l) in lines.iter().skip(usize::from(has_header)) {
        let quote = claims_export || !points.is_empty();
        let err = |span: Span, message: String, hint: &str| -> TrackError {
            let e = LocatedError::new(path, source.clone(), span, message, hint).in_utf8();
            if quote { e } else { e.without_quote() }.into()
        };
        let fields = split(l, sep);
        let field = |i: usize| fields.get(i).copied();
        let Some((name_at, name)) = field(cols[0]) else {
            return Err(err(
                at(line, 0, l.len()),
                format!(
                    "{} field(s), the name is in column {}",
                    fields.len(),
                    cols[0] + 1
                ),
                "write one point per line: name x y z",
            ));
        };
        let mut xyz = [0.0; 3];
        for (k, (slot, axis)) in xyz.iter_mut().zip(["x", "y", "z"]).enumerate() {
            let Some((offset, f)) = field(cols[k + 1]) else {
                return Err(err(
                    at(line, 0, l.len()),
                    format!(
                        "{} field(s), {axis} is in column {}",
                        fields.len(),
                        cols[k + 1] + 1
                    ),
                    "write one point per line: name x y z (or give the columns)",
                ));
            };
            *slot = number(f, decimal_comma).ok_or_else(|| {
                err(
                    at(line, offset, f.len()),
                    format!("`{f}` ({axis} of point `{name}`) is not a number"),
                    "write the coordinate as a number in mm",
                )
            })?;
            saw_decimal_comma |= decimal_comma && f.contains(',');
        }
        if name.is_empty() {
            return Err(err(
                at(line, name_at, 0),
                "a point without a name".to_owned(),
                "name every point",
            ));
        }
        if let Some(before) = seen.insert(name.to_owned(), line as u64) {
            return Err(err(
                at(line, name_at, name.len()),
                format!("point `{name}` was already exported on line {before}"),
                "keep one line per point (remove or rename the repeated measurement)",
            ));
        }
        points.push(NamedPoint {
            name: name.to_owned(),
            xyz,
            line: line as u64,
        });
    }
    if points.is_empty() {
        return Err(err(
            at(first_line, 0, first.len()),
            "no points: the file has a header but no data lines".to_owned(),
            "export at least one point (name x y z)",
        ));
    }
    let notes = vec![format!(
        "{}: {} point(s), fields separated by {}{}, {}; name, x, y, z in columns {}, {}, {}, {}",
        path.display(),
        points.len(),
        sep.describe(),
        if saw_decimal_comma {
            " with `,` as the decimal point"
        } else {
            ""
        },
        if has_header {
            "a header line"
        } else {
            "no header line"
        },
        cols[0] + 1,
        cols[1] + 1,
        cols[2] + 1,
        cols[3] + 1
    )];
    Ok(PointExport { points, notes })
}

/// `point,x,y,z` CSV of the points (mm with 4 decimals; names quoted when they need it).
pub fn points_csv(points: &[NamedPoint]) -> String {
    let mut out = String::from("point,x,y,z\n");
    for p in points {
        let name = if p.name.contains([',', '"', '\n']) {
            format!("\"{}\"", p.name.replace('"', "\"\""))
        } else {
            p.name.clone()
        };
        out.push_str(&format!(
            "{name},{:.4},{:.4},{:.4}\n",
            p.xyz[0], p.xyz[1], p.xyz[2]
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, map: Option<&str>) -> Result<PointExport, TrackError> {
        let map: Option<ColumnMap> = map.map(|m| m.parse().unwrap());
        parse_point_export(Path::new("e.txt"), text.as_bytes(), map.as_ref())
    }

    fn names_and_x(e: &PointExport) -> Vec<(String, f64)> {
        e.points
            .iter()
            .map(|p| (p.name.clone(), p.xyz[0]))
            .collect()
    }

    #[test]
    fn the_usual_exports_give_the_same_points() {
        let want = vec![("P1".to_owned(), 1234.5), ("P2".to_owned(), -10.25)];
        for text in [
            "P1 1234.5 20 30\nP2 -10.25 0 1\n",
            "P1\t1234.5\t20\t30\nP2\t-10.25\t0\t1\n",
            "Name;X;Y;Z\nP1;1234,5;20;30\nP2;-10,25;0;1\n",
            "# exported\npoint,x,y,z\nP1,1234.5,20,30\nP2,-10.25,0,1\n",
            "  P1   1234,5   20   30\r\n  P2  -10,25  0  1\r\n",
        ] {
            let e = read(text, None).unwrap();
            assert_eq!(names_and_x(&e), want, "{text:?}");
            assert_eq!(e.points[1].xyz, [-10.25, 0.0, 1.0]);
        }
        let e = read("Name;X;Y;Z\nP1;1234,5;20;30\nP2;-10,25;0;1\n", None).unwrap();
        assert_eq!(
            e.notes,
            [
                "e.txt: 2 point(s), fields separated by `;` with `,` as the decimal point, a header line; name, x, y, z in columns 1, 2, 3, 4"
            ]
        );
    }

    #[test]
    fn map_picks_columns_by_position_or_header() {
        let text = "Nr;Punkt;Zeit;Ost;Nord;Hoehe\n1;A;12:00;1,5;2,5;3,5\n";
        let e = read(text, Some("name=Punkt,x=Ost,y=Nord,z=Hoehe")).unwrap();
        assert_eq!(e.points[0].name, "A");
        assert_eq!(e.points[0].xyz, [1.5, 2.5, 3.5]);
        let e = read("1 A 1.5 2.5 3.5\n", Some("name=2,x=3,y=4,z=5")).unwrap();
        assert_eq!(e.points[0].xyz, [1.5, 2.5, 3.5]);
        assert!("name=1,x=2,y=3".parse::<ColumnMap>().is_err());
        assert!("name=0,x=2,y=3,z=4".parse::<ColumnMap>().is_err());
        let e = read(text, Some("name=Punkt,x=East,y=Nord,z=Hoehe")).unwrap_err();
        assert!(e.to_string().contains("no column `East` for x"), "{e}");
    }

    #[test]
    fn errors_are_located() {
        let e = read("P1 1 2 3\nP2 1 x2 3\n", None).unwrap_err();
        let l = e.located().unwrap();
        assert_eq!(l.line_col(), (2, 6));
        assert!(l.message().contains("`x2` (y of point `P2`)"), "{e}");
        let passwd =
            "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n";
        let e = read(passwd, None).unwrap_err().to_string();
        assert!(!e.contains("daemon") && !e.contains("root:"), "{e}");
        let e = read("P1 1 2 3\nP1 1 2 3\n", None).unwrap_err();
        assert!(e.to_string().contains("already exported on line 1"), "{e}");
        let e = read("P1 1 2 3\nP2 1 2\n", None).unwrap_err();
        assert!(
            e.to_string().contains("3 field(s), z is in column 4"),
            "{e}"
        );
    }
}
