//! `transfer` (docs/design.md §4): zero with robot A, optionally mirror, correct with robot B.
//!
//! The three steps run through text exactly as three commands in a row would: each step's output
//! is parsed again before the next, so the written precision rounds in the same places and
//! `transfer` equals `zero; mirror; correct` byte for byte. Nothing is written between the steps:
//! RAPID re-parses the bytes, a KRL pair goes through `krl::load_program_from_sources`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use crate::position::{NumField, Orientation, ParsedFile, Position, Program};
use crate::program::{LoadError, LoadOptions};
use crate::syntax::{Edit, EditError, Span, apply_edits};

use super::edits::{FileResult, ProgramEdits, ProgramResult, TargetChange, apply};
use super::kinematic_policy::flange_move;
use super::mirror::{
    MirrorSettings, Reflection, joint_image_flange, mirror_reading, reflection_for,
};
use super::policy::KeptTargets;
use super::refusal::{Refusal, RefusalKind};
use super::rewrite::{DEG_DECIMALS, MM_DECIMALS, QUAT_DECIMALS, pose_change};
use super::stamp::StampReading;
use super::track_correction::{Direction, TrackSetup, track_rule};

/// Why a chain of transforms stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TransferError {
    /// A step's edits could not be applied (a bug of the step, not of the input).
    #[error(transparent)]
    Edit(#[from] EditError),
    /// A step's output could not be parsed again.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// A step's output has another number of targets than its input, so the steps' changes
    /// cannot be matched target by target.
    #[error("{}: the transformed file no longer has the same targets ({before} before, {after} after)", path.display())]
    Drift {
        /// The file.
        path: PathBuf,
        /// Targets before the step.
        before: usize,
        /// Targets after it.
        after: usize,
    },
}

/// The three steps of a transfer.
pub struct TransferPlan<'a> {
    /// The source robot's track: its deviation is taken out (`zero`).
    pub from: TrackSetup<'a>,
    /// The mirror between the two robots, when the target robot is a mirror image.
    pub mirror: Option<MirrorSettings>,
    /// The target robot's track: its deviation is put in (`correct`).
    pub to: TrackSetup<'a>,
}

/// Parses a transform's output again, as the next command of a chain would read it. File paths
/// stay the original ones.
pub fn reparse(
    program: &Program,
    result: &ProgramResult,
    options: &LoadOptions,
) -> Result<Program, TransferError> {
    let files = result
        .files
        .iter()
        .map(|f| (f.path.clone(), f.output.clone()))
        .collect();
    // The program's own dialect reads it again (a KRL pair through its loader, in memory, so
    // that the .src's motions resolve the .dat's targets exactly as on the command line).
    match program.language() {
        Some(language) => Ok(language.dialect().reparse(files, options)?),
        None => Ok(Program { files: Vec::new() }),
    }
}

/// One transform of a chain.
#[derive(Clone, Copy)]
pub enum TransformStep<'a> {
    /// `correct` or `zero` with a robot's track.
    Track(&'a TrackSetup<'a>, Direction),
    /// `mirror` with its settings.
    Mirror(&'a MirrorSettings),
}

impl TransformStep<'_> {
    /// The step's edits of `program` (reading the files' provenance stamps for the targets
    /// they list as kept as written: docs/design.md §4).
    pub fn edits(&self, program: &Program) -> ProgramEdits {
        self.edits_in_chain(program, StampReading::Read, false)
    }

    /// What the step is, as a refusal it makes in a chain says it: `` `correct` for robot `r2` ``.
    fn label(&self) -> String {
        match *self {
            TransformStep::Track(setup, dir) => match &setup.robot {
                Some(robot) => format!("`{}` for robot `{robot}`", dir.as_str()),
                None => format!("`{}`", dir.as_str()),
            },
            TransformStep::Mirror(_) => "`mirror`".to_owned(),
        }
    }

    /// The edits of a step of a chain: `chain` for the first step of a `transfer`.
    fn edits_in_chain(&self, program: &Program, stamps: StampReading, chain: bool) -> ProgramEdits {
        match *self {
            TransformStep::Track(setup, dir) => track_rule(program, setup, dir, stamps, chain),
            TransformStep::Mirror(settings) => mirror_reading(program, settings, stamps),
        }
    }
}

