//! The ISO 9283 section of the track report: what `accuracy pose` computes, as tables and a
//! bar chart of AP, RP and MAX per point.

use super::svg::{Chart, Span};
use super::track::{AccuracyResult, DataTable, SourceFile};
use crate::accuracy::PoseReport;

fn fixed(v: Option<f64>) -> String {
    v.map_or_else(|| "-".to_owned(), |v| super::svg::fmt_fixed(v, 4))
}

const POSE_COLUMNS: [&str; 14] = [
    "point", "n", "AP", "APx", "APy", "APz", "APa", "APb", "APc", "RP", "RPa", "RPb", "RPc", "MAX",
];

/// One `accuracy pose` result: the per-point table with the worst of each figure, and the
/// chart. `commanded` and `measured` name the files.
pub fn pose_result(
    report: &PoseReport,
    commanded: SourceFile,
    measured: SourceFile,
) -> AccuracyResult {
    let mut rows: Vec<Vec<String>> = report
        .points
        .iter()
        .map(|p| {
            let mut row = vec![p.point.clone(), p.n.to_string()];
            row.extend(p.figures().map(fixed));
            row
        })
        .collect();
    let w = &report.summary;
    let mut worst = vec!["worst".to_owned(), String::new()];
    worst.extend(
        [
            Some(w.ap),
            Some(w.ap_x),
            Some(w.ap_y),
            Some(w.ap_z),
            w.ap_a,
            w.ap_b,
            w.ap_c,
            Some(w.rp),
            w.rp_a,
            w.rp_b,
            w.rp_c,
            Some(w.max),
        ]
        .map(fixed),
    );
    rows.push(worst);
    let table = DataTable {
        title: format!(
            "Pose accuracy and repeatability: {} point(s), {} visit(s) of {}",
            w.points, w.visits, measured.path
        ),
        columns: POSE_COLUMNS.iter().map(|c| (*c).to_owned()).collect(),
        rows,
        note: Some(format!(
            "AP, APx..APz, RP, MAX in mm; APa..APc, RPa..RPc in degrees ('-': no orientation columns). RP = mean + 3 S over n - 1. Worst AP at {}, RP at {}, MAX at {}.",
            w.worst_ap_point, w.worst_rp_point, w.worst_max_point
        )),
    };
    AccuracyResult {
        sources: vec![
            ("commanded poses".to_owned(), commanded),
            ("pose measurements".to_owned(), measured),
        ],
        tables: vec![table],
        figure: Some((
            pose_chart(report),
            "Per point: AP (accuracy, blue), RP (repeatability, grey), MAX (largest single deviation, red dot), mm."
                .to_owned(),
        )),
    }
}

/// Bars of AP and RP and a dot for MAX, per point.
fn pose_chart(report: &PoseReport) -> String {
    let n = report.points.len().max(1);
    let top = report
        .points
        .iter()
        .flat_map(|p| [p.ap, p.rp, p.max])
        .filter(|v| v.is_finite())
        .fold(1e-6, f64::max);
    let every = n.div_ceil(24);
    let cats = report
        .points
        .iter()
        .enumerate()
        .filter(|(i, _)| i % every == 0)
        .map(|(i, p)| (i as f64 + 0.5, p.point.clone()))
        .collect();
    let mut ch = Chart::new(
        1040.0,
        300.0,
        Span::new(0.0, n as f64),
        Span::new(0.0, top * 1.12),
    )
    .title("ISO 9283 pose accuracy (AP, MAX) and repeatability (RP) per point")
    .labels("point", "mm")
    .x_categories(cats);
    for (i, p) in report.points.iter().enumerate() {
        let x = i as f64;
        ch.bar(
            x + 0.15,
            x + 0.5,
            p.ap,
            "bar",
            &format!("{}: AP {:.4} mm", p.point, p.ap),
        );
        ch.bar(
            x + 0.5,
            x + 0.85,
            p.rp,
            "bar rp",
            &format!("{}: RP {:.4} mm", p.point, p.rp),
        );
        ch.dot(
            x + 0.325,
            p.max,
            3.5,
            "knot",
            Some(&format!("{}: MAX {:.4} mm", p.point, p.max)),
        );
    }
    ch.render()
}
