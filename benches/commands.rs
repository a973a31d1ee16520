//! Benchmark (divan). Run: `cargo bench --bench commands` (add `TRACKFIX_BENCH_100MB=1` for the
//! 100 MB inputs; `scripts/perf-compare.py` times the binary against `grep -c` and a regex
//! script in the same run).
//!
//! What the commands do, end to end from a file on disk, on generated programs of 1, 10 (and
//! 100) MB: `check` (load + lints), `inspect --format json` (load + the streamed JSON),
//! `correct` (load + track correction + the edited text) and `mirror` (load + mirror + text),
//! for a RobotStudio-style RAPID module and a KUKA.Sim-style `.src`/`.dat` pair. Throughput is
//! the input's bytes per second; the allocation profiler gives allocations and the peak bytes
//! allocated on top of what was live before the run.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use divan::{AllocProfiler, Bencher, black_box, counter::BytesCount};
use trackfix::program::{LoadOptions, load};
use trackfix::report::{InspectJson, InspectOptions, findings};
use trackfix::track::Profile;
use trackfix::transform::{
    Cell, Direction, MirrorSettings, TrackSetup, apply_owned, mirror, track_correction,
};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

/// One input: a language and a size in MB.
#[derive(Clone, Copy, Debug)]
struct Case {
    lang: Lang,
    mb: usize,
}

impl std::fmt::Display for Case {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {:>3} MB", self.lang, self.mb)
    }
}

/// Both languages at 1 and 10 MB; 100 MB too when `TRACKFIX_BENCH_100MB` is set (a minute per
/// case on the build machine).
fn cases() -> Vec<Case> {
    let mut sizes = vec![1, 10];
    if std::env::var_os("TRACKFIX_BENCH_100MB").is_some() {
        sizes.push(100);
    }
    [Lang::Rapid, Lang::Krl]
        .into_iter()
        .flat_map(|lang| sizes.iter().map(move |&mb| Case { lang, mb }))
        .collect()
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[path = "support/rapid_module.rs"]
mod rapid_module;
use rapid_module::module as rapid_module;

/// The pair shape of `benches/krl_parse.rs`, one point per declaration and inline form,
/// `mb` megabytes for both files together.
fn krl_pair(mb: usize) -> (Vec<u8>, Vec<u8>) {
    use std::fmt::Write as _;
    let target = mb * 1_000_000;
    let mut dat = String::from("&ACCESS RVP\r\n&REL 1\r\nDEFDAT bench PUBLIC\r\n");
    let mut src = String::from("&ACCESS RVP\r\n&REL 1\r\nDEF bench( )\r\n");
    let mut i = 0usize;
    while dat.len() + src.len() < target {
        i += 1;
        let e1 = 100.0 + (i % 7800) as f64;
        let _ = write!(
            dat,
            "DECL E6POS XP{i}={{X {:.3},Y {:.3},Z 1020.500,A -178.2500,B 12.5000,C 179.4000,S 6,T 50,E1 {e1:.3},E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}\r\n\
             DECL FDAT FP{i}={{TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE,POINT2[] \" \",TQ_STATE FALSE}}\r\n\
             DECL LDAT LCPDAT{i}={{VEL 2.0,ACC 100.0,APO_DIST 100.0,APO_FAC 50.0,ORI_TYP #VAR,CIRC_TYP #BASE}}\r\n",
            1200.0 + i as f64 * 0.25,
            -800.0 + (i % 100) as f64
        );
        let _ = write!(
            src,
            ";FOLD LIN P{i} CONT Vel=2 m/s CPDAT{i} Tool[1]:gun1 Base[1]:car;%{{PE}}%R 8.3.31,%MKUKATPBASIS,%CMOVE,%VLIN,%P 1:LIN, 2:P{i}, 3:C_DIS C_DIS, 5:2, 7:CPDAT{i}\r\n\
             $BWDSTART=FALSE\r\nLDAT_ACT=LCPDAT{i}\r\nFDAT_ACT=FP{i}\r\nBAS(#CP_PARAMS,2)\r\n\
             LIN XP{i} C_DIS C_DIS\r\n;ENDFOLD\r\n"
        );
    }
    dat.push_str("ENDDAT\r\n");
    src.push_str("END\r\n");
    (src.into_bytes(), dat.into_bytes())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lang {
    Rapid,
    Krl,
}

impl std::fmt::Display for Lang {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Lang::Rapid => "rapid",
            Lang::Krl => "krl",
        })
    }
}

