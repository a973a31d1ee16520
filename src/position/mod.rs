//! The position model shared by RAPID and KRL.
//!
//! A language's parser finds every Cartesian or joint target (declared or inline), every work
//! object / base / tool declaration and every `Offs`/`RelTool` call, and describes each with the
//! byte span of each numeric field. Transforms read values from here and write [`Edit`]s to
//! exactly those spans; nothing else in the file is touched.
//!
//! [`Edit`]: crate::syntax::Edit

use std::path::PathBuf;
use std::sync::Arc;

use crate::geometry::{Pose, abb_quat, kuka_abc};
use crate::output::InputBytes;
use crate::syntax::{Diagnostic, LineIndex, NumLit, PackedLit, Span, Span32};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// Values at or above this are RAPID/KRL "not connected" external axes (`9E9`, `9E+09`).
pub const NOT_CONNECTED: f64 = 8.9e9;

pub use crate::dialect::Language;

mod list;
pub(crate) use list::ReadAgainTarget;
pub use list::{DecodeMemo, OrientationAndConfig, PositionList, Reading, TargetForLints};

/// What a position literal is, by its declared or inferred data type: the type's name as its
/// language writes it, and whether it is Cartesian. Each dialect defines its kinds
/// (`PositionKind::Robtarget`, `PositionKind::E6Pos`, …).
///
/// One pointer to its [`KindSpec`], which the dialect keeps in a constant: every target holds
/// its kind, and a name and a flag in place were 24 bytes each.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct PositionKind(&'static KindSpec);

/// A [`PositionKind`]'s name and whether it is Cartesian. Written in a `const` item,
/// `PositionKind::new(&KindSpec::pose("…"))` keeps it as a constant of the program (`'static`).
#[derive(Debug, PartialEq, Eq, Hash)]
pub struct KindSpec {
    /// The type's name as its language writes it (`robtarget`, `E6POS`).
    pub name: &'static str,
    /// A pose, which transforms change; false for joint values.
    pub cartesian: bool,
}

impl KindSpec {
    /// A Cartesian kind named `name`.
    pub const fn pose(name: &'static str) -> KindSpec {
        KindSpec {
            name,
            cartesian: true,
        }
    }

    /// A kind of joint values named `name`.
    pub const fn joints(name: &'static str) -> KindSpec {
        KindSpec {
            name,
            cartesian: false,
        }
    }
}

impl PositionKind {
    /// The kind `spec` describes:
    /// `PositionKind::new(&KindSpec::pose("robtarget"))`.
    pub const fn new(spec: &'static KindSpec) -> PositionKind {
        PositionKind(spec)
    }

    /// The name `inspect` prints (as the language writes it: `robtarget`, `E6POS`).
    pub fn as_str(self) -> &'static str {
        self.0.name
    }

    /// Cartesian targets are transformed; joint targets never are (docs/design.md §4).
    pub fn is_cartesian(self) -> bool {
        self.0.cartesian
    }
}

impl std::fmt::Debug for PositionKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PositionKind")
            .field("name", &self.0.name)
            .field("cartesian", &self.0.cartesian)
            .finish()
    }
}

/// A numeric literal inside a position, with the span of its text.
///
/// Sixteen bytes, and `Option<NumField>` too: a module holds about 17 of these per target, and
/// at 24 bytes they were more than a third of `check`'s heap peak on a 20 MB module. The value is kept as
/// is, the literal's style and the text's length packed in four bytes beside a `u32` start
/// (inputs are at most [`MAX_INPUT_BYTES`](crate::output::MAX_INPUT_BYTES), 512 MiB, so a start
/// always fits). A literal the compact form cannot hold — text longer than 255 bytes, or a
/// precision beyond ±8191 decimals without an exponent a rewrite keeps (`1E-9000`) — is not
/// stored as a number ([`NumField::new`] gives `None`, the field reads as an expression, which
/// transforms refuse).
#[derive(Clone, Copy, PartialEq)]
pub struct NumField {
    value: f64,
    start: u32,
    packed: PackedLit,
}

/// Most of a target is these fields: a layout change that grows them fails the build.
const _: () = assert!(std::mem::size_of::<Option<NumField>>() == 16);

impl NumField {
    /// The field of literal `lit` written at `span` (its text: `span` is as long as the
    /// literal); `None` if it does not fit the compact form (see the type).
    #[inline]
    pub fn new(span: Span, lit: NumLit) -> Option<NumField> {
        Some(NumField {
            value: lit.value(),
            start: u32::try_from(span.start).ok()?,
            packed: lit.pack(span.end.checked_sub(span.start)?)?,
        })
    }

    /// The literal's bytes (what an edit replaces).
    pub fn span(&self) -> Span {
        let start = self.start as usize;
        Span::new(start, start + self.packed.len())
    }

    /// The literal as written: its value and how it is spelled, so a rewrite keeps the style.
    #[inline]
    pub fn lit(&self) -> NumLit {
        NumLit::unpack(self.value, self.packed)
    }

    /// The literal's value.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The field of the literal [`NumLit::parse_prefix`] reads at `start` of `src`, if it
    /// reads one there that fits the compact form: [`NumField::new`] of it, the literal
    /// packed as it is read ([`NumLit::parse_packed`]).
    #[inline(always)]
    pub(crate) fn read_at(src: &[u8], start: usize) -> Option<NumField> {
        let (value, packed) = NumLit::parse_packed(src.get(start..)?)?;
        start.checked_add(packed.len())?;
        Some(NumField {
            value,
            start: u32::try_from(start).ok()?,
            packed,
        })
    }

    /// Value and packed style, for [`NumField::from_parts`] (with the start, which
    /// [`span`](Self::span) gives).
    pub(crate) fn value_and_style(&self) -> (f64, u32) {
        (self.value, self.packed.bits())
    }

    /// The field at `start` with what [`NumField::value_and_style`] gave; `None` for a style
    /// word no field has.
    pub(crate) fn from_parts(start: u32, value: f64, packed: u32) -> Option<NumField> {
        Some(NumField {
            value,
            start,
            packed: PackedLit::from_bits(packed)?,
        })
    }
}

impl std::fmt::Debug for NumField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NumField")
            .field("span", &self.span())
            .field("lit", &self.lit())
            .finish()
    }
}

/// A KUKA Status or Turn as written: decimal (`S 6`) or a binary string (`S 'B110'`).
///
/// Sixteen bytes, and `Option<BitField>` too (with a `usize` span and digit count it was 40):
/// every KRL Cartesian target has two.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct BitField {
    span: Span32,
    value: u32,
    binary_digits: Option<u8>,
}

impl BitField {
    /// The field written at `span` (the whole token, quotes included for the binary form)
    /// with `value`, and `Some(n)` for `'B…'` with n digits, `None` for a decimal integer;
    /// `None` if the span is reversed, an offset does not fit 32 bits, or there are more than
    /// 255 digits (neither in an input trackfix reads, nor in a Status or Turn of 32 bits).
    pub fn new(span: Span, value: u32, binary_digits: Option<usize>) -> Option<BitField> {
        if span.start > span.end {
            return None;
        }
        Some(BitField {
            span: Span32::of(span)?,
            value,
            binary_digits: match binary_digits {
                Some(n) => Some(u8::try_from(n).ok()?),
                None => None,
            },
        })
    }

    /// The whole token, quotes included for the binary form.
    pub fn span(&self) -> Span {
        self.span.span()
    }

    /// The value.
    pub fn value(&self) -> u32 {
        self.value
    }

