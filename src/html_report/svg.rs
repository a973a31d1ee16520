//! Small inline SVG charts written by hand: axes with round ticks, curves, bands, markers,
//! bars and labels. Coordinates are printed with one decimal, so the same data gives the same
//! bytes on every machine; styling comes from the page's stylesheet (classes), so a chart is
//! a few kilobytes, not a font-metrics dump.

use std::fmt::Write as _;

use super::html::escape;

/// A closed value interval of one axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Span {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
}

impl Span {
    pub(crate) fn new(lo: f64, hi: f64) -> Span {
        Span { lo, hi }
    }

    /// The finite values' range with 6 % margin; a flat or empty series gets a small one around
    /// its value, so every chart has an extent.
    pub(crate) fn padded(values: impl IntoIterator<Item = f64>) -> Span {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.into_iter().filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if !lo.is_finite() {
            return Span::new(-1.0, 1.0);
        }
        let span = hi - lo;
        let pad = if span > 1e-12 * (1.0 + lo.abs().max(hi.abs())) {
            0.06 * span
        } else {
            1e-3_f64.max(lo.abs() * 0.1)
        };
        Span::new(lo - pad, hi + pad)
    }

    /// The same range, widened to include `v`.
    pub(crate) fn including(self, v: f64) -> Span {
        if !v.is_finite() {
            return self;
        }
        Span::new(self.lo.min(v), self.hi.max(v))
    }

    fn width(&self) -> f64 {
        let w = self.hi - self.lo;
        if w > 0.0 && w.is_finite() { w } else { 1.0 }
    }
}

/// Round tick positions (1, 2 or 5 × 10ⁿ apart) inside `span`, about `target` of them, and
/// the number of decimals that prints them exactly.
pub(crate) fn ticks(span: Span, target: usize) -> (Vec<f64>, usize) {
    let raw = span.width() / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    if !(step > 0.0 && step.is_finite()) {
        return (Vec::new(), 0);
    }
    let decimals = (-step.log10().floor()).clamp(0.0, 12.0) as usize;
    let (first, last) = ((span.lo / step).ceil(), (span.hi / step).floor());
    // A range far from zero at a tiny width would ask for more ticks than a chart has pixels.
    if !(first.is_finite() && last.is_finite()) || last - first > 100.0 {
        return (Vec::new(), decimals);
    }
    let ticks = (0..=(last - first).max(-1.0) as i64)
        .map(|i| (first + i as f64) * step)
        .collect();
    (ticks, decimals)
}

/// `v` with `decimals` digits, never `-0`.
pub(crate) fn fmt_fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_owned()
    } else {
        s
    }
}

/// One pixel coordinate.
fn c(v: f64) -> String {
    fmt_fixed(v, 1)
}

/// A chart under construction: a plot area mapped from data ranges, and its elements.
#[derive(Clone, Debug)]
pub(crate) struct Chart {
    width: f64,
    height: f64,
    left: f64,
    right: f64,
    top: f64,
    bottom: f64,
    x: Span,
    y: Span,
    title: String,
    x_label: String,
    y_label: String,
    /// Replaces the numeric x ticks: (position, label).
    x_categories: Option<Vec<(f64, String)>>,
    body: String,
}

impl Chart {
    /// A `width` × `height` px chart showing `x` × `y`.
    pub(crate) fn new(width: f64, height: f64, x: Span, y: Span) -> Chart {
        Chart {
            width,
            height,
            left: 62.0,
            right: 16.0,
            top: 26.0,
            bottom: 42.0,
            x,
            y,
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            x_categories: None,
            body: String::new(),
        }
    }

    pub(crate) fn title(mut self, t: &str) -> Chart {
        self.title = t.to_owned();
        self
    }

    pub(crate) fn labels(mut self, x: &str, y: &str) -> Chart {
        self.x_label = x.to_owned();
        self.y_label = y.to_owned();
        self
    }

    /// Widens one of the ranges so that a unit is as long on x as on y (the twist diagram must
    /// not exaggerate one direction).
    pub(crate) fn equal_scale(mut self) -> Chart {
        let (pw, ph) = (self.plot_width(), self.plot_height());
        let scale = (pw / self.x.width()).min(ph / self.y.width());
        let grow = |s: Span, len: f64| {
            let mid = 0.5 * (s.lo + s.hi);
            let half = 0.5 * len / scale;
            Span::new(mid - half, mid + half)
        };
        self.x = grow(self.x, pw);
        self.y = grow(self.y, ph);
        self
    }

    /// Labels the x axis at these positions instead of numeric ticks.
    pub(crate) fn x_categories(mut self, labels: Vec<(f64, String)>) -> Chart {
        self.x_categories = Some(labels);
        self
    }

    fn plot_width(&self) -> f64 {
        (self.width - self.left - self.right).max(1.0)
    }

    fn plot_height(&self) -> f64 {
        (self.height - self.top - self.bottom).max(1.0)
    }

    /// Pixel x of data x.
    pub(crate) fn px(&self, x: f64) -> f64 {
        self.left + (x - self.x.lo) / self.x.width() * self.plot_width()
    }

