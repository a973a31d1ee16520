//! What the integration tests share: the crate root and one way to run the built binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use trackfix::position::NumField;
use trackfix::syntax::latin1;

/// The package root, where the samples are.
pub(crate) fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The text of `samples/cell.toml` with the files it names made absolute, to be written
/// elsewhere (changed).
pub(crate) fn sample_cell() -> String {
    let samples = root().join("samples");
    std::fs::read_to_string(samples.join("cell.toml"))
        .unwrap()
        .replace("\"track/", &format!("\"{}/track/", samples.display()))
        .replace("\"krl/", &format!("\"{}/krl/", samples.display()))
}

/// Every file under `dir`, in any depth, sorted.
pub(crate) fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                todo.push(path);
            } else {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Runs the built `trackfix` binary from the package root.
pub(crate) fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trackfix"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("the trackfix binary runs")
}

pub(crate) fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs the binary; returns (exit code, stdout, stderr), -1 for a signal.
pub(crate) fn trackfix(args: &[&str]) -> (i32, String, String) {
    let o = run(args);
    (o.status.code().unwrap_or(-1), stdout(&o), stderr(&o))
}

/// A numeric field as written in `src` (read back through its span), `-` where the field is not
/// a numeric literal.
pub(crate) fn text(src: &[u8], f: &Option<NumField>) -> String {
    match f {
        Some(f) => latin1(f.span().slice(src)),
        None => "-".to_owned(),
    }
}

/// Several fields as written, comma-separated.
pub(crate) fn texts(src: &[u8], fs: &[Option<NumField>]) -> String {
    fs.iter()
        .map(|f| text(src, f))
        .collect::<Vec<_>>()
        .join(",")
}

/// Runs `f` with the track setup of robot `r1` of a one-robot cell (track along world x, base at
/// y = -1000 turned 90° about z, skid in `eax_a`, no kinematics) whose track deviates by `d` at
/// every skid: a correction of known size for tests of what a transform does with it.
pub(crate) fn with_constant_deviation<R>(
    d: trackfix::geometry::Pose,
    f: impl FnOnce(&trackfix::transform::TrackSetup) -> R,
) -> R {
    let cell = trackfix::transform::Cell::parse(
        Path::new("cell.toml"),
        "[robot.r1]\nprofile = \"track/profile.toml\"\n\
         base = { x = 0, y = -1000, z = 0, rx = 0, ry = 0, rz = 90 }\n\
         track_axis = [1, 0, 0]\nskid = \"eax_a\"\n",
    )
    .expect("the cell parses");
    let robot = cell.robot("r1").expect("the cell has r1");
    let dev =
        move |_s: f64| -> Result<trackfix::geometry::Pose, trackfix::track::TrackError> { Ok(d) };
    f(&trackfix::transform::TrackSetup::new(robot, &dev))
}

/// The work objects (KRL bases) a target's usage records, sorted.
pub(crate) fn sorted_work_objects(usage: &trackfix::position::Usage) -> Vec<String> {
    let mut all: Vec<String> = usage.work_objects().map(str::to_owned).collect();
    all.sort();
    all
}
