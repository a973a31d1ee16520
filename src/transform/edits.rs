//! What a transform wants to change in a program, and the bytes that result.

use std::path::PathBuf;

use crate::output::InputBytes;
use crate::position::{Name, Program};
use crate::syntax::packed::{Chunks, VARINT_MAX, put_varint, read_varint};
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
    /// The target's name, when it has one (inline targets have none).
    pub name: Option<Name>,
    /// 1-based line of the target.
    pub line: usize,
    /// Expanded uncertainty (k = 2, mm) of the corrected TCP, when the profile carries
    /// uncertainties (docs/design.md §14): a correction smaller than this is within the
    /// measurement's own doubt.
    pub uncertainty_mm: Option<f64>,
    /// A joint target changed without the arm's kinematics (`mirror` negating axes 1, 4 and 6):
    /// the largest change of one of its axes, degrees. Its flange, and so its move, is not
    /// known: `mm` and `deg` are then 0 and no move.
    pub axes_deg: Option<f64>,
}

/// The change records of one file, packed: what a transform keeps of each changed target for
/// the summary and the run report, from its first target until the process ends.
///
/// A `correct` of a 20 MB module changes 100,000 targets; as [`TargetChange`]s (80 bytes) in a
/// vector grown by doubling they took 10.5 MB, next to the source and the output. Here a record
/// is a byte of which parts it has, the numbers as they are (8 bytes each, so every value reads
/// back bit for bit), the line and the name's length in LEB128, and the name's text in one
/// string beside the log (about 30 bytes for a named target; see `syntax::packed`). They read back as [`TargetChange`]s, in the order they were
/// added.
#[derive(Clone, Default)]
pub struct Changes {
    log: Chunks,
    /// The names' bytes, one after the other (a record has its name's length), taken from
    /// each `Name` without reading it as a `str` (a UTF-8 check per name, 0.8 M instructions
    /// of `correct` on the 2 MB bench module); [`Changes::iter`] checks them once, whole.
    names: Vec<u8>,
    len: usize,
}

/// Which optional parts a packed [`TargetChange`] has.
const HAS_SKID: u8 = 1;
const HAS_UNCERTAINTY: u8 = 2;
const HAS_NAME: u8 = 4;
const HAS_AXES: u8 = 8;

impl Changes {
    /// No changes.
    pub fn new() -> Changes {
        Changes::default()
    }

    /// Adds one changed target.
    pub fn push(&mut self, c: TargetChange) {
        let name = c.name.as_ref().map(Name::as_bytes);
        let flags = [
            (c.skid.is_some(), HAS_SKID),
            (c.uncertainty_mm.is_some(), HAS_UNCERTAINTY),
            (name.is_some(), HAS_NAME),
            (c.axes_deg.is_some(), HAS_AXES),
        ]
        .into_iter()
        .filter(|&(present, _)| present)
        .fold(0, |flags, (_, bit)| flags | bit);
        let mut head = [0; 1 + 5 * 8 + 2 * VARINT_MAX];
        head[0] = flags;
        let mut n = 1;
        for v in [
            Some(c.mm),
            Some(c.deg),
            c.skid,
            c.uncertainty_mm,
            c.axes_deg,
        ]
        .into_iter()
        .flatten()
        {
            head[n..n + 8].copy_from_slice(&v.to_le_bytes());
            n += 8;
        }
        put_varint(&mut head, &mut n, c.line as u64);
        if let Some(name) = name {
            put_varint(&mut head, &mut n, name.len() as u64);
        }
        self.log.room(n).extend_from_slice(&head[..n]);
        if let Some(name) = name {
            self.names.extend_from_slice(name);
        }
        self.len += 1;
    }

    /// How many targets changed.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no target changed.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The changes, in the order they were added, read in place (the name borrowed).
    pub fn iter(&self) -> impl Iterator<Item = ChangeRef<'_>> + '_ {
        let mut place = self.log.start();
        let mut left = self.len;
        let mut name_at = 0;
        // Every name pushed is a whole `Name`'s text: the bytes are UTF-8, and each name's
        // slice lies on its boundaries.
        let names = std::str::from_utf8(&self.names).unwrap_or_default();
        std::iter::from_fn(move || {
            if left == 0 {
                return None;
            }
            let bytes = self.log.rest(&mut place);
            let mut at = 0;
            // The log holds what `push` wrote, so every record reads back whole.
            let c = read_change(bytes, &mut at, names, &mut name_at)?;
            place.at += at;
            left -= 1;
            Some(c)
        })
    }

    /// Gives back the room to spare (the file's changes are all in).
    pub fn shrink_to_fit(&mut self) {
        self.log.shrink_to_fit();
        self.names.shrink_to_fit();
    }
}