    /// Pixel y of data y (up is up).
    pub(crate) fn py(&self, y: f64) -> f64 {
        self.top + (self.y.hi - y) / self.y.width() * self.plot_height()
    }

    fn points(&self, pts: &[(f64, f64)]) -> String {
        pts.iter()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|&(x, y)| format!("{},{}", c(self.px(x)), c(self.py(y))))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// A line through the points.
    pub(crate) fn polyline(&mut self, pts: &[(f64, f64)], class: &str) {
        let _ = writeln!(
            self.body,
            "<polyline class=\"{class}\" points=\"{}\"/>",
            self.points(pts)
        );
    }

    /// The area between `lower` and `upper` (same x, in order).
    pub(crate) fn band(&mut self, lower: &[(f64, f64)], upper: &[(f64, f64)]) {
        let mut pts: Vec<(f64, f64)> = lower.to_vec();
        pts.extend(upper.iter().rev());
        let _ = writeln!(
            self.body,
            "<polygon class=\"band\" points=\"{}\"/>",
            self.points(&pts)
        );
    }

    /// A dot; `tip` becomes its tooltip.
    pub(crate) fn dot(&mut self, x: f64, y: f64, r: f64, class: &str, tip: Option<&str>) {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        let (cx, cy) = (c(self.px(x)), c(self.py(y)));
        match tip {
            Some(t) => {
                let _ = writeln!(
                    self.body,
                    "<circle class=\"{class}\" cx=\"{cx}\" cy=\"{cy}\" r=\"{r}\"><title>{}</title></circle>",
                    escape(t)
                );
            }
            None => {
                let _ = writeln!(
                    self.body,
                    "<circle class=\"{class}\" cx=\"{cx}\" cy=\"{cy}\" r=\"{r}\"/>"
                );
            }
        }
    }

    /// A bar from `y = 0` (or the bottom of the range) to `y`, between `x0` and `x1`.
    pub(crate) fn bar(&mut self, x0: f64, x1: f64, y: f64, class: &str, tip: &str) {
        let base = self.py(0.0_f64.clamp(self.y.lo, self.y.hi));
        let top = self.py(y);
        let (y0, h) = if top < base {
            (top, base - top)
        } else {
            (base, top - base)
        };
        let _ = writeln!(
            self.body,
            "<rect class=\"{class}\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"><title>{}</title></rect>",
            c(self.px(x0)),
            c(y0),
            c((self.px(x1) - self.px(x0)).max(0.5)),
            c(h),
            escape(tip)
        );
    }

    /// A horizontal line across the plot at data `y`, labelled at its right end.
    pub(crate) fn hline(&mut self, y: f64, class: &str, label: Option<&str>) {
        let (x0, x1, py) = (self.left, self.left + self.plot_width(), self.py(y));
        let _ = writeln!(
            self.body,
            "<line class=\"{class}\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
            c(x0),
            c(py),
            c(x1),
            c(py)
        );
        if let Some(l) = label {
            let _ = writeln!(
                self.body,
                "<text class=\"{class}-label\" x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
                c(x1 - 4.0),
                c(py - 4.0),
                escape(l)
            );
        }
    }

    /// A vertical line over the plot at data `x`, labelled near its top.
    pub(crate) fn vline(&mut self, x: f64, class: &str, label: Option<&str>) {
        let (px, y0, y1) = (self.px(x), self.top, self.top + self.plot_height());
        let _ = writeln!(
            self.body,
            "<line class=\"{class}\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
            c(px),
            c(y0),
            c(px),
            c(y1)
        );
        if let Some(l) = label {
            let anchor = if px > self.left + 0.6 * self.plot_width() {
                ("end", -4.0)
            } else {
                ("start", 4.0)
            };
            let _ = writeln!(
                self.body,
                "<text class=\"{class}-label\" x=\"{}\" y=\"{}\" text-anchor=\"{}\">{}</text>",
                c(px + anchor.1),
                c(y0 + 14.0),
                anchor.0,
                escape(l)
            );
        }
    }

    /// A text label at data (x, y), offset by (dx, dy) px.
    pub(crate) fn label(&mut self, x: f64, y: f64, dx: f64, dy: f64, text: &str) {
        let _ = writeln!(
            self.body,
            "<text x=\"{}\" y=\"{}\">{}</text>",
            c(self.px(x) + dx),
            c(self.py(y) + dy),
            escape(text)
        );
    }

