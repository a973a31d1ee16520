//! Byte-level fast path for the common `.dat` line `DECL TYPE NAME={FIELD value, …}` (an
//! `E6POS`, `FDAT`, `LDAT` … with literal fields): read straight from the bytes, without tokens
//! or the precedence descent. It builds exactly the statement the general path builds for such a
//! line and gives up (`None`) on anything else, so the general path decides every unusual line,
//! its diagnostics included. `tests` below compare both paths on generated, mutated and sample
//! lines.

use super::lexer::{IDENT, is_ident_start, number_end};
use super::tree::{Aggregate, DeclVar, Expr, ExprKind, Field, StmtKind};
use crate::syntax::Span;

/// A declaration line read by the fast path.
pub(super) struct DeclLine {
    pub kind: StmtKind,
    /// `DECL` to the closing `}`.
    pub span: Span,
    /// Past the line's newline (or the end of the source).
    pub end: usize,
    pub had_newline: bool,
}

/// Only plain blanks: other bytes the lexer counts as whitespace are left to the general path.
#[inline(always)]
fn blanks(src: &[u8], mut i: usize) -> usize {
    while matches!(src.get(i), Some(b' ' | b'\t')) {
        i += 1;
    }
    i
}

#[inline(always)]
fn ident(src: &[u8], i: usize) -> Option<usize> {
    if !is_ident_start(*src.get(i)?) {
        return None;
    }
    let mut j = i + 1;
    while src.get(j).is_some_and(|&b| IDENT[b as usize]) {
        j += 1;
    }
    Some(j)
}

/// Words after `DECL` that the general path treats other than as a type.
fn reserved_after_decl(word: &[u8]) -> bool {
    ["GLOBAL", "CONST", "INTERRUPT", "STRUC", "ENUM", "SIGNAL"]
        .iter()
        .any(|k| word.eq_ignore_ascii_case(k.as_bytes()))
}

/// A lone literal or name (what `Cursor::simple_value` accepts) starting at `i`.
#[inline(always)]
fn value(src: &[u8], i: usize) -> Option<(ExprKind, usize)> {
    let b = *src.get(i)?;
    let starts_number = |j: usize| match src.get(j) {
        Some(c) if c.is_ascii_digit() => true,
        Some(b'.') => src.get(j + 1).is_some_and(u8::is_ascii_digit),
        _ => false,
    };
    match b {
        b'-' | b'+' if starts_number(i + 1) => Some((ExprKind::Number, number_end(src, i + 1))),
        _ if starts_number(i) => Some((ExprKind::Number, number_end(src, i))),
        b'"' | b'\'' => {
            let mut j = i + 1;
            loop {
                match *src.get(j)? {
                    c if c == b => break,
                    b'\n' | b'\r' => return None,
                    _ => j += 1,
                }
            }
            let kind = if b == b'"' {
                ExprKind::Str
            } else {
                ExprKind::Quoted
            };
            Some((kind, j + 1))
        }
        b'#' => {
            let j = ident(src, i + 1)?;
            Some((ExprKind::Enum, j))
        }
        _ => {
            let j = ident(src, i)?;
            let word = src.get(i..j)?;
            if word.eq_ignore_ascii_case(b"NOT") || word.eq_ignore_ascii_case(b"B_NOT") {
                return None;
            }
            Some((ExprKind::Name, j))
        }
    }
}

/// Reads the line starting at `start` if it has the common shape; `fields` is scratch space
/// reused across lines so that each aggregate allocates once, at its exact size.
// Out of line: when the build inlined it into the parser's line loop, `check` of the 3 MB pair
// ran 0.7 M instructions more (147.67 M against 146.93 M).
#[inline(never)]
pub(super) fn decl_line(src: &[u8], start: usize, fields: &mut Vec<Field>) -> Option<DeclLine> {
    fields.clear();
    let decl_at = blanks(src, start);
    let i = ident(src, decl_at)?;
    if !src.get(decl_at..i)?.eq_ignore_ascii_case(b"DECL") {
        return None;
    }
    let type_at = blanks(src, i);
    let type_end = ident(src, type_at)?;
    if reserved_after_decl(src.get(type_at..type_end)?) {
        return None;
    }
    let name_at = blanks(src, type_end);
    let name_end = ident(src, name_at)?;
    let mut i = blanks(src, name_end);
    if src.get(i) != Some(&b'=') || src.get(i + 1) == Some(&b'=') {
        return None;
    }
    let open = blanks(src, i + 1);
    if src.get(open) != Some(&b'{') {
        return None;
    }
    i = open + 1;
    let close = loop {
        let field_at = blanks(src, i);
        let field_end = ident(src, field_at)?;
        i = blanks(src, field_end);
        // Char-array fields: `POINT2[] " "`.
        if src.get(i) == Some(&b'[') {
            i = blanks(src, i + 1);
            if src.get(i) != Some(&b']') {
                return None;
            }
            i = blanks(src, i + 1);
        }
        let (kind, value_end) = value(src, i)?;
        fields.push(Field {
            name: Span::new(field_at, field_end),
            value: Expr {
                span: Span::new(i, value_end),
                kind,
            },
        });
        i = blanks(src, value_end);
        match src.get(i) {
            Some(b',') => i += 1,
            Some(b'}') => break i,
            _ => return None,
        }
    };
    let mut i = blanks(src, close + 1);
    if src.get(i) == Some(&b';') {
        while src.get(i).is_some_and(|&b| b != b'\n' && b != b'\r') {
            i += 1;
        }
    }
    let (end, had_newline) = match src.get(i) {
        None => (i, false),
        Some(b'\n') => (i + 1, true),
        Some(b'\r') => (i + if src.get(i + 1) == Some(&b'\n') { 2 } else { 1 }, true),
        Some(_) => return None,
    };
    // Exactly sized: a kept `krl::parse` of a 50 MB `.dat` holds 400 000 of these.
    let mut exact = Vec::with_capacity(fields.len());
    exact.append(fields);
    let init = Expr {
        span: Span::new(open, close + 1),
        kind: ExprKind::Aggregate(Aggregate {
            type_name: None,
            fields: exact,
        }),
    };
    Some(DeclLine {
        kind: StmtKind::Decl {
            type_name: Span::new(type_at, type_end),
            vars: vec![DeclVar {
                name: Span::new(name_at, name_end),
                dims: Vec::new(),
                init: Some(init),
            }],
            // `DECL GLOBAL` is left to the general path (`reserved_after_decl`).
            global: false,
        },
        span: Span::new(decl_at, close + 1),
        end,
        had_newline,
    })
}

