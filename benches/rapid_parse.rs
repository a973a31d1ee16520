//! Benchmark (divan). Run: `cargo bench --bench rapid_parse`.
//!
//! Parse+print and position extraction on generated modules of 1, 10 and 50 MB (the 50 MB one
//! holds ~200,000 robtargets), generated in memory. Throughput is reported in bytes per second;
//! the allocation profiler reports the bytes allocated per run (an upper bound on the peak
//! memory added to the source itself).

use divan::{AllocProfiler, Bencher, black_box, counter::BytesCount};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

/// A RobotStudio-style module of about `mb` megabytes: robtarget declarations along an 8 m
/// track, then a routine that visits them with `MoveL`, `Offs` and comments, CRLF line ends.
fn module(mb: usize) -> Vec<u8> {
    use std::fmt::Write as _;
    let target = mb * 1_000_000;
    let mut decls = String::with_capacity(target / 2 + 1024);
    let mut moves = String::with_capacity(target / 2 + 1024);
    decls.push_str("%%%\r\n  VERSION:1\r\n  LANGUAGE:ENGLISH\r\n%%%\r\n\r\nMODULE Bench\r\n");
    decls.push_str("  PERS tooldata tGun:=[TRUE,[[12.5,-3.2,412.8],[0.965926,0,0.258819,0]],[48.5,[0,0,180],[1,0,0,0],0.9,1.1,0.6]];\r\n");
    decls.push_str("  TASK PERS wobjdata wCar:=[FALSE,TRUE,\"\",[[1520.3,-1850.75,612.4],[1,0,0,0]],[[150,0,0],[1,0,0,0]]];\r\n");
    moves.push_str("  PROC main()\r\n");
    let mut i = 0usize;
    while decls.len() + moves.len() < target {
        let s = 150.0 + (i % 7700) as f64;
        let x = s - 1670.3 + (i % 37) as f64 * 0.37;
        let _ = write!(
            decls,
            "  CONST robtarget p{i}:=[[{x:.2},-{:.2},{:.2}],[0.000000,0.707107,0.707107,0.000000],[0,0,-1,0],[{s:.1},9E+09,9E+09,9E+09,9E+09,9E+09]];\r\n",
            700.0 + (i % 13) as f64,
            250.0 + (i % 29) as f64 * 12.5
        );
        if i.is_multiple_of(10) {
            let _ = write!(moves, "    ! group {}\r\n", i / 10);
            let _ = write!(
                moves,
                "    MoveL Offs(p{i},0,0,100), v1000, z10, tGun\\WObj:=wCar;\r\n"
            );
        }
        let _ = write!(moves, "    MoveL p{i}, v1000, z10, tGun\\WObj:=wCar;\r\n");
        i += 1;
    }
    moves.push_str("  ENDPROC\r\nENDMODULE");
    decls.push_str(&moves);
    decls.into_bytes()
}

#[divan::bench(args = [1, 10, 50], sample_count = 5, sample_size = 1)]
fn parse_and_print(bencher: Bencher, mb: usize) {
    let src = module(mb);
    bencher.counter(BytesCount::new(src.len())).bench(|| {
        let parse = trackfix::rapid::parse_tree(black_box(&src));
        let mut sink = std::io::sink();
        let _ = parse.tree.write_to(&src, &mut sink);
        black_box(parse.tree.nodes.len())
    });
}

#[divan::bench(args = [1, 10, 50], sample_count = 3, sample_size = 1)]
fn positions(bencher: Bencher, mb: usize) {
    let src = module(mb);
    bencher
        .counter(BytesCount::new(src.len()))
        .with_inputs(|| src.clone())
        .bench_values(|s| {
            let f = trackfix::rapid::parse_file(std::path::Path::new("bench.mod"), s);
            assert!(f.round_trip);
            black_box(f.positions.len())
        });
}