    /// `Some(n)` for `'B…'` with n digits, `None` for a decimal integer.
    pub fn binary_digits(&self) -> Option<usize> {
        self.binary_digits.map(usize::from)
    }

    /// The text for `new` in the same style, or `None` if the value is unchanged.
    pub fn rewrite(&self, new: u32) -> Option<String> {
        if new == self.value {
            return None;
        }
        Some(match self.binary_digits() {
            Some(n) => format!("'B{new:0n$b}'"),
            None => new.to_string(),
        })
    }
}

/// Two per KRL target, as for [`NumField`].
const _: () = assert!(std::mem::size_of::<Option<BitField>>() <= 16);

impl std::fmt::Debug for BitField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BitField")
            .field("span", &self.span())
            .field("value", &self.value)
            .field("binary_digits", &self.binary_digits)
            .finish()
    }
}

/// An orientation as written: ABB quaternion or KUKA A, B, C. A field that is not a numeric
/// literal (an expression) is `None`.
#[derive(Clone, Debug, PartialEq)]
pub enum Orientation {
    /// `[q1, q2, q3, q4]`, scalar first.
    Quaternion([Option<NumField>; 4]),
    /// `A, B, C` in degrees.
    Abc([Option<NumField>; 3]),
}

impl Orientation {
    /// The quaternion as written, for ABB literals with all four fields numeric.
    pub fn written_quaternion(&self) -> Option<[f64; 4]> {
        match self {
            Orientation::Quaternion(q) => values(q),
            Orientation::Abc(_) => None,
        }
    }
}

/// The Cartesian part of a target or frame: translation and orientation fields.
#[derive(Clone, Debug, PartialEq)]
pub struct CartesianFields {
    /// `x, y, z` in mm.
    pub trans: [Option<NumField>; 3],
    /// `None` where the literal does not write one (a partial KRL aggregate).
    pub orient: Option<Orientation>,
}

fn values<const N: usize>(fields: &[Option<NumField>; N]) -> Option<[f64; N]> {
    let mut out = [0.0; N];
    for (o, f) in out.iter_mut().zip(fields) {
        *o = f.as_ref()?.value();
    }
    Some(out)
}

impl CartesianFields {
    /// `[x, y, z]` if all three are numeric literals.
    pub fn translation(&self) -> Option<[f64; 3]> {
        values(&self.trans)
    }

    /// The orientation, if all its fields are numeric literals (and the quaternion is not zero).
    pub fn rotation(&self) -> Option<UnitQuaternion<f64>> {
        match self.orient.as_ref()? {
            Orientation::Quaternion(q) => abb_quat(values(q)?),
            Orientation::Abc(abc) => {
                let [a, b, c] = values(abc)?;
                Some(kuka_abc(a, b, c))
            }
        }
    }

    /// The quaternion as written, for ABB literals with all four fields numeric.
    pub fn written_quaternion(&self) -> Option<[f64; 4]> {
        self.orient.as_ref()?.written_quaternion()
    }

    /// The pose, if every field is a numeric literal (and the quaternion is not zero).
    pub fn pose(&self) -> Option<Pose> {
        let [x, y, z] = self.translation()?;
        Some(Isometry3::from_parts(
            Translation3::new(x, y, z),
            self.rotation()?,
        ))
    }
}

/// A robot configuration as written, by convention (the dialect says which its targets
/// write; [`Dialect::configuration_of`](crate::dialect::Dialect::configuration_of)).
#[derive(Clone, Debug, PartialEq)]
pub enum Config {
    /// Axis quadrants `[cf1, cf4, cf6, cfx]`: the quarter turn axes 1, 4 and 6 are in, and the
    /// arm configuration number (ABB `confdata`).
    Quadrants([Option<NumField>; 4]),
    /// Status and Turn bits: the arm configuration, and which axes are negative (KUKA `S`,
    /// `T`).
    StatusTurn {
        /// `S`, when written.
        status: Option<BitField>,
        /// `T`, when written.
        turn: Option<BitField>,
    },
    /// Not written (POS without S/T, FRAME, joint targets).
    None,
}

/// A work object's, base's or tool's name as a target's [`Usage`] keeps it: text that reads as
/// a `&str` (`u.wobj.as_deref() == Some("wCar")`), shared by every target used with the frame.
///
/// One pointer (an `Arc<str>` is two): a module's targets are used with a handful of frames
/// and tools, and each of 100,000 targets holds two of these.
#[derive(Clone, PartialEq, Eq, Hash)]
pub struct FrameName(Arc<Box<str>>);

impl From<&str> for FrameName {
    fn from(s: &str) -> FrameName {
        FrameName(Arc::new(s.into()))
    }
}

impl std::ops::Deref for FrameName {
    type Target = str;

    fn deref(&self) -> &str {
        &self.0
    }
}

/// A set of names is looked up by `&str` (hashed and compared as the text, like the derived
/// `Hash` and `Eq`).
impl std::borrow::Borrow<str> for FrameName {
    fn borrow(&self) -> &str {
        &self.0
    }
}

impl PartialEq<str> for FrameName {
    fn eq(&self, other: &str) -> bool {
        **self.0 == *other
    }
}

impl PartialEq<&str> for FrameName {
    fn eq(&self, other: &&str) -> bool {
        **self.0 == **other
    }
}

impl std::fmt::Debug for FrameName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Debug::fmt(&**self.0, f)
    }
}

impl std::fmt::Display for FrameName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// Where and how a target is used by the motion instructions that reference it.
///
/// Forty bytes (it was 96), one per target: the names are shared [`FrameName`]s, and what few
/// targets have — a second work object, a reason their pose is only known at run time, a
/// stationary tool — is kept apart, behind one pointer ([`Usage::other_wobjs`],
/// [`Usage::run_time`], [`Usage::stationary_tool`]). A flag of its own made it 48: the
/// position list keeps a usage per target, and every page of it is one the kernel clears.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Usage {
    /// The RAPID work object, or the KRL base (`"BASE_DATA[3]"`), of the first use. `None` if
    /// never used or unresolved.
    pub wobj: Option<FrameName>,
    /// The tool of the first use.
    pub tool: Option<FrameName>,
    /// 1-based lines of the instructions that use it.
    pub lines: Lines,
    /// Further work objects and the run-time reason, when there are any.
    rare: Option<Box<RareUsage>>,
}

/// The parts of a [`Usage`] that few targets have.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct RareUsage {
    other_wobjs: Vec<FrameName>,
    other_tools: Vec<FrameName>,
    run_time: Option<RunTimeValue>,
    stationary_tool: bool,
    zone: Option<NonPosition>,
    /// The first motion to the target whose frame is not known (a KRL base set on one path
    /// only, a RAPID frame its module sees another declaration of than the target's).
    unresolved_frame: Option<UnresolvedFrame>,
    /// The first motion to the target with a tool its routine is passed.
    unresolved_tool: Option<UnresolvedFrame>,
    /// The first motion to the target that may run while its work object holds its declared
    /// value, the program giving the frame another; and the first that may while its tool
    /// does (at most one of each kind).
    two_values: Vec<TwoValues>,
}

/// A target's usage is kept for each of 100,000 targets: a layout change that grows it fails
/// the build.
const _: () = assert!(std::mem::size_of::<Usage>() <= 40);