/// One changed target as [`Changes`] hold it: a [`TargetChange`] with its name borrowed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangeRef<'a> {
    /// Translation change in mm.
    pub mm: f64,
    /// Rotation change in degrees.
    pub deg: f64,
    /// The skid value the target was transformed at.
    pub skid: Option<f64>,
    /// The target's name, when it has one.
    pub name: Option<&'a str>,
    /// 1-based line of the target.
    pub line: usize,
    /// Expanded uncertainty (k = 2, mm) of the corrected TCP, when known.
    pub uncertainty_mm: Option<f64>,
    /// A joint target's largest change of one axis (°), where its move is not known.
    pub axes_deg: Option<f64>,
}

impl ChangeRef<'_> {
    /// As a [`TargetChange`] of its own.
    pub fn to_change(&self) -> TargetChange {
        TargetChange {
            mm: self.mm,
            deg: self.deg,
            skid: self.skid,
            name: self.name.map(Name::from),
            line: self.line,
            uncertainty_mm: self.uncertainty_mm,
            axes_deg: self.axes_deg,
        }
    }
}

/// One [`Changes::push`] record at `*at`, moving `*at` past it, with its name from `names` at
/// `*name_at` (moved past it).
#[inline]
fn read_change<'a>(
    bytes: &[u8],
    at: &mut usize,
    names: &'a str,
    name_at: &mut usize,
) -> Option<ChangeRef<'a>> {
    let flags = *bytes.get(*at)?;
    *at += 1;
    let mm = f64_at(bytes, at)?;
    let deg = f64_at(bytes, at)?;
    let skid = match flags & HAS_SKID {
        0 => None,
        _ => Some(f64_at(bytes, at)?),
    };
    let uncertainty_mm = match flags & HAS_UNCERTAINTY {
        0 => None,
        _ => Some(f64_at(bytes, at)?),
    };
    let axes_deg = match flags & HAS_AXES {
        0 => None,
        _ => Some(f64_at(bytes, at)?),
    };
    let line = usize::try_from(read_varint(bytes, at)?).ok()?;
    let name = if flags & HAS_NAME != 0 {
        let n = usize::try_from(read_varint(bytes, at)?).ok()?;
        let name = names.get(*name_at..name_at.checked_add(n)?)?;
        *name_at += n;
        Some(name)
    } else {
        None
    };
    Some(ChangeRef {
        mm,
        deg,
        skid,
        name,
        line,
        uncertainty_mm,
        axes_deg,
    })
}

/// The eight bytes at `*at` as a number, moving `*at` past them.
#[inline(always)]
fn f64_at(bytes: &[u8], at: &mut usize) -> Option<f64> {
    let b = bytes.get(*at..)?.first_chunk::<8>()?;
    *at += 8;
    Some(f64::from_le_bytes(*b))
}

impl FromIterator<TargetChange> for Changes {
    fn from_iter<I: IntoIterator<Item = TargetChange>>(changes: I) -> Changes {
        let mut out = Changes::default();
        for c in changes {
            out.push(c);
        }
        out
    }
}

/// Equal when they read back as the same changes (however the bytes are chunked; a NaN is
/// unequal to itself, as in a [`TargetChange`]).
impl PartialEq for Changes {
    fn eq(&self, other: &Changes) -> bool {
        self.len == other.len && self.iter().eq(other.iter())
    }
}

/// As the list of its changes.
impl std::fmt::Debug for Changes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
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
    pub changes: Changes,
    /// The targets the stamp of the output is to list as kept as written (see
    /// [`Kept`](super::stamp::Kept)): those refused, and those a stamp listed that stay
    /// neither side's.
    pub kept: Vec<super::stamp::KeptTarget>,
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
    /// Its bytes before the transform, as they were loaded: read, or mapped from a file the
    /// run does not write (see `LoadOptions::map_inputs`).
    pub original: InputBytes,
    /// Its bytes after: `original` with the edits spliced in, every other byte unchanged.
    pub output: Vec<u8>,
    /// The targets left unchanged, and why.
    pub refusals: Vec<Refusal>,
    /// Unset slots and the like, left as written (see [`FileEdits::notes`]).
    pub notes: Vec<Refusal>,
    /// One entry per target whose text changed.
    pub changes: Changes,
    /// The precision record of `output` as the edits that made it gave it
    /// ([`EditCarry`](super::stamp::EditCarry)), for
    /// [`carry_precision_known`](super::stamp::carry_precision_known): `None` where it is not
    /// known, and to be set so by whatever changes `output` after.
    pub widened: Option<super::stamp::Widened>,
    /// The targets the output's stamp lists as kept as written ([`FileEdits::kept`]).
    pub kept: Vec<super::stamp::KeptTarget>,
}