impl TransferPlan<'_> {
    /// `zero` with `from`, `mirror` if asked, `correct` with `to`.
    pub fn steps(&self) -> Vec<TransformStep<'_>> {
        let mut steps = vec![TransformStep::Track(&self.from, Direction::Zero)];
        steps.extend(self.mirror.as_ref().map(TransformStep::Mirror));
        steps.push(TransformStep::Track(&self.to, Direction::Correct));
        steps
    }
}

/// Runs `zero` with `plan.from`, `mirror` if asked, `correct` with `plan.to`. The first step
/// reads the input's provenance stamps for the targets they list as kept as written; the steps
/// after it do not (their input carries the same stamp line, but not what it says).
pub fn transfer(
    program: &Program,
    plan: &TransferPlan,
    options: &LoadOptions,
) -> Result<ProgramResult, TransferError> {
    let mut current: Option<Program> = None;
    let mut steps = Vec::new();
    for (k, step) in plan.steps().into_iter().enumerate() {
        let input = current.as_ref().unwrap_or(program);
        let edits = match k {
            0 => step.edits_in_chain(input, StampReading::Read, true),
            _ => step.edits_in_chain(input, StampReading::Ignore, false),
        };
        let result = apply(input, edits)?;
        let refused = refused_targets(input, &result);
        let next = reparse(input, &result, options)?;
        steps.push(Step {
            result,
            refused,
            label: step.label(),
        });
        current = Some(next);
    }
    let last = current.as_ref().unwrap_or(program);
    combine(program, last, &steps, plan)
}

/// Per file of `input` and refusal of `result`'s file (in order), the index of the target the
/// refusal is about: the position whose literal holds the refused span. `None` for a refusal
/// of something else, an offset call say.
fn refused_targets(input: &Program, result: &ProgramResult) -> Vec<Vec<Option<usize>>> {
    input
        .files
        .iter()
        .zip(&result.files)
        .map(|(file, out)| {
            if out.refusals.is_empty() {
                return Vec::new();
            }
            // Literals do not overlap: the one that may hold a span is the last to start at
            // or before it.
            let mut spans: Vec<(Span, usize)> = (0..file.positions.len())
                .filter_map(|i| Some((file.positions.span(i)?, i)))
                .filter(|(sp, _)| sp.start < sp.end)
                .collect();
            spans.sort_unstable_by_key(|(sp, _)| sp.start);
            out.refusals
                .iter()
                .map(|r| {
                    let after = spans.partition_point(|(sp, _)| sp.start <= r.span.start);
                    let (sp, i) = *spans.get(after.checked_sub(1)?)?;
                    (r.span.end <= sp.end).then_some(i)
                })
                .collect()
        })
        .collect()
}

