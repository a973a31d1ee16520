//! Targets a transform will not change, each with its location and what to do (docs/design.md §4).

use std::path::PathBuf;

use crate::located::{LineAt, Located};
use crate::position::ParsedFile;
use crate::syntax::{Diagnostic, Severity, Span};

/// Why a target is left untouched. Each kind can be kept as written on its own (the command
/// line's keep option takes exactly these, by their kebab-case names and the aliases below).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
#[value(rename_all = "kebab-case")]
pub enum RefusalKind {
    /// A joint target (`jointtarget`, `E6AXIS`, `AXIS`).
    #[value(alias = "joint-targets")]
    JointTarget,
    /// A field of the target is an expression, not a numeric literal.
    Expression,
    /// The target is used with two different work objects / bases, or with a work object or
    /// tool in two values (the program gives it another while a motion may still run with the
    /// declared one).
    #[value(alias = "two-wobjs")]
    TwoWorkObjects,
    /// An `Offs` offset that stands for several targets (an array's elements through a computed
    /// index, a routine's parameter) whose corrections turn it apart: one written offset cannot
    /// follow each.
    SharedOffset,
    /// The work object is moved by a mechanical unit (`ufprog FALSE`).
    MovingWorkObject,
    /// Stationary tool (a work object with `robhold TRUE` or a tool with `robhold FALSE`, KRL
    /// `IPO_FRAME #TCP`).
    StationaryTool,
    /// The skid axis is `9E9` (not connected).
    #[value(alias = "not-connected-skid")]
    SkidNotConnected,
    /// The skid axis is not written.
    SkidMissing,
    /// The skid lies outside the profile (under `extrapolate = "error"`).
    SkidOutOfRange,
    /// The work object / base could not be found or has non-numeric fields.
    #[value(alias = "unresolved-wobj", alias = "unresolved-base")]
    UnresolvedWorkObject,
    /// Coordinates beyond any robot cell (over 1 km), an angle beyond a turn, a configuration
    /// that is not a small integer: a typo or a placeholder, not a target.
    Implausible,
    /// The computed pose is not finite or lies beyond any robot cell (an absurd profile or
    /// cell value): nothing is written for it.
    #[value(alias = "non-finite")]
    ImplausibleResult,
    /// The target's pose is only known when the program runs: the program computes the target
    /// (`p10 := CRobT()`, a `PERS` array filled by the program) or the work object / base it is
    /// used with (`wobj1.uframe := …`, `$BASE = EK(…)`). Not correctable offline.
    RuntimeData,
    /// An all-zero quaternion: an unset slot (e.g. of a `PERS` array), not an orientation and
    /// not a target: reported as a note, never a refusal (so nothing to keep).
    #[value(skip)]
    ZeroQuaternion,
    /// A joint target a world zone takes as its joint limits (RAPID `WZLimJointDef`): not a
    /// position, and the mirrored robot's limits are not a transform of it.
    WorldZoneLimits,
    /// A mirror of a position the program adds to a frame with KRL's geometric operator `:`
    /// (`FPALLET:SLOT:XPLACE_REL`): an offset in the frame before it, whose mirror image is the
    /// offset reflected in that frame, not a transform of a target.
    ComposedOffset,
    /// A target the program uses as other than a position, right as written under the
    /// transform: a world zone's tolerance (RAPID `WZHomeJointDef`'s `DeltaJointVal`), its
    /// joint limits where the robot's joint ranges stay, a KRL offset after `:` under a track
    /// correction. Reported as a note, never a refusal (so nothing to keep).
    #[value(skip)]
    NotAPosition,
    /// A KRL point held in a member of a structure (`DECL SPT S1={P {X …, E1 500}, K 1}`): the
    /// structure's values travel where trackfix does not follow a member (a copy of the whole
    /// structure, an array of structures, a parameter, another module), so the base the robot
    /// moves to it in is not known.
    StructureMember,
    /// With the robot's kinematics: the target is out of reach, outside the joint limits or in
    /// another configuration than written, before or after the transform; a target whose move
    /// would turn an axis by more than 5° (axes 4 and 6, near the wrist singularity); or its
    /// tool is unknown, so it cannot be checked.
    Reach,
    /// A target the file's provenance stamp lists as left as written by the transform that
    /// wrote the file, which the transform now undoing that one leaves as written too (it never
    /// carried what is undone). Reported as a note, never a refusal (so nothing to keep).
    #[value(skip)]
    KeptAsWritten,
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

impl RefusalKind {
    /// The target's values are only known when the program runs: no offline transform can
    /// correct it, so summaries count such refusals apart from the ones a change to the program
    /// would fix. (An unset `[0,0,0,0]` slot is a note, not a refusal.)
    pub fn is_runtime_data(self) -> bool {
        matches!(self, RefusalKind::RuntimeData)
    }

    /// Said of something that is no target, as a note: never a refusal, nothing to keep.
    pub fn is_note(self) -> bool {
        matches!(
            self,
            RefusalKind::ZeroQuaternion | RefusalKind::NotAPosition | RefusalKind::KeptAsWritten
        )
    }
}

/// One refused target.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Refusal {
    /// The file the target is in.
    pub path: PathBuf,
    /// 1-based line of the refused literal or call.
    pub line: usize,
    /// 1-based column of its start.
    pub column: usize,
    /// The refused literal or call in the file.
    #[serde(skip)]
    pub span: Span,
    /// The target's name or `inline robtarget`.
    pub target: String,
    /// Why, as a category the caller can match on.
    pub kind: RefusalKind,
    /// Why, in words.
    pub message: String,
    /// What to do, in words (no command-line flags).
    pub hint: String,
    /// A transform setting that gets past it, when there is one.
    pub remedy: Option<Remedy>,
    /// Where the excerpt of the refused line sits in the file.
    #[serde(skip)]
    at: LineAt,
    /// The piece of the refused line a diagnostic shows (at most a window of
    /// [`WINDOW`](crate::syntax::WINDOW) bytes around the span), so a refusal renders without
    /// its file and a line of 2,000 targets costs 2,000 small excerpts, not 2,000 copies of it.
    #[serde(skip)]
    excerpt: Vec<u8>,
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
        let (at, shown) = LineAt::of(&file.source, &file.lines, span);
        Refusal {
            path: file.path.clone(),
            line: at.line,
            column: at.column,
            span,
            target,
            kind,
            message,
            hint: hint.into(),
            remedy,
            at,
            excerpt: file.source[shown].to_vec(),
        }
    }

    /// The same refusal of the same target, at `span` of `file`: where a chain of transforms
    /// places a refusal one of its later steps made in a file of its own.
    pub(crate) fn placed_in(&self, file: &ParsedFile, span: Span) -> Refusal {
        Refusal::new(
            file,
            span,
            self.target.clone(),
            self.kind,
            self.message.clone(),
            self.hint.clone(),
            self.remedy,
        )
    }

    /// The refusal as a located diagnostic at `severity` with `hint` (the renderer's words for
    /// what to do), rendered on `Display` with the refused line and a caret.
    pub fn located(&self, severity: Severity, hint: impl Into<String>) -> Located {
        let d = Diagnostic::new(severity, self.span, self.message.clone()).with_hint(hint);
        Located::excerpt(self.path.clone(), self.excerpt.clone(), self.at, d)
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
        let target = &f.position(0).unwrap();
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
