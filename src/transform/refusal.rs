//! Targets a transform will not change, each with its location and what to do (DESIGN.md §4).

use std::path::PathBuf;

use crate::located::Located;
use crate::position::ParsedFile;
use crate::syntax::{Diagnostic, Severity, Span};

/// Why a target is left untouched.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RefusalKind {
    /// A joint target (`jointtarget`, `E6AXIS`, `AXIS`).
    JointTarget,
    /// A field of the target is an expression, not a numeric literal.
    Expression,
    /// The target is used with two different work objects / bases.
    TwoWorkObjects,
    /// The work object is moved by a mechanical unit (`ufprog FALSE`).
    MovingWorkObject,
    /// Stationary tool (`robhold TRUE`, KRL `IPO_FRAME #TCP`).
    StationaryTool,
    /// The skid axis is `9E9` (not connected).
    SkidNotConnected,
    /// The skid axis is not written.
    SkidMissing,
    /// The skid lies outside the profile (under `extrapolate = "error"`).
    SkidOutOfRange,
    /// The work object / base could not be found or has non-numeric fields.
    UnresolvedWorkObject,
    /// Coordinates beyond any robot cell (over 1 km): a typo or a placeholder, not a target.
    Implausible,
    /// An all-zero quaternion: an unset slot (e.g. of a `PERS` array), not an orientation.
    ZeroQuaternion,
    /// With the robot's kinematics: the target is out of reach, outside the joint limits or in
    /// another configuration than written, before or after the transform; or its tool is
    /// unknown, so it cannot be checked.
    Reach,
}

/// A setting of the transform that gets past a refusal; whoever shows the refusal says how to
/// give it (the CLI names its flag). Every refusal can also be skipped, leaving the target as
/// written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Remedy {
    /// Name the work object of declared targets no motion uses.
    DefaultWorkObject,
    /// Mirror joint targets too (axes 1, 4 and 6 negated).
    MirrorJoints,
}

/// The refused target's line, so that a refusal renders without its whole file.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Excerpt {
    /// The line's bytes, without its terminator.
    text: Vec<u8>,
    /// Byte offset of the line's start in the file.
    start: usize,
}

/// One refused target.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Refusal {
    pub path: PathBuf,
    pub line: usize,
    pub column: usize,
    /// The refused literal or call in the file.
    #[serde(skip)]
    pub span: Span,
    /// The target's name or `inline robtarget`.
    pub target: String,
    pub kind: RefusalKind,
    pub message: String,
    /// What to do, in words (no command-line flags).
    pub hint: String,
    /// A transform setting that gets past it, when there is one.
    pub remedy: Option<Remedy>,
    #[serde(skip)]
    excerpt: Excerpt,
}

impl Refusal {
    pub(crate) fn new(
        file: &ParsedFile,
        span: Span,
        target: String,
        kind: RefusalKind,
        message: String,
        hint: impl Into<String>,
        remedy: Option<Remedy>,
    ) -> Refusal {
        let (line, column) = file.lines.line_col(span.start);
        let line_span = file.lines.line_span(&file.source, line);
        Refusal {
            path: file.path.clone(),
            line,
            column,
            span,
            target,
            kind,
            message,
            hint: hint.into(),
            remedy,
            excerpt: Excerpt {
                text: line_span.slice(&file.source).to_vec(),
                start: line_span.start,
            },
        }
    }

    /// The refusal as a located diagnostic at `severity` with `hint` (the renderer's words for
    /// what to do), rendered on `Display` with the refused line and a caret.
    pub fn located(&self, severity: Severity, hint: impl Into<String>) -> Located {
        // Only the refused line is kept: empty lines before it put it at its own line number.
        let pad = self.line.saturating_sub(1);
        let mut source = vec![b'\n'; pad];
        source.extend_from_slice(&self.excerpt.text);
        let at = |offset: usize| pad + offset.saturating_sub(self.excerpt.start);
        let span = Span::new(at(self.span.start), at(self.span.end));
        let d = Diagnostic::new(severity, span, self.message.clone()).with_hint(hint);
        Located::new(self.path.clone(), source, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::test_support::rapid;

    #[test]
    fn a_refusal_renders_its_own_line_at_its_line_number_and_chosen_severity() {
        let p = rapid(
            "x\n\ty\n\t[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]\n",
            "w",
        );
        let f = &p.files[0];
        let target = &f.positions[0];
        let span = Span::new(target.span.start + 1, target.span.start + 8);
        let r = Refusal::new(
            f,
            span,
            "p3".into(),
            RefusalKind::SkidNotConnected,
            "no skid".into(),
            "write one",
            None,
        );
        assert_eq!((r.line, r.column), (3, 2));
        let text = r
            .located(Severity::Warning, "write one (left unchanged)")
            .to_string();
        assert_eq!(
            text,
            "t.mod:3:2: warning: no skid\n  |\n3 | \t[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]\n  | \t^^^^^^^\n  = help: write one (left unchanged)"
        );
    }
}