    /// The `<svg>` element: grid, axes, ticks, labels, then the data elements. No `xmlns`: the
    /// HTML parser puts inline SVG in its namespace, and the page stays free of any URL.
    pub(crate) fn render(&self) -> String {
        let (w, h) = (self.width, self.height);
        let (l, t, pw, ph) = (self.left, self.top, self.plot_width(), self.plot_height());
        let mut s = String::new();
        let _ = writeln!(
            s,
            "<svg viewBox=\"0 0 {} {}\" width=\"{}\" height=\"{}\" role=\"img\" aria-label=\"{}\">",
            c(w),
            c(h),
            c(w),
            c(h),
            escape(&self.title)
        );
        let _ = writeln!(
            s,
            "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#fff\"/>",
            c(w),
            c(h)
        );
        if !self.title.is_empty() {
            let _ = writeln!(
                s,
                "<text class=\"title\" x=\"{}\" y=\"16\">{}</text>",
                c(l),
                escape(&self.title)
            );
        }
        let (yt, yd) = ticks(self.y, 6);
        for v in yt {
            let py = self.py(v);
            let _ = writeln!(
                s,
                "<line class=\"gridline\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
                c(l),
                c(py),
                c(l + pw),
                c(py),
                c(l - 5.0),
                c(py + 4.0),
                fmt_fixed(v, yd)
            );
        }
        let xt: Vec<(f64, String)> = match &self.x_categories {
            Some(cats) => cats.clone(),
            None => {
                let (xt, xd) = ticks(self.x, 8);
                xt.into_iter().map(|v| (v, fmt_fixed(v, xd))).collect()
            }
        };
        for (v, text) in &xt {
            let px = self.px(*v);
            let _ = writeln!(
                s,
                "<line class=\"gridline\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/><text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
                c(px),
                c(t),
                c(px),
                c(t + ph),
                c(px),
                c(t + ph + 14.0),
                escape(text)
            );
        }
        let _ = writeln!(
            s,
            "<rect class=\"axis\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>",
            c(l),
            c(t),
            c(pw),
            c(ph)
        );
        if !self.x_label.is_empty() {
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
                c(l + pw / 2.0),
                c(h - 8.0),
                escape(&self.x_label)
            );
        }
        if !self.y_label.is_empty() {
            let (x, y) = (c(14.0), c(t + ph / 2.0));
            let _ = writeln!(
                s,
                "<text x=\"{x}\" y=\"{y}\" text-anchor=\"middle\" transform=\"rotate(-90 {x} {y})\">{}</text>",
                escape(&self.y_label)
            );
        }
        s.push_str(&self.body);
        s.push_str("</svg>\n");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_inside() {
        let (t, d) = ticks(Span::new(-0.13, 0.87), 6);
        assert_eq!(d, 1);
        assert!(t.iter().all(|v| *v >= -0.13 && *v <= 0.87));
        assert_eq!(
            t.iter().map(|v| fmt_fixed(*v, d)).collect::<Vec<_>>(),
            ["0.0", "0.2", "0.4", "0.6", "0.8"]
        );
        let (t, d) = ticks(Span::new(0.0, 8000.0), 8);
        assert_eq!(d, 0);
        assert_eq!(t.len(), 9);
    }

    #[test]
    fn degenerate_ranges_give_no_ticks_rather_than_panic() {
        // Infinite width falls back to a unit one, far from zero: no tick fits.
        assert_eq!(ticks(Span::new(1e308, f64::INFINITY), 6).0.len(), 0);
        assert_eq!(ticks(Span::new(8000.0, 8000.0), 6).0, vec![8000.0]);
        assert!(ticks(Span::new(f64::NAN, 1.0), 6).0.len() <= 101);
        assert!(ticks(Span::new(-1e308, 1e308), 6).0.len() <= 101);
        let svg = Chart::new(100.0, 100.0, Span::new(5.0, 5.0), Span::new(0.0, 0.0)).render();
        assert!(svg.starts_with("<svg"));
    }

    #[test]
    fn fixed_format_never_prints_negative_zero() {
        assert_eq!(fmt_fixed(-0.00001, 2), "0.00");
        assert_eq!(fmt_fixed(-0.5, 1), "-0.5");
    }

    #[test]
    fn mapping_puts_corners_on_the_plot_area() {
        let ch = Chart::new(400.0, 300.0, Span::new(0.0, 10.0), Span::new(-1.0, 1.0));
        assert_eq!(ch.px(0.0), 62.0);
        assert_eq!(ch.px(10.0), 400.0 - 16.0);
        assert_eq!(ch.py(1.0), 26.0);
        assert_eq!(ch.py(-1.0), 300.0 - 42.0);
    }

    #[test]
    fn equal_scale_gives_the_same_pixels_per_unit() {
        let ch = Chart::new(500.0, 300.0, Span::new(0.0, 10.0), Span::new(0.0, 1.0)).equal_scale();
        let sx = ch.px(1.0) - ch.px(0.0);
        let sy = ch.py(0.0) - ch.py(1.0);
        assert!((sx - sy).abs() < 1e-9, "{sx} vs {sy}");
    }

    #[test]
    fn labels_are_escaped() {
        let mut ch = Chart::new(200.0, 100.0, Span::new(0.0, 1.0), Span::new(0.0, 1.0))
            .title("a<b")
            .labels("x&", "y\"");
        ch.label(0.5, 0.5, 0.0, 0.0, "<script>");
        let svg = ch.render();
        assert!(svg.contains("a&lt;b") && svg.contains("x&amp;") && svg.contains("y&quot;"));
        assert!(svg.contains("&lt;script&gt;") && !svg.contains("<script>"));
    }
}
