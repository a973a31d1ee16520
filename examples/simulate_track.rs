//! How the track samples were made: a deformed track and its tracker measurements, simulated.
//! A developer's tool, not part of the `trackfix` command (samples/track/README.md):
//!
//! ```text
//! cargo run --example simulate_track -- --robot r1 --out-dir samples/track --noise 0.02 --seed 1
//! ```

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Parser as _;
use trackfix::output::write_file;
use trackfix::track::simulate::{
    TrackTruth, measurements_csv, sample_tcp_points, scan_csv, simulate_measurements, simulate_scan,
};

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum SampleRobot {
    R1,
    R2,
}

/// Simulate a deformed track and its tracker measurements (measurements.csv, scan.csv).
#[derive(clap::Parser)]
struct Args {
    /// Which sample track (see samples/track/README.md).
    #[arg(long, value_enum)]
    robot: SampleRobot,
    /// Folder for measurements.csv and scan.csv.
    #[arg(long)]
    out_dir: PathBuf,
    /// Tracker noise, mm (standard deviation per axis).
    #[arg(long, default_value_t = 0.02)]
    noise: f64,
    /// PRNG seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

fn main() -> anyhow::Result<()> {
    let a = Args::parse();
    let truth = match a.robot {
        SampleRobot::R1 => TrackTruth::sample_r1(),
        SampleRobot::R2 => TrackTruth::sample_r2(),
    };
    std::fs::create_dir_all(&a.out_dir).with_context(|| a.out_dir.display().to_string())?;
    let skids: Vec<f64> = (0..=16).map(|i| i as f64 * 500.0).collect();
    let rows = simulate_measurements(&truth, &skids, &sample_tcp_points(), a.noise, a.seed);
    let m = a.out_dir.join("measurements.csv");
    write_file(&m, measurements_csv(&rows).as_bytes())?;
    let reflector = nalgebra::Point3::new(0.0, 0.0, 250.0);
    let scan = simulate_scan(
        &truth,
        reflector,
        0.0,
        8000.0,
        10.0,
        a.noise,
        a.seed.wrapping_add(1000),
    );
    let sc = a.out_dir.join("scan.csv");
    write_file(&sc, scan_csv(&scan).as_bytes())?;
    #[allow(clippy::print_stdout)]
    {
        println!(
            "wrote {} ({} rows) and {} ({} rows), noise {} mm, seed {}",
            m.display(),
            rows.len(),
            sc.display(),
            scan.len(),
            a.noise,
            a.seed
        );
    }
    Ok(())
}