impl FileResult {
    /// Whether the output differs from the original.
    pub fn changed(&self) -> bool {
        *self.original != *self.output
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
    for (file, mut fe) in program.files.iter().zip(edits.files) {
        let output = fe.edits.apply(&file.source)?;
        fe.changes.shrink_to_fit();
        files.push(FileResult {
            path: file.path.clone(),
            original: file.source.clone(),
            output,
            refusals: fe.refusals,
            notes: fe.notes,
            changes: fe.changes,
            widened: None,
            kept: fe.kept,
        });
    }
    Ok(ProgramResult { files })
}

/// [`apply`] for a program that is not needed after: each file's source becomes its result's
/// `original` without a copy, and the rest of the model (positions, frames, diagnostics) is
/// dropped before the first output is built. On a large program the model is several times the
/// file, and with it alive the outputs and their copies (stamp, precision) set `correct`'s peak.
pub fn apply_owned(program: Program, edits: ProgramEdits) -> Result<ProgramResult, EditError> {
    let sources: Vec<(PathBuf, InputBytes)> = program
        .files
        .into_iter()
        .map(|f| (f.path, f.source))
        .collect();
    let mut files = Vec::with_capacity(sources.len());
    for ((path, original), mut fe) in sources.into_iter().zip(edits.files) {
        // The precision record is worked out as the edits go in: the stamp's carry then need
        // not scan the output.
        let mut carry = super::stamp::EditCarry::new();
        let src: &[u8] = &original;
        let output = fe.edits.apply_seen(src, |span, text, window| {
            carry.edit(src, span, text, window)
        })?;
        // Kept with the result to the end of the run.
        fe.changes.shrink_to_fit();
        files.push(FileResult {
            widened: carry.finish(src),
            path,
            original,
            output,
            refusals: fe.refusals,
            notes: fe.notes,
            changes: fe.changes,
            kept: fe.kept,
        });
    }
    Ok(ProgramResult { files })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changes_read_back_bit_for_bit_in_order() {
        let long = "a_target_name_longer_than_any_inline_name_of_the_model";
        let all: Vec<TargetChange> = (0..20_000usize)
            .map(|i| TargetChange {
                mm: i as f64 * 0.001 + 1e-17,
                deg: -(i as f64) / 3.0,
                skid: (i % 3 != 0).then_some(i as f64 * 7.25),
                name: match i % 4 {
                    0 => None,
                    1 => Some(long.into()),
                    2 => Some("".into()),
                    _ => Some(format!("p{i}").into()),
                },
                line: if i == 7 { usize::MAX } else { i * 3 + 1 },
                uncertainty_mm: (i % 5 == 0).then_some(f64::NAN),
                axes_deg: (i % 7 == 0).then_some(i as f64 * 0.5),
            })
            .collect();
        let packed: Changes = all.iter().cloned().collect();
        assert_eq!(packed.len(), all.len());
        let back: Vec<TargetChange> = packed.iter().map(|c| c.to_change()).collect();
        assert_eq!(back.len(), all.len());
        for (a, b) in all.iter().zip(&back) {
            // NaN is not equal to itself: compare the bits.
            let bits = |c: &TargetChange| {
                (
                    c.mm.to_bits(),
                    c.deg.to_bits(),
                    c.skid.map(f64::to_bits),
                    c.uncertainty_mm.map(f64::to_bits),
                    c.axes_deg.map(f64::to_bits),
                )
            };
            assert_eq!(bits(a), bits(b));
            assert_eq!((&a.name, a.line), (&b.name, b.line));
        }
        // Packed, a change takes a byte of flags, its numbers, its line and its name (its
        // length in the log, its text beside it): no padding, no room for absent parts.
        let varint = |v: usize| (usize::BITS - v.max(1).leading_zeros()).div_ceil(7) as usize;
        let want: usize = all
            .iter()
            .map(|c| {
                let optional = c.skid.is_some() as usize
                    + c.uncertainty_mm.is_some() as usize
                    + c.axes_deg.is_some() as usize;
                let name = c.name.as_deref().map_or(0, |n| varint(n.len()) + n.len());
                1 + 16 + 8 * optional + varint(c.line) + name
            })
            .sum();
        assert_eq!(packed.log.bytes() + packed.names.len(), want);
        let mut shrunk = packed.clone();
        shrunk.shrink_to_fit();
        shrunk.push(all[1].clone());
        assert_eq!(shrunk.len(), all.len() + 1);
        assert_eq!(
            shrunk.iter().last().map(|c| c.to_change()),
            Some(all[1].clone())
        );
        assert_eq!(shrunk.iter().nth(1).and_then(|c| c.name), Some(long));
        assert!(Changes::new().is_empty());
        assert_eq!(Changes::new().iter().count(), 0);
    }
}
