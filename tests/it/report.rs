//! Integration tests: the HTML reports. Snapshots of each sample report's outline (headings,
//! figures, table shapes, chart element counts), self-containment, escaping, outliers and the
//! uncertainty band, and every sample report rendered in headless Chromium.

use std::path::{Path, PathBuf};
use std::process::Command;

use trackfix::html_report::run::{RunFile, RunInput, RunReport, headings as run_headings};
use trackfix::html_report::track::{deviation_section, headings as track_headings};
use trackfix::html_report::{AccuracyResult, DataTable, TrackInputs, TrackReport, run_report};
use trackfix::program::{LoadOptions, load};
use trackfix::track::{Extrapolate, Knot, Profile};
use trackfix::transform::{Cell, Direction, TrackSetup, apply, track_correction};

use crate::support::{root, trackfix};

/// Runs `trackfix report ARGS -o DIR/NAME` and returns the HTML.
fn cli_report(dir: &Path, name: &str, args: &[&str]) -> String {
    let out = dir.join(name);
    let out_s = out.display().to_string();
    let mut all: Vec<&str> = vec!["report"];
    all.extend(args);
    all.extend(["-o", &out_s]);
    let (code, stdout, stderr) = trackfix(&all);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    std::fs::read_to_string(&out).unwrap()
}

/// The report of the issue's command.
fn r1_report(dir: &Path) -> String {
    cli_report(
        dir,
        "r1.html",
        &[
            "--measurements",
            "samples/track/measurements.csv",
            "--scan",
            "samples/track/scan.csv",
        ],
    )
}

/// `correct samples/rapid/spot_line.mod --cell samples/cell.toml --robot r1` through the
/// library, as the run report sees it: one changed file and one refused joint target.
fn spot_line_run() -> RunReport {
    let cell_path = Path::new("samples/cell.toml");
    let cell = Cell::load(cell_path).unwrap();
    let robot = cell.robot("r1").unwrap();
    let profile = Profile::load(&robot.profile).unwrap();
    let setup = TrackSetup::new(robot, &profile);
    let program = load(
        Path::new("samples/rapid/spot_line.mod"),
        &LoadOptions::default(),
    )
    .unwrap();
    let result = apply(
        &program,
        track_correction(&program, &setup, Direction::Correct),
    )
    .unwrap();
    let read = |p: &Path| std::fs::read(p).unwrap();
    RunReport {
        command: "correct".into(),
        arguments: "correct samples/rapid/spot_line.mod --cell samples/cell.toml --robot r1 --skip-unsupported -o spot_line.mod".into(),
        outcome: "1 target left unchanged (--skip-unsupported); written to spot_line.mod".into(),
        inputs: vec![
            RunInput::new("cell", "samples/cell.toml", &read(cell_path), "robot r1"),
            RunInput::new(
                "profile r1",
                "samples/track/profile.toml",
                &read(&robot.profile),
                &format!("{} knots", profile.knots().len()),
            ),
        ],
        files: result.files.iter().map(RunFile::from_result).collect(),
        checks: vec![],
    }
}

fn strip_tags(s: &str) -> String {
    let mut out = String::new();
    let mut in_tag = false;
    for c in s.chars() {
        match c {
            '<' => in_tag = true,
            '>' => in_tag = false,
            c if !in_tag => out.push(c),
            _ => {}
        }
    }
    out
}

/// The value of `name="…"` in a tag.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!("{name}=\"");
    let start = tag.find(&key)? + key.len();
    tag[start..].find('"').map(|end| &tag[start..start + end])
}