/// Why a target's pose is only known when the program runs, so no offline transform can
/// correct it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RunTimeValue {
    /// The program gives the target a computed value (`p10 := CRobT()`, `pArr{i} := …`,
    /// `P[I] = $POS_ACT`) at `line`; for an array element written through a computed index,
    /// every element of the array.
    Target {
        /// Where the assignment is.
        at: UseLine,
    },
    /// The work object or base of a motion that uses the target is computed when the program
    /// runs (`wobj1.uframe := …`, `$BASE = EK(…)`).
    Frame {
        /// The frame's name, when it has one (`wobj1`); `None` for an expression that selects
        /// the base (`$BASE = BASE_DATA[I]`).
        name: Option<String>,
        /// Where the assignment is.
        at: UseLine,
    },
    /// The program gives the work object or tool (KRL base or tool data) a motion uses a whole
    /// value other than its declaration (`wobj1 := [FALSE,TRUE,"",[[2100,…]],…];`,
    /// `BASE_DATA[1] = {X 100, …}`): known offline, but which of the two a motion runs with
    /// depends on the program's flow.
    FrameAssigned {
        /// The frame's name as declared (`wobj1`, `BASE_DATA[1]`).
        name: String,
        /// Where the assignment is.
        at: UseLine,
    },
    /// The program offsets the external axes (RAPID `EOffsSet`, `EOffsOn`): a motion moves
    /// the track to the written position plus an offset known only when it runs, so the skid
    /// the correction depends on is not the one written.
    AxesOffset {
        /// The instruction, as the language spells it.
        instruction: &'static str,
        /// Where it is.
        at: UseLine,
    },
    /// The program displaces its motions (RAPID `PDispSet`, `PDispOn`): a motion reaches the
    /// target in its work object moved by a frame known only when it runs.
    ProgramDisplacement {
        /// The instruction, as the language spells it.
        instruction: &'static str,
        /// Where it is.
        at: UseLine,
    },
    /// A call that names its data or routine only when the program runs may read, write or
    /// move to the target (RAPID `SetDataVal`, `GetDataVal` with a computed name,
    /// `SetAllDataVal`; a late-bound call `%name% p10;`), in a work object trackfix cannot tell.
    NamedAtRunTime {
        /// The call, as written (`SetDataVal`, `%pn%`).
        call: String,
        /// Where it is.
        at: UseLine,
    },
}

/// A work object or tool a target is moved to with in two values: its declaration's, and the
/// one the program gives it (`wA := [FALSE,TRUE,"",[[…]]…];`), which trackfix takes for the
/// frame (docs/design.md, "Frames the program assigns"). A motion to the target may run while
/// the declared value still holds: before the assignment in program order, in a routine called
/// before it as well as after, in `main` the first time it runs, or in a routine the program
/// enters from outside.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TwoValues {
    /// A work object's or a tool's.
    pub kind: FrameKind,
    /// The frame's name as declared.
    pub frame: String,
    /// Its declaration.
    pub declared: UseLine,
    /// The assignment of the other value (the first, where several give it).
    pub given: UseLine,
    /// A motion to the target that may run with the declared value (the first found).
    pub motion: UseLine,
}

impl std::fmt::Display for TwoValues {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "`{}` as declared ({}) and as the program gives it ({}): the motion on {} may run before the assignment",
            self.frame, self.declared, self.given, self.motion
        )
    }
}

/// A motion to a target with a work object (base) trackfix cannot tell.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnresolvedFrame {
    /// Where the motion is.
    pub at: UseLine,
    /// Why the frame is not known there.
    pub cause: UnresolvedCause,
}

/// Why the frame (or tool) of a motion is not known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UnresolvedCause {
    /// A KRL base set on some paths only.
    SomePaths,
    /// The motion names a frame that means another declaration there than where the target
    /// is declared (a RAPID `LOCAL` frame, or one a routine declares for itself).
    Shadowed(String),
    /// The motion names a parameter of its routine: the frame is whatever each caller passes.
    Parameter(String),
    /// The target is passed to a routine of the program (KRL), whose motions trackfix does
    /// not follow: the base they move in is not known.
    PassedTo(String),
    /// A routine the program runs where trackfix does not follow it (KRL: a function, called
    /// inside an expression; an interrupt's or a trigger's) changes the base or tool.
    ChangedBy(String),
    /// A routine hands the target's value back to its callers (KRL: written into a parameter
    /// not `:IN`, or returned by a function): how, in words (``returned by `GETPT` ``). The
    /// motions that move to what the callers get are not tied to the target.
    HandedBack(String),
    /// The target is a literal held in a member of a KRL structure (`DECL SPT S1={P {X …}, K
    /// 1}`, `S1.P={X …}`): the structure's name as written (`S1`, `SA[1]`). A structure's
    /// values travel where trackfix does not follow a member (a copy of the whole structure,
    /// an array of structures chosen at run time, a parameter, another module), so the base
    /// the robot moves to it in is not known.
    Member(String),
}

/// The line of a use, and the file it is in when that is not the used target's own (a KRL
/// `.dat` target used in its `.src`, a RAPID target of one module used in another): a
/// message on the target names a line of another file only together with that file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UseLine {
    /// 1-based line of the use.
    pub line: usize,
    /// The name of the file the use is in, when it is not the target's own.
    pub file: Option<std::sync::Arc<str>>,
}

impl UseLine {
    /// Line `line` of the target's own file.
    pub fn new(line: usize) -> UseLine {
        UseLine { line, file: None }
    }

    /// Line `line` of the file named `use_file` (as [`UseLine::file_name`] gives it): of
    /// another file when `use_file_index` is not `target_file_index`.
    pub(crate) fn of(
        line: usize,
        use_file_index: usize,
        target_file_index: usize,
        use_file: &std::sync::Arc<str>,
    ) -> UseLine {
        UseLine {
            line,
            file: (use_file_index != target_file_index).then(|| use_file.clone()),
        }
    }

    /// How messages name the file at `path`: its file name, as it is listed in its folder.
    pub fn file_name(path: &std::path::Path) -> std::sync::Arc<str> {
        path.file_name()
            .unwrap_or(path.as_os_str())
            .to_string_lossy()
            .into()
    }
}

impl std::fmt::Display for UseLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.file {
            None => write!(f, "line {}", self.line),
            Some(file) => write!(f, "line {} of {file}", self.line),
        }
    }
}

/// A target the program uses as other than a position the robot moves to: a joint target a
/// world-zone instruction takes as a tolerance or as limits (RAPID `WZHomeJointDef`'s
/// `DeltaJointVal`, `WZLimJointDef`'s `LowJointVal` and `HighJointVal`), a KRL position added
/// to a frame with the geometric operator `:` (`FPALLET:SLOT:XPLACE_REL`), a target a search
/// writes the position it finds into (`SearchL`'s `SearchPoint`). Moved as a position,
/// it would give the zone or the composed frame nonsense.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NonPosition {
    /// What uses it, as the language spells it (`WZHomeJointDef`, `:`).
    pub instruction: &'static str,
    /// As what (`DeltaJointVal`; `right operand` of `:`).
    pub parameter: &'static str,
    /// What its values are.
    pub role: NonPositionRole,
    /// Where the use is.
    pub at: UseLine,
}

/// What a [`NonPosition`]'s values are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NonPositionRole {
    /// Half-widths around a middle position, each axis's own and non-negative: the same for
    /// the track corrected and for the mirrored robot.
    Tolerance,
    /// One end of the joint ranges: a mirrored robot's zone has other ends (axis 1 negated
    /// swaps low and high), which no transform of one target gives.
    Limit,
    /// An offset in the frame of what stands before the `:`: a correction of that frame moves
    /// the composed one with it, and a mirror reflects the offset in its own frame, which no
    /// transform of a target gives.
    Offset,
    /// Written by the instruction with the position it finds (RAPID `SearchL`'s
    /// `SearchPoint`): what it holds when the program runs is measured, whatever its
    /// declaration says, so no transform has anything to change in it.
    Found,
}

