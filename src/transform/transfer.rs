//! `transfer` (DESIGN.md §4): zero with robot A, optionally mirror, correct with robot B.
//!
//! The three steps run through text exactly as three commands in a row would: each step's output
//! is parsed again before the next, so the written precision rounds in the same places and
//! `transfer` equals `zero; mirror; correct` byte for byte. Nothing is written between the steps:
//! RAPID re-parses the bytes, a KRL pair goes through `krl::load_program_from_sources`.

use std::collections::BTreeSet;
use std::path::PathBuf;

use crate::position::Program;
use crate::program::{LoadError, LoadOptions};
use crate::syntax::EditError;

use super::edits::{FileResult, ProgramEdits, ProgramResult, TargetChange, apply};
use super::mirror::{MirrorSettings, Reflection, mirror, reflection_for};
use super::rewrite::pose_change;
use super::track_correction::{Direction, TrackSetup, track_correction};

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
    /// The step's edits of `program`.
    pub fn edits(&self, program: &Program) -> ProgramEdits {
        match *self {
            TransformStep::Track(setup, dir) => track_correction(program, setup, dir),
            TransformStep::Mirror(settings) => mirror(program, settings),
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

/// Runs `zero` with `plan.from`, `mirror` if asked, `correct` with `plan.to`.
pub fn transfer(
    program: &Program,
    plan: &TransferPlan,
    options: &LoadOptions,
) -> Result<ProgramResult, TransferError> {
    let mut current: Option<Program> = None;
    let mut steps = Vec::new();
    for step in plan.steps() {
        let input = current.as_ref().unwrap_or(program);
        let result = apply(input, step.edits(input))?;
        let next = reparse(input, &result, options)?;
        steps.push(result);
        current = Some(next);
    }
    let last = current.as_ref().unwrap_or(program);
    combine(
        program,
        last,
        &steps,
        plan.from.skid_axis,
        plan.mirror.as_ref(),
    )
}

/// One result from a chain of steps: the first step's input, the last step's output, every
/// distinct refusal, and each changed target's track correction: the change from start to end
/// beyond the mirror itself (a mirror moves points by metres; the correction is what matters).
fn combine(
    start: &Program,
    end: &Program,
    steps: &[ProgramResult],
    skid_axis: usize,
    mirror: Option<&MirrorSettings>,
) -> Result<ProgramResult, TransferError> {
    let own = mirror.map(Reflection::new);
    let mut files = Vec::new();
    for (i, (a, b)) in start.files.iter().zip(&end.files).enumerate() {
        if a.positions.len() != b.positions.len() {
            return Err(TransferError::Drift {
                path: a.path.clone(),
                before: a.positions.len(),
                after: b.positions.len(),
            });
        }
        let mut seen = BTreeSet::new();
        let refusals = steps
            .iter()
            .filter_map(|s| s.files.get(i))
            .flat_map(|f| f.refusals.iter())
            .filter(|r| seen.insert((r.line, r.target.clone(), r.kind)))
            .cloned()
            .collect();
        let changes = a
            .positions
            .iter()
            .zip(&b.positions)
            .filter(|(p, q)| p.span.slice(&a.source) != q.span.slice(&b.source))
            .map(|(p, q)| {
                let poses = p
                    .cartesian
                    .as_ref()
                    .and_then(|c| c.pose())
                    .map(|x| match (mirror, &own) {
                        (Some(m), Some(own)) => match reflection_for(start, p, m, own) {
                            Ok(r) => r.target(&x).0,
                            Err(_) => x,
                        },
                        _ => x,
                    })
                    .zip(q.cartesian.as_ref().and_then(|c| c.pose()));
                let (mm, deg) = poses.map_or((0.0, 0.0), |(x, y)| pose_change(&x, &y));
                let skid = match p.skid(skid_axis) {
                    crate::position::Skid::At(s) => Some(s),
                    _ => None,
                };
                TargetChange { mm, deg, skid }
            })
            .collect();
        files.push(FileResult {
            path: a.path.clone(),
            original: a.source.clone(),
            output: b.source.clone(),
            refusals,
            changes,
        });
    }
    Ok(ProgramResult { files })
}
