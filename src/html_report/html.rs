//! Escaping, tables and the page skeleton shared by every report: one HTML document with its
//! stylesheet inline, sections that start on a new page when printed, and nothing fetched.

use std::fmt::Write as _;

/// `text` safe inside an element or a quoted attribute: `& < > " '` become entities.
/// Names come from files (profile names, target names, paths), so everything goes through here.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// One report section: an `<h2>` and its body (HTML, already escaped).
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// The anchor (`#id`) of the table of contents; letters, digits and `-` only.
    pub id: String,
    /// Plain text, escaped when rendered.
    pub heading: String,
    /// Already escaped HTML, built by the methods below.
    pub body: String,
}

impl Section {
    /// An empty section; in `id` every character but ASCII letters and digits becomes `-`.
    pub fn new(id: &str, heading: &str) -> Section {
        Section {
            id: id
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
                .collect(),
            heading: heading.to_owned(),
            body: String::new(),
        }
    }

    /// Appends a paragraph of plain text.
    pub fn para(&mut self, text: &str) -> &mut Section {
        let _ = writeln!(self.body, "<p>{}</p>", escape(text));
        self
    }

    /// Appends a paragraph with a CSS class (`note`, `warn`).
    pub fn para_class(&mut self, class: &str, text: &str) -> &mut Section {
        let _ = writeln!(self.body, "<p class=\"{class}\">{}</p>", escape(text));
        self
    }

    /// Appends an `<h3>` sub-heading.
    pub fn sub(&mut self, text: &str) -> &mut Section {
        let _ = writeln!(self.body, "<h3>{}</h3>", escape(text));
        self
    }

    /// Appends raw HTML (an SVG figure, a table).
    pub fn raw(&mut self, html: &str) -> &mut Section {
        self.body.push_str(html);
        if !html.ends_with('\n') {
            self.body.push('\n');
        }
        self
    }

    /// Appends a figure: an inline SVG and its caption.
    pub fn figure(&mut self, svg: &str, caption: &str) -> &mut Section {
        let _ = writeln!(
            self.body,
            "<figure>\n{svg}<figcaption>{}</figcaption>\n</figure>",
            escape(caption)
        );
        self
    }
}

/// A table cell: text and how it is set (`n`: a number, right-aligned with tabular digits;
/// `code`: a hash or path, monospace, broken anywhere so a narrow page keeps the table).
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// Plain text, escaped when rendered.
    pub text: String,
    /// The CSS class that sets it, if any.
    pub class: Option<&'static str>,
}

impl Cell {
    /// A plain text cell.
    pub fn text(s: impl Into<String>) -> Cell {
        Cell {
            text: s.into(),
            class: None,
        }
    }

    /// A number cell.
    pub fn num(s: impl Into<String>) -> Cell {
        Cell {
            text: s.into(),
            class: Some("n"),
        }
    }

    /// A hash or path cell.
    pub fn code(s: impl Into<String>) -> Cell {
        Cell {
            text: s.into(),
            class: Some("code"),
        }
    }
}

/// A table row and an optional CSS class (`outlier` highlights it).
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The cells in column order.
    pub cells: Vec<Cell>,
    /// The CSS class of the row, if any.
    pub class: Option<&'static str>,
}

impl Row {
    /// A row with no class.
    pub fn new(cells: Vec<Cell>) -> Row {
        Row { cells, class: None }
    }

    /// The row with CSS class `class`.
    pub fn with_class(mut self, class: &'static str) -> Row {
        self.class = Some(class);
        self
    }
}

