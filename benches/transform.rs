//! Benchmark (divan). Run: `cargo bench --bench transform`.
//!
//! The transforms on the two spot-line samples (226 RAPID targets, 161 KRL targets), with the
//! sample cell and profiles: in-memory edits only (parsing is measured by the parser benches),
//! and the whole `transfer` chain, which re-reads the text between its three steps.

use std::path::{Path, PathBuf};

use trackfix::position::Program;
use trackfix::program::{LoadOptions, load};
use trackfix::track::Profile;
use trackfix::transform::{
    Cell, Direction, MirrorSettings, TrackSetup, TransferPlan, apply, mirror, track_correction,
    transfer,
};

fn main() {
    divan::main();
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

struct Fixture {
    cell: Cell,
    r1: Profile,
    r2: Profile,
    options: LoadOptions,
}

fn fixture() -> Fixture {
    let cell = Cell::load(&root().join("samples/cell.toml")).expect("sample cell");
    let r1 = Profile::load(&cell.robots["r1"].profile).expect("r1 profile");
    let r2 = Profile::load(&cell.robots["r2"].profile).expect("r2 profile");
    let options = LoadOptions {
        krl_config_dat: cell.robots["r1"].config_dat.clone(),
        map_inputs: false,
        ..LoadOptions::default()
    };
    Fixture {
        cell,
        r1,
        r2,
        options,
    }
}

fn program(f: &Fixture, sample: &str) -> Program {
    load(Path::new(&root().join(sample)), &f.options).expect("sample program")
}

const SAMPLES: &[&str] = &["samples/rapid/spot_line.mod", "samples/krl/spot_line.src"];

#[divan::bench(args = SAMPLES)]
fn correct(bencher: divan::Bencher, sample: &str) {
    let f = fixture();
    let p = program(&f, sample);
    let setup = TrackSetup::new(&f.cell.robots["r1"], &f.r1);
    bencher.bench(|| apply(&p, track_correction(&p, &setup, Direction::Correct)));
}

#[divan::bench(args = SAMPLES)]
fn mirror_xz(bencher: divan::Bencher, sample: &str) {
    let f = fixture();
    let p = program(&f, sample);
    let settings = MirrorSettings::default();
    bencher.bench(|| apply(&p, mirror(&p, &settings)));
}

#[divan::bench(args = SAMPLES, sample_count = 20)]
fn transfer_mirrored(bencher: divan::Bencher, sample: &str) {
    let f = fixture();
    let p = program(&f, sample);
    let plan = TransferPlan {
        from: TrackSetup::new(&f.cell.robots["r1"], &f.r1),
        mirror: Some(MirrorSettings::default()),
        to: TrackSetup::new(&f.cell.robots["r2"], &f.r2),
    };
    bencher.bench(|| transfer(&p, &plan, &f.options));
}
