//! Benchmark (divan). Run: `cargo bench --bench rapid_parse`.

fn main() {
    divan::main();
}