impl RunTimeValue {
    /// Where the assignment is.
    pub fn at(&self) -> &UseLine {
        match self {
            RunTimeValue::Target { at }
            | RunTimeValue::Frame { at, .. }
            | RunTimeValue::FrameAssigned { at, .. }
            | RunTimeValue::AxesOffset { at, .. }
            | RunTimeValue::ProgramDisplacement { at, .. }
            | RunTimeValue::NamedAtRunTime { at, .. } => at,
        }
    }

    pub(crate) fn at_mut(&mut self) -> &mut UseLine {
        match self {
            RunTimeValue::Target { at }
            | RunTimeValue::Frame { at, .. }
            | RunTimeValue::FrameAssigned { at, .. }
            | RunTimeValue::AxesOffset { at, .. }
            | RunTimeValue::ProgramDisplacement { at, .. }
            | RunTimeValue::NamedAtRunTime { at, .. } => at,
        }
    }

    /// Why, in words, after the target's description.
    pub fn describe(&self) -> String {
        match self {
            RunTimeValue::Target { at } => {
                format!("is given a computed value at run time ({at})")
            }
            RunTimeValue::Frame { name: Some(n), at } => {
                format!("is used with `{n}`, which is computed at run time ({at})")
            }
            RunTimeValue::Frame { name: None, at } => {
                format!("is used with a base computed at run time ({at})")
            }
            RunTimeValue::FrameAssigned { name, at } => format!(
                "is used with `{name}`, which the program gives another value than its declaration ({at})"
            ),
            RunTimeValue::AxesOffset { instruction, at } => format!(
                "is moved to by a program that offsets the external axes (`{instruction}`, {at}): its skid when it runs is not the one written"
            ),
            RunTimeValue::ProgramDisplacement { instruction, at } => format!(
                "is moved to by a program that displaces its motions (`{instruction}`, {at}): the frame it is reached in is not its work object's"
            ),
            RunTimeValue::NamedAtRunTime { call, at } => format!(
                "may be read, written or moved to by `{call}` ({at}), whose data or routine the program names only when it runs"
            ),
        }
    }
}

impl RunTimeValue {
    /// What to do about it, in words.
    pub fn hint(&self) -> &'static str {
        match self {
            RunTimeValue::FrameAssigned { .. } => {
                "declare the frame with the value the program gives it, so that one value holds"
            }
            _ => "correct the program's computation of it by hand, or teach the target",
        }
    }
}

impl Usage {
    /// Further distinct work objects the target is used with. Non-empty means the target is
    /// used with two work objects and cannot be transformed unambiguously.
    pub fn other_wobjs(&self) -> &[FrameName] {
        self.rare.as_ref().map_or(&[], |r| &r.other_wobjs)
    }

    /// Every work object the target is used with: the first use's, then the others (which
    /// only a target with a first one has).
    pub fn work_objects(&self) -> impl Iterator<Item = &str> {
        let others = self.other_wobjs().iter().map(|w| &**w);
        self.wobj.as_deref().into_iter().chain(others)
    }

    /// Further distinct tools the target is used with: its joints, reach and configuration
    /// depend on the tool, so each is checked, and a transform that writes a configuration
    /// needs them to agree.
    pub fn other_tools(&self) -> &[FrameName] {
        self.rare.as_ref().map_or(&[], |r| &r.other_tools)
    }

    /// Every tool the target is used with: the first use's, then the others.
    pub fn tools(&self) -> impl Iterator<Item = &str> {
        let others = self.other_tools().iter().map(|t| &**t);
        self.tool.as_deref().into_iter().chain(others)
    }

    /// The target is a stationary-tool point (KRL `IPO_FRAME #TCP`, RAPID `robhold TRUE`):
    /// some use of it says so.
    pub fn stationary_tool(&self) -> bool {
        self.rare.as_ref().is_some_and(|r| r.stationary_tool)
    }

    /// Set when the target's pose is only known when the program runs: the first reason found.
    pub fn run_time(&self) -> Option<&RunTimeValue> {
        self.rare.as_ref()?.run_time.as_ref()
    }

    /// Marks the target as known only at run time, keeping the first reason.
    pub fn set_run_time(&mut self, why: RunTimeValue) {
        let rare = self.rare.get_or_insert_with(Box::default);
        if rare.run_time.is_none() {
            rare.run_time = Some(why);
        }
    }

    /// Set when the program uses the target as other than a position: the first use found.
    pub fn non_position(&self) -> Option<&NonPosition> {
        self.rare.as_ref()?.zone.as_ref()
    }

    /// The first line of a motion to the target whose work object (base) is not known, if any:
    /// whatever the others use, the target's frame is then not known either.
    pub fn unresolved_frame(&self) -> Option<&UnresolvedFrame> {
        self.rare.as_ref()?.unresolved_frame.as_ref()
    }

    /// Records a motion to the target whose work object (base) is not known.
    pub fn mark_unresolved_frame(&mut self, why: UnresolvedFrame) {
        let rare = self.rare.get_or_insert_with(Box::default);
        if rare.unresolved_frame.is_none() {
            rare.unresolved_frame = Some(why);
        }
    }

    /// The first motion to the target with a tool that is not known (a RAPID routine's tool
    /// parameter): the target's joints depend on it.
    pub fn unresolved_tool(&self) -> Option<&UnresolvedFrame> {
        self.rare.as_ref()?.unresolved_tool.as_ref()
    }

    /// Records a motion to the target whose tool is not known.
    pub fn mark_unresolved_tool(&mut self, why: UnresolvedFrame) {
        let rare = self.rare.get_or_insert_with(Box::default);
        if rare.unresolved_tool.is_none() {
            rare.unresolved_tool = Some(why);
        }
    }

    /// The target is moved to in two values of its work object or of its tool (see
    /// [`TwoValues`]): a motion to it may run while the frame holds its declared value, the
    /// program giving it another. The first motion found for each kind of frame.
    pub fn two_values(&self, kind: FrameKind) -> Option<&TwoValues> {
        let rare = self.rare.as_ref()?;
        rare.two_values.iter().find(|t| t.kind == kind)
    }

    /// Every [`two_values`](Usage::two_values) of the target, in the order found.
    pub fn every_two_values(&self) -> &[TwoValues] {
        self.rare.as_ref().map_or(&[], |r| r.two_values.as_slice())
    }

    /// Records a motion to the target that may run while its work object or tool holds its
    /// declared value, keeping the first of each kind.
    pub fn mark_two_values(&mut self, why: TwoValues) {
        let rare = self.rare.get_or_insert_with(Box::default);
        if rare.two_values.iter().all(|t| t.kind != why.kind) {
            rare.two_values.push(why);
        }
    }

    /// Marks the target as used as other than a position, keeping the first use found.
    pub fn set_non_position(&mut self, zone: NonPosition) {
        let rare = self.rare.get_or_insert_with(Box::default);
        if rare.zone.is_none() {
            rare.zone = Some(zone);
        }
    }

    /// Records one use by a motion at `line` with work object (or base) `wobj` and `tool`.
    /// The first work object stays the target's; another (names compared as the languages
    /// compare them, case-insensitively) is added to `other_wobjs`; tools likewise, to
    /// `other_tools`.
    pub fn record(
        &mut self,
        wobj: Option<&str>,
        tool: Option<&str>,
        stationary: bool,
        line: usize,
    ) {
        let wobj = wobj.map(FrameName::from);
        let tool = tool.map(FrameName::from);
        self.record_shared(wobj.as_ref(), tool.as_ref(), stationary, line);
    }

