//! The one loop every transform runs: per target refuse → skid → frame → new pose → edits →
//! change record, then the program's offset calls and frame declarations. A transform is a
//! [`TargetRule`]: it says what it does at each step and nothing else.

use crate::geometry::Pose;
use crate::position::{
    FrameDecl, NonPositionRole, OffsetCall, ParsedFile, Position, Program, Reading,
};
use crate::syntax::Edit;

use super::edits::{ProgramEdits, TargetChange};
use super::policy::{Why, common_refusal, implausible_result, joint_target};
use super::refusal::{Refusal, RefusalKind};
use super::rewrite::{OrientationHint, pose_change, push_reversible_pose_edits};
use super::stamp::{KeptTarget, Stamp};

/// Where a rule is looking: the program (for frames declared in other files) and the file.
#[derive(Clone, Copy)]
pub(crate) struct Scope<'a> {
    pub program: &'a Program,
    pub file: &'a ParsedFile,
}

/// The outcome for one target: its edits and change record, nothing to do, or a refusal.
pub(crate) type Step = Result<Option<(Vec<Edit>, TargetChange)>, Box<Refusal>>;

/// What a rule makes of one target.
pub(crate) struct NewPose {
    /// The target's new pose.
    pub pose: Pose,
    /// How to write its orientation.
    pub hint: OrientationHint,
    /// The change the inverse transform will apply to this target read back from the written
    /// text (`zero`'s for `correct`), when the rule writes its results so that the inverse
    /// gives back the original text (docs/design.md §5, round trip). Given with the pose: both
    /// come from one evaluation of the track's deviation.
    pub undo: Option<Pose>,
}

/// What a rule does with the targets a file's provenance stamp lists as left as written by the
/// transform that wrote the file ([`Kept`](super::stamp::Kept)): those lack what the rest of the
/// file carries.
pub(crate) enum KeptByStamp {
    /// The rule undoes the stamp's transform: they are left as written, with a note whose
    /// message ends in `said`. `carry`: they are neither side's (a `transfer` left them as its
    /// source robot's program wrote them), and the stamp the run writes lists them again.
    Leave { said: String, carry: bool },
    /// The rule would treat them as it treats the rest, which is wrong for them: refused, each
    /// with the kind of its first refusal, the message ending in `said`.
    Refuse { said: String },
}

/// What one transform does to each target, offset call and frame declaration.
pub(crate) trait TargetRule {
    /// What the rule needs from a target's work object (its pose, a mirror plane in it, …).
    type Frame;

    /// The fields of each target the rule and the driver read: every one unless the rule says
    /// it reads fewer, whose decoding is then left out.
    fn reading(&self) -> Reading {
        Reading::Whole
    }

    /// A joint target: refused unless the rule changes joints.
    fn joint(&self, scope: Scope, p: &Position) -> Step {
        Err(joint_target(p).at(scope.file, p))
    }

    /// The checks before a Cartesian target is touched (docs/design.md §4).
    fn refusal(&self, scope: Scope, p: &Position) -> Option<Why> {
        common_refusal(scope.file, p)
    }

    /// The target's skid, for the change record; a refusal if the rule needs one it lacks.
    fn skid(&self, scope: Scope, p: &Position) -> Result<Option<f64>, Why>;

    /// The target's work object as the rule needs it.
    fn frame(&self, scope: Scope, p: &Position) -> Result<Self::Frame, Why>;

    /// The new pose of a target at `t`, how to write its orientation, and the inverse's change.
    fn new_pose(
        &self,
        p: &Position,
        frame: &Self::Frame,
        skid: Option<f64>,
        t: &Pose,
    ) -> Result<NewPose, Why>;

    /// Whether what the program uses as `role` stays right as written under the rule (see
    /// [`NonPositionRole`]): so under the track rules, which move the robot's base and keep its
    /// joint ranges; not a mirror's joint limits or offsets.
    fn keeps(&self, role: NonPositionRole) -> bool {
        let _ = role;
        true
    }

