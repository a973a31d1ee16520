//! Targets a transform will not change, each with its location and what to do (DESIGN.md §4).

use std::path::PathBuf;

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
}

/// One refused target.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Refusal {
    pub path: PathBuf,
    pub line: usize,
    pub column: usize,
    /// The target's name or `inline robtarget`.
    pub target: String,
    pub kind: RefusalKind,
    pub message: String,
    pub hint: String,
    /// `file:line:col: error: …`, the line, a caret and the hint.
    pub rendered: String,
}

impl Refusal {
    pub(crate) fn new(
        file: &ParsedFile,
        span: Span,
        target: String,
        kind: RefusalKind,
        message: String,
        hint: impl Into<String>,
    ) -> Refusal {
        let hint = hint.into();
        let (line, column) = file.lines.line_col(span.start);
        let d = Diagnostic::new(Severity::Error, span, message.clone()).with_hint(hint.clone());
        Refusal {
            path: file.path.clone(),
            line,
            column,
            target,
            kind,
            message,
            hint,
            rendered: file.render(&d),
        }
    }
}

/// The hint printed under every refusal: how to get past it.
pub(crate) const SKIP_HINT: &str = "or pass --skip-unsupported to leave it unchanged";
