//! What a transform wants to change in a program, and the bytes that result.

use std::path::PathBuf;

use crate::position::{Name, Program};
use crate::syntax::{EditError, EditList};

use super::refusal::Refusal;

/// How much one changed target moved.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetChange {
    /// Translation change in mm.
    pub mm: f64,
    /// Rotation change in degrees.
    pub deg: f64,
    /// The skid value the target was transformed at (`None` for transforms that use none).
    pub skid: Option<f64>,
    /// The target's name, when it has one (inline targets have none). A [`Name`], not a
    /// `String`: a `correct` of a large module holds one change per target next to the model,
    /// and a heap block per name was 100,000 of them on a 20 MB module.
    pub name: Option<Name>,
    /// 1-based line of the target.
    pub line: usize,
    /// Expanded uncertainty (k = 2, mm) of the corrected TCP, when the profile carries
    /// uncertainties (docs/design.md §14): a correction smaller than this is within the
    /// measurement's own doubt.
    pub uncertainty_mm: Option<f64>,
}

/// The edits and refusals of one file.
#[derive(Clone, Debug, Default)]
pub struct FileEdits {
    /// The span-splice edits to the file's source, packed ([`EditList`]).
    pub edits: EditList,
    /// The targets left unchanged, and why.
    pub refusals: Vec<Refusal>,
    /// Things that look like targets but are none (unset `[0,0,0,0]` array slots): left as
    /// written and reported as notes, never refusals.
    pub notes: Vec<Refusal>,
    /// One entry per target whose text changes.
    pub changes: Vec<TargetChange>,
}

/// The edits of every file of a program, in the program's file order.
#[derive(Clone, Debug, Default)]
pub struct ProgramEdits {
    /// One entry per file of the program.
    pub files: Vec<FileEdits>,
}

impl ProgramEdits {
    /// No edits yet, one empty entry per file of `program`.
    pub fn for_program(program: &Program) -> ProgramEdits {
        ProgramEdits {
            files: vec![FileEdits::default(); program.files.len()],
        }
    }

    /// Every refusal of every file, in file order.
    pub fn refusals(&self) -> impl Iterator<Item = &Refusal> {
        self.files.iter().flat_map(|f| &f.refusals)
    }
}

/// One file after a transform.
#[derive(Clone, Debug)]
pub struct FileResult {
    /// The file, as loaded.
    pub path: PathBuf,
    /// Its bytes before the transform.
    pub original: Vec<u8>,
    /// Its bytes after: `original` with the edits spliced in, every other byte unchanged.
    pub output: Vec<u8>,
    /// The targets left unchanged, and why.
    pub refusals: Vec<Refusal>,
    /// Unset slots and the like, left as written (see [`FileEdits::notes`]).
    pub notes: Vec<Refusal>,
    /// One entry per target whose text changed.
    pub changes: Vec<TargetChange>,
}

impl FileResult {
    /// Whether the output differs from the original.
    pub fn changed(&self) -> bool {
        self.original != self.output
    }

    /// Largest translation (mm) and rotation (degrees) change of any target.
    pub fn largest_change(&self) -> (f64, f64) {
        self.changes
            .iter()
            .fold((0.0, 0.0), |(mm, deg), c| (mm.max(c.mm), deg.max(c.deg)))
    }

    /// The smallest and largest skid of the changed targets.
    pub fn skid_range(&self) -> Option<(f64, f64)> {
        self.changes
            .iter()
            .filter_map(|c| c.skid)
            .fold(None, |acc, s| match acc {
                None => Some((s, s)),
                Some((lo, hi)) => Some((f64::min(lo, s), f64::max(hi, s))),
            })
    }
}

/// A program after a transform.
#[derive(Clone, Debug)]
pub struct ProgramResult {
    /// One entry per file of the program, in its order.
    pub files: Vec<FileResult>,
}

impl ProgramResult {
    /// Every refusal of every file, in file order.
    pub fn refusals(&self) -> impl Iterator<Item = &Refusal> {
        self.files.iter().flat_map(|f| &f.refusals)
    }

    /// Whether any file changed.
    pub fn changed(&self) -> bool {
        self.files.iter().any(FileResult::changed)
    }
}

/// Applies a transform's edits to the program's sources.
pub fn apply(program: &Program, edits: ProgramEdits) -> Result<ProgramResult, EditError> {
    let mut files = Vec::with_capacity(program.files.len());
    for (file, fe) in program.files.iter().zip(edits.files) {
        let output = fe.edits.apply(&file.source)?;
        files.push(FileResult {
            path: file.path.clone(),
            original: file.source.clone(),
            output,
            refusals: fe.refusals,
            notes: fe.notes,
            changes: fe.changes,
        });
    }
    Ok(ProgramResult { files })
}

/// [`apply`] for a program that is not needed after: each file's source becomes its result's
/// `original` without a copy, and the rest of the model (positions, frames, diagnostics) is
/// dropped before the first output is built. On a large program the model is several times the
/// file, and with it alive the outputs and their copies (stamp, precision) set `correct`'s peak.
pub fn apply_owned(program: Program, edits: ProgramEdits) -> Result<ProgramResult, EditError> {
    let sources: Vec<(PathBuf, Vec<u8>)> = program
        .files
        .into_iter()
        .map(|f| (f.path, f.source))
        .collect();
    let mut files = Vec::with_capacity(sources.len());
    for ((path, original), fe) in sources.into_iter().zip(edits.files) {
        let output = fe.edits.apply(&original)?;
        files.push(FileResult {
            path,
            original,
            output,
            refusals: fe.refusals,
            notes: fe.notes,
            changes: fe.changes,
        });
    }
    Ok(ProgramResult { files })
}