/// One result from a chain of steps: the first step's input, the last step's output, every
/// distinct refusal, and each changed target's track correction: the change from start to end
/// beyond the mirror itself (a mirror moves points by metres; the correction is what matters).
///
/// A target any step refused is written as it was at the start, and refused once, at its place
/// in the first step's input: a step's refusal leaves the target as that step read it, and the
/// steps after it would otherwise go on moving it, so that a target reported as left unchanged
/// came out neither as written nor transferred.
fn combine(
    start: &Program,
    end: &Program,
    steps: &[Step],
    plan: &TransferPlan,
) -> Result<ProgramResult, TransferError> {
    let (skid_axis, mirror) = (plan.from.skid_axis, plan.mirror.as_ref());
    let own = mirror.map(Reflection::new);
    let mut refused = Vec::with_capacity(start.files.len());
    for (i, (a, b)) in start.files.iter().zip(&end.files).enumerate() {
        if a.positions.len() != b.positions.len() {
            return Err(TransferError::Drift {
                path: a.path.clone(),
                before: a.positions.len(),
                after: b.positions.len(),
            });
        }
        refused.push(chain_refusals(a, steps, i));
    }
    // The targets kept in any file, whose offset calls in every file stay as written.
    let kept_offsets = KeptTargets::of(
        refused
            .iter()
            .enumerate()
            .flat_map(|(fi, (_, kept))| kept.iter().map(move |(&t, &kind)| ((fi, t), kind))),
    );
    let mut files = Vec::new();
    for (i, ((a, b), (refusals, kept))) in
        start.files.iter().zip(&end.files).zip(refused).enumerate()
    {
        let mut seen = BTreeSet::new();
        let notes = steps
            .iter()
            .filter_map(|s| s.result.files.get(i))
            .flat_map(|f| f.notes.iter())
            .filter(|r| seen.insert((r.line, r.target.clone(), r.kind)))
            .cloned()
            .collect();
        let (output, came_back) = restore_unmoved(a, b, &kept, &kept_offsets)?;
        // A target the chain brought back, written again as it was, did not change.
        let changes = a
            .positions()
            .zip(b.positions())
            .enumerate()
            .filter(|(k, (p, q))| {
                !kept.contains_key(k)
                    && !came_back.contains(k)
                    && p.span.slice(&a.source) != q.span.slice(&b.source)
            })
            .map(|(_, (p, q))| {
                let poses = p
                    .cartesian
                    .as_ref()
                    .and_then(|c| c.pose())
                    .map(|x| match (mirror, &own) {
                        (Some(m), Some(own)) => match reflection_for(start, Some(a), &p, m, own) {
                            Ok(r) => r.target(&x).0,
                            Err(_) => x,
                        },
                        _ => x,
                    })
                    .zip(q.cartesian.as_ref().and_then(|c| c.pose()));
                // A joint target's correction is its flange's; where the cell gives no
                // kinematics that is not known, and its largest axis change is said instead
                // (the steps refuse such a target today, so none is expected here).
                let ((mm, deg), axes_deg) = match poses {
                    Some((x, y)) => (pose_change(&x, &y), None),
                    None => match joint_correction(plan, &p, &q) {
                        Some(size) => (size, None),
                        None => ((0.0, 0.0), Some(largest_axis_change(&p, &q))),
                    },
                };
                let skid = match p.skid(skid_axis) {
                    crate::position::Skid::At(s) => Some(s),
                    _ => None,
                };
                TargetChange {
                    mm,
                    deg,
                    skid,
                    name: p.name.clone(),
                    line: p.line,
                    uncertainty_mm: None,
                    axes_deg,
                }
            })
            .collect();
        files.push(FileResult {
            path: a.path.clone(),
            original: a.source.clone(),
            output,
            refusals,
            notes,
            changes,
            widened: None,
            // The targets kept at the start, which the stamp of the transfer lists.
            kept: kept
                .iter()
                .map(|(&index, &kind)| super::stamp::KeptTarget {
                    index,
                    kind,
                    name: a.positions.name(index).map(str::to_owned),
                })
                .collect(),
        });
    }
    Ok(ProgramResult { files })
}

/// The track correction of joint target `p` transferred to `q`, as a Cartesian target's: the
/// move of the flange beyond the mirror itself, in the base of robot B, from the mirror image of
/// `p`'s flange ([`joint_image_flange`]), or without a mirror from `p`'s flange on robot A, to
/// `q`'s. `None` where the cell gives the robots no kinematics or the joints do not read (the
/// steps refuse such a target).
fn joint_correction(plan: &TransferPlan, p: &Position, q: &Position) -> Option<(f64, f64)> {
    let to = plan.to.arm.as_ref()?;
    let end = to.joints_of(q).ok()?;
    match &plan.mirror {
        None => {
            let from = plan.from.arm.as_ref()?;
            let start = from.joints_of(p).ok()?;
            Some(flange_move(&from.kinematics, &start, &to.kinematics, &end))
        }
        Some(settings) => {
            let m = settings.arm.as_ref()?;
            let start = m.arm.joints_of(p).ok()?;
            let (image, _, _) = joint_image_flange(settings, m, p, &start).ok()?;
            Some(pose_change(&image, &to.kinematics.forward(&end)))
        }
    }
}

/// The largest change of one axis from joint target `p` to `q`, degrees (an axis that is not a
/// number in either is left out).
fn largest_axis_change(p: &Position, q: &Position) -> f64 {
    p.joints
        .iter()
        .zip(&q.joints)
        .filter_map(|(a, b)| Some((b.as_ref()?.value() - a.as_ref()?.value()).abs()))
        .fold(0.0, f64::max)
}