    /// What the rule does with the targets `stamp` lists as kept as written (`None`: what it does
    /// with every target).
    fn kept_by_stamp(&self, stamp: &Stamp) -> Option<KeptByStamp> {
        let _ = stamp;
        None
    }

    /// Whether the rule writes KUKA targets at B = ±90° with the split a `correct` recorded in
    /// the file's stamp (`zero`, the inverse of `correct`; docs/design.md §5, round trip).
    fn keeps_lock_splits(&self) -> bool {
        false
    }

    /// The expanded uncertainty (k = 2, mm) of the new target's TCP, when the rule knows one.
    fn uncertainty(&self, _frame: &Self::Frame, _skid: Option<f64>, _new: &Pose) -> Option<f64> {
        None
    }

    /// Edits beyond the pose (configuration, skid axes).
    fn more_edits(&self, _scope: Scope, _p: &Position) -> Vec<Edit> {
        Vec::new()
    }

    /// The edits of an `Offs`/`RelTool` call.
    fn offset(&self, _scope: Scope, _call: &OffsetCall) -> Result<Vec<Edit>, Box<Refusal>> {
        Ok(Vec::new())
    }

    /// The edits of a work object, base or tool declaration.
    fn declaration(&self, _scope: Scope, _decl: &FrameDecl) -> Vec<Edit> {
        Vec::new()
    }
}

/// Runs `rule` over every target, offset call and frame declaration of `program`.
pub(crate) fn apply_rule<R: TargetRule>(program: &Program, rule: &R) -> ProgramEdits {
    let mut out = ProgramEdits::for_program(program);
    // The targets left as written, by (file, index), whose offset calls stay as written.
    let mut refused = Vec::new();
    for (fi, (file, fe)) in program.files.iter().zip(out.files.iter_mut()).enumerate() {
        let scope = Scope { program, file };
        let stamp = super::stamp::find(file).map(|(s, _)| s);
        let splits = stamp
            .as_ref()
            .filter(|_| rule.keeps_lock_splits())
            .map(|s| s.gimbal.clone())
            .unwrap_or_default();
        // A record out of step with its file says nothing of which targets it lists, and is
        // not read (the command line refuses such a file before, `Kept::out_of_step`).
        let kept_by_stamp = stamp
            .as_ref()
            .filter(|s| !s.kept.targets.is_empty() && s.kept.out_of_step(file).is_none())
            .and_then(|s| Some((s, rule.kept_by_stamp(s)?)));
        // One vector for the edits of every target, emptied into the file's edits.
        let mut edits = Vec::new();
        let reading = rule.reading();
        let mut memo = crate::position::DecodeMemo::default();
        let mut listed = kept_by_stamp
            .as_ref()
            .map(|(s, _)| s.kept.targets.as_slice())
            .unwrap_or_default()
            .iter()
            .peekable();
        for i in 0..file.positions.len() {
            let p = file
                .positions
                .decoded_with(i, &file.source, reading, &mut memo);
            edits.clear();
            let by_stamp = listed.next_if(|k| k.index == i);
            let step = if let (Some(k), Some((s, how))) = (by_stamp, &kept_by_stamp) {
                let what = super::policy::describe(&p);
                let by = format!(
                    "{what} was left as written by the `{}` this file's stamp records (refused as {})",
                    s.command,
                    super::stamp::kind_name(k.kind)
                );
                match how {
                    KeptByStamp::Leave { said, carry } => {
                        refused.push(((fi, i), k.kind));
                        if *carry {
                            fe.kept.push(k.clone());
                        }
                        let hint = if *carry {
                            "left as written; the stamp written lists it as kept again"
                        } else {
                            "left as written"
                        };
                        fe.notes.push(*Why::new(RefusalKind::KeptAsWritten, format!("{by}: {said}"), hint).at(file, &p));
                        continue;
                    }
                    KeptByStamp::Refuse { said } => Err(Why::new(
                        k.kind,
                        format!("{by}: {said}"),
                        format!(
                            "transform the file that `{}` read, or fix the target and run `{}` on it again",
                            s.command, s.command
                        ),
                    )
                    .at(file, &p)),
                }
            } else if let Some(np) = p.usage.non_position() {
                Err(super::policy::non_position(np, &p, rule.keeps(np.role)).at(file, &p))
            } else if p.kind.is_cartesian() {
                cartesian(rule, scope, &p, splits.a_of(i), &mut edits)
            } else {
                match (rule.joint(scope, &p), super::policy::run_time(&p)) {
                    // A joint target the rule would move, but whose value the program computes
                    // when it runs (`jPark := CalcJointT(…)`): refused as a Cartesian one is.
                    (Ok(Some(_)), Some(why)) => Err(why.at(file, &p)),
                    (step, _) => step.map(|step| {
                        step.map(|(joint_edits, change)| {
                            edits = joint_edits;
                            change
                        })
                    }),
                }
            };
            match step {
                Ok(Some(change)) if !edits.is_empty() => {
                    fe.edits.extend(edits.drain(..));
                    fe.changes.push(change);
                }
                Ok(_) => {}
                // An unset array slot, a world zone's tolerance: not targets, worth a note,
                // never a refusal.
                Err(r) if r.kind.is_note() => fe.notes.push(*r),
                Err(r) => {
                    refused.push(((fi, i), r.kind));
                    fe.kept.push(KeptTarget {
                        index: i,
                        kind: r.kind,
                        name: file.positions.name(i).map(str::to_owned),
                    });
                    fe.refusals.push(*r);
                }
            }
        }
    }
    // An offset call of a target left as written stays as written with it.
    let kept = super::policy::KeptTargets::of(refused);
    for (file, fe) in program.files.iter().zip(out.files.iter_mut()) {
        let scope = Scope { program, file };
        for call in &file.offsets {
            match kept.kept_bases(call) {
                0 => {}
                n if n == call.bases.len() => continue,
                n => {
                    let why = super::policy::partly_kept_offset(call, n);
                    fe.refusals.push(*why.at_call(file, call));
                    continue;
                }
            }
            match rule.offset(scope, call) {
                Ok(edits) => fe.edits.extend(edits),
                Err(r) => fe.refusals.push(*r),
            }
        }
        for decl in file.frames.iter().chain(&file.frame_values) {
            fe.edits.extend(rule.declaration(scope, decl));
        }
    }
    out
}