    /// [`Usage::record`] with names already shared: a name kept is a clone of the handle, not
    /// a copy of the text.
    pub fn record_shared(
        &mut self,
        wobj: Option<&FrameName>,
        tool: Option<&FrameName>,
        stationary: bool,
        line: usize,
    ) {
        self.record_frames(wobj, tool, stationary);
        // Lines of an input of at most 512 MiB fit 32 bits.
        let line = u32::try_from(line).unwrap_or(u32::MAX);
        if !self.lines.contains(&line) {
            self.lines.push(line);
        }
    }

    /// Records the frames a target is used with, as [`Usage::record_shared`] does, without a
    /// line: for a target no motion uses whose frames the program states otherwise (a KRL
    /// point's inline-form `FDAT`).
    #[inline]
    pub fn record_frames(
        &mut self,
        wobj: Option<&FrameName>,
        tool: Option<&FrameName>,
        stationary: bool,
    ) {
        if let Some(w) = wobj {
            match &self.wobj {
                None => self.wobj = Some(w.clone()),
                // The same handle is the same text: call after call names the frame its
                // target was first used with, told by one compare of pointers.
                Some(first) if Arc::ptr_eq(&first.0, &w.0) || first.eq_ignore_ascii_case(w) => {}
                Some(_) => {
                    let rare = self.rare.get_or_insert_with(Box::default);
                    if !rare.other_wobjs.iter().any(|o| o.eq_ignore_ascii_case(w)) {
                        rare.other_wobjs.push(w.clone());
                    }
                }
            }
        }
        if let Some(t) = tool {
            match &self.tool {
                None => self.tool = Some(t.clone()),
                Some(first) if Arc::ptr_eq(&first.0, &t.0) || first.eq_ignore_ascii_case(t) => {}
                Some(_) => {
                    let rare = self.rare.get_or_insert_with(Box::default);
                    if !rare.other_tools.iter().any(|o| o.eq_ignore_ascii_case(t)) {
                        rare.other_tools.push(t.clone());
                    }
                }
            }
        }
        if stationary {
            self.rare.get_or_insert_with(Box::default).stationary_tool = true;
        }
    }
}

/// A short list kept in place, up to `N` items, read as a slice; a longer one spills into a
/// vector behind one pointer (so the rare long list does not widen every target's). What
/// [`Axes`] and [`Lines`] hold: one each for 100,000 targets, where a vector each was 100,000
/// heap blocks.
#[derive(Clone)]
enum InlineList<T, const N: usize> {
    Inline(u8, [T; N]),
    #[allow(clippy::box_collection)] // a thin pointer: see the type
    Spilled(Box<Vec<T>>),
}

impl<T: Copy, const N: usize> InlineList<T, N> {
    /// No items; `fill` only fills the unused places.
    const fn empty(fill: T) -> InlineList<T, N> {
        InlineList::Inline(0, [fill; N])
    }

    fn push(&mut self, item: T) {
        match self {
            InlineList::Inline(len, items) => match items.get_mut(*len as usize) {
                Some(slot) => {
                    *slot = item;
                    *len += 1;
                }
                None => {
                    let mut all = Vec::with_capacity(N * 2);
                    all.extend_from_slice(items);
                    all.push(item);
                    *self = InlineList::Spilled(Box::new(all));
                }
            },
            InlineList::Spilled(all) => all.push(item),
        }
    }

    fn as_slice(&self) -> &[T] {
        match self {
            InlineList::Inline(len, items) => items.get(..*len as usize).unwrap_or_default(),
            InlineList::Spilled(all) => all,
        }
    }
}

/// Lists are equal by their items, wherever they are kept.
impl<T: Copy + PartialEq, const N: usize> PartialEq for InlineList<T, N> {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl<T: Copy + Eq, const N: usize> Eq for InlineList<T, N> {}

/// How many fields [`Axes`] keeps without a heap block: the six external axes of both
/// languages (RAPID `eax_a..eax_f`, KRL `E1..E6`).
const INLINE_AXES: usize = 6;

/// A position's external axes as written: a list of fields that reads as a slice
/// (`p.extax.get(0)`, `p.extax.len()`, `p.extax.iter()`).
///
/// Up to six are kept in place: a 20 MB module holds 100,000 targets, and a vector each was
/// 14 MB of `check`'s peak and 100,000 allocations. A longer list (an aggregate that is not
/// a RAPID `extjoint`) keeps all its fields, in a vector.
#[derive(Clone, PartialEq)]
pub struct Axes(InlineList<Option<NumField>, INLINE_AXES>);

impl Axes {
    /// No fields.
    pub const fn new() -> Axes {
        Axes(InlineList::empty(None))
    }

    /// Appends `field`.
    pub fn push(&mut self, field: Option<NumField>) {
        self.0.push(field);
    }
}

impl Default for Axes {
    fn default() -> Axes {
        Axes::new()
    }
}

impl std::ops::Deref for Axes {
    type Target = [Option<NumField>];

    fn deref(&self) -> &[Option<NumField>] {
        self.0.as_slice()
    }
}

impl std::fmt::Debug for Axes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl FromIterator<Option<NumField>> for Axes {
    fn from_iter<I: IntoIterator<Item = Option<NumField>>>(iter: I) -> Axes {
        let mut out = Axes::new();
        for f in iter {
            out.push(f);
        }
        out
    }
}

impl From<Vec<Option<NumField>>> for Axes {
    fn from(v: Vec<Option<NumField>>) -> Axes {
        v.into_iter().collect()
    }
}

impl<'a> IntoIterator for &'a Axes {
    type Item = &'a Option<NumField>;
    type IntoIter = std::slice::Iter<'a, Option<NumField>>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl PartialEq<Vec<Option<NumField>>> for Axes {
    fn eq(&self, other: &Vec<Option<NumField>>) -> bool {
        **self == **other
    }
}

/// The 1-based lines of the instructions that use a target, in the order found: a list that
/// reads as a slice of `u32` (lines of an input of at most 512 MiB fit).
///
/// Sixteen bytes. Nearly every target is used once or twice: up to three lines are kept in
/// place, more spill into a vector (see [`InlineList`]).
#[derive(Clone, PartialEq, Eq)]
pub struct Lines(InlineList<u32, INLINE_LINES>);

/// How many lines [`Lines`] keeps in place.
const INLINE_LINES: usize = 3;

const _: () = assert!(std::mem::size_of::<Lines>() <= 16);

impl Default for Lines {
    fn default() -> Lines {
        Lines(InlineList::empty(0))
    }
}

impl Lines {
    /// Appends `line`.
    pub fn push(&mut self, line: u32) {
        self.0.push(line);
    }
}

impl std::ops::Deref for Lines {
    type Target = [u32];