/// One step of a chain: its result, the target each of its refusals is about (per file, see
/// [`refused_targets`]) and what it is.
struct Step {
    result: ProgramResult,
    refused: Vec<Vec<Option<usize>>>,
    label: String,
}

/// The refusals of file `i` over a chain's steps, and the targets refused with the kind of
/// their first refusal: one refusal per target (that one), placed in `start` (a later step's
/// refusal points into that step's input, whose rewritten numbers moved it, and says which
/// step: "as written" in it means as the steps before wrote it), then every other refusal once.
fn chain_refusals(
    start: &ParsedFile,
    steps: &[Step],
    i: usize,
) -> (Vec<Refusal>, BTreeMap<usize, RefusalKind>) {
    let mut kept = BTreeMap::new();
    let mut seen = BTreeSet::new();
    let mut refusals = Vec::new();
    for (
        step,
        Step {
            result,
            refused: targets,
            label,
        },
    ) in steps.iter().enumerate()
    {
        let Some(file) = result.files.get(i) else {
            continue;
        };
        let targets = targets.get(i).map_or(&[][..], Vec::as_slice);
        for (k, r) in file.refusals.iter().enumerate() {
            match targets.get(k).copied().flatten() {
                Some(t) => {
                    if let std::collections::btree_map::Entry::Vacant(e) = kept.entry(t) {
                        e.insert(r.kind);
                        refusals.push(match (step, start.positions.span(t)) {
                            (1.., Some(span)) => {
                                let mut placed = r.placed_in(start, span);
                                placed.message = format!(
                                    "{} (in the transfer's {label}, of the target as the steps before it wrote it)",
                                    placed.message
                                );
                                placed
                            }
                            _ => r.clone(),
                        });
                    }
                }
                None => {
                    if seen.insert((r.line, r.target.clone(), r.kind)) {
                        refusals.push(r.clone());
                    }
                }
            }
        }
    }
    (refusals, kept)
}

/// The translation, orientation and other literals of a target (the last: joints and external
/// axes), and the unit of the last place the transforms write for each group (docs/design.md §5:
/// at least 3 decimals for mm, 6 for quaternion components, 4 for degrees).
struct TargetLiterals<'a> {
    trans: Vec<&'a NumField>,
    orient: Vec<&'a NumField>,
    /// The rotation (radians) one unit of the orientation's last place amounts to.
    orient_unit_rad: f64,
    others: Vec<&'a NumField>,
}

fn unit(fields: &[&NumField], house: i32) -> f64 {
    let places = fields
        .iter()
        .map(|f| f.lit().precision().clamp(0, 12))
        .max()
        .unwrap_or(0)
        .max(house);
    10f64.powi(-places)
}

fn target_literals(p: &Position) -> TargetLiterals<'_> {
    let mut t = TargetLiterals {
        trans: Vec::new(),
        orient: Vec::new(),
        orient_unit_rad: 0.0,
        others: Vec::new(),
    };
    if let Some(c) = &p.cartesian {
        t.trans = c.trans.iter().flatten().collect();
        match &c.orient {
            Some(Orientation::Quaternion(q)) => {
                t.orient = q.iter().flatten().collect();
                t.orient_unit_rad = 2.0 * unit(&t.orient, QUAT_DECIMALS as i32);
            }
            Some(Orientation::Abc(abc)) => {
                t.orient = abc.iter().flatten().collect();
                t.orient_unit_rad = unit(&t.orient, DEG_DECIMALS as i32).to_radians();
            }
            None => {}
        }
    }
    t.others = p.joints.iter().chain(&p.extax).flatten().collect();
    t
}

/// Each of a chain's intermediate files rounds every value it writes by up to half a unit of
/// its last place: three steps can leave an unmoved value this many units off.
const CHAIN_ROUNDING_UNITS: f64 = 1.5;