/// What a reader sees, line by line: headings, paragraphs, figures, table shapes (headers,
/// row count, first and last row) and per chart its title and element counts. The HTML puts
/// each block on its own line, so a line scanner reads it.
fn outline(html: &str) -> String {
    let mut out = Vec::new();
    let mut table: Option<(String, Vec<String>)> = None;
    let mut svg: Option<(String, std::collections::BTreeMap<String, usize>)> = None;
    for line in html.lines() {
        if let Some((_, counts)) = &mut svg {
            if line.starts_with("</svg>") {
                let (label, counts) = svg.take().unwrap_or_default();
                let counts: Vec<String> = counts.iter().map(|(k, v)| format!("{v} {k}")).collect();
                out.push(format!("  svg \"{label}\": {}", counts.join(", ")));
            } else if let Some(tag) = line.strip_prefix('<') {
                let name = tag.split([' ', '>', '/']).next().unwrap_or("");
                let key = match attr(line, "class") {
                    Some(c) => format!("{name}.{}", c.replace(' ', ".")),
                    None => name.to_owned(),
                };
                if !matches!(name, "line" | "text" | "rect") || key.contains('.') {
                    *counts.entry(key).or_default() += 1;
                }
            }
            continue;
        }
        if let Some((headers, rows)) = &mut table {
            if line.starts_with("<thead>") {
                *headers = strip_tags(&line.replace("</th><th>", " | "));
            } else if line.starts_with("<tr") {
                rows.push(strip_tags(&line.replace("</td><td", " | <td")));
            } else if line.starts_with("</table>") {
                let (headers, rows) = table.take().unwrap_or_default();
                out.push(format!("  table [{headers}] x {} rows", rows.len()));
                if let Some(first) = rows.first() {
                    out.push(format!("    first: {first}"));
                }
                if rows.len() > 1
                    && let Some(last) = rows.last()
                {
                    out.push(format!("    last: {last}"));
                }
            }
            continue;
        }
        if line.starts_with("<svg") {
            svg = Some((
                attr(line, "aria-label").unwrap_or("").to_owned(),
                Default::default(),
            ));
        } else if line.starts_with("<table") {
            table = Some((String::new(), Vec::new()));
        } else if line.starts_with("<section") {
            out.push(format!("section #{}", attr(line, "id").unwrap_or("")));
        } else if let Some(rest) = line.strip_prefix("<h") {
            let level = rest.chars().next().unwrap_or('?');
            if level.is_ascii_digit() {
                out.push(format!(
                    "{} {}",
                    "#".repeat(level as usize - '0' as usize),
                    strip_tags(line)
                ));
            }
        } else if line.starts_with("<p") || line.starts_with("<figcaption") {
            out.push(format!("  p: {}", strip_tags(line)));
        } else if line.starts_with("<dt>") {
            out.push(format!(
                "  {}",
                strip_tags(&line.replace("</dt><dd>", ": "))
            ));
        } else if line.starts_with("<title>") || line.starts_with("<footer>") {
            out.push(strip_tags(line));
        }
    }
    out.join("\n")
}

#[test]
fn track_report_of_the_samples_outline() {
    let tmp = tempfile::tempdir().unwrap();
    insta::assert_snapshot!(
        "track_r1_measurements_scan",
        outline(&r1_report(tmp.path()))
    );
    let r2 = cli_report(
        tmp.path(),
        "r2.html",
        &["--profile", "samples/track/r2/profile.toml"],
    );
    insta::assert_snapshot!("track_r2_profile_only", outline(&r2));
    let acc = cli_report(tmp.path(), "acc.html", &["--accuracy-pose", POSE_C, POSE_M]);
    insta::assert_snapshot!("track_accuracy_pose_only", outline(&acc));
}

#[test]
fn run_report_of_spot_line_outline() {
    insta::assert_snapshot!(
        "run_spot_line_correct",
        outline(&run_report(&spot_line_run()))
    );
}

/// The sections appear exactly for the inputs given.
#[test]
fn sections_follow_the_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let h2s = |html: &str| -> Vec<String> {
        html.lines()
            .filter(|l| l.starts_with("<h2>"))
            .map(strip_tags)
            .collect()
    };
    use track_headings::*;
    assert_eq!(
        h2s(&r1_report(tmp.path())),
        [
            INPUTS,
            CONTROLLER,
            IDENTIFICATION,
            DEVIATION,
            ADJUSTMENT,
            BOUNDS,
            SPECTRUM
        ]
    );
    let frames = cli_report(
        tmp.path(),
        "f.html",
        &["--frames", "samples/track/frames.csv"],
    );
    assert_eq!(
        h2s(&frames),
        [INPUTS, CONTROLLER, DEVIATION, ADJUSTMENT, BOUNDS]
    );
    let scan = cli_report(tmp.path(), "s.html", &["--scan", "samples/track/scan.csv"]);
    assert_eq!(h2s(&scan), [INPUTS, SPECTRUM]);
    let acc = cli_report(tmp.path(), "a.html", &["--accuracy-pose", POSE_C, POSE_M]);
    assert_eq!(h2s(&acc), [INPUTS, ACCURACY]);
    // A library caller's own table model shows the same way.
    let own = TrackReport::compute(TrackInputs {
        accuracy: vec![AccuracyResult {
            tables: vec![DataTable {
                title: "Pose accuracy per point".into(),
                columns: vec!["point".into(), "AP [mm]".into()],
                rows: vec![vec!["P1".into(), "0.08".into()]],
                note: None,
            }],
            ..AccuracyResult::default()
        }],
        ..TrackInputs::default()
    })
    .unwrap()
    .render();
    assert_eq!(h2s(&own), [INPUTS, ACCURACY]);
    assert!(own.contains("<td>P1</td><td class=\"n\">0.08</td>"));
}