    fn deref(&self) -> &[u32] {
        self.0.as_slice()
    }
}

impl std::fmt::Debug for Lines {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl FromIterator<u32> for Lines {
    fn from_iter<I: IntoIterator<Item = u32>>(iter: I) -> Lines {
        let mut out = Lines::default();
        for l in iter {
            out.push(l);
        }
        out
    }
}

impl From<Vec<u32>> for Lines {
    fn from(v: Vec<u32>) -> Lines {
        v.into_iter().collect()
    }
}

impl<'a> IntoIterator for &'a Lines {
    type Item = &'a u32;
    type IntoIter = std::slice::Iter<'a, u32>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl PartialEq<Vec<u32>> for Lines {
    fn eq(&self, other: &Vec<u32>) -> bool {
        **self == **other
    }
}

impl<const N: usize> PartialEq<[u32; N]> for Lines {
    fn eq(&self, other: &[u32; N]) -> bool {
        **self == other[..]
    }
}

/// Names up to this many bytes are kept in place in a [`Name`].
pub(crate) const INLINE_NAME: usize = 22;

/// A target's declared name as written: text that reads as a `&str` (`p.name.as_deref()`).
///
/// Names of up to 22 bytes (nearly all: `p10`, `XP100001`, `pGrid{2,1}`) are kept in place:
/// a `String` each was 100,000 heap blocks on a 20 MB module. Longer ones are boxed.
#[derive(Clone)]
pub struct Name(NameRepr);

#[derive(Clone)]
enum NameRepr {
    Inline(u8, [u8; INLINE_NAME]),
    Boxed(Box<str>),
}

impl Name {
    /// The name as text.
    pub fn as_str(&self) -> &str {
        match &self.0 {
            // Always valid: the bytes are a whole `&str` copied in (see `From<&str>`).
            NameRepr::Inline(len, bytes) => bytes
                .get(..*len as usize)
                .and_then(|b| std::str::from_utf8(b).ok())
                .unwrap_or_default(),
            NameRepr::Boxed(s) => s,
        }
    }

    /// The name's bytes: comparing names needs no UTF-8 check of the inline bytes (resolving a
    /// KRL program compares and looks up names by the hundred thousand).
    pub(crate) fn as_bytes(&self) -> &[u8] {
        match &self.0 {
            NameRepr::Inline(len, bytes) => bytes.get(..*len as usize).unwrap_or_default(),
            NameRepr::Boxed(s) => s.as_bytes(),
        }
    }

    /// A name of ASCII bytes, without the UTF-8 check a `&str` would need first; `None` if
    /// `bytes` is not ASCII.
    pub(crate) fn from_ascii(bytes: &[u8]) -> Option<Name> {
        if !bytes.is_ascii() {
            return None;
        }
        match Name::inline(bytes) {
            Some(name) => Some(name),
            None => Some(Name::from(std::str::from_utf8(bytes).ok()?)),
        }
    }

    /// `bytes` kept in place, if they fit; the caller vouches that they are UTF-8.
    fn inline(bytes: &[u8]) -> Option<Name> {
        let mut inline = [0u8; INLINE_NAME];
        inline.get_mut(..bytes.len())?.copy_from_slice(bytes);
        Some(Name(NameRepr::Inline(bytes.len() as u8, inline)))
    }
}

impl From<&str> for Name {
    fn from(s: &str) -> Name {
        Name::inline(s.as_bytes()).unwrap_or_else(|| Name(NameRepr::Boxed(s.into())))
    }
}

impl From<String> for Name {
    fn from(s: String) -> Name {
        if s.len() <= INLINE_NAME {
            Name::from(s.as_str())
        } else {
            Name(NameRepr::Boxed(s.into_boxed_str()))
        }
    }
}

impl std::ops::Deref for Name {
    type Target = str;

    fn deref(&self) -> &str {
        self.as_str()
    }
}

impl PartialEq for Name {
    fn eq(&self, other: &Name) -> bool {
        self.as_bytes() == other.as_bytes()
    }
}

impl Eq for Name {}

impl PartialEq<str> for Name {
    fn eq(&self, other: &str) -> bool {
        self.as_bytes() == other.as_bytes()
    }
}

impl PartialEq<&str> for Name {
    fn eq(&self, other: &&str) -> bool {
        self.as_bytes() == other.as_bytes()
    }
}

/// A map keyed by names is looked up by `&str` (hashed and compared as the text, like the
/// `Hash` and `Eq` here).
impl std::borrow::Borrow<str> for Name {
    fn borrow(&self) -> &str {
        self.as_str()
    }
}

impl std::hash::Hash for Name {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.as_str().hash(state);
    }
}

impl std::fmt::Debug for Name {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Debug::fmt(self.as_str(), f)
    }
}

impl std::fmt::Display for Name {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One target: a declaration (`name = Some`) or an inline literal in an instruction.
#[derive(Clone, Debug, PartialEq)]
pub struct Position {
    /// Declared name; `None` for an inline literal.
    pub name: Option<Name>,
    /// Its data type.
    pub kind: PositionKind,
    /// The literal (aggregate) itself.
    pub span: Span,
    /// 1-based line and column of the literal's start.
    pub line: usize,
    /// 1-based column of the literal's start.
    pub column: usize,
    /// Translation and orientation, for Cartesian kinds.
    pub cartesian: Option<CartesianFields>,
    /// Robot axis values of joint kinds (`rax_1..rax_6`, `A1..A6`), degrees.
    pub joints: Vec<Option<NumField>>,
    /// The robot configuration, as written.
    pub config: Config,
    /// External axes as written: RAPID `eax_a..eax_f`, KRL `E1..E6` (shorter if fewer are
    /// written).
    pub extax: Axes,
    /// The frames and tool of the motion instructions that reference it, and their lines.
    pub usage: Usage,
}

/// A skid value read from a target's external axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Skid {
    /// The skid position, mm (the axis value as written).
    At(f64),
    /// `9E9`: the axis is not connected.
    NotConnected,
    /// The axis is not written, or is an expression.
    Missing,
}

impl Position {
    /// The value of external axis `index` (0 = `eax_a` / `E1`) as a skid position.
    pub fn skid(&self, index: usize) -> Skid {
        match self.extax.get(index).and_then(Option::as_ref) {
            Some(f) if f.value().abs() >= NOT_CONNECTED => Skid::NotConnected,
            Some(f) => Skid::At(f.value()),
            None => Skid::Missing,
        }
    }

    /// A human name for messages: the declared name or `inline <kind>`.
    pub fn label(&self) -> String {
        label(self.name.as_deref(), self.kind)
    }
}

/// [`Position::label`] of a target named `name` (`None`: inline) of `kind`.
pub(crate) fn label(name: Option<&str>, kind: PositionKind) -> String {
    match name {
        Some(n) => n.to_owned(),
        None => format!("inline {}", kind.as_str()),
    }
}

/// What a declared frame is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrameKind {
    /// RAPID `wobjdata`.
    WorkObject,
    /// RAPID `tooldata` or KRL `TOOL_DATA[n]`.
    Tool,
    /// KRL `BASE_DATA[n]`.
    Base,
}

/// A declared work object, tool or base.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameDecl {
    /// `wobj_car`, `tGun`, `BASE_DATA[3]`, `TOOL_DATA[1]`.
    pub name: String,
    /// What it is.
    pub kind: FrameKind,
    /// The declaration's bytes.
    pub span: Span,
    /// 1-based line of the declaration.
    pub line: usize,
    /// Whether the robot holds it, where the language says (RAPID `robhold`): a work object
    /// the robot holds, or a tool it does not, is a stationary-tool setup.
    pub held_by_robot: Option<bool>,
    /// Whether the frame stays where it is declared, where the language says (RAPID `ufprog`):
    /// `Some(false)` is a frame a mechanical unit moves.
    pub fixed: Option<bool>,
    /// The mechanical unit that moves the frame, when named (RAPID `ufmec`).
    pub moved_by: Option<String>,
    /// The frame itself: RAPID wobj `uframe`, tool `tframe`; KRL `BASE_DATA`/`TOOL_DATA` value.
    pub frame: Option<CartesianFields>,
    /// RAPID wobj `oframe` (object frame in the user frame).
    pub oframe: Option<CartesianFields>,
    /// Where its name is seen.
    pub scope: FrameScope,
    /// How the program keeps its value.
    pub storage: FrameStorage,
    /// The value is one a routine of the program gives the frame (`wobj1 := [FALSE,…];`),
    /// which stands for the declaration's (docs/design.md, "Frames the program assigns").
    pub assigned: bool,
}

