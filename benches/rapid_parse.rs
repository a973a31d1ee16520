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