#[cfg(test)]
mod tests {
    use super::super::parser::parse_lines;
    use super::*;
    use proptest::prelude::*;

    fn kept() -> crate::syntax::TreeBuilder<crate::krl::tree::Krl> {
        crate::syntax::TreeBuilder::with_capacity(8)
    }

    /// Both paths over `src`: the tree's nodes, statements, diagnostics and opaque count agree.
    fn same_as_general(src: &[u8]) {
        let mut fast_stmts = Vec::new();
        let fast = parse_lines(src, &mut |s| fast_stmts.push(s), true, kept());
        let mut slow_stmts = Vec::new();
        let slow = parse_lines(src, &mut |s| slow_stmts.push(s), false, kept());
        let shown = String::from_utf8_lossy(src);
        assert_eq!(fast.tree.nodes, slow.tree.nodes, "nodes of {shown:?}");
        assert_eq!(fast_stmts, slow_stmts, "statements of {shown:?}");
        assert_eq!(
            fast.diagnostics, slow.diagnostics,
            "diagnostics of {shown:?}"
        );
        assert_eq!(fast.opaque, slow.opaque, "opaque count of {shown:?}");
        assert_eq!(fast.tree.print(src), src);
        assert!(
            fast.round_trip && slow.round_trip,
            "round trip of {shown:?}"
        );
    }

    #[test]
    fn the_benchmark_lines_take_the_fast_path() {
        let lines: [&[u8]; 4] = [
            b"DECL E6POS XP1={X 1200.250,Y -799.000,Z 1020.500,A -178.2500,B 12.5000,C 179.4000,S 6,T 50,E1 101.000,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}\r\n",
            b"DECL FDAT FP1={TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE,POINT2[] \" \",TQ_STATE FALSE}\r\n",
            b"  decl LDAT LCPDAT1 = { VEL 2.0, ACC 100.0 ,ORI_TYP #VAR } ; note\n",
            b"DECL POS P={S 'B010',T +.5E+2}",
        ];
        let mut fields = Vec::new();
        for line in lines {
            let read = decl_line(line, 0, &mut fields);
            assert!(read.is_some(), "{}", String::from_utf8_lossy(line));
            assert_eq!(read.map(|l| l.end), Some(line.len()));
            same_as_general(line);
        }
        let StmtKind::Decl { vars, .. } =
            decl_line(lines[0], 0, &mut fields).map(|l| l.kind).unwrap()
        else {
            panic!("not a declaration")
        };
        let Some(Expr {
            kind: ExprKind::Aggregate(agg),
            ..
        }) = &vars[0].init
        else {
            panic!("no aggregate")
        };
        assert_eq!(agg.fields.len(), 14);
        assert_eq!(agg.fields[1].value.span.slice(lines[0]), b"-799.000");
    }

    #[test]
    fn unusual_lines_are_left_to_the_general_path() {
        let lines: [&[u8]; 12] = [
            b"DECL GLOBAL E6POS XP1={X 1}\n",
            b"DECL E6POS XP1[2]={X 1}\n",
            b"DECL E6POS XP1={X - 1}\n",
            b"DECL E6POS XP1={X NOT A}\n",
            b"DECL E6POS XP1={E6POS: X 1}\n",
            b"DECL E6POS XP1={X 1,}\n",
            b"DECL E6POS XP1={X 1}, XP2\n",
            b"DECL E6POS XP1=={X 1}\n",
            b"DECL E6POS XP1={X \"open}\n",
            b"DECL E6POS XP1={X 1\x0C}\n",
            b"DECL E6POS XP\xE41={X 1}\n",
            b"E6POS XP1={X 1}\n",
        ];
        let mut fields = Vec::new();
        for line in lines {
            assert!(
                decl_line(line, 0, &mut fields).is_none(),
                "{}",
                String::from_utf8_lossy(line)
            );
            same_as_general(line);
        }
    }