const POSE_C: &str = "samples/accuracy/pose_commanded.csv";
const POSE_M: &str = "samples/accuracy/pose_measured.csv";

/// The ISO 9283 table holds what `accuracy pose` prints, row for row.
#[test]
fn accuracy_table_equals_accuracy_pose() {
    let (code, text, err) = trackfix(&["accuracy", "pose", POSE_C, POSE_M]);
    assert_eq!(code, 0, "{err}");
    let tmp = tempfile::tempdir().unwrap();
    let html = cli_report(tmp.path(), "a.html", &["--accuracy-pose", POSE_C, POSE_M]);
    let mut rows = 0;
    for line in text.lines() {
        let cells: Vec<&str> = line.split_whitespace().collect();
        let is_point = cells
            .first()
            .is_some_and(|c| c.starts_with('P') && c[1..].parse::<u32>().is_ok());
        if !(is_point && cells.len() == 14) {
            continue;
        }
        let mut want = format!("<tr><td>{}</td><td class=\"n\">{}</td>", cells[0], cells[1]);
        for c in &cells[2..] {
            want.push_str(&format!("<td class=\"n\">{c}</td>"));
        }
        assert!(html.contains(&want), "missing {want}");
        rows += 1;
    }
    assert_eq!(rows, 10, "{text}");
}

/// The controller figures are the ones `track fit` prints, character for character, whether
/// the report fits the profile itself or reads the one `track fit` wrote.
#[test]
fn controller_figures_equal_track_fit() {
    let tmp = tempfile::tempdir().unwrap();
    let profile = tmp.path().join("profile.toml");
    let p = profile.display().to_string();
    let (code, fit_out, err) = trackfix(&[
        "track",
        "fit",
        "samples/track/frames.csv",
        "-o",
        &p,
        "--measured-in",
        "tracker",
    ]);
    assert_eq!(code, 0, "{err}");
    // The frame the figures are in is the profile's, on both sides (it was always "world").
    let tracker = "the tracker's; take the base and direction into the cell's world";
    assert!(
        fit_out.contains(&format!("(measurement frame: {tracker}")),
        "{fit_out}"
    );
    let line_with = |needle: &str| -> String {
        fit_out
            .lines()
            .find(|l| l.trim().starts_with(needle))
            .unwrap_or_else(|| panic!("no `{needle}` in\n{fit_out}"))
            .trim()
            .to_owned()
    };
    let gear = line_with("gear factor: the skid moves");
    let gear = gear.trim_start_matches("gear factor: ");
    let literals = line_with("ABB [[");
    let abb = literals
        .split("   KUKA ")
        .next()
        .unwrap()
        .trim_start_matches("ABB ");
    let kuka = literals.split("   KUKA ").nth(1).unwrap();
    let base = line_with("base frame at skid 0:");
    let base = base.trim_start_matches("base frame at skid 0: ");
    let dir_line = line_with("track direction:");
    let world = &dir_line["track direction: ".len()..dir_line.find(" (in the base").unwrap()];
    let in_base = &dir_line[dir_line.find("skid 0: ").unwrap() + 8..dir_line.len() - 1];
    for html in [
        cli_report(
            tmp.path(),
            "m.html",
            &["--measurements", "samples/track/measurements.csv"],
        ),
        cli_report(tmp.path(), "p.html", &["--profile", &p]),
    ] {
        for (what, want) in [
            ("gear factor", gear),
            ("ABB (pose)", abb),
            ("KUKA (FRAME)", kuka),
            ("base frame at skid 0", base),
            ("track direction (measurement frame)", world),
            ("track direction (base at skid 0)", in_base),
        ] {
            let dt = format!("<dt>{what}</dt><dd>{want}</dd>");
            assert!(html.contains(&dt), "missing {dt}");
        }
    }
    let html = std::fs::read_to_string(tmp.path().join("p.html")).unwrap();
    assert!(
        html.contains(&format!(
            "Measurement frame: {}",
            tracker.replace('\'', "&#39;")
        )),
        "{html}"
    );
}

