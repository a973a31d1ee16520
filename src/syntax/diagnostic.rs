//! Located messages about a source file, rendered the way compilers do.
#![warn(missing_docs, unreachable_pub)]

use super::{LineIndex, Span};
use std::fmt::Write as _;

/// How serious a diagnostic is, least first. The parser's choice is a default: whoever renders
/// it (the CLI) may show it at another severity (`docs/design.md §8`, errors that render
/// themselves).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Information: nothing is wrong.
    Note,
    /// Something to check; the result is still complete.
    Warning,
    /// The input cannot be used as it is.
    Error,
}

impl Severity {
    /// The word the rendering prints (`note`, `warning`, `error`).
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Note => "note",
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
}

/// A message about the bytes `span` of one source, with an optional hint saying what to do.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Diagnostic {
    /// How serious it is.
    pub severity: Severity,
    /// The bytes of the source it is about (the caret covers them).
    pub span: Span,
    /// What is wrong, in one line.
    pub message: String,
    /// What to do about it (rendered as `= help: …`).
    pub hint: Option<String>,
}

impl Diagnostic {
    /// A diagnostic without a hint.
    pub fn new(severity: Severity, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity,
            span,
            message: message.into(),
            hint: None,
        }
    }

    /// An error without a hint.
    pub fn error(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Error, span, message)
    }

    /// A warning without a hint.
    pub fn warning(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Warning, span, message)
    }

    /// A note without a hint.
    pub fn note(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Note, span, message)
    }

    /// The same diagnostic with `hint` as what to do.
    pub fn with_hint(mut self, hint: impl Into<String>) -> Diagnostic {
        self.hint = Some(hint.into());
        self
    }

    /// `path:line:column: severity: message`, the source line, a caret line and the hint.
    ///
    /// Bytes are shown as Latin-1 so that a Windows-125x comment never breaks the caret's column.
    pub fn render(&self, path: &str, src: &[u8], index: &LineIndex) -> String {
        let (line, col) = index.line_col(self.span.start);
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{path}:{line}:{col}: {}: {}",
            self.severity.as_str(),
            self.message
        );
        let text_span = index.line_span(src, line);
        let text = text_span.slice(src);
        let gutter = line.to_string().len();
        let _ = writeln!(out, "{:gutter$} |", "");
        let _ = writeln!(out, "{line} | {}", latin1(text));
        let caret_start = col - 1;
        let caret_len = self
            .span
            .end
            .min(text_span.end)
            .saturating_sub(self.span.start)
            .max(1);
        let pad: String = text
            .iter()
            .take(caret_start)
            .map(|&b| if b == b'\t' { '\t' } else { ' ' })
            .collect();
        let _ = writeln!(out, "{:gutter$} | {pad}{}", "", "^".repeat(caret_len));
        if let Some(hint) = &self.hint {
            let _ = writeln!(out, "{:gutter$} = help: {hint}", "");
        }
        out
    }
}

/// Bytes as Latin-1 text: every byte is one char, so columns stay columns.
pub fn latin1(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| b as char).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_location_line_and_caret() {
        let src = b"MODULE m\r\n  MoveL p1 v100;\r\nENDMODULE";
        let idx = LineIndex::new(src);
        let d = Diagnostic::error(Span::new(18, 20), "unknown target `p1`")
            .with_hint("declare it or check the spelling");
        let text = d.render("m.mod", src, &idx);
        assert_eq!(
            text,
            "m.mod:2:9: error: unknown target `p1`\n  |\n2 |   MoveL p1 v100;\n  |         ^^\n  = help: declare it or check the spelling\n"
        );
    }
}