/// `b.source`, except that a target the chain brings back to where it was written at the start
/// (every coordinate, and the orientation as a rotation, within the rounding of the intermediate
/// files) keeps its original text, and so do joint and external-axis values that came back: an
/// identity transfer would otherwise rewrite `-1200` as `-1200.000`. The targets `kept` (some
/// step refused them) keep their whole literal as written, and the offset calls of the
/// program's `kept_offsets` their numbers (the steps move an offset call apart from its target).
fn restore_unmoved(
    a: &ParsedFile,
    b: &ParsedFile,
    kept: &BTreeMap<usize, RefusalKind>,
    kept_offsets: &KeptTargets,
) -> Result<(Vec<u8>, BTreeSet<usize>), EditError> {
    let mut edits = Vec::new();
    for &t in kept.keys() {
        if let (Some(p), Some(q)) = (a.positions.span(t), b.positions.span(t)) {
            let old = p.slice(&a.source);
            if old != q.slice(&b.source) {
                edits.push(Edit::new(q, old.to_vec()));
            }
        }
    }
    let keep = |edits: &mut Vec<Edit>, f: &NumField, g: &NumField| {
        let old = f.span().slice(&a.source);
        if old != g.span().slice(&b.source) {
            edits.push(Edit::new(g.span(), old.to_vec()));
        }
    };
    let close = |f: &NumField, g: &NumField, house: i32| {
        (f.value() - g.value()).abs() <= CHAIN_ROUNDING_UNITS * unit(&[f, g], house) * (1.0 + 1e-9)
    };
    if a.offsets.len() == b.offsets.len() {
        for (c, d) in a.offsets.iter().zip(&b.offsets) {
            // An offset the steps turned and turned back (`correct` turns an `Offs` offset
            // with its target) keeps its text, as a target that came back does; a kept
            // target's offset call keeps its rotations too.
            let back = c.delta.iter().zip(&d.delta).all(|pair| match pair {
                (Some(f), Some(g)) => close(f, g, MM_DECIMALS as i32),
                (None, None) => true,
                _ => false,
            });
            let pairs = c.delta.iter().zip(&d.delta);
            let rotations = c.rot.iter().zip(&d.rot);
            let kept = kept_offsets.offsets(c);
            let restored = pairs
                .filter(|_| kept || back)
                .chain(rotations.filter(|_| kept));
            for (f, g) in restored {
                if let (Some(f), Some(g)) = (f, g) {
                    keep(&mut edits, f, g);
                }
            }
        }
    }
    let mut came_back = BTreeSet::new();
    for (t, (p, q)) in a.positions().zip(b.positions()).enumerate() {
        if kept.contains_key(&t) {
            continue;
        }
        let from = edits.len();
        restore_target(&p, &q, &close, &keep, &mut edits);
        // The literal as it is written now, its restored fields put back.
        let own: Vec<Edit> = edits
            .get(from..)
            .unwrap_or_default()
            .iter()
            .map(|e| {
                let sp = e.span();
                Edit::new(
                    Span::new(
                        sp.start.saturating_sub(q.span.start),
                        sp.end.saturating_sub(q.span.start),
                    ),
                    e.text.to_vec(),
                )
            })
            .collect();
        if apply_edits(q.span.slice(&b.source), &own)
            .is_ok_and(|now| now == p.span.slice(&a.source))
        {
            came_back.insert(t);
        }
    }
    Ok((apply_edits(&b.source, &edits)?, came_back))
}

