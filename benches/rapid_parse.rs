//! Benchmark (divan). Run: `cargo bench --bench rapid_parse`.
//!
//! Parse+print and position extraction on generated modules of 1, 10 and 50 MB (the 50 MB one
//! holds ~200,000 robtargets), generated in memory, and extraction on modules of 1,000 to
//! 10,000 routines that call each other (each call's routine is looked up by name). Throughput is reported in bytes per second;
//! the allocation profiler reports the bytes allocated per run (an upper bound on the peak
//! memory added to the source itself).

use divan::{AllocProfiler, Bencher, black_box, counter::BytesCount};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

#[path = "support/rapid_module.rs"]
mod rapid_module;
use rapid_module::module;

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

/// `parse_file` of `src` as the file `path`, which round-trips and holds `positions` targets
/// (any number for `None`).
fn extracted(bencher: Bencher, src: Vec<u8>, path: &str, positions: Option<usize>) {
    bencher
        .counter(BytesCount::new(src.len()))
        .with_inputs(|| src.clone())
        .bench_values(|s| {
            let f = trackfix::rapid::parse_file(std::path::Path::new(path), s);
            assert!(f.round_trip && positions.is_none_or(|n| f.positions.len() == n));
            black_box(f.positions.len())
        });
}

#[divan::bench(args = [1, 10, 50], sample_count = 3, sample_size = 1)]
fn positions(bencher: Bencher, mb: usize) {
    extracted(bencher, module(mb), "bench.mod", None);
}

/// A module of `routines` routines, each calling eight others and moving to one target.
fn calling_module(routines: usize) -> Vec<u8> {
    let mut out = String::from(
        "MODULE Calls\r\n  CONST robtarget p0:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\r\n",
    );
    for r in 0..routines {
        out.push_str(&format!("  PROC r{r}()\r\n"));
        for k in 0..8 {
            out.push_str(&format!("    r{};\r\n", (r * 7 + k) % routines));
        }
        out.push_str("    MoveL p0, v1000, z10, tool0;\r\n  ENDPROC\r\n");
    }
    out.push_str("ENDMODULE\r\n");
    out.into_bytes()
}

/// Linear in the routines: finding each call's routine by scanning every routine was
/// quadratic (3,000 routines: 0.23 s for a 0.46 MB module, 4 G instructions).
#[divan::bench(args = [1000, 3000, 10000], sample_count = 3, sample_size = 1)]
fn routines_calling_each_other(bencher: Bencher, routines: usize) {
    extracted(bencher, calling_module(routines), "calls.mod", Some(1));
}