/// Every report the samples give, for the self-containment and browser tests.
fn sample_reports(dir: &Path) -> Vec<(String, String, Vec<String>)> {
    use track_headings::*;
    let track_all: Vec<String> = [
        INPUTS,
        CONTROLLER,
        IDENTIFICATION,
        DEVIATION,
        ADJUSTMENT,
        BOUNDS,
        SPECTRUM,
    ]
    .map(str::to_owned)
    .to_vec();
    let r2 = cli_report(
        dir,
        "r2.html",
        &[
            "--measurements",
            "samples/track/r2/measurements.csv",
            "--scan",
            "samples/track/r2/scan.csv",
            "--threshold",
            "0.03",
        ],
    );
    let run = spot_line_run();
    let mut run_all: Vec<String> = vec![
        run_headings::SUMMARY.into(),
        run_headings::INPUTS.into(),
        run_headings::ALONG_SKID.into(),
    ];
    run_all.extend(
        run.files
            .iter()
            .map(|f| format!("{}{}", run_headings::FILE_PREFIX, f.path)),
    );
    run_all.push(run_headings::REFUSALS.into());
    let cell = cli_report(
        dir,
        "cell.html",
        &[
            "--profile",
            "samples/track/profile.toml",
            "--accuracy-pose",
            POSE_C,
            POSE_M,
            "--accuracy-pose",
            POSE_C,
            "samples/accuracy/pose_before.csv",
        ],
    );
    let cell_all: Vec<String> = [INPUTS, CONTROLLER, DEVIATION, ADJUSTMENT, BOUNDS, ACCURACY]
        .map(str::to_owned)
        .to_vec();
    let reports: Vec<(String, String, Vec<String>)> = vec![
        ("r1.html".into(), r1_report(dir), track_all.clone()),
        ("cell.html".into(), cell, cell_all),
        ("r2.html".into(), r2, track_all),
        ("run.html".into(), run_report(&run), run_all),
    ];
    // TRACKFIX_REPORT_DIR=DIR keeps a copy to look at.
    if let Some(keep) = std::env::var_os("TRACKFIX_REPORT_DIR") {
        for (name, html, _) in &reports {
            std::fs::write(Path::new(&keep).join(name), html).unwrap();
        }
    }
    reports
}

/// Nothing in a report points outside the file: no URL, no `src`, no link but `#anchors`, no
/// stylesheet import, no `url(` but `data:`, no script, image or embedded object.
#[test]
fn reports_reference_nothing_outside_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    for (name, html, _) in sample_reports(tmp.path()) {
        let lower = html.to_ascii_lowercase();
        for bad in [
            "http:",
            "https:",
            "file://",
            "ftp:",
            "//",
            "@import",
            " src=",
            "<script",
            "<link",
            "<img",
            "<iframe",
            "<object",
            "<embed",
            "<base",
            "@font-face",
        ] {
            if bad == "//" {
                // `//` only as part of a URL: the stylesheet and text have none either.
                assert!(
                    !lower.contains("\"//") && !lower.contains("'//") && !lower.contains("(//"),
                    "{name}: {bad}"
                );
                continue;
            }
            assert!(!lower.contains(bad), "{name} contains `{bad}`");
        }
        for (i, _) in lower.match_indices("url(") {
            assert!(
                lower[i + 4..]
                    .trim_start_matches(['"', '\''])
                    .starts_with("data:"),
                "{name}: url( at {i}"
            );
        }
        for (i, _) in lower.match_indices("href=\"") {
            assert!(lower[i + 6..].starts_with('#'), "{name}: href at {i}");
        }
        assert!(lower.starts_with("<!doctype html>"), "{name}");
    }
}

/// Names from files cannot inject markup: a profile named like a script tag shows as text.
#[test]
fn names_from_files_are_escaped() {
    let evil = "<script>alert('x')</script> & \"q\"";
    let knots: Vec<Knot> = (0..4)
        .map(|i| {
            Knot::from_components(
                i as f64 * 1000.0,
                [0.1 * i as f64, 0.0, 0.0, 0.0, 0.0, 0.01],
            )
        })
        .collect();
    let p = Profile::from_knots(evil, knots, Extrapolate::Error).unwrap();
    let html = TrackReport::compute(TrackInputs {
        profile: Some((
            trackfix::html_report::SourceFile::new("<dir>/p&q.toml", b"x"),
            p,
        )),
        ..TrackInputs::default()
    })
    .unwrap()
    .render();
    assert!(!html.contains("<script"), "unescaped script");
    assert!(html.contains("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; &quot;q&quot;"));
    assert!(html.contains("&lt;dir&gt;/p&amp;q.toml"));
}