/// The restoring edits of one target `q` (as the chain wrote it) against `p` (as written at
/// the start): see [`restore_unmoved`].
fn restore_target(
    p: &Position,
    q: &Position,
    close: &dyn Fn(&NumField, &NumField, i32) -> bool,
    keep: &dyn Fn(&mut Vec<Edit>, &NumField, &NumField),
    edits: &mut Vec<Edit>,
) {
    let (x, y) = (target_literals(p), target_literals(q));
    if x.others.len() == y.others.len() {
        for (f, g) in x.others.iter().zip(&y.others) {
            if close(f, g, MM_DECIMALS as i32) {
                keep(edits, f, g);
            }
        }
    }
    if x.trans.len() != y.trans.len() || x.orient.len() != y.orient.len() {
        return;
    }
    let trans_back = x
        .trans
        .iter()
        .zip(&y.trans)
        .all(|(f, g)| close(f, g, MM_DECIMALS as i32));
    let rot = |t: &Position| t.cartesian.as_ref().and_then(|c| c.rotation());
    let orient_back = match (rot(p), rot(q)) {
        (Some(r), Some(s)) => r.angle_to(&s) <= CHAIN_ROUNDING_UNITS * x.orient_unit_rad,
        _ => x.orient.is_empty(),
    };
    if trans_back && orient_back {
        for (f, g) in x
            .trans
            .iter()
            .zip(&y.trans)
            .chain(x.orient.iter().zip(&y.orient))
        {
            keep(edits, f, g);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Pose, pose_xyz_deg};
    use crate::track::TrackError;
    use crate::transform::track_correction::Deviation;
    use nalgebra::Vector3;
    use std::path::Path;

    /// Three targets taught at skids 1000, 6000 and 9000 mm, all moved to in `wobj0`.
    const MODULE: &str = "MODULE m\n\
        CONST robtarget pNear:=[[1200,0,800],[0,0,1,0],[0,0,0,0],[1000,9E9,9E9,9E9,9E9,9E9]];\n\
        CONST robtarget pFar:=[[1200,0,800],[0,0,1,0],[0,0,0,0],[6000,9E9,9E9,9E9,9E9,9E9]];\n\
        CONST robtarget pBeyond:=[[1200,0,800],[0,0,1,0],[0,0,0,0],[9000,9E9,9E9,9E9,9E9,9E9]];\n\
        PROC main()\n\
        MoveL pNear, v1000, z10, tool0\\WObj:=wobj0;\n\
        MoveL pFar, v1000, z10, tool0\\WObj:=wobj0;\n\
        MoveL pBeyond, v1000, z10, tool0\\WObj:=wobj0;\n\
        ENDPROC\n\
        ENDMODULE\n";

    fn setup(deviation: &dyn Deviation) -> TrackSetup<'_> {
        TrackSetup {
            base0: Pose::identity(),
            track_axis: Vector3::x(),
            skid_axis: 0,
            frames: BTreeMap::new(),
            deviation,
            default_wobj: None,
            uncertainty: None,
            arm: None,
            robot: None,
        }
    }

    /// A track measured from skid 0 up to `max` mm (beyond: out of range), `dz` mm high.
    fn measured(max: f64, dz: f64) -> impl Fn(f64) -> Result<Pose, TrackError> + Sync {
        move |s: f64| match s > max {
            true => Err(TrackError::OutOfRange {
                skid: s,
                min: 0.0,
                max,
            }),
            false => Ok(pose_xyz_deg(0.0, 0.0, dz, 0.0, 0.0, 0.0)),
        }
    }

    fn literal<'a>(text: &'a str, name: &str) -> &'a str {
        let at = text.find(&format!("{name}:=")).unwrap();
        let line = &text[at..];
        &line[..line.find(";\n").unwrap()]
    }

    /// A target the last step refuses (its skid is beyond robot B's profile) was moved by the
    /// steps before: the chain writes it as it was written, and refuses it once, at its line;
    /// one both steps refuse is refused once.
    #[test]
    fn a_target_one_step_refuses_is_written_as_it_was() {
        let program = Program {
            files: vec![crate::rapid::parse_file(
                Path::new("m.mod"),
                MODULE.as_bytes().to_vec(),
            )],
        };
        // Robot A's track is measured up to skid 8000 and 2 mm low, robot B's up to 5000 and
        // 0.5 mm high.
        let (from_dev, to_dev) = (measured(8000.0, -2.0), measured(5000.0, 0.5));
        let plan = TransferPlan {
            from: setup(&from_dev),
            mirror: None,
            to: setup(&to_dev),
        };
        let result = transfer(&program, &plan, &LoadOptions::default()).unwrap();
        let file = &result.files[0];
        let out = String::from_utf8(file.output.clone()).unwrap();
        // pNear: zeroed with A (D_A, 2 mm down), then corrected with B (D_B⁻¹, 0.5 mm down).
        assert_eq!(
            literal(&out, "pNear"),
            "pNear:=[[1200,0,797.500],[0,0,1,0],[0,0,0,0],[1000,9E9,9E9,9E9,9E9,9E9]]"
        );
        // pFar: zeroed, then refused by B: as written, not left at z 798.
        assert_eq!(literal(&out, "pFar"), literal(MODULE, "pFar"));
        assert_eq!(literal(&out, "pBeyond"), literal(MODULE, "pBeyond"));
        let refused: Vec<_> = file
            .refusals
            .iter()
            .map(|r| (r.target.as_str(), r.kind, r.line))
            .collect();
        assert_eq!(
            refused,
            [
                ("pBeyond", RefusalKind::SkidOutOfRange, 4),
                ("pFar", RefusalKind::SkidOutOfRange, 3),
            ]
        );
        let changed: Vec<_> = file.changes.iter().map(|c| c.line).collect();
        assert_eq!(changed, [2]);
    }

    /// The offsets of a kept target stay as written with it: the mirror turns the `Offs`
    /// offset of a target robot B then refuses (taken directly or through a `RelTool`).
    #[test]
    fn a_kept_targets_offsets_are_written_as_they_were() {
        let module = "MODULE m\n\
            CONST robtarget pFar:=[[1200,0,800],[0,0,1,0],[0,0,0,0],[6000,9E9,9E9,9E9,9E9,9E9]];\n\
            PROC main()\n\
            MoveL Offs(pFar,0,100,0), v1000, z10, tool0\\WObj:=wobj0;\n\
            MoveL Offs(RelTool(pFar,0,0,10),0,100,0), v1000, z10, tool0\\WObj:=wobj0;\n\
            MoveL pFar, v1000, z10, tool0\\WObj:=wobj0;\n\
            ENDPROC\n\
            ENDMODULE\n";
        let program = Program {
            files: vec![crate::rapid::parse_file(
                Path::new("m.mod"),
                module.as_bytes().to_vec(),
            )],
        };
        // Robot A's track is straight, robot B's measured up to skid 5000.
        let (from_dev, to_dev) = (measured(f64::INFINITY, 0.0), measured(5000.0, 0.0));
        let plan = TransferPlan {
            from: setup(&from_dev),
            mirror: Some(MirrorSettings::default()),
            to: setup(&to_dev),
        };
        let mirrored = apply(&program, plan.steps()[1].edits(&program)).unwrap();
        let mirrored = String::from_utf8(mirrored.files[0].output.clone()).unwrap();
        assert!(mirrored.contains("Offs(pFar,0,-100,0)"), "{mirrored}");
        assert!(
            mirrored.contains("Offs(RelTool(pFar,0,0,10),0,-100,0)"),
            "{mirrored}"
        );
        let result = transfer(&program, &plan, &LoadOptions::default()).unwrap();
        assert_eq!(
            String::from_utf8(result.files[0].output.clone()).unwrap(),
            module
        );
        assert_eq!(result.files[0].refusals.len(), 1);
    }

    /// So do they in another module of the task than the target's.
    #[test]
    fn a_kept_targets_offsets_in_another_module_are_written_as_they_were() {
        let data = "MODULE Data\n\
            CONST robtarget pFar:=[[1200,0,800],[0,0,1,0],[0,0,0,0],[6000,9E9,9E9,9E9,9E9,9E9]];\n\
            ENDMODULE\n";
        let main = "MODULE Main\n\
            PROC main()\n\
            MoveL Offs(pFar,0,100,0), v1000, z10, tool0\\WObj:=wobj0;\n\
            MoveL pFar, v1000, z10, tool0\\WObj:=wobj0;\n\
            ENDPROC\n\
            ENDMODULE\n";
        let program = Program {
            files: crate::rapid::parse_task(vec![
                ("Data.mod".into(), data.as_bytes().to_vec().into()),
                ("Main.mod".into(), main.as_bytes().to_vec().into()),
            ]),
        };
        // Robot A's track is straight, robot B's measured up to skid 5000.
        let (from_dev, to_dev) = (measured(f64::INFINITY, 0.0), measured(5000.0, 0.0));
        let plan = TransferPlan {
            from: setup(&from_dev),
            mirror: Some(MirrorSettings::default()),
            to: setup(&to_dev),
        };
        let mirrored = apply(&program, plan.steps()[1].edits(&program)).unwrap();
        let mirrored = String::from_utf8(mirrored.files[1].output.clone()).unwrap();
        assert!(mirrored.contains("Offs(pFar,0,-100,0)"), "{mirrored}");
        let result = transfer(&program, &plan, &LoadOptions::default()).unwrap();
        let outputs: Vec<_> = result
            .files
            .iter()
            .map(|f| String::from_utf8(f.output.clone()).unwrap())
            .collect();
        assert_eq!(outputs, [data, main]);
    }
}
