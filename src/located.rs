//! Errors that render themselves: a [`Diagnostic`] about a named source, shown on `Display` as
//! `path:line:col: severity: message`, the line, a caret and the hint. The library returns the
//! data; whoever shows it (the CLI) picks the severity and prints it.

use std::path::PathBuf;

use crate::syntax::{Diagnostic, LineIndex, Severity};

/// A diagnostic located in one source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Located {
    /// The file, as the user named it (shown in the `path:line:col` prefix).
    pub path: PathBuf,
    /// The source the diagnostic's span points into.
    pub source: Vec<u8>,
    /// What is wrong, where, and what to do.
    pub diagnostic: Diagnostic,
}

impl Located {
    /// The diagnostic about `source`, read from `path`.
    pub fn new(path: impl Into<PathBuf>, source: Vec<u8>, diagnostic: Diagnostic) -> Located {
        Located {
            path: path.into(),
            source,
            diagnostic,
        }
    }

    /// The same message at another severity (a refusal the run skips is a warning).
    pub fn with_severity(mut self, severity: Severity) -> Located {
        self.diagnostic.severity = severity;
        self
    }

    /// 1-based line and column of the diagnostic.
    pub fn line_col(&self) -> (usize, usize) {
        LineIndex::new(&self.source).line_col(self.diagnostic.span.start)
    }
}

impl std::fmt::Display for Located {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let index = LineIndex::new(&self.source);
        let text = self
            .diagnostic
            .render(&self.path.display().to_string(), &self.source, &index);
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
}