/// One Cartesian target, its edits appended to `edits`; `keep_a`: the A its file's stamp
/// recorded for it at B = ±90°.
fn cartesian<R: TargetRule>(
    rule: &R,
    scope: Scope,
    p: &Position,
    keep_a: Option<f64>,
    edits: &mut Vec<Edit>,
) -> Result<Option<TargetChange>, Box<Refusal>> {
    let refuse = |why: Why| why.at(scope.file, p);
    if let Some(why) = rule.refusal(scope, p) {
        return Err(refuse(why));
    }
    let skid = rule.skid(scope, p).map_err(refuse)?;
    let frame = rule.frame(scope, p).map_err(refuse)?;
    // `refusal` has refused targets whose fields are not all numbers.
    let Some(fields) = p.cartesian.as_ref() else {
        return Ok(None);
    };
    let Some(t) = fields.pose() else {
        return Ok(None);
    };
    let NewPose {
        pose: new,
        hint,
        undo,
    } = rule.new_pose(p, &frame, skid, &t).map_err(refuse)?;
    if let Some(why) = implausible_result(p, &new, scope.file.language.dialect().vocabulary()) {
        return Err(refuse(why));
    }
    push_reversible_pose_edits(edits, fields, Some(t), &new, hint, undo.as_ref(), keep_a);
    edits.extend(rule.more_edits(scope, p));
    let (mm, deg) = pose_change(&t, &new);
    let uncertainty_mm = rule.uncertainty(&frame, skid, &new);
    Ok(Some(TargetChange {
        mm,
        deg,
        skid,
        name: p.name.clone(),
        line: p.line,
        axes_deg: None,
        uncertainty_mm,
    }))
}