/// A data table: header cells and rows; every text is escaped.
pub fn table(headers: &[&str], rows: &[Row]) -> String {
    let mut s = String::from("<table>\n<thead><tr>");
    for h in headers {
        let _ = write!(s, "<th>{}</th>", escape(h));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for r in rows {
        match r.class {
            Some(c) => {
                let _ = write!(s, "<tr class=\"{c}\">");
            }
            None => s.push_str("<tr>"),
        }
        for c in &r.cells {
            match c.class {
                Some(class) => {
                    let _ = write!(s, "<td class=\"{class}\">{}</td>", escape(&c.text));
                }
                None => {
                    let _ = write!(s, "<td>{}</td>", escape(&c.text));
                }
            }
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table>\n");
    s
}

/// A two-column list of what and value (`<dl>`), for key figures.
pub fn definitions(items: &[(&str, String)]) -> String {
    let mut s = String::from("<dl class=\"figures\">\n");
    for (k, v) in items {
        let _ = writeln!(s, "<dt>{}</dt><dd>{}</dd>", escape(k), escape(v));
    }
    s.push_str("</dl>\n");
    s
}

/// The stylesheet: system fonts only, print rules that start each section on a new page and
/// keep figures and table rows whole.
const STYLE: &str = "\
:root { color-scheme: light; }
body { font-family: system-ui, -apple-system, 'Segoe UI', Roboto, 'DejaVu Sans', sans-serif;
  margin: 0 auto; max-width: 1100px; padding: 1.5rem; color: #111; background: #fff; line-height: 1.4; }
h1 { font-size: 1.6rem; margin: 0 0 .3rem; }
h2 { font-size: 1.3rem; border-bottom: 2px solid #245; padding-bottom: .2rem; margin-top: 2rem; }
h3 { font-size: 1.05rem; margin: 1.2rem 0 .4rem; }
.meta { color: #444; margin: 0 0 1rem; }
nav ol { columns: 2; margin: .4rem 0 1rem; }
table { border-collapse: collapse; margin: .5rem 0 1rem; font-size: .85rem; max-width: 100%; }
th, td { border: 1px solid #bbb; padding: .15rem .45rem; vertical-align: top; }
td.code { font-family: ui-monospace, 'DejaVu Sans Mono', Consolas, monospace; font-size: .78rem; overflow-wrap: anywhere; }
table.lines code { white-space: pre-wrap; overflow-wrap: anywhere; }
th { background: #e8edf3; text-align: left; }
td.n { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
tr.outlier td { background: #fde2e2; }
code, .literal { font-family: ui-monospace, 'DejaVu Sans Mono', Consolas, monospace; font-size: .85rem; }
dl.figures { display: grid; grid-template-columns: max-content auto; gap: .25rem 1rem; }
dl.figures dt { font-weight: 600; }
dl.figures dd { margin: 0; font-family: ui-monospace, 'DejaVu Sans Mono', Consolas, monospace; overflow-wrap: anywhere; }
p.note { color: #444; font-size: .9rem; }
p.warn { color: #8a1c1c; font-weight: 600; }
figure { margin: .5rem 0 1rem; }
figcaption { font-size: .85rem; color: #333; }
.grid { display: grid; grid-template-columns: repeat(auto-fill, minmax(480px, 1fr)); gap: .5rem; }
svg { max-width: 100%; height: auto; background: #fff; }
svg text { font-family: system-ui, 'DejaVu Sans', sans-serif; font-size: 11px; fill: #222; }
svg .title { font-size: 13px; font-weight: 600; }
svg .axis { stroke: #333; stroke-width: 1; fill: none; }
svg .gridline { stroke: #ddd; stroke-width: 1; }
svg .curve { stroke: #1f4fa0; stroke-width: 1.6; fill: none; }
svg .band { fill: #1f4fa0; fill-opacity: .18; stroke: none; }
svg .knot { fill: #c62828; }
svg .bar { fill: #4a78c2; }
svg .bar.outlier { fill: #c62828; }
svg .bar.rp { fill: #8a8f98; }
svg .limit { stroke: #c62828; stroke-width: 1.2; stroke-dasharray: 6 3; }
svg .median { stroke: #555; stroke-width: 1; stroke-dasharray: 2 3; }
svg .marker { stroke: #c62828; stroke-width: 1.2; }
svg text.limit-label, svg text.marker-label { fill: #c62828; }
svg .point { fill: #c62828; }
footer { margin-top: 2rem; color: #555; font-size: .8rem; }
@page { size: A4; margin: 14mm; }
@media print {
  body { max-width: none; padding: 0; font-size: 10pt; }
  nav { display: none; }
  section { break-before: page; }
  section:first-of-type { break-before: auto; }
  figure, tr, dl.figures { break-inside: avoid; }
  h2, h3 { break-after: avoid; }
  .grid { grid-template-columns: 1fr 1fr; }
}
";

/// A whole report page.
#[derive(Clone, Debug, PartialEq)]
pub struct Page {
    /// The `<title>` and `<h1>`, plain text.
    pub title: String,
    /// One line under the title (what the report is of), plain text.
    pub subtitle: String,
    /// The sections in page order.
    pub sections: Vec<Section>,
}

impl Page {
    /// The document: doctype, inline stylesheet, a table of contents, the sections and a
    /// footer naming the trackfix version. No script, no external resource, no clock: the same
    /// inputs give the same bytes.
    pub fn render(&self) -> String {
        let mut s = String::new();
        s.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        s.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        let _ = writeln!(s, "<title>{}</title>", escape(&self.title));
        let _ = writeln!(s, "<style>\n{STYLE}</style>\n</head>\n<body>\n<header>");
        let _ = writeln!(s, "<h1>{}</h1>", escape(&self.title));
        let _ = writeln!(
            s,
            "<p class=\"meta\">{}</p>\n</header>",
            escape(&self.subtitle)
        );
        s.push_str("<nav aria-label=\"contents\"><ol>\n");
        for sec in &self.sections {
            let _ = writeln!(
                s,
                "<li><a href=\"#{}\">{}</a></li>",
                sec.id,
                escape(&sec.heading)
            );
        }
        s.push_str("</ol></nav>\n<main>\n");
        for sec in &self.sections {
            let _ = writeln!(
                s,
                "<section id=\"{}\">\n<h2>{}</h2>\n{}</section>",
                sec.id,
                escape(&sec.heading),
                sec.body
            );
        }
        let _ = writeln!(
            s,
            "</main>\n<footer>trackfix {}: one self-contained file; print it to PDF from the browser.</footer>\n</body>\n</html>",
            env!("CARGO_PKG_VERSION")
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_covers_markup_and_quotes() {
        assert_eq!(
            escape(r#"<a href="x">'T&C'</a>"#),
            "&lt;a href=&quot;x&quot;&gt;&#39;T&amp;C&#39;&lt;/a&gt;"
        );
        assert_eq!(escape("plain ä"), "plain ä");
    }

    #[test]
    fn section_ids_are_anchor_safe_and_headings_escaped() {
        let mut sec = Section::new("a b<c", "x < y");
        sec.para("1 & 2");
        let page = Page {
            title: "t".into(),
            subtitle: "s".into(),
            sections: vec![sec],
        };
        let html = page.render();
        assert!(html.contains("<section id=\"a-b-c\">\n<h2>x &lt; y</h2>"));
        assert!(html.contains("<a href=\"#a-b-c\">x &lt; y</a>"));
        assert!(html.contains("<p>1 &amp; 2</p>"));
    }

    #[test]
    fn table_escapes_cells_and_marks_numbers() {
        let t = table(
            &["name", "v"],
            &[Row::new(vec![Cell::text("<p1>"), Cell::num("1.5")]).with_class("outlier")],
        );
        assert!(
            t.contains("<tr class=\"outlier\"><td>&lt;p1&gt;</td><td class=\"n\">1.5</td></tr>")
        );
    }
}
