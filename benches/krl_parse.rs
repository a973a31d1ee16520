//! Benchmark (divan). Run: `cargo bench --bench krl_parse`.

fn main() {
    divan::main();
}