/// The generated program on disk (written once per size and language), and its byte count.
fn input(lang: Lang, mb: usize) -> (PathBuf, usize) {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    let dir = DIR
        .get_or_init(|| tempfile::tempdir().expect("temp dir"))
        .path();
    match lang {
        Lang::Rapid => {
            let path = dir.join(format!("bench_{mb}.mod"));
            if !path.exists() {
                std::fs::write(&path, rapid_module(mb)).expect("write module");
            }
            let len = std::fs::metadata(&path).expect("module").len() as usize;
            (path, len)
        }
        Lang::Krl => {
            let path = dir.join(format!("bench_{mb}.src"));
            if !path.exists() {
                let (src, dat) = krl_pair(mb);
                std::fs::write(path.with_extension("dat"), dat).expect("write .dat");
                std::fs::write(&path, src).expect("write .src");
            }
            let len = std::fs::metadata(&path).expect("src").len()
                + std::fs::metadata(path.with_extension("dat"))
                    .expect("dat")
                    .len();
            (path, len as usize)
        }
    }
}

struct Setup {
    cell: Cell,
    profile: Profile,
    options: LoadOptions,
}

impl Setup {
    /// The options of the commands that write nothing, which map large inputs.
    fn mapped(&self) -> LoadOptions {
        LoadOptions {
            map_inputs: true,
            ..self.options.clone()
        }
    }
}

fn setup() -> &'static Setup {
    static SETUP: OnceLock<Setup> = OnceLock::new();
    SETUP.get_or_init(|| {
        let cell = Cell::load(&root().join("samples/cell.toml")).expect("sample cell");
        let profile = Profile::load(&cell.robots["r1"].profile).expect("r1 profile");
        let options = LoadOptions {
            krl_config_dat: cell.robots["r1"].config_dat.clone(),
            map_inputs: false,
            ..LoadOptions::default()
        };
        Setup {
            cell,
            profile,
            options,
        }
    })
}

fn run(bencher: Bencher, case: Case, command: impl Fn(&Path, &Setup) -> usize + Sync) {
    let (path, len) = input(case.lang, case.mb);
    let s = setup();
    bencher
        .counter(BytesCount::new(len))
        .bench(|| black_box(command(black_box(&path), s)));
}

#[divan::bench(args = cases(), sample_count = 3, sample_size = 1)]
fn check(bencher: Bencher, case: Case) {
    run(bencher, case, |path, s| {
        let p = load(path, &s.mapped()).expect("program");
        p.files.iter().map(|f| findings(f).len()).sum()
    });
}

#[divan::bench(args = cases(), sample_count = 3, sample_size = 1)]
fn inspect_json(bencher: Bencher, case: Case) {
    run(bencher, case, |path, s| {
        let p = load(path, &s.mapped()).expect("program");
        // What `inspect --format json` runs: the report written as it is built.
        let programs = [p];
        let doc = InspectJson {
            programs: &programs,
            grouped: &[false],
            options: InspectOptions::default(),
        };
        let out = std::io::BufWriter::new(std::io::sink());
        serde_json::to_writer_pretty(out, &doc).expect("json");
        programs[0].files.len()
    });
}

#[divan::bench(args = cases(), sample_count = 3, sample_size = 1)]
fn correct(bencher: Bencher, case: Case) {
    run(bencher, case, |path, s| {
        let p = load(path, &s.options).expect("program");
        let track = TrackSetup::new(&s.cell.robots["r1"], &s.profile);
        // As the command does: the program is handed over, its model dropped before the outputs.
        let edits = track_correction(&p, &track, Direction::Correct);
        let result = apply_owned(p, edits).expect("edits");
        black_box(&result);
        result.files.len()
    });
}

#[divan::bench(args = cases(), sample_count = 3, sample_size = 1)]
fn mirror_xz(bencher: Bencher, case: Case) {
    run(bencher, case, |path, s| {
        let p = load(path, &s.options).expect("program");
        let edits = mirror(&p, &MirrorSettings::default());
        let result = apply_owned(p, edits).expect("edits");
        black_box(&result);
        result.files.len()
    });
}
