//! Benchmark (divan). Run: `cargo bench --bench krl_parse`.
//!
//! Generated inline-form programs of 1, 10 and 50 MB: a `.dat` of `E6POS`/`FDAT`/`LDAT`
//! declarations and a `.src` of `;FOLD LIN …` inline forms. Measures the lossless parse and
//! print (`print(parse(x))`) and the full `parse_file` (positions, base/tool resolution), also
//! of a `.src` whose motions write their targets inline (`PTP {X …}`), each one of the file's
//! own positions to bind.

use std::path::Path;
use std::sync::OnceLock;

use divan::{Bencher, black_box};

const MB: usize = 1 << 20;
const SIZES: &[usize] = &[1, 10, 50];

fn main() {
    divan::main();
}

/// `head`, then `line(1)`, `line(2)`, … until the text is `mb` MB long, then `tail`.
fn generated(mb: usize, head: &[u8], tail: &[u8], line: impl Fn(usize) -> String) -> Vec<u8> {
    let mut out = head.to_vec();
    let mut i = 0usize;
    while out.len() < mb * MB {
        i += 1;
        out.extend_from_slice(line(i).as_bytes());
    }
    out.extend_from_slice(tail);
    out
}

fn generated_dat(mb: usize) -> Vec<u8> {
    let head = b"&ACCESS RVP\r\n&REL 1\r\nDEFDAT bench PUBLIC\r\n";
    generated(mb, head, b"ENDDAT\r\n", |i| {
        let e1 = 100.0 + (i % 7800) as f64;
        format!(
            "DECL E6POS XP{i}={{X {:.3},Y {:.3},Z 1020.500,A -178.2500,B 12.5000,C 179.4000,S 6,T 50,E1 {e1:.3},E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}\r\n\
             DECL FDAT FP{i}={{TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE,POINT2[] \" \",TQ_STATE FALSE}}\r\n\
             DECL LDAT LCPDAT{i}={{VEL 2.0,ACC 100.0,APO_DIST 100.0,APO_FAC 50.0,ORI_TYP #VAR,CIRC_TYP #BASE}}\r\n",
            1200.0 + i as f64 * 0.25,
            -800.0 + (i % 100) as f64
        )
    })
}

fn generated_src(mb: usize) -> Vec<u8> {
    let head = b"&ACCESS RVP\r\n&REL 1\r\nDEF bench( )\r\n";
    generated(mb, head, b"END\r\n", |i| {
        format!(
            ";FOLD LIN P{i} CONT Vel=2 m/s CPDAT{i} Tool[1]:gun1 Base[1]:car;%{{PE}}%R 8.3.31,%MKUKATPBASIS,%CMOVE,%VLIN,%P 1:LIN, 2:P{i}, 3:C_DIS C_DIS, 5:2, 7:CPDAT{i}\r\n\
             $BWDSTART=FALSE\r\nLDAT_ACT=LCPDAT{i}\r\nFDAT_ACT=FP{i}\r\nBAS(#CP_PARAMS,2)\r\n\
             LIN XP{i} C_DIS C_DIS\r\n;ENDFOLD\r\n"
        )
    })
}

fn generated_inline_src(mb: usize) -> Vec<u8> {
    let head = b"&ACCESS RVP\r\n&REL 1\r\nDEF inline( )\r\nBAS(#INITMOV,0)\r\n";
    generated(mb, head, b"END\r\n", |i| {
        format!(
            "PTP {{X {:.1},Y -500.0,Z 800.0,A 0.0,B 90.0,C 0.0,S 6,T 50,E1 {:.1}}} C_PTP\r\n",
            1000.0 + i as f64 * 0.1,
            100.0 + (i % 7000) as f64
        )
    })
}

fn dat(mb: usize) -> &'static [u8] {
    static CACHE: [OnceLock<Vec<u8>>; 3] = [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    let slot = SIZES.iter().position(|&s| s == mb).unwrap_or(0);
    CACHE[slot].get_or_init(|| generated_dat(mb))
}

fn src(mb: usize) -> &'static [u8] {
    static CACHE: [OnceLock<Vec<u8>>; 3] = [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    let slot = SIZES.iter().position(|&s| s == mb).unwrap_or(0);
    CACHE[slot].get_or_init(|| generated_src(mb))
}

#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn dat_parse_and_print(bencher: Bencher, mb: usize) {
    let input = dat(mb);
    bencher
        .counter(divan::counter::BytesCount::new(input.len()))
        .bench(|| {
            let parse = trackfix::krl::parse(black_box(input));
            assert_eq!(parse.tree.print(input).len(), input.len());
        });
}

/// What `parse_file` runs: every statement parsed into its expression tree and handed on,
/// the tree keeping only lines.
#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn dat_parse_streamed_and_print(bencher: Bencher, mb: usize) {
    let input = dat(mb);
    bencher
        .counter(divan::counter::BytesCount::new(input.len()))
        .bench(|| {
            let parse =
                trackfix::krl::parse_with(black_box(input), &mut |s: trackfix::krl::Stmt| {
                    black_box(s);
                });
            assert_eq!(parse.tree.print(input).len(), input.len());
        });
}

#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn src_parse_and_print(bencher: Bencher, mb: usize) {
    let input = src(mb);
    bencher
        .counter(divan::counter::BytesCount::new(input.len()))
        .bench(|| {
            let parse = trackfix::krl::parse(black_box(input));
            assert_eq!(parse.tree.print(input).len(), input.len());
        });
}

/// `parse_file` of `input` as the file `path`, which round-trips (and, with `positions`,
/// holds positions).
fn positions_of(bencher: Bencher, input: &[u8], path: &str, positions: bool) {
    bencher
        .counter(divan::counter::BytesCount::new(input.len()))
        .with_inputs(|| input.to_vec())
        .bench_values(|bytes| {
            let file = trackfix::krl::parse_file(Path::new(path), bytes);
            assert!(file.round_trip && (!positions || !file.positions.is_empty()));
        });
}

#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn dat_positions(bencher: Bencher, mb: usize) {
    positions_of(bencher, dat(mb), "bench.dat", true);
}

#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn src_positions(bencher: Bencher, mb: usize) {
    positions_of(bencher, src(mb), "bench.src", false);
}

#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn dat_lex_only(bencher: Bencher, mb: usize) {
    let input = dat(mb);
    bencher
        .counter(divan::counter::BytesCount::new(input.len()))
        .bench(|| trackfix::krl::lex(black_box(input)).len());
}

/// Binding an inline target finds it among the file's positions by its span: linear in the
/// motions (a scan per motion was quadratic: 3.4 s for 20,000 motions in 1.5 MB).
#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn inline_src_positions(bencher: Bencher, mb: usize) {
    positions_of(bencher, &generated_inline_src(mb), "inline.src", true);
}