/// Where a declared frame's name is seen, as a motion looks it up: its own module's
/// declaration first (a routine's own, for a motion in that routine), then one the whole
/// program sees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrameScope {
    /// Every module (RAPID module data not `LOCAL`, KRL `$config.dat`).
    #[default]
    Program,
    /// Its module only (RAPID `LOCAL`).
    Module,
    /// The routine it is declared in only, by its index among the module's routines.
    Routine(usize),
}

/// How the program keeps a frame's value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrameStorage {
    /// Never given another (RAPID `CONST`): the controller rejects an assignment.
    Constant,
    /// Starts from its declaration whenever the program starts (RAPID `VAR`).
    Variable,
    /// Keeps the last value the program gave it, written back to its declaration (RAPID
    /// `PERS`, a KRL data list's).
    #[default]
    Persistent,
}

impl FrameDecl {
    /// Whether `other` (a value the program assigns the frame) is this frame's value, in what
    /// trackfix reads of a frame: who holds it, whether it is fixed and by what unit moved, and
    /// its pose, to 1e-9 mm and rad (`2100` and `2100.000` are one value). A value with a field
    /// that is not a number is no frame's.
    pub fn same_value(&self, other: &FrameDecl) -> bool {
        let close = |x: Pose, y: Pose| {
            (x.translation.vector - y.translation.vector).norm() < 1e-9
                && x.rotation.angle_to(&y.rotation) < 1e-9
        };
        (self.held_by_robot, self.fixed, &self.moved_by)
            == (other.held_by_robot, other.fixed, &other.moved_by)
            && matches!((self.pose(), other.pose()), (Some(x), Some(y)) if close(x, y))
    }

    /// The frame in world (work objects: `uframe · oframe`), if every field is numeric.
    pub fn pose(&self) -> Option<Pose> {
        let frame = self.frame.as_ref()?.pose()?;
        match &self.oframe {
            Some(o) => Some(frame * o.pose()?),
            None => Some(frame),
        }
    }
}

/// Which offset function a call is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OffsetKind {
    /// `Offs(p, dx, dy, dz)`: object-frame offsets.
    Offs,
    /// `RelTool(p, dx, dy, dz \Rx \Ry \Rz)`: tool-frame offsets and rotations.
    RelTool,
}

/// An `Offs` or `RelTool` call with numeric offset fields.
#[derive(Clone, Debug, PartialEq)]
pub struct OffsetCall {
    /// Which function.
    pub kind: OffsetKind,
    /// The call's bytes.
    pub span: Span,
    /// 1-based line of the call.
    pub line: usize,
    /// The first argument's text (usually a target name).
    pub target: String,
    /// `dx, dy, dz` (mm); `None` where not a numeric literal.
    pub delta: [Option<NumField>; 3],
    /// Rotations about x, y, z (degrees; RAPID `RelTool`'s `\Rx, \Ry, \Rz`); `None` where
    /// absent or not a numeric literal.
    pub rot: [Option<NumField>; 3],
    /// The rotations that are written as an expression (`\Rz:=angle`), not a number: an
    /// absent rotation is zero, an expression is unknown offline.
    pub rot_expression: [bool; 3],
    /// The declared targets the offset is taken from, as (file of the program, index in its
    /// positions): those the first argument's reference names where the call is written
    /// (`p10` in `Offs(p10, …)`, `pBed` in `Offs(RelTool(pBed, …), …)`, every element of
    /// `pGrid` in `Offs(pGrid{r,c}, …)`), as a motion there would reach them; for a routine's
    /// parameter, the targets the calls pass there. Empty for a computed value.
    pub bases: Vec<(usize, usize)>,
}

/// One parsed source file and everything trackfix understands in it.
#[derive(Clone, Debug)]
pub struct ParsedFile {
    /// The file, as named on input.
    pub path: PathBuf,
    /// Its language (dialect).
    pub language: Language,
    /// The bytes read (or mapped); every span of the file points into them.
    pub source: InputBytes,
    /// Line starts of `source`, for `line:column`.
    pub lines: LineIndex,
    /// Every position declared or written inline, in file order, packed
    /// ([`ParsedFile::positions`] decodes them).
    pub positions: PositionList,
    /// The work objects, tools and bases declared.
    pub frames: Vec<FrameDecl>,
    /// Whole values the program gives a frame in a routine that are the frame's own value (its
    /// declaration's, or that of the one assignment that stands for it in `frames`): a
    /// transform that rewrites the frames rewrites these too, or the program would set the old
    /// value again when it runs. For a frame that one assignment stands for, its declaration
    /// (`assigned` false) is here too: the motions that may run before the assignment move
    /// with it.
    pub frame_values: Vec<FrameDecl>,
    /// The `Offs`/`RelTool` calls with numeric offsets.
    pub offsets: Vec<OffsetCall>,
    /// Constructs the grammar does not know, kept verbatim.
    pub opaque: usize,
    /// Parse errors, unknown constructs and lints, located in this file.
    pub diagnostics: Vec<Diagnostic>,
    /// `print(parse(source)) == source`.
    pub round_trip: bool,
}

impl ParsedFile {
    /// Every position, in file order, decoded.
    pub fn positions(&self) -> impl ExactSizeIterator<Item = Position> + '_ {
        self.positions.iter(&self.source)
    }

    /// Position `i`, decoded.
    pub fn position(&self, i: usize) -> Option<Position> {
        self.positions.get(i, &self.source)
    }

    /// `path:line:col` of a byte offset.
    pub fn location(&self, offset: usize) -> String {
        let (l, c) = self.lines.line_col(offset);
        format!("{}:{l}:{c}", self.path.display())
    }

    /// Renders a diagnostic about this file.
    pub fn render(&self, d: &Diagnostic) -> String {
        d.render(&self.path.display().to_string(), &self.source, &self.lines)
    }
}

/// A program: one RAPID module, or a KRL `.src`/`.dat` pair (either may be alone).
#[derive(Clone, Debug)]
pub struct Program {
    /// Its parsed files, each with its own positions, frames and diagnostics.
    pub files: Vec<ParsedFile>,
}

impl Program {
    /// The dialect of the program's first file (every file of a program shares one).
    pub fn language(&self) -> Option<Language> {
        self.files.first().map(|f| f.language)
    }

    /// The frame `name` (of a kind `kind` accepts) means for a target of file `own`, as a
    /// motion of that file's module looks it up: the file's own declaration (not one a routine
    /// makes for itself), else one every module sees (not `LOCAL`), with the file declaring
    /// it. Where a motion of another module sees another declaration, the usage pass has said
    /// so (`Usage::unresolved_frame`).
    pub fn frame_seen_from<'p>(
        &'p self,
        own: Option<&'p ParsedFile>,
        name: &str,
        kind: impl Fn(FrameKind) -> bool,
    ) -> Option<(&'p ParsedFile, &'p FrameDecl)> {
        let in_file = |f: &'p ParsedFile, seen: &dyn Fn(FrameScope) -> bool| {
            f.frames
                .iter()
                .find(|d| kind(d.kind) && seen(d.scope) && d.name.eq_ignore_ascii_case(name))
                .map(|d| (f, d))
        };
        own.and_then(|f| in_file(f, &|s| !matches!(s, FrameScope::Routine(_))))
            .or_else(|| {
                self.files
                    .iter()
                    .find_map(|f| in_file(f, &|s| s == FrameScope::Program))
            })
    }
}