    #[test]
    fn samples_and_fuzz_regressions_parse_the_same_both_ways() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut seen = 0;
        for dir in ["samples/krl", "tests/fuzz_regressions/krl"] {
            let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
                continue;
            };
            for entry in entries.flatten() {
                if let Ok(bytes) = std::fs::read(entry.path()) {
                    same_as_general(&bytes);
                    seen += 1;
                }
            }
        }
        assert!(seen >= 12, "only {seen} files found");
        // Real programs, when given (not committed): see `krl::real_corpus`.
        if let Some(dir) = std::env::var_os("TRACKFIX_KRL_CORPUS") {
            for entry in walkdir::WalkDir::new(dir).into_iter().flatten() {
                if entry.file_type().is_file()
                    && let Ok(bytes) = std::fs::read(entry.path())
                {
                    same_as_general(&bytes);
                }
            }
        }
    }

    fn line() -> impl Strategy<Value = Vec<u8>> {
        let blank = prop::sample::select(vec!["", " ", "\t", "  "]);
        let head = prop::sample::select(vec![
            "DECL",
            "decl",
            "Decl",
            "DECL GLOBAL",
            "GLOBAL DECL",
            "DECL CONST",
            "",
            "DECLX",
        ]);
        let ty = prop::sample::select(vec![
            "E6POS",
            "FDAT",
            "LDAT",
            "POS",
            "INTERRUPT",
            "STRUC",
            "signal",
            "E6AXIS",
            "1X",
        ]);
        let name = prop::sample::select(vec!["XP1", "FP2", "x", "$V", "XP1[2]", "A B", ""]);
        let eq = prop::sample::select(vec!["=", " = ", "==", "", "=\t"]);
        let field_name =
            prop::sample::select(vec!["X", "E1", "POINT2[]", "POINT2[ ]", "NOT", "", "TYPE:"]);
        let value = prop::sample::select(vec![
            "1", "-1.5", "+.5", "- 3", "1.0E+02", "1e", "5.", "TRUE", "not", "B_NOT 1", "#BASE",
            "#", "\" \"", "'B010'", "\"open", "F(1)", "1:2", "", "A.B", "1X", "-X",
        ]);
        let field = (
            blank.clone(),
            field_name,
            blank.clone(),
            value,
            blank.clone(),
        )
            .prop_map(|(a, n, b, v, c)| format!("{a}{n} {b}{v}{c}"));
        let fields = prop::collection::vec(field, 0..5);
        let tail = prop::sample::select(vec!["", " ", " ; c", ";{X 1}", ", XP2", " X", "}"]);
        let newline = prop::sample::select(vec!["\r\n", "\n", "\r", ""]);
        (
            (blank.clone(), head, blank.clone(), ty, blank, name, eq),
            (fields, tail, newline),
        )
            .prop_map(|((b1, h, b2, t, b3, n, e), (fs, tail, nl))| {
                format!("{b1}{h} {b2}{t} {b3}{n}{e}{{{}}}{tail}{nl}", fs.join(",")).into_bytes()
            })
    }

    /// Bytes that change how a line lexes.
    const MUTANTS: &[u8] = b" \t,{}=\"'-+;\r\n[]#.0E:(\x0C\xE4\x00";

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        #[test]
        fn generated_lines_parse_the_same_both_ways(
            lines in prop::collection::vec(line(), 1..6),
            wrap in any::<bool>(),
        ) {
            let mut src = Vec::new();
            if wrap {
                src.extend_from_slice(b"&ACCESS RVP\r\nDEFDAT d\r\nIF A THEN\r\n");
            }
            for l in &lines {
                src.extend_from_slice(l);
                if !l.ends_with(b"\n") && !l.ends_with(b"\r") {
                    src.extend_from_slice(b"\n");
                }
            }
            same_as_general(&src);
        }

        #[test]
        fn mutated_lines_parse_the_same_both_ways(
            l in line(),
            edits in prop::collection::vec((any::<prop::sample::Index>(), prop::sample::select(MUTANTS), 0..3u8), 1..4),
        ) {
            let mut src = l;
            for (at, byte, op) in edits {
                let i = at.index(src.len() + 1);
                match op {
                    0 => src.insert(i, byte),
                    1 if i < src.len() => src[i] = byte,
                    _ if i < src.len() => { src.remove(i); }
                    _ => src.push(byte),
                }
            }
            src.splice(0..0, b"DEFDAT d\n".iter().copied());
            same_as_general(&src);
        }
    }
}