/// A point pushed 1 mm off is the one marked: one red bar, its skid row highlighted, and the
/// outlier table names skid and point.
#[test]
fn the_outlier_is_marked() {
    let text = std::fs::read_to_string(root().join("samples/track/measurements.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    // Row of skid 2500, point 4: meas_x + 1 mm.
    let i = lines.iter().position(|l| l.starts_with("2500,4,")).unwrap();
    let mut cells: Vec<String> = lines[i].split(',').map(str::to_owned).collect();
    let x: f64 = cells[5].parse().unwrap();
    cells[5] = format!("{:.4}", x + 1.0);
    lines[i] = cells.join(",");
    let tmp = tempfile::tempdir().unwrap();
    let m = tmp.path().join("measurements.csv");
    std::fs::write(&m, lines.join("\n") + "\n").unwrap();
    let html = cli_report(
        tmp.path(),
        "o.html",
        &["--measurements", m.to_str().unwrap()],
    );
    // The fit spreads the error over the skid's other points, but only there.
    let red: Vec<&str> = html
        .lines()
        .filter(|l| l.starts_with("<rect class=\"bar outlier\""))
        .collect();
    assert!(!red.is_empty());
    assert!(
        red.iter()
            .all(|l| l.contains("<title>skid 2500 mm, point ")),
        "{red:?}"
    );
    assert!(
        red.iter()
            .any(|l| l.contains("<title>skid 2500 mm, point 4: "))
    );
    // The outlier table lists each red bar; the per-skid table highlights skid 2500 once.
    let prefix = "<tr class=\"outlier\"><td class=\"n\">2500</td><td class=\"n\">";
    assert_eq!(
        html.lines().filter(|l| l.starts_with(prefix)).count(),
        red.len() + 1
    );
    assert_eq!(
        html.matches("<tr class=\"outlier\">").count(),
        red.len() + 1
    );
    assert!(html.contains(&format!("{prefix}4</td>")));
}

/// The band appears with uncertainties and only then: one polygon per component, its half
/// width at a knot equal to that knot's u in the chart's own scale.
#[test]
fn uncertainty_band_only_when_given() {
    let knots: Vec<Knot> = (0..5)
        .map(|i| Knot::from_components(i as f64 * 1000.0, [0.0; 6]))
        .collect();
    let p = Profile::from_knots("flat", knots, Extrapolate::Error).unwrap();
    let without = deviation_section(&p, None).body;
    assert_eq!(without.matches("class=\"band\"").count(), 0);
    let u = vec![[0.5, 0.5, 0.5, 0.01, 0.01, 0.01]; 5];
    let with = deviation_section(&p, Some(&u)).body;
    assert_eq!(with.matches("<polygon class=\"band\"").count(), 6);
    // Flat zero curve, constant band: the polygon's y values are two levels, symmetric about
    // the curve's pixel row.
    let poly = with
        .lines()
        .find(|l| l.starts_with("<polygon class=\"band\""))
        .unwrap();
    let curve = with
        .lines()
        .find(|l| l.starts_with("<polyline class=\"curve\""))
        .unwrap();
    let ys = |l: &str| -> Vec<f64> {
        attr(l, "points")
            .unwrap()
            .split(' ')
            .map(|p| p.split(',').nth(1).unwrap().parse().unwrap())
            .collect()
    };
    let (band, mid) = (ys(poly), ys(curve));
    let (lo, hi) = band
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    assert!(mid.iter().all(|y| (y - mid[0]).abs() < 1e-9));
    assert!(
        ((hi - mid[0]) - (mid[0] - lo)).abs() <= 0.1,
        "{lo} {} {hi}",
        mid[0]
    );
    assert!(hi - lo > 50.0, "the band spans the chart: {lo} .. {hi}");
}

/// The browser the tests use: `TRACKFIX_BROWSER`, or chromium / chrome on the PATH.
fn browser() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("TRACKFIX_BROWSER") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    for name in [
        "chromium",
        "chromium-browser",
        "google-chrome",
        "google-chrome-stable",
    ] {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Recorders added to a copy of the report: errors (script and resource loads, captured at the
/// window) from the top of `<head>`, and at the end of `<body>` what the browser laid out —
/// visible `<h2>` headings, rendered SVG sizes, the amount of text — as JSON in a `<pre>`.
const ERROR_RECORDER: &str = "<script>window.__errors=[];window.addEventListener('error',function(e){window.__errors.push(e.message||('failed to load '+((e.target&&(e.target.src||e.target.href))||'?')));},true);</script>";
const LAYOUT_PROBE: &str = r#"<script>(function(){var o={errors:window.__errors,headings:[],svgs:0,small_svgs:0,text:document.body.innerText.length,height:document.documentElement.scrollHeight};document.querySelectorAll('h2').forEach(function(h){var r=h.getBoundingClientRect(),s=getComputedStyle(h);if(r.width>0&&r.height>0&&s.visibility==='visible'&&s.display!=='none'&&parseFloat(s.opacity)>0&&s.color!==getComputedStyle(document.body).backgroundColor){o.headings.push(h.textContent);}});document.querySelectorAll('svg').forEach(function(s){var r=s.getBoundingClientRect();o.svgs++;if(!(r.width>100&&r.height>100)){o.small_svgs++;}});var p=document.createElement('pre');p.id='browser-check';p.textContent=JSON.stringify(o);document.body.appendChild(p);})();</script>"#;

fn chromium(browser: &Path, profile: &Path, args: &[&str]) -> std::process::Output {
    let user_data = format!("--user-data-dir={}", profile.display());
    Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            &user_data,
        ])
        .args(args)
        .output()
        .expect("the browser starts")
}

/// Each sample report in headless Chromium: no error, every section's heading laid out and
/// visible, every chart drawn at its size, a page full of text and a screenshot that is not
/// one colour. Skipped (with a message) only where no browser exists and `CI` is unset.
#[test]
fn reports_render_in_a_real_browser() {
    let Some(browser) = browser() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but no browser was found: .ci/run installs chromium (or set TRACKFIX_BROWSER)"
        );
        #[allow(clippy::print_stderr)] // the skip must be seen in the test output
        {
            eprintln!("skipped: no chromium on PATH (set TRACKFIX_BROWSER or install chromium)");
        }
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    for (name, html, headings) in sample_reports(tmp.path()) {
        let probed = html
            .replacen("<head>", &format!("<head>{ERROR_RECORDER}"), 1)
            .replacen("</body>", &format!("{LAYOUT_PROBE}</body>"), 1);
        let page = tmp.path().join(format!("probed-{name}"));
        std::fs::write(&page, &probed).unwrap();
        let url = format!("file://{}", page.display());
        let profile = tempfile::tempdir().unwrap();
        let out = chromium(
            &browser,
            profile.path(),
            &["--enable-logging=stderr", "--v=0", "--dump-dom", &url],
        );
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let dom = String::from_utf8_lossy(&out.stdout);
        let log = String::from_utf8_lossy(&out.stderr);
        let console: Vec<&str> = log.lines().filter(|l| l.contains("CONSOLE")).collect();
        assert!(console.is_empty(), "{name}: console messages {console:?}");
        let start = dom
            .find("<pre id=\"browser-check\">")
            .expect("the probe ran")
            + 24;
        let end = start + dom[start..].find("</pre>").unwrap();
        let json = dom[start..end]
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&");
        let check: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(check["errors"], serde_json::json!([]), "{name}: {json}");
        let visible: Vec<String> = check["headings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|h| h.as_str().unwrap().to_owned())
            .collect();
        assert_eq!(visible, headings, "{name}");
        assert_eq!(
            check["svgs"].as_u64(),
            Some(html.matches("<svg").count() as u64),
            "{name}"
        );
        assert_eq!(check["small_svgs"].as_u64(), Some(0), "{name}: {json}");
        assert!(check["text"].as_u64().unwrap() > 2000, "{name}: {json}");

        let shot = tmp.path().join(format!("{name}.png"));
        let shot_arg = format!("--screenshot={}", shot.display());
        let profile = tempfile::tempdir().unwrap();
        let out = chromium(
            &browser,
            profile.path(),
            &["--window-size=1000,1000", &shot_arg, &url],
        );
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let colours = png_colours(&std::fs::read(&shot).unwrap());
        assert!(colours > 16, "{name}: the screenshot has {colours} colours");
    }
}

/// Printed, each section starts on a new page: the scan-only report (a short inputs table
/// and one chart, together less than a page) prints on exactly two pages.
#[test]
fn printed_sections_start_on_new_pages() {
    let Some(browser) = browser() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but no browser was found"
        );
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    cli_report(
        tmp.path(),
        "scan.html",
        &["--scan", "samples/track/scan.csv"],
    );
    let pdf = tmp.path().join("scan.pdf");
    let pdf_arg = format!("--print-to-pdf={}", pdf.display());
    let url = format!("file://{}", tmp.path().join("scan.html").display());
    let profile = tempfile::tempdir().unwrap();
    let out = chromium(
        &browser,
        profile.path(),
        &["--no-pdf-header-footer", &pdf_arg, &url],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(pdf_pages(&std::fs::read(&pdf).unwrap()), 2);
}

/// Page objects of a PDF: `/Type /Page` not followed by `s` (that is the page tree).
fn pdf_pages(bytes: &[u8]) -> usize {
    let key = b"/Type /Page";
    bytes
        .windows(key.len() + 1)
        .filter(|w| w.starts_with(key) && w[key.len()] != b's')
        .count()
}

/// The number of distinct pixel values of a PNG (up to 4096).
fn png_colours(bytes: &[u8]) -> usize {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = info.color_type.samples() * (info.bit_depth as usize).div_ceil(8);
    let mut seen = std::collections::BTreeSet::new();
    for p in buf[..info.buffer_size()].chunks(px.max(1)) {
        seen.insert(p.to_vec());
        if seen.len() >= 4096 {
            break;
        }
    }
    seen.len()
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]

    /// Any profile (any name, any finite knots) gives a whole page: the four profile sections
    /// after the inputs, balanced sections and charts, the name only escaped.
    #[test]
    fn any_profile_renders_a_whole_escaped_page(
        name in "\\PC{0,24}",
        steps in proptest::collection::vec(1.0f64..5000.0, 1..12),
        values in proptest::collection::vec(-1e3f64..1e3, 6 * 12),
    ) {
        let mut skid = -1000.0;
        let knots: Vec<Knot> = steps
            .iter()
            .enumerate()
            .map(|(i, step)| {
                skid += step;
                let mut c = [0.0; 6];
                c.copy_from_slice(&values[6 * i..6 * i + 6]);
                Knot::from_components(skid, c)
            })
            .collect();
        let first = Knot::zero(-1000.0);
        let knots = std::iter::once(first).chain(knots).collect();
        let p = Profile::from_knots(name.clone(), knots, Extrapolate::Error).unwrap();
        let html = TrackReport::compute(TrackInputs {
            profile: Some((trackfix::html_report::SourceFile::new("p.toml", b""), p)),
            ..TrackInputs::default()
        })
        .unwrap()
        .render();
        proptest::prop_assert_eq!(html.matches("<section").count(), 5);
        proptest::prop_assert_eq!(html.matches("</section>").count(), 5);
        proptest::prop_assert_eq!(html.matches("<svg").count(), html.matches("</svg>").count());
        let escaped = trackfix::html_report::html::escape(&name);
        let numbers = html.replace(&escaped, "");
        proptest::prop_assert!(!numbers.contains("NaN") && !numbers.contains("inf"));
        let title = format!("<title>trackfix track report: {escaped}</title>");
        proptest::prop_assert!(html.contains(&title));
        // Whatever the name holds, it adds no element: one page title, one h1, no script.
        proptest::prop_assert_eq!(html.matches("<title>trackfix").count(), 1);
        proptest::prop_assert_eq!(html.matches("</title>\n").count(), 1);
        proptest::prop_assert_eq!(html.matches("<h1>").count(), 1);
        proptest::prop_assert!(!html.contains("<script"));
        if escaped != name {
            let raw = format!("report: {name}</title>");
            proptest::prop_assert!(!html.contains(&raw));
        }
    }
}

/// `correct … --report run.html` through the binary: the report is written beside the output,
/// names the cell and profile it read with their sha256, lists the refused joint target at its
/// location, carries no external reference, and its sections are those of the library's run
/// report.
#[test]
fn correct_with_report_writes_the_run_report() {
    let tmp = tempfile::tempdir().unwrap();
    let report = tmp.path().join("run.html");
    let out = tmp.path().join("out");
    let (code, _, stderr) = trackfix(&[
        "correct",
        "samples/rapid/spot_line.mod",
        "--cell",
        "samples/cell_rules.toml",
        "--robot",
        "r1",
        "--skip-unsupported",
        "--out-dir",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "written, the joint target kept: {stderr}");
    assert!(stderr.contains("the run report"), "{stderr}");
    let html = std::fs::read_to_string(&report).unwrap();
    let cell = std::fs::read(root().join("samples/cell_rules.toml")).unwrap();
    let profile = std::fs::read(root().join("samples/track/profile.toml")).unwrap();
    for hash in [&cell, &profile].map(|b| trackfix::digest::sha256_hex(b)) {
        assert!(
            html.contains(&hash),
            "the report names the input with hash {hash}"
        );
    }
    assert!(html.contains("jHome"), "the refused joint target is listed");
    assert!(html.contains("spot_line.mod:14:28") || html.contains("14:28"));
    for external in ["http:", "https:", "src=\"//", "@import"] {
        assert!(
            !html.contains(external),
            "no external reference: {external}"
        );
    }
    let headings: Vec<String> = html
        .lines()
        .filter(|l| l.starts_with("<h2>"))
        .map(strip_tags)
        .collect();
    assert!(
        headings.iter().any(|h| h == "Refused targets"),
        "{headings:?}"
    );
    assert!(
        headings.iter().any(|h| h == "Cell, profiles and programs"),
        "{headings:?}"
    );
    assert!(out.join("spot_line.mod").is_file());
}

/// A KRL pair written under a new name (`-o side_b.src`) has its DEF/DEFDAT renamed: the run
/// report's output hashes are those of the files on disk, not of the outputs before the rename.
#[test]
fn run_report_hashes_the_renamed_files_that_were_written() {
    let tmp = tempfile::tempdir().unwrap();
    let report = tmp.path().join("run.html");
    let out = tmp.path().join("side_b.src");
    let (code, _, stderr) = trackfix(&[
        "correct",
        "samples/krl/spot_line.src",
        "--cell",
        "samples/cell.toml",
        "--robot",
        "r1",
        "--skip-unsupported",
        "-o",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(code == 0 || code == 4, "{stderr}");
    assert!(
        stderr.contains("renamed `spot_line` to `side_b`"),
        "{stderr}"
    );
    let html = std::fs::read_to_string(&report).unwrap();
    for written in [out.clone(), out.with_extension("dat")] {
        let hash = trackfix::digest::sha256_hex(&std::fs::read(&written).unwrap());
        assert!(
            html.contains(&hash),
            "the report gives {} its hash {hash}",
            written.display()
        );
    }
}

/// A run report, and every other file a command writes besides its outputs, never replaces a
/// file the run reads or writes: the program, the cell, the run's own output, a command's own
/// measurements. It is refused before anything is written (exit 2, every file as it was), as
/// is a report in a folder that does not exist.
#[test]
fn a_written_file_never_replaces_what_the_run_reads_or_writes() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let program = dir.join("spot_line.mod");
    let cell = dir.join("cell.toml");
    std::fs::copy("samples/rapid/spot_line.mod", &program).unwrap();
    let cell_text = std::fs::read_to_string("samples/cell_rules.toml")
        .unwrap()
        .replace(
            "\"track/",
            &format!("\"{}/samples/track/", root().display()),
        )
        .replace("\"krl/", &format!("\"{}/samples/krl/", root().display()));
    std::fs::write(&cell, &cell_text).unwrap();
    let out = dir.join("out.mod");
    let snapshot = || {
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let p = e.unwrap().path();
                (p.clone(), std::fs::read(&p).unwrap_or_default())
            })
            .collect();
        files.sort();
        files
    };
    let before = snapshot();
    let path = |p: &Path| p.to_str().unwrap().to_owned();
    for (report, extra) in [
        (path(&program), vec!["-o".to_owned(), path(&out)]),
        (path(&out), vec!["-o".to_owned(), path(&out)]),
        (path(&cell), vec!["-o".to_owned(), path(&out)]),
        (path(&program), vec!["--diff".to_owned()]),
        (path(&program), vec!["--in-place".to_owned()]),
        // The backup the run would make.
        (
            format!("{}.orig", path(&program)),
            vec!["--in-place".to_owned()],
        ),
        (
            path(&dir.join("no/such/run.html")),
            vec!["-o".to_owned(), path(&out)],
        ),
        (path(dir), vec!["-o".to_owned(), path(&out)]),
    ] {
        let mut args = vec![
            "correct".to_owned(),
            path(&program),
            "--cell".to_owned(),
            path(&cell),
            "--robot".to_owned(),
            "r1".to_owned(),
            "--skip-unsupported".to_owned(),
            "--report".to_owned(),
            report.clone(),
        ];
        args.extend(extra.iter().cloned());
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = trackfix(&args);
        assert_eq!(code, 2, "{report} {extra:?}: {err}");
        assert!(err.contains(&format!("{report}: ")), "{err}");
        assert_eq!(snapshot(), before, "{report} {extra:?}: {err}");
    }
    // Another command's output over its own input.
    let measurements = dir.join("m.csv");
    std::fs::copy("samples/track/measurements.csv", &measurements).unwrap();
    let m = path(&measurements);
    let kept = std::fs::read(&measurements).unwrap();
    for args in [
        vec!["track", "identify", &m, "-o", &m],
        vec!["report", "--measurements", &m, "-o", &m],
    ] {
        let (code, _, err) = trackfix(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("refusing to write there: this run reads or writes that file"),
            "{err}"
        );
        assert_eq!(std::fs::read(&measurements).unwrap(), kept, "{args:?}");
    }
}
