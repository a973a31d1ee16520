//! Errors that render themselves: a [`Diagnostic`] about a named source, shown on `Display` as
//! `path:line:col: severity: message`, the line, a caret and the hint. The library returns the
//! data; whoever shows it (the CLI) picks the severity and prints it.

use std::ops::Range;
use std::path::PathBuf;

use crate::syntax::{Diagnostic, Encoding, Excerpt, LineIndex, Severity, Span};

/// A diagnostic located in one source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Located {
    /// The file, as the user named it (shown in the `path:line:col` prefix).
    pub path: PathBuf,
    /// The source the diagnostic's span points into: the whole file, or (see [`LineAt`]) only
    /// the piece of the line it shows.
    pub source: Vec<u8>,
    /// What is wrong, where, and what to do.
    pub diagnostic: Diagnostic,
    /// Set when `source` is a piece of one line rather than the file.
    pub at: Option<LineAt>,
    /// How `source`'s bytes are text: Latin-1 for a program, UTF-8 for a TOML file.
    pub encoding: Encoding,
}

/// Where a one-line excerpt sits in its file (see [`Excerpt`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LineAt {
    /// 1-based line of the span's start.
    pub line: usize,
    /// 1-based column (bytes) of the span's start.
    pub column: usize,
    /// Byte offset of the excerpt in the file.
    pub start: usize,
    /// The line goes on before the excerpt (it was cut to a window around the span).
    pub cut_before: bool,
    /// The line goes on after the excerpt.
    pub cut_after: bool,
}

impl LineAt {
    /// Where `span` starts in `source` (whose lines `index` holds), and the bytes of its line
    /// an excerpt shows: the whole line, or a window around the span of a long one.
    pub(crate) fn of(source: &[u8], index: &LineIndex, span: Span) -> (LineAt, Range<usize>) {
        let (line, column) = index.line_col(span.start);
        let line_span = index.line_span(source, line);
        let len = line_span.end - line_span.start;
        let at = span.start.saturating_sub(line_span.start).min(len);
        let end = span.end.saturating_sub(line_span.start).clamp(at, len);
        let (from, to) = crate::syntax::window(len, at, end);
        let at = LineAt {
            line,
            column,
            start: line_span.start + from,
            cut_before: from > 0,
            cut_after: to < len,
        };
        (at, line_span.start + from..line_span.start + to)
    }
}

impl Located {
    /// The diagnostic about `source`, read from `path`.
    pub fn new(path: impl Into<PathBuf>, source: Vec<u8>, diagnostic: Diagnostic) -> Located {
        Located {
            path: path.into(),
            source,
            diagnostic,
            at: None,
            encoding: Encoding::Latin1,
        }
    }

    /// A diagnostic that keeps only the piece of its line it shows (memory stays small however
    /// long the line): `text` starts at `at.start` of the file; the span is in file offsets.
    pub fn excerpt(
        path: impl Into<PathBuf>,
        text: Vec<u8>,
        at: LineAt,
        diagnostic: Diagnostic,
    ) -> Located {
        Located {
            path: path.into(),
            source: text,
            diagnostic,
            at: Some(at),
            encoding: Encoding::Latin1,
        }
    }

    /// The diagnostic about `source`, keeping only the window of the span's line it shows (the
    /// error then stays small however large the file is).
    pub fn in_line(path: impl Into<PathBuf>, source: &[u8], diagnostic: Diagnostic) -> Located {
        let (at, shown) = LineAt::of(source, &LineIndex::new(source), diagnostic.span);
        Located::excerpt(path, source[shown].to_vec(), at, diagnostic)
    }

    /// The same diagnostic about a source whose text is in `encoding` (a program's is Latin-1,
    /// the default).
    pub fn in_encoding(mut self, encoding: Encoding) -> Located {
        self.encoding = encoding;
        self
    }

    /// The same message at another severity (a refusal the run skips is a warning).
    pub fn with_severity(mut self, severity: Severity) -> Located {
        self.diagnostic.severity = severity;
        self
    }

    /// 1-based line and column of the diagnostic.
    pub fn line_col(&self) -> (usize, usize) {
        match self.at {
            Some(at) => (at.line, at.column),
            None => LineIndex::new(&self.source).line_col(self.diagnostic.span.start),
        }
    }
}

impl std::fmt::Display for Located {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let path = self.path.display().to_string();
        let text = match self.at {
            Some(at) => self.diagnostic.render_excerpt(
                &path,
                &Excerpt {
                    line: at.line,
                    column: at.column,
                    text: &self.source,
                    start: at.start,
                    cut_before: at.cut_before,
                    cut_after: at.cut_after,
                    encoding: self.encoding,
                },
            ),
            None => {
                let index = LineIndex::new(&self.source);
                self.diagnostic
                    .render_in(&path, &self.source, &index, self.encoding)
            }
        };
        f.write_str(text.trim_end())
    }
}

impl std::error::Error for Located {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::syntax::Span;

    #[test]
    fn renders_path_line_caret_and_hint_at_the_chosen_severity() {
        let d = Diagnostic::error(Span::new(9, 11), "no `p1`").with_hint("declare it");
        let l = Located::new("m.mod", b"MODULE m\np1;\n".to_vec(), d);
        assert_eq!(l.line_col(), (2, 1));
        assert_eq!(
            l.clone().with_severity(Severity::Warning).to_string(),
            "m.mod:2:1: warning: no `p1`\n  |\n2 | p1;\n  | ^^\n  = help: declare it"
        );
        assert!(l.to_string().starts_with("m.mod:2:1: error: "));
    }

    #[test]
    fn in_line_keeps_the_line_and_renders_as_the_whole_source_does() {
        let src = b"MODULE m\r\n  p1;\r\nENDMODULE\r\n";
        let d = Diagnostic::error(Span::new(12, 14), "no `p1`").with_hint("declare it");
        let whole = Located::new("m.mod", src.to_vec(), d.clone());
        let cut = Located::in_line("m.mod", src, d);
        assert_eq!(cut.line_col(), (2, 3));
        assert_eq!(cut.source, b"  p1;");
        assert_eq!(cut.to_string(), whole.to_string());
    }
}