/// Index of an external axis by name: RAPID `eax_a`..`eax_f` or KRL `E1`..`E6` (any case) →
/// 0..5.
pub fn external_axis_index(name: &str) -> Option<usize> {
    let n = name.trim().to_ascii_lowercase();
    if let Some(letter) = n.strip_prefix("eax_") {
        return match letter.as_bytes() {
            [c @ b'a'..=b'f'] => Some((c - b'a') as usize),
            _ => None,
        };
    }
    match n.as_bytes() {
        [b'e', d @ b'1'..=b'6'] => Some((d - b'1') as usize),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::strategy::Strategy as _;

    #[test]
    fn a_use_records_the_first_frame_and_tool_and_every_other_one_once() {
        let mut u = Usage::default();
        u.record(Some("wCar"), Some("tGun"), false, 10);
        u.record(Some("WCAR"), Some("tOther"), false, 12);
        u.record(Some("wTable"), None, true, 12);
        u.record(Some("wtable"), Some("TGUN"), false, 20);
        u.record(Some("wCar"), Some("tother"), false, 20);
        assert_eq!(u.wobj.as_deref(), Some("wCar"));
        assert_eq!(u.tool.as_deref(), Some("tGun"));
        assert_eq!(u.other_wobjs(), ["wTable"]);
        assert_eq!(u.other_tools(), ["tOther"]);
        assert_eq!(u.tools().collect::<Vec<_>>(), ["tGun", "tOther"]);
        assert!(u.stationary_tool());
        assert_eq!(u.lines, [10, 12, 20]);
    }

    proptest::proptest! {
        /// Lines read back as pushed, in place or spilled, and a usage records each line once.
        #[test]
        fn lines_keep_what_was_pushed(lines in proptest::collection::vec(1u32..50, 0..12)) {
            let kept: Lines = lines.iter().copied().collect();
            proptest::prop_assert_eq!(&*kept, &lines[..]);
            let mut u = Usage::default();
            for &l in &lines {
                u.record(Some("w"), None, false, l as usize);
            }
            let mut once = Vec::new();
            for &l in &lines {
                if !once.contains(&l) {
                    once.push(l);
                }
            }
            proptest::prop_assert_eq!(&*u.lines, &once[..]);
        }
    }

    /// A literal text from its parts: sign, integer digits, point, decimals, exponent.
    fn literal(
        sign: &str,
        int: &str,
        frac: Option<&str>,
        exp: Option<(&str, &str, &str)>,
    ) -> String {
        let mut text = format!("{sign}{int}");
        if let Some(f) = frac {
            text.push('.');
            text.push_str(f);
        }
        if let Some((letter, sign, digits)) = exp {
            text.push_str(letter);
            text.push_str(sign);
            text.push_str(digits);
        }
        text
    }

    proptest::proptest! {
        /// A field gives back the literal and span it was made of, bit for bit, and every
        /// literal a program plausibly writes (up to 40 bytes, exponent below 100) is kept.
        #[test]
        fn a_field_keeps_its_literal(
            sign in proptest::sample::select(vec!["", "+", "-"]),
            int in "[0-9]{0,20}",
            frac in proptest::option::of("[0-9]{0,40}"),
            exp in proptest::option::of((
                proptest::sample::select(vec!["E", "e"]),
                proptest::sample::select(vec!["", "+", "-"]),
                // Zeros (`E-0`, `E+00`) and the bounds a rewrite keeps, and any digits.
                proptest::prop_oneof![
                    proptest::sample::select(vec!["0", "00", "000", "09", "99", "100", "0099"])
                        .prop_map(|s| s.to_owned()),
                    "[0-9]{1,4}",
                ],
            )),
            nines in proptest::sample::select(vec![
                "", "9E9", "9E+09", "9e+9", "9E+009", "-9E9", "+9E9", "9.0E9", "9E09",
            ]),
            start in 0usize..=u32::MAX as usize - 256,
        ) {
            let text = if nines.is_empty() {
                literal(sign, &int, frac.as_deref(), exp.as_ref().map(|(l, s, d)| (*l, *s, d.as_str())))
            } else {
                nines.to_owned()
            };
            // Texts that are no literal (`.`, `-E5`) have no field to make.
            let Some(lit) = NumLit::parse(text.as_bytes()) else {
                return Ok(());
            };
            let span = Span::new(start, start + text.len());
            let field = NumField::new(span, lit);
            if let Some(f) = field {
                proptest::prop_assert_eq!((f.lit(), f.span()), (lit, span), "{}", text);
                proptest::prop_assert_eq!(f.value().to_bits(), lit.value().to_bits(), "{}", text);
                proptest::prop_assert_eq!(f.lit().value().to_bits(), lit.value().to_bits());
            }
            let exponent = text
                .find(['e', 'E'])
                .and_then(|at| text[at + 1..].parse::<i64>().ok())
                .unwrap_or(0);
            if text.len() <= 40 && exponent.abs() < 100 {
                proptest::prop_assert!(field.is_some(), "{}", text);
            }
        }
    }

    #[test]
    fn a_field_refuses_what_it_cannot_keep() {
        let field = |text: &str, len: usize| {
            NumField::new(
                Span::new(7, 7 + len),
                NumLit::parse(text.as_bytes()).unwrap(),
            )
        };
        let long = format!("1.{}", "5".repeat(253));
        assert_eq!(field(&long, 255).map(|f| f.span().len()), Some(255));
        let longer = format!("1.{}", "5".repeat(254));
        assert_eq!(field(&longer, 256), None);
        // Precision beyond ±8191 without a kept exponent (four exponent digits are not kept).
        assert!(field("1E-8191", 7).is_some());
        assert_eq!(field("1E-8192", 7), None);
        assert!(field("1E-0099", 7).is_some());
        assert!(field(".0e-0", 5).is_some());
        // The precision of a kept exponent's literal comes from the length of its text: a span
        // of another length would give another literal.
        assert!(field("1.25E+2", 7).is_some());
        assert_eq!(field("1.25E+2", 6), None);
        assert_eq!(field("1.25E+2", 8), None);
        assert_eq!(field("1", 0), None);
    }

    #[test]
    fn a_bit_field_keeps_what_it_was_given() {
        let b = BitField::new(Span::new(10, 16), 2, Some(3)).unwrap();
        assert_eq!(
            (b.span(), b.value(), b.binary_digits()),
            (Span::new(10, 16), 2, Some(3))
        );
        assert_eq!(b.rewrite(5).as_deref(), Some("'B101'"));
        let d = BitField::new(Span::new(3, 5), 35, None).unwrap();
        assert_eq!(
            (d.span(), d.value(), d.binary_digits()),
            (Span::new(3, 5), 35, None)
        );
        assert_eq!(d.rewrite(35), None);
        assert_eq!(BitField::new(Span::new(0, 300), 0, Some(256)), None);
    }

    #[test]
    fn axis_names() {
        assert_eq!(external_axis_index("eax_a"), Some(0));
        assert_eq!(external_axis_index("EAX_F"), Some(5));
        assert_eq!(external_axis_index("E1"), Some(0));
        assert_eq!(external_axis_index("e6"), Some(5));
        assert_eq!(external_axis_index("E7"), None);
        assert_eq!(external_axis_index("eax_g"), None);
    }
}
