//! Tiny stand-ins for the language parsers, so the transforms' math and rewriting are tested
//! through text on their own: one target per line, every number in a fixed order.
//!
//! RAPID line: `[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[ea,eb,ec,ed,ee,ef]]`
//! KRL line:   `{X x,Y y,Z z,A a,B b,C c,S s,T t,E1 e1}`

use std::path::PathBuf;

use crate::position::{
    BitField, CartesianFields, Config, Language, NumField, Orientation, ParsedFile, Position,
    PositionKind, PositionList, Program, Usage,
};
use crate::syntax::{LineIndex, NumLit, Span};

fn numbers(src: &[u8], from: usize, to: usize) -> Vec<NumField> {
    let mut out = Vec::new();
    let mut i = from;
    while i < to {
        let c = src[i];
        let starts = c.is_ascii_digit()
            || c == b'.'
            || ((c == b'-' || c == b'+')
                && src
                    .get(i + 1)
                    .is_some_and(|n| n.is_ascii_digit() || *n == b'.'));
        if !starts {
            i += 1;
            continue;
        }
        let s = i;
        i += 1;
        while i < to {
            let c = src[i];
            let exp_sign = (c == b'-' || c == b'+') && matches!(src[i - 1], b'e' | b'E');
            if c.is_ascii_digit() || c == b'.' || c == b'e' || c == b'E' || exp_sign {
                i += 1;
            } else {
                break;
            }
        }
        if let Some(lit) = NumLit::parse(&src[s..i]) {
            out.extend(NumField::new(Span::new(s, i), lit));
        }
    }
    out
}

fn line_spans(src: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for (i, &b) in src.iter().enumerate() {
        if b == b'\n' {
            out.push((s, i));
            s = i + 1;
        }
    }
    if s < src.len() {
        out.push((s, src.len()));
    }
    out
}

fn usage(wobj: &str, line: usize) -> Usage {
    let mut u = Usage::default();
    u.record(Some(wobj), Some("tool0"), false, line);
    u
}

fn file(path: &str, language: Language, source: Vec<u8>, positions: Vec<Position>) -> Program {
    Program {
        files: vec![ParsedFile {
            path: PathBuf::from(path),
            language,
            lines: LineIndex::new(&source),
            positions: PositionList::packed(positions, &source),
            source: source.into(),
            frames: Vec::new(),
            frame_values: Vec::new(),
            offsets: Vec::new(),
            opaque: 0,
            diagnostics: Vec::new(),
            round_trip: true,
        }],
    }
}

/// RAPID robtargets, one per line, all used with `wobj`.
pub(crate) fn rapid(src: &str, wobj: &str) -> Program {
    let bytes = src.as_bytes().to_vec();
    let mut positions = Vec::new();
    for (n, (s, e)) in line_spans(&bytes).into_iter().enumerate() {
        let v = numbers(&bytes, s, e);
        if v.len() < 17 {
            continue;
        }
        let o = |i: usize| Some(v[i]);
        positions.push(Position {
            name: Some(format!("p{}", n + 1).into()),
            kind: PositionKind::Robtarget,
            span: Span::new(s, e),
            line: n + 1,
            column: 1,
            cartesian: Some(CartesianFields {
                trans: [o(0), o(1), o(2)],
                orient: Some(Orientation::Quaternion([o(3), o(4), o(5), o(6)])),
            }),
            joints: Vec::new(),
            config: Config::Quadrants([o(7), o(8), o(9), o(10)]),
            extax: (11..17).map(o).collect(),
            usage: usage(wobj, n + 1),
        });
    }
    file("t.mod", Language::Rapid, bytes, positions)
}

/// KRL E6POS, one per line, all used with `base`.
pub(crate) fn krl(src: &str, base: &str) -> Program {
    let bytes = src.as_bytes().to_vec();
    let mut positions = Vec::new();
    for (n, (s, e)) in line_spans(&bytes).into_iter().enumerate() {
        let v = numbers(&bytes, s, e);
        if v.len() < 9 {
            continue;
        }
        let o = |i: usize| Some(v[i]);
        let bits = |i: usize| BitField::new(v[i].span(), v[i].value() as u32, None);
        positions.push(Position {
            name: Some(format!("XP{}", n + 1).into()),
            kind: PositionKind::E6Pos,
            span: Span::new(s, e),
            line: n + 1,
            column: 1,
            cartesian: Some(CartesianFields {
                trans: [o(0), o(1), o(2)],
                orient: Some(Orientation::Abc([o(3), o(4), o(5)])),
            }),
            joints: Vec::new(),
            config: Config::StatusTurn {
                status: bits(6),
                turn: bits(7),
            },
            extax: vec![o(8)].into(),
            usage: usage(base, n + 1),
        });
    }
    file("t.src", Language::Krl, bytes, positions)
}
