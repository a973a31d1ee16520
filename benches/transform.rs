//! Benchmark (divan). Run: `cargo bench --bench transform`.

fn main() {
    divan::main();
}
