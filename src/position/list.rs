//! A file's positions, kept packed: each one's fields as a few bytes that point into the
//! source, decoded into a [`Position`] when asked for.
//!
//! A generated 20 MB RAPID module holds 100,000 targets; as [`Position`]s they were half of
//! `check`'s peak (432 bytes each, 17 number fields of 16 bytes). Packed (LEB128, as
//! [`packed`] writes it), a number field the
//! source spells is its offset from the start of the field before (one or two bytes): its value, style and
//! length are read again from the source ([`NumField::read_at`]), which gives the same field
//! bit for bit — checked when it is packed; a field that would not come back so is kept whole.
//! The usage stays unpacked beside the bytes: binding records it after the positions are read.
//! See docs/design.md, "Positions in memory".

use super::{
    Axes, BitField, CartesianFields, Config, Name, NumField, Orientation, Position, PositionKind,
    Usage,
};
use crate::syntax::{PackedLit, Span, packed};

/// The positions of one file, in the order pushed (see the module).
#[derive(Clone, Debug, Default)]
pub struct PositionList {
    heads: Vec<Head>,
    bytes: Vec<u8>,
    /// The kinds met, indexed by the packed kind byte (a program has a handful).
    kinds: Vec<PositionKind>,
}

#[derive(Clone, Debug)]
struct Head {
    usage: Usage,
    /// Where the position's packed bytes start in [`PositionList::bytes`].
    body: usize,
}

/// One head per target, 100,000 in a 20 MB module: a layout change that grows it fails the
/// build.
const _: () = assert!(std::mem::size_of::<Head>() <= 48);

/// Slot tags of a number or bit field.
const ABSENT: u8 = 0;
const READ_AGAIN: u8 = 1;
const WHOLE: u8 = 2;

/// What a whole number field keeps after its offset: the value's bits and the packed style.
const WHOLE_VALUE_AND_STYLE: usize = 8 + 4;

/// Cartesian part tags: none, or the translation with no orientation, a quaternion, or A, B, C.
const NO_CARTESIAN: u8 = 0;
const NO_ORIENTATION: u8 = 1;
const QUATERNION: u8 = 2;
const ABC: u8 = 3;

/// Configuration tags.
const NO_CONFIG: u8 = 0;
const QUADRANTS: u8 = 1;
const STATUS_TURN: u8 = 2;

impl PositionList {
    /// No positions.
    pub fn new() -> PositionList {
        PositionList::default()
    }

    /// No positions, with room for `positions` of about `bytes_each` packed bytes.
    pub fn with_capacity(positions: usize, bytes_each: usize) -> PositionList {
        PositionList {
            heads: Vec::with_capacity(positions),
            bytes: Vec::with_capacity(positions.saturating_mul(bytes_each)),
            kinds: Vec::new(),
        }
    }

    /// `ps`, whose spans point into `src`, packed.
    pub fn packed(ps: impl IntoIterator<Item = Position>, src: &[u8]) -> PositionList {
        let mut list = PositionList::new();
        list.extend(ps, src);
        list
    }

    /// How many positions.
    pub fn len(&self) -> usize {
        self.heads.len()
    }

    /// No positions.
    pub fn is_empty(&self) -> bool {
        self.heads.is_empty()
    }

    /// Appends `p`, whose spans point into `src`.
    pub fn push(&mut self, p: Position, src: &[u8]) {
        self.push_checking(p, src, true);
    }

    /// [`push`](Self::push), checking each number field against what [`NumField::read_at`]
    /// reads at its start only if `check`: a parser that read every field of `p` so (scanned
    /// with [`NumLit::parse_prefix`](crate::syntax::NumLit::parse_prefix) there) passes false,
    /// and the fields are packed as read again without reading them once more.
    pub(crate) fn push_checking(&mut self, p: Position, src: &[u8], check: bool) {
        // Every test run checks each position it reads through its packed bytes.
        #[cfg(debug_assertions)]
        let pushed = p.clone();
        let body = self.bytes.len();
        let kind = self.kind_index(p.kind);
        let mut w = Writer {
            out: &mut self.bytes,
            src,
            cursor: p.span.start,
            check,
        };
        let orient = p.cartesian.as_ref().and_then(|c| c.orient.as_ref());
        w.head(
            p.span,
            kind,
            crate::report::values_pass_lints(orient, &p.config),
            p.name.as_ref().map(|n| n.as_bytes()),
            p.line,
            p.column,
        );
        match &p.cartesian {
            None => w.byte(NO_CARTESIAN),
            Some(c) => {
                match &c.orient {
                    None => w.byte(NO_ORIENTATION),
                    Some(Orientation::Quaternion(_)) => w.byte(QUATERNION),
                    Some(Orientation::Abc(_)) => w.byte(ABC),
                }
                w.nums(&c.trans);
                match &c.orient {
                    None => {}
                    Some(Orientation::Quaternion(q)) => w.nums(q),
                    Some(Orientation::Abc(abc)) => w.nums(abc),
                }
            }
        }
        w.uint(p.joints.len() as u64);
        w.nums(&p.joints);
        match &p.config {
            Config::None => w.byte(NO_CONFIG),
            Config::Quadrants(q) => {
                w.byte(QUADRANTS);
                w.nums(q);
            }
            Config::StatusTurn { status, turn } => {
                w.byte(STATUS_TURN);
                w.bits(status.as_ref());
                w.bits(turn.as_ref());
            }
        }
        w.uint(p.extax.len() as u64);
        w.nums(&p.extax);
        self.heads.push(Head {
            usage: p.usage,
            body,
        });
        #[cfg(debug_assertions)]
        debug_assert_eq!(self.get(self.len() - 1, src).as_ref(), Some(&pushed));
    }

    /// Appends a robtarget-shaped position whose every number field is a literal that
    /// [`NumField::read_at`] reads back at its start: the bytes [`push_checking`]
    /// (`check` false) writes for it, straight from where the fields start, with no
    /// [`Position`] built. A parser that scanned each literal with
    /// [`NumLit::parse_prefix`](crate::syntax::NumLit::parse_prefix) and saw it fit the
    /// compact form ([`NumField::new`]) gives this; it is most of what a robtarget file holds.
    ///
    /// [`push_checking`]: Self::push_checking
    pub(crate) fn push_read_again(&mut self, t: &ReadAgainTarget<'_>) {
        let body = self.bytes.len();
        let kind = self.kind_index(t.kind);
        let mut staged = [0; STAGED_ROOM];
        let Some(len) = stage_read_again(&mut staged, kind, t) else {
            return self.push_read_again_by_writer(t);
        };
        self.bytes
            .extend_from_slice(staged.get(..len).unwrap_or_default());
        self.heads.push(Head {
            usage: Usage::default(),
            body,
        });
    }

    /// [`push_read_again`](Self::push_read_again) through a [`Writer`], byte by byte: for a
    /// target whose bytes do not fit [`STAGED_ROOM`], and the reference the tests hold the
    /// staged writing to.
    fn push_read_again_by_writer(&mut self, t: &ReadAgainTarget<'_>) {
        let body = self.bytes.len();
        let kind = self.kind_index(t.kind);
        let mut w = Writer {
            out: &mut self.bytes,
            src: &[],
            cursor: t.span.start,
            check: false,
        };
        w.head(t.span, kind, t.values_pass_lints, t.name, t.line, t.column);
        w.byte(QUATERNION);
        w.read_again(&t.trans);
        w.read_again(&t.quaternion);
        // No joints.
        w.uint(0);
        w.byte(QUADRANTS);
        w.read_again(&t.quadrants);
        w.uint(t.extax.len() as u64);
        w.read_again(t.extax);
        self.heads.push(Head {
            usage: Usage::default(),
            body,
        });
    }

    fn kind_index(&mut self, kind: PositionKind) -> usize {
        // The same kind is mostly the same constant: its pointer is compared before the
        // name, which is a call to memcmp.
        match self
            .kinds
            .iter()
            .position(|&k| std::ptr::eq(k.0, kind.0) || k == kind)
        {
            Some(k) => k,
            None => {
                self.kinds.push(kind);
                self.kinds.len() - 1
            }
        }
    }

    /// Position `i`, decoded against `src` (the bytes it was pushed with).
    pub fn get(&self, i: usize, src: &[u8]) -> Option<Position> {
        self.get_head(self.heads.get(i)?, src, Reading::Whole, None)
    }

    /// Position `i` with only the fields `reading` names decoded (see [`Reading`]).
    pub fn get_reading(&self, i: usize, src: &[u8], reading: Reading) -> Option<Position> {
        self.get_head(self.heads.get(i)?, src, reading, None)
    }

    #[inline]
    fn get_head(
        &self,
        head: &Head,
        src: &[u8],
        reading: Reading,
        mut memo: Option<&mut DecodeMemo>,
    ) -> Option<Position> {
        let mut r = self.reader(head, src)?;
        let PackedHead {
            span,
            kind,
            values_pass_lints,
            name,
            line,
            column,
        } = r.head(&self.kinds)?;
        let name = match name {
            // Nearly every name is ASCII, which needs no UTF-8 check.
            Some(text) => Some(match Name::from_ascii(text) {
                Some(n) => n,
                None => Name::from(std::str::from_utf8(text).ok()?),
            }),
            None => None,
        };
        let cartesian = match r.byte()? {
            NO_CARTESIAN => None,
            tag => {
                let trans = r.nums::<3>()?;
                let orient = match memo.as_deref_mut() {
                    Some(m) => r.orientation_seen(tag, &mut m.orient)?,
                    None => r.orientation(tag)?,
                };
                Some(CartesianFields { trans, orient })
            }
        };
        // Loops, not `collect::<Option<_>>()`: through its adapter each external axis cost
        // a third more than a field read into an array (the list moved at every step).
        let mut joints = Vec::new();
        for _ in 0..r.uint()? {
            joints.push(r.num()?);
        }
        let (config, extax) = match reading {
            Reading::Whole => {
                let config = match memo.as_deref_mut() {
                    Some(m) => r.config_seen(&mut m.config)?,
                    None => r.config()?,
                };
                let mut extax = Axes::new();
                for k in 0..r.uint()? {
                    extax.push(match DecodeMemo::axis(&mut memo, k) {
                        Some(seen) => r.num_seen(seen)?,
                        None => r.num()?,
                    });
                }
                (config, extax)
            }
            Reading::Track { skid_axis } => {
                let config = match (values_pass_lints, memo.as_deref_mut()) {
                    (true, _) => r.skip_config()?,
                    (false, Some(m)) => r.config_seen(&mut m.config)?,
                    (false, None) => r.config()?,
                };
                let mut extax = Axes::new();
                // The axes after the skid's are not read; those before it are stepped over.
                for k in 0..r.uint()?.min(skid_axis as u64 + 1) {
                    match k == skid_axis as u64 {
                        true => extax.push(match DecodeMemo::axis(&mut memo, k) {
                            Some(seen) => r.num_seen(seen)?,
                            None => r.num()?,
                        }),
                        false => {
                            r.skip_num()?;
                            extax.push(None);
                        }
                    }
                }
                (config, extax)
            }
        };
        Some(Position {
            name,
            kind,
            span,
            line,
            column,
            cartesian,
            joints,
            config,
            extax,
            usage: head.usage.clone(),
        })
    }

    /// Every position in order, decoded against `src`.
    pub fn iter<'a>(&'a self, src: &'a [u8]) -> impl ExactSizeIterator<Item = Position> + 'a {
        self.iter_reading(src, Reading::Whole)
    }

    /// [`iter`](Self::iter), each position with only the fields `reading` names decoded.
    pub fn iter_reading<'a>(
        &'a self,
        src: &'a [u8],
        reading: Reading,
    ) -> impl ExactSizeIterator<Item = Position> + 'a {
        let mut memo = DecodeMemo::default();
        (0..self.len()).map(move |i| self.decoded_with(i, src, reading, &mut memo))
    }

    /// Position `i` of [`iter_reading`](Self::iter_reading), for a loop over the indices: the
    /// position comes straight to the caller, where through the iterator's adapters it was
    /// copied three times (a position is some 400 bytes). Its orientation, configuration and
    /// external axes are taken from `memo` where their text is the text the position decoded
    /// before had there (see [`DecodeMemo`]); the same position either way.
    pub fn decoded_with(
        &self,
        i: usize,
        src: &[u8],
        reading: Reading,
        memo: &mut DecodeMemo,
    ) -> Position {
        // Every position pushed decodes (a proptest and, in debug builds, every push holds it):
        // the placeholder is never given, and it keeps the count and the indices exact.
        self.heads
            .get(i)
            .and_then(|h| self.get_head(h, src, reading, Some(memo)))
            .unwrap_or_else(|| self.placeholder(i))
    }

    /// A position that could not be decoded: never met (see [`PositionList::iter`]); it keeps
    /// the count, with no fields, rather than shift the indices of the rest.
    fn placeholder(&self, i: usize) -> Position {
        Position {
            name: None,
            kind: self
                .kinds
                .first()
                .copied()
                .unwrap_or(PositionKind::Robtarget),
            span: Span::new(0, 0),
            line: 0,
            column: 0,
            cartesian: None,
            joints: Vec::new(),
            config: Config::None,
            extax: Axes::new(),
            usage: self
                .heads
                .get(i)
                .map(|h| h.usage.clone())
                .unwrap_or_default(),
        }
    }

    /// The span, kind and declared name of position `i`, without decoding its fields.
    pub fn head(&self, i: usize) -> Option<(Span, PositionKind, Option<&str>)> {
        let PackedHead {
            span, kind, name, ..
        } = self.reader(self.heads.get(i)?, &[])?.head(&self.kinds)?;
        let name = match name {
            Some(text) => Some(std::str::from_utf8(text).ok()?),
            None => None,
        };
        Some((span, kind, name))
    }

    /// The literal's span of position `i`, without decoding its fields.
    pub fn span(&self, i: usize) -> Option<Span> {
        Some(self.head(i)?.0)
    }

    /// The declared name of position `i` (`None` for an inline literal). Read past the span
    /// and kind without decoding them, and not on to the line and column: the usage pass
    /// indexes every target by name, and the whole head was a quarter of building its index.
    pub fn name(&self, i: usize) -> Option<&str> {
        std::str::from_utf8(self.name_bytes(i)?).ok()
    }

    /// [`PositionList::name`] as the bytes of its text, unchecked: what indexes the names
    /// by their bytes need (checking each was a third of reading it).
    pub(crate) fn name_bytes(&self, i: usize) -> Option<&[u8]> {
        self.reader(self.heads.get(i)?, &[])?.name(&self.kinds)?
    }

    /// The head, orientation and configuration of position `i` as written, its other fields
    /// stepped over unread: what `check`'s lints look at (a field is found from the one before
    /// without reading the literal between).
    pub fn orientation_and_config<'a>(
        &'a self,
        i: usize,
        src: &'a [u8],
    ) -> Option<OrientationAndConfig<'a>> {
        let mut r = self.reader(self.heads.get(i)?, src)?;
        let PackedHead {
            span, kind, name, ..
        } = r.head(&self.kinds)?;
        let orient = match r.byte()? {
            NO_CARTESIAN => None,
            tag => {
                for _ in 0..3 {
                    r.skip_num()?;
                }
                r.orientation(tag)?
            }
        };
        for _ in 0..r.uint()? {
            r.skip_num()?;
        }
        Some(OrientationAndConfig {
            span,
            kind,
            name,
            orient,
            config: r.config()?,
        })
    }

    /// What `check`'s lints need of position `i`: its head, and its orientation and
    /// configuration only where the lints could find something in them. Whether they could
    /// was decided when it was pushed ([`values_pass_lints`](crate::report::values_pass_lints),
    /// one bit beside the kind): reading eight literals of every target again was 13 % of
    /// `check`, for lints that pass nearly every target.
    pub fn for_lints<'a>(&'a self, i: usize, src: &'a [u8]) -> Option<TargetForLints<'a>> {
        let head = self.heads.get(i)?;
        let h = self.reader(head, &[])?.head(&self.kinds)?;
        let values = match h.values_pass_lints {
            true => None,
            false => {
                let t = self.orientation_and_config(i, src)?;
                Some((t.orient, t.config))
            }
        };
        Some(TargetForLints {
            span: h.span,
            kind: h.kind,
            name: h.name,
            values,
        })
    }

    /// The literal's span of position `i` and the lints' verdict on its values
    /// ([`crate::report::values_pass_lints`]), read without the rest of its head: what
    /// `check`'s lints ask of every target before they look closer at the few that may find
    /// something.
    pub fn span_and_verdict(&self, i: usize) -> Option<(Span, bool)> {
        let (span, _, verdict) = self
            .reader(self.heads.get(i)?, &[])?
            .span_and_kind(&self.kinds)?;
        Some((span, verdict))
    }

    /// Whether position `i` has Cartesian fields ([`Position::cartesian`] is `Some`).
    pub fn has_cartesian(&self, i: usize) -> bool {
        self.cartesian_tag(i).is_some_and(|tag| tag != NO_CARTESIAN)
    }

    /// Whether position `i` writes its orientation as A, B, C ([`Orientation::Abc`]).
    pub fn writes_abc(&self, i: usize) -> bool {
        self.cartesian_tag(i) == Some(ABC)
    }

    /// The A, B and C fields of position `i` when it writes its orientation so, decoded
    /// against `src` without the rest of the position (its head, translation, configuration
    /// and axes are stepped over): the stamp's record of the targets at the gimbal lock reads
    /// every KUKA target's A and B, and decoding each whole was 5 % of a KRL `correct`.
    pub fn abc_fields(&self, i: usize, src: &[u8]) -> Option<[Option<NumField>; 3]> {
        let mut r = self.reader(self.heads.get(i)?, src)?;
        r.head(&self.kinds)?;
        if r.byte()? != ABC {
            return None;
        }
        for _ in 0..3 {
            r.skip_num()?;
        }
        r.nums::<3>()
    }

    fn cartesian_tag(&self, i: usize) -> Option<u8> {
        let mut r = self.reader(self.heads.get(i)?, &[])?;
        r.head(&self.kinds)?;
        r.byte()
    }

    /// The usage of position `i`.
    pub fn usage(&self, i: usize) -> Option<&Usage> {
        self.heads.get(i).map(|h| &h.usage)
    }

    /// The usage of position `i`, to record a use in.
    pub fn usage_mut(&mut self, i: usize) -> Option<&mut Usage> {
        self.heads.get_mut(i).map(|h| &mut h.usage)
    }

    /// Every position's usage, in order.
    pub fn usages(&self) -> impl ExactSizeIterator<Item = &Usage> + '_ {
        self.heads.iter().map(|h| &h.usage)
    }

    /// Every position's usage, in order, to change.
    pub fn usages_mut(&mut self) -> impl ExactSizeIterator<Item = &mut Usage> + '_ {
        self.heads.iter_mut().map(|h| &mut h.usage)
    }

    /// Removes position `i` (its packed bytes stay, unreferenced).
    pub fn remove(&mut self, i: usize) {
        if i < self.heads.len() {
            self.heads.remove(i);
        }
    }

    /// Appends every position of `ps`, whose spans point into `src`.
    pub fn extend(&mut self, ps: impl IntoIterator<Item = Position>, src: &[u8]) {
        for p in ps {
            self.push(p, src);
        }
    }

    /// Removes the positions from `at` on and gives them back decoded, in order.
    pub fn split_off(&mut self, at: usize, src: &[u8]) -> Vec<Position> {
        let tail: Vec<Position> = (at..self.len()).filter_map(|i| self.get(i, src)).collect();
        self.heads.truncate(at);
        tail
    }

    /// Keeps only the positions `keep` holds to (their packed bytes stay, unreferenced).
    pub fn retain(&mut self, src: &[u8], mut keep: impl FnMut(&Position) -> bool) {
        let mut kept = Vec::with_capacity(self.heads.len());
        for h in std::mem::take(&mut self.heads) {
            if self
                .get_head(&h, src, Reading::Whole, None)
                .is_some_and(|p| keep(&p))
            {
                kept.push(h);
            }
        }
        self.heads = kept;
    }

    /// Removes every position.
    pub fn clear(&mut self) {
        self.heads.clear();
        self.bytes.clear();
    }

    /// Orders the positions by where their literal starts (a stable sort).
    pub fn sort_by_start(&mut self) {
        let mut keyed: Vec<(usize, Head)> = std::mem::take(&mut self.heads)
            .into_iter()
            .map(|h| {
                let start = self.reader(&h, &[]).and_then(|mut r| r.uint()).unwrap_or(0);
                (start as usize, h)
            })
            .collect();
        keyed.sort_by_key(|(start, _)| *start);
        self.heads = keyed.into_iter().map(|(_, h)| h).collect();
    }

    fn reader<'a>(&'a self, head: &Head, src: &'a [u8]) -> Option<Reader<'a>> {
        Some(Reader {
            bytes: self.bytes.get(head.body..)?,
            src,
            cursor: 0,
        })
    }
}

/// Which fields a decoded position holds ([`PositionList::get_reading`]).
///
/// A target's fields are read again from the source literal by literal (most of decoding
/// it), and a transform looks at few of them: a track correction without an arm reads the
/// translation, the orientation and one external axis of a robtarget's 17 fields, and its
/// configuration only to refuse an implausible one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reading {
    /// Every field.
    #[default]
    Whole,
    /// The head, the usage, the Cartesian fields and the joints, as [`Reading::Whole`]
    /// decodes them; of the external axes only `skid_axis` (those before it are absent, and
    /// the list ends there: [`Position::skid`] of that axis is the whole position's); and
    /// the configuration only where the lints' verdict packed with the position says its
    /// values could be implausible, else [`Config::None`]. Either way the transforms' test of
    /// implausible orientation and configuration values finds in it what it finds in the
    /// whole position (a passing verdict means it finds nothing).
    Track {
        /// The external axis the skid is read from (0 = `eax_a` / `E1`).
        skid_axis: usize,
    },
}

/// What [`PositionList::orientation_and_config`] reads of a position.
#[derive(Clone, Debug)]
pub struct OrientationAndConfig<'a> {
    /// The literal's bytes.
    pub span: Span,
    /// What kind of target it is.
    pub kind: PositionKind,
    /// The declared name's text, read as UTF-8 only when it is shown ([`Self::name`]).
    name: Option<&'a [u8]>,
    /// The orientation as written (`None` without Cartesian fields or orientation).
    pub orient: Option<Orientation>,
    /// The configuration as written.
    pub config: Config,
}

impl OrientationAndConfig<'_> {
    /// The declared name (`None` for an inline literal).
    pub fn name(&self) -> Option<&str> {
        std::str::from_utf8(self.name?).ok()
    }
}

/// What [`PositionList::for_lints`] reads of a position.
#[derive(Clone, Debug)]
pub struct TargetForLints<'a> {
    /// The literal's bytes.
    pub span: Span,
    /// What kind of target it is.
    pub kind: PositionKind,
    name: Option<&'a [u8]>,
    /// The orientation and configuration as written, where the lints that look at values
    /// could find something in them; `None` where they pass.
    pub values: Option<(Option<Orientation>, Config)>,
}

impl TargetForLints<'_> {
    /// The declared name (`None` for an inline literal).
    pub fn name(&self) -> Option<&str> {
        std::str::from_utf8(self.name?).ok()
    }
}

/// A robtarget as [`PositionList::push_read_again`] takes it: where its literal is, what it
/// is named, and where each of its number fields starts.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ReadAgainTarget<'a> {
    pub span: Span,
    pub kind: PositionKind,
    /// The declared name's text (UTF-8), as [`Position::name`] holds it.
    pub name: Option<&'a [u8]>,
    pub line: usize,
    pub column: usize,
    pub trans: [usize; 3],
    pub quaternion: [usize; 4],
    pub quadrants: [usize; 4],
    pub extax: &'a [usize],
    /// [`values_pass_lints`](crate::report::values_pass_lints) of its orientation and
    /// configuration.
    pub values_pass_lints: bool,
}

/// Writes one position's packed bytes.
struct Writer<'a> {
    out: &'a mut Vec<u8>,
    src: &'a [u8],
    /// Where the field before started (the literal's start before the first): offsets from
    /// it let a reader step over a field without reading its literal.
    cursor: usize,
    /// Whether a field is checked against what [`NumField::read_at`] reads at its start (see
    /// [`PositionList::push_checking`]).
    check: bool,
}

impl Writer<'_> {
    fn byte(&mut self, b: u8) {
        self.out.push(b);
    }

    fn uint(&mut self, v: u64) {
        packed::push_varint(self.out, v);
    }

    /// Zigzagged: a KRL aggregate may write its fields in any order.
    fn int(&mut self, v: i64) {
        self.uint(packed::zigzag(v));
    }

    /// Span, kind index with the lints' verdict, name's text, line and column: what
    /// [`Reader::head`] reads.
    fn head(
        &mut self,
        span: Span,
        kind: usize,
        values_pass_lints: bool,
        name: Option<&[u8]>,
        line: usize,
        column: usize,
    ) {
        self.uint(span.start as u64);
        // Signed: a span a dialect gives reversed comes back as it was given.
        self.int(span.end as i64 - span.start as i64);
        // The verdict as the low bit: a program has a handful of kinds, so it still fits the
        // one byte the kind took alone.
        self.uint((kind as u64) << 1 | u64::from(values_pass_lints));
        match name {
            Some(n) => {
                self.uint(n.len() as u64 + 1);
                self.out.extend_from_slice(n);
            }
            None => self.uint(0),
        }
        self.uint(line as u64);
        self.uint(column as u64);
    }

    /// Number fields read again at these starts, as [`Writer::num`] packs them unchecked.
    fn read_again(&mut self, starts: &[usize]) {
        for &at in starts {
            self.byte(READ_AGAIN);
            self.offset(at);
        }
    }

    fn offset(&mut self, at: usize) {
        self.int(at as i64 - self.cursor as i64);
        self.cursor = at;
    }

    fn nums(&mut self, fields: &[Option<NumField>]) {
        for f in fields {
            self.num(f.as_ref());
        }
    }

    fn num(&mut self, f: Option<&NumField>) {
        let Some(f) = f else {
            return self.byte(ABSENT);
        };
        let span = f.span();
        if !self.check || NumField::read_at(self.src, span.start).as_ref() == Some(f) {
            self.byte(READ_AGAIN);
            self.offset(span.start);
        } else {
            let (value, packed) = f.value_and_style();
            self.byte(WHOLE);
            self.offset(span.start);
            self.out.extend_from_slice(&value.to_bits().to_le_bytes());
            self.out.extend_from_slice(&packed.to_le_bytes());
        }
    }

    fn bits(&mut self, f: Option<&BitField>) {
        let Some(f) = f else {
            return self.byte(ABSENT);
        };
        let span = f.span();
        self.byte(WHOLE);
        self.offset(span.start);
        self.uint((span.end - span.start.min(span.end)) as u64);
        self.uint(u64::from(f.value()));
        match f.binary_digits() {
            Some(n) => self.uint(n as u64 + 1),
            None => self.uint(0),
        }
    }
}

/// Room for a robtarget's packed bytes as [`stage_read_again`] writes them: its head with a
/// name of a few dozen bytes, tags and counts, and two dozen fields of two bytes (a tag and an
/// offset of one byte: the field before is a few bytes back), with some to spare. Small enough
/// for its zeroing to be a few stores, where room for every field's longest offset was a call
/// to memset.
const STAGED_ROOM: usize = 128;

/// Writes the bytes of robtarget `t` of kind index `kind`, as [`Writer`] writes them for
/// [`PositionList::push_read_again_by_writer`], into `staged`, to be appended in one copy:
/// pushed byte by byte, each of the two dozen fields' tag and offset and each number of the
/// head checked the vector's room and stored its length again. Their length, or `None` when
/// they do not fit.
#[inline(always)]
fn stage_read_again(
    staged: &mut [u8; STAGED_ROOM],
    kind: usize,
    t: &ReadAgainTarget<'_>,
) -> Option<usize> {
    let len = stage_uint(staged, 0, t.span.start as u64)?;
    // Signed, as the writer writes it.
    let reach = t.span.end as i64 - t.span.start as i64;
    let len = stage_uint(staged, len, packed::zigzag(reach))?;
    let len = stage_uint(
        staged,
        len,
        (kind as u64) << 1 | u64::from(t.values_pass_lints),
    )?;
    let len = match t.name {
        Some(name) => {
            let mut len = stage_uint(staged, len, name.len() as u64 + 1)?;
            // Byte by byte: a name is a few bytes, and a copy of its length a call to memcpy.
            for &b in name {
                *staged.get_mut(len)? = b;
                len += 1;
            }
            len
        }
        None => stage_uint(staged, len, 0)?,
    };
    let len = stage_uint(staged, len, t.line as u64)?;
    let len = stage_uint(staged, len, t.column as u64)?;
    let len = stage_uint(staged, len, u64::from(QUATERNION))?;
    let mut cursor = t.span.start;
    let len = stage_fields(staged, len, &mut cursor, &t.trans)?;
    let len = stage_fields(staged, len, &mut cursor, &t.quaternion)?;
    // No joints.
    let len = stage_uint(staged, len, 0)?;
    let len = stage_uint(staged, len, u64::from(QUADRANTS))?;
    let len = stage_fields(staged, len, &mut cursor, &t.quadrants)?;
    let len = stage_uint(staged, len, t.extax.len() as u64)?;
    stage_fields(staged, len, &mut cursor, t.extax)
}

/// `v` as [`packed::push_varint`] writes it, at `len` of `staged`: the length after it.
#[inline(always)]
fn stage_uint(staged: &mut [u8], mut len: usize, mut v: u64) -> Option<usize> {
    while v >= 0x80 {
        *staged.get_mut(len)? = (v as u8) | 0x80;
        len += 1;
        v >>= 7;
    }
    *staged.get_mut(len)? = v as u8;
    Some(len + 1)
}

/// Number fields read again at `starts`, as [`Writer::read_again`] writes them, at `len` of
/// `staged`: the length after them. An offset within 63 bytes either way (nearly every one)
/// is written with its tag as one pair.
#[inline(always)]
fn stage_fields(
    staged: &mut [u8],
    mut len: usize,
    cursor: &mut usize,
    starts: &[usize],
) -> Option<usize> {
    for &at in starts {
        let offset = packed::zigzag(at as i64 - *cursor as i64);
        *cursor = at;
        match staged.get_mut(len..len + 2) {
            Some(pair) if offset < 0x80 => {
                pair.copy_from_slice(&[READ_AGAIN, offset as u8]);
                len += 2;
            }
            _ => {
                let tagged = stage_uint(staged, len, u64::from(READ_AGAIN))?;
                len = stage_uint(staged, tagged, offset)?;
            }
        }
    }
    Some(len)
}

/// What [`Reader::head`] reads: span, kind, the lints' verdict on the values, name's text,
/// line and column.
struct PackedHead<'a> {
    span: Span,
    kind: PositionKind,
    values_pass_lints: bool,
    name: Option<&'a [u8]>,
    line: usize,
    column: usize,
}

/// The literals decoded last at a position's orientation, configuration and external axes,
/// for [`PositionList::decoded_with`]: a program's targets come in runs that share their
/// orientation and configuration text, and their unused axes are all `9E+09`. A field whose
/// text is the one seen at its place in the position before is that field again, moved:
/// comparing 16 bytes is a fraction of reading the literal (`correct` read each target's
/// quaternion again, 8.3 M of 238 M instructions on a 2 MB module). The translation is not
/// kept: it is seldom the same twice.
#[derive(Clone, Debug, Default)]
pub struct DecodeMemo {
    orient: [Option<SeenField>; 4],
    config: [Option<SeenField>; 4],
    extax: [Option<SeenField>; 6],
}

impl DecodeMemo {
    /// External axis `k`'s slot of `memo`, if there is a memo and it keeps that axis.
    fn axis<'m>(
        memo: &'m mut Option<&mut DecodeMemo>,
        k: u64,
    ) -> Option<&'m mut Option<SeenField>> {
        memo.as_deref_mut()?.extax.get_mut(usize::try_from(k).ok()?)
    }
}

/// One literal's text and what it decoded to.
#[derive(Clone, Copy, Debug)]
struct SeenField {
    /// The literal's bytes and the one after it, little-endian, and the mask of their length.
    text: u128,
    mask: u128,
    value: f64,
    packed: PackedLit,
}

impl SeenField {
    /// `field` as `src` spells it, when its text and the byte after it are 16 bytes or fewer
    /// (and 16 can be read there) and that byte is a `,` or `]`: a number's reading stops at
    /// either without looking further, so the same bytes at another place read as the same
    /// literal there. `None` otherwise (the field is then read each time).
    fn of(src: &[u8], field: &NumField) -> Option<SeenField> {
        let start = field.start as usize;
        let len = field.packed.len();
        let word = src.get(start..)?.first_chunk::<16>()?;
        if len >= 16 || !matches!(word[len], b',' | b']') {
            return None;
        }
        let mask = u128::MAX >> (8 * (15 - len));
        Some(SeenField {
            text: u128::from_le_bytes(*word) & mask,
            mask,
            value: field.value,
            packed: field.packed,
        })
    }

    /// The field at `start` of `src`, if the text there is this one.
    #[inline(always)]
    fn at(&self, src: &[u8], start: usize) -> Option<NumField> {
        let word = src.get(start..)?.first_chunk::<16>()?;
        (u128::from_le_bytes(*word) & self.mask == self.text).then_some(NumField {
            value: self.value,
            start: u32::try_from(start).ok()?,
            packed: self.packed,
        })
    }
}

/// Reads one position's packed bytes back.
struct Reader<'a> {
    bytes: &'a [u8],
    src: &'a [u8],
    cursor: usize,
}

impl<'a> Reader<'a> {
    fn byte(&mut self) -> Option<u8> {
        let (&b, rest) = self.bytes.split_first()?;
        self.bytes = rest;
        Some(b)
    }

    fn uint(&mut self) -> Option<u64> {
        let mut at = 0;
        let v = packed::read_varint(self.bytes, &mut at)?;
        self.bytes = self.bytes.get(at..)?;
        Some(v)
    }

    fn usize(&mut self) -> Option<usize> {
        usize::try_from(self.uint()?).ok()
    }

    fn offset(&mut self) -> Option<usize> {
        let zigzagged = self.uint()?;
        self.moved_by(zigzagged)
    }

    /// Moves the cursor by a field's zigzagged offset from the field before: its start.
    #[inline(always)]
    fn moved_by(&mut self, zigzagged: u64) -> Option<usize> {
        let delta = packed::unzigzag(zigzagged);
        self.cursor = usize::try_from(self.cursor as i64 + delta).ok()?;
        Some(self.cursor)
    }

    /// The fields every position has, first.
    fn head(&mut self, kinds: &[PositionKind]) -> Option<PackedHead<'a>> {
        let (span, kind, values_pass_lints) = self.span_and_kind(kinds)?;
        self.cursor = span.start;
        let name = match self.head_usize()? {
            0 => None,
            n => {
                let (text, rest) = self.bytes.split_at_checked(n - 1)?;
                self.bytes = rest;
                Some(text)
            }
        };
        Some(PackedHead {
            span,
            kind,
            values_pass_lints,
            name,
            line: self.head_usize()?,
            column: self.head_usize()?,
        })
    }

    /// The first three numbers of a head: the span, and the kind with the lints' verdict.
    #[inline(always)]
    fn span_and_kind(&mut self, kinds: &[PositionKind]) -> Option<(Span, PositionKind, bool)> {
        let start = self.head_usize()?;
        let end = i64::try_from(start).ok()? + packed::unzigzag(self.head_uint()?);
        let span = Span::new(start, usize::try_from(end).ok()?);
        let kind_and_verdict = self.head_usize()?;
        let kind = *kinds.get(kind_and_verdict >> 1)?;
        Some((span, kind, kind_and_verdict & 1 == 1))
    }

    /// The name [`Reader::head`] reads, the span's two numbers stepped over (each ends at its
    /// first byte below 0x80) and the kind checked as it checks it.
    #[inline(always)]
    fn name(&mut self, kinds: &[PositionKind]) -> Option<Option<&'a [u8]>> {
        for _ in 0..2 {
            let len = self.bytes.iter().position(|&b| b < 0x80)? + 1;
            self.bytes = self.bytes.get(len..)?;
        }
        kinds.get(self.head_usize()? >> 1)?;
        Some(match self.head_usize()? {
            0 => None,
            n => Some(self.bytes.get(..n - 1)?),
        })
    }

    /// [`Reader::uint`] with the LEB128 reading inlined, for the six numbers of a head, which
    /// every use of a position reads (`check`'s lints, binding, `correct`'s decoding): through
    /// a call each they were half of a head.
    #[inline(always)]
    fn head_uint(&mut self) -> Option<u64> {
        let mut at = 0;
        let v = packed::read_varint_inlined(self.bytes, &mut at)?;
        self.bytes = self.bytes.get(at..)?;
        Some(v)
    }

    #[inline(always)]
    fn head_usize(&mut self) -> Option<usize> {
        usize::try_from(self.head_uint()?).ok()
    }

    /// Inlined, with the literal's reading, into each loop over a part's fields: a call per
    /// field and its result through memory were a tenth of `correct`'s decoding of a target.
    #[inline(always)]
    fn num(&mut self) -> Option<Option<NumField>> {
        // Nearly every field is read again, a few bytes after the one before: its offset is
        // one byte. Through the general tag and LEB128 reading that was a fifth of a field.
        if let [READ_AGAIN, delta @ 0..0x80, rest @ ..] = self.bytes {
            self.bytes = rest;
            let start = self.moved_by(u64::from(*delta))?;
            return Some(Some(NumField::read_at(self.src, start)?));
        }
        let f = match self.byte()? {
            ABSENT => return Some(None),
            READ_AGAIN => {
                let start = self.offset()?;
                NumField::read_at(self.src, start)?
            }
            WHOLE => {
                let start = u32::try_from(self.offset()?).ok()?;
                let (value, rest) = self.bytes.split_first_chunk::<8>()?;
                let (packed, rest) = rest.split_first_chunk::<4>()?;
                self.bytes = rest;
                NumField::from_parts(
                    start,
                    f64::from_bits(u64::from_le_bytes(*value)),
                    u32::from_le_bytes(*packed),
                )?
            }
            _ => return None,
        };
        Some(Some(f))
    }

    /// Steps over a field [`Reader::num`] would read, without reading its literal. Inlined
    /// into each loop over the fields stepped over, as `num` is into those read.
    #[inline(always)]
    fn skip_num(&mut self) -> Option<()> {
        // The one-byte offset of nearly every field, taken as `num` takes it.
        if let [READ_AGAIN, delta @ 0..0x80, rest @ ..] = self.bytes {
            self.bytes = rest;
            self.moved_by(u64::from(*delta))?;
            return Some(());
        }
        match self.byte()? {
            ABSENT => {}
            READ_AGAIN => {
                self.offset()?;
            }
            WHOLE => {
                self.offset()?;
                self.bytes = self.bytes.get(WHOLE_VALUE_AND_STYLE..)?;
            }
            _ => return None,
        }
        Some(())
    }

    /// [`Reader::num`], taken from `seen` when the literal's text is the one `seen` holds,
    /// else read and kept there. Inlined as `num` is.
    #[inline(always)]
    fn num_seen(&mut self, seen: &mut Option<SeenField>) -> Option<Option<NumField>> {
        if let [READ_AGAIN, delta @ 0..0x80, rest @ ..] = self.bytes {
            self.bytes = rest;
            let start = self.moved_by(u64::from(*delta))?;
            if let Some(f) = seen.as_ref().and_then(|s| s.at(self.src, start)) {
                debug_assert!(NumField::read_at(self.src, start) == Some(f));
                return Some(Some(f));
            }
            let f = NumField::read_at(self.src, start)?;
            *seen = SeenField::of(self.src, &f);
            return Some(Some(f));
        }
        self.num()
    }

    /// [`Reader::nums`] through [`Reader::num_seen`], field `k` with `seen[k]`.
    fn nums_seen<const N: usize>(
        &mut self,
        seen: &mut [Option<SeenField>; N],
    ) -> Option<[Option<NumField>; N]> {
        let mut out = [None; N];
        for (o, s) in out.iter_mut().zip(seen) {
            *o = self.num_seen(s)?;
        }
        Some(out)
    }

    /// [`Reader::orientation`] through [`Reader::num_seen`].
    fn orientation_seen(
        &mut self,
        tag: u8,
        seen: &mut [Option<SeenField>; 4],
    ) -> Option<Option<Orientation>> {
        Some(match tag {
            NO_ORIENTATION => None,
            QUATERNION => Some(Orientation::Quaternion(self.nums_seen(seen)?)),
            ABC => Some(Orientation::Abc(
                self.nums_seen(seen.first_chunk_mut::<3>()?)?,
            )),
            _ => return None,
        })
    }

    /// [`Reader::config`] through [`Reader::num_seen`] (quadrants; a Status and Turn are read).
    fn config_seen(&mut self, seen: &mut [Option<SeenField>; 4]) -> Option<Config> {
        match self.bytes.first() {
            Some(&QUADRANTS) => {
                self.byte()?;
                Some(Config::Quadrants(self.nums_seen(seen)?))
            }
            _ => self.config(),
        }
    }

    /// The orientation after a Cartesian tag, its translation stepped over or read.
    fn orientation(&mut self, tag: u8) -> Option<Option<Orientation>> {
        Some(match tag {
            NO_ORIENTATION => None,
            QUATERNION => Some(Orientation::Quaternion(self.nums::<4>()?)),
            ABC => Some(Orientation::Abc(self.nums::<3>()?)),
            _ => return None,
        })
    }

    fn config(&mut self) -> Option<Config> {
        Some(match self.byte()? {
            NO_CONFIG => Config::None,
            QUADRANTS => Config::Quadrants(self.nums::<4>()?),
            STATUS_TURN => Config::StatusTurn {
                status: self.bits()?,
                turn: self.bits()?,
            },
            _ => return None,
        })
    }

    /// Steps over what [`Reader::config`] reads, giving [`Config::None`].
    fn skip_config(&mut self) -> Option<Config> {
        match self.byte()? {
            NO_CONFIG => {}
            QUADRANTS => {
                for _ in 0..4 {
                    self.skip_num()?;
                }
            }
            STATUS_TURN => {
                self.bits()?;
                self.bits()?;
            }
            _ => return None,
        }
        Some(Config::None)
    }

    fn nums<const N: usize>(&mut self) -> Option<[Option<NumField>; N]> {
        let mut out = [None; N];
        for o in &mut out {
            *o = self.num()?;
        }
        Some(out)
    }

    fn bits(&mut self) -> Option<Option<BitField>> {
        match self.byte()? {
            ABSENT => Some(None),
            WHOLE => {
                let start = self.offset()?;
                let end = start.checked_add(self.usize()?)?;
                let value = u32::try_from(self.uint()?).ok()?;
                let digits = match self.usize()? {
                    0 => None,
                    n => Some(n - 1),
                };
                Some(Some(BitField::new(Span::new(start, end), value, digits)?))
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::position::{FrameName, Lines};
    use proptest::prelude::*;

    /// Literals as programs write them; the last ones go past what the compact form or the
    /// fast path takes.
    const TEXTS: &[&str] = &[
        "-1520.30",
        "0.707107",
        "0",
        "9E+09",
        "9E9",
        "+12.5",
        ".5",
        "5.",
        "2.69E-07",
        "-0.000",
        "1234567890123456789012",
        "1E400",
    ];

    /// A source of literals separated by `,` and the span of each.
    fn source(picks: &[usize]) -> (Vec<u8>, Vec<Span>) {
        let mut src = b"[".to_vec();
        let mut spans = Vec::new();
        for (k, &t) in picks.iter().enumerate() {
            if k > 0 {
                src.push(b',');
            }
            let text = TEXTS[t % TEXTS.len()].as_bytes();
            spans.push(Span::new(src.len(), src.len() + text.len()));
            src.extend_from_slice(text);
        }
        src.push(b']');
        (src, spans)
    }

    /// A field for literal `k`: as the source reads it, or (`moved`) the literal of `j`
    /// placed at `k`'s start, which the source does not read back (kept whole).
    fn field(src: &[u8], spans: &[Span], k: usize, moved: Option<usize>) -> Option<NumField> {
        let at = spans.get(k % spans.len().max(1))?;
        match moved {
            None => NumField::read_at(src, at.start),
            Some(j) => {
                let from = spans.get(j % spans.len())?;
                let (lit, len) = NumLit::parse_prefix(from.slice(src))?;
                NumField::new(Span::new(at.start, at.start + len), lit)
            }
        }
    }

    use crate::syntax::NumLit;

    type Pick = Option<(usize, Option<usize>)>;

    fn picks(n: usize) -> impl Strategy<Value = Vec<Pick>> {
        proptest::collection::vec(
            proptest::option::weighted(0.85, (0usize..64, proptest::option::of(0usize..64))),
            n,
        )
    }

    proptest! {
        /// Every position comes back from its packed bytes as it was pushed: fields the source
        /// reads back and fields kept whole, in any order (KRL writes fields in any order),
        /// absent fields, long and non-ASCII names, bit fields and spilled axis lists.
        #[test]
        fn a_position_decodes_to_what_was_pushed(
            lits in proptest::collection::vec(0usize..TEXTS.len(), 1..24),
            cart in 0u8..4,
            fields in picks(7),
            joints in proptest::collection::vec(
                proptest::option::weighted(0.85, (0usize..64, proptest::option::of(0usize..64))),
                0..8,
            ),
            config in 0u8..3,
            quads in picks(4),
            bits in proptest::collection::vec(
                proptest::option::of((0usize..64, 0u32..64, proptest::option::of(1usize..9))),
                2,
            ),
            extax in proptest::collection::vec(
                proptest::option::weighted(0.85, (0usize..64, proptest::option::of(0usize..64))),
                0..10,
            ),
            name in proptest::option::of("[a-zA-Z_é{}0-9,]{0,40}"),
            kind in 0usize..3,
            (line, column) in (0usize..100_000, 0usize..500),
            wobj in proptest::option::of("w[A-Za-z]{0,4}"),
            lines in proptest::collection::vec(1u32..5000, 0..6),
            others in 1usize..3,
            reversed in proptest::bool::weighted(0.1),
        ) {
            let (src, spans) = source(&lits);
            let f = |p: &Pick| p.and_then(|(k, moved)| field(&src, &spans, k, moved));
            let all: Vec<Option<NumField>> = fields.iter().map(f).collect();
            let cartesian = (cart > 0).then(|| CartesianFields {
                trans: [all[0], all[1], all[2]],
                orient: match cart {
                    1 => None,
                    2 => Some(Orientation::Quaternion([all[3], all[4], all[5], all[6]])),
                    _ => Some(Orientation::Abc([all[3], all[4], all[5]])),
                },
            });
            let bit = |b: &Option<(usize, u32, Option<usize>)>| {
                b.and_then(|(k, value, digits)| {
                    BitField::new(spans[k % spans.len()], value, digits)
                })
            };
            let config = match config {
                0 => Config::None,
                1 => Config::Quadrants([f(&quads[0]), f(&quads[1]), f(&quads[2]), f(&quads[3])]),
                _ => Config::StatusTurn { status: bit(&bits[0]), turn: bit(&bits[1]) },
            };
            let mut usage = Usage::default();
            for (n, &l) in lines.iter().enumerate() {
                let w = wobj.as_deref().map(|w| if n % others == 0 { w.to_owned() } else { format!("{w}{n}") });
                usage.record(w.as_deref(), Some("tGun"), n == 2, l as usize);
            }
            let kinds = [PositionKind::Robtarget, PositionKind::E6Pos, PositionKind::Jointtarget];
            let p = Position {
                name: name.map(Name::from),
                kind: kinds[kind],
                // A dialect may give a span reversed; it comes back as given.
                span: if reversed {
                    Span::new(src.len() - 1, 1)
                } else {
                    Span::new(1, src.len() - 1)
                },
                line,
                column,
                cartesian,
                joints: joints.iter().map(f).collect(),
                config,
                extax: extax.iter().map(f).collect(),
                usage,
            };
            let mut list = PositionList::new();
            // A second position first: a position's bytes do not start at 0.
            let mut first = p.clone();
            first.name = None;
            first.kind = kinds[(kind + 1) % 3];
            list.push(first.clone(), &src);
            list.push(p.clone(), &src);
            prop_assert_eq!(list.len(), 2);
            prop_assert_eq!(list.get(0, &src), Some(first.clone()));
            prop_assert_eq!(list.get(1, &src), Some(p.clone()));
            prop_assert_eq!(list.head(1), Some((p.span, p.kind, p.name.as_deref())));
            prop_assert_eq!(list.name(1), p.name.as_deref());
            prop_assert_eq!(list.name_bytes(1), p.name.as_deref().map(str::as_bytes));
            prop_assert_eq!(list.name(0), None);
            prop_assert_eq!(list.has_cartesian(1), p.cartesian.is_some());
            let read = list.orientation_and_config(1, &src).map(|t| {
                (t.span, t.kind, t.name().map(str::to_owned), t.orient, t.config)
            });
            prop_assert_eq!(
                read,
                Some((
                    p.span,
                    p.kind,
                    p.name.as_deref().map(str::to_owned),
                    p.cartesian.as_ref().and_then(|c| c.orient.clone()),
                    p.config.clone()
                ))
            );
            prop_assert_eq!(list.iter(&src).collect::<Vec<_>>(), vec![first, p.clone()]);
            // A track's reading: the fields it names as the whole position has them, the
            // rest left out as it says, and the same verdict of the refusal.
            let orient = p.cartesian.as_ref().and_then(|c| c.orient.as_ref());
            let passes = crate::report::values_pass_lints(orient, &p.config);
            for skid_axis in 0..8 {
                let got = list.get_reading(1, &src, Reading::Track { skid_axis }).unwrap();
                let mut want = p.clone();
                if passes {
                    want.config = Config::None;
                }
                want.extax = p
                    .extax
                    .iter()
                    .enumerate()
                    .take(skid_axis + 1)
                    .map(|(k, f)| if k == skid_axis { *f } else { None })
                    .collect();
                prop_assert_eq!(&got, &want);
                prop_assert_eq!(got.skid(skid_axis), p.skid(skid_axis));
                let implausible = |q: &Position| {
                    let orient = q.cartesian.as_ref().and_then(|c| c.orient.as_ref());
                    crate::transform::policy::implausible_values(orient, &q.config)
                };
                prop_assert_eq!(implausible(&got), implausible(&p));
            }
            prop_assert_eq!(list.get_reading(1, &src, Reading::Whole), Some(p));
        }
    }

    proptest! {
        /// A robtarget's bytes staged on the stack are the bytes the writer writes one by
        /// one: offsets of one byte and of more, either way, lines and columns of any width,
        /// and more external axes than fit the room, one target after another.
        #[test]
        fn a_staged_target_is_written_as_the_writer_writes_it(
            starts in prop_oneof![
                proptest::collection::vec(0usize..160, 12..48),
                proptest::collection::vec(0usize..1 << 34, 12..48),
            ],
            line in prop_oneof![0usize..200, any::<usize>()],
            column in 0usize..1 << 20,
            named in any::<bool>(),
            pass in any::<bool>(),
        ) {
            let target = |k: usize| ReadAgainTarget {
                span: Span::new(starts[0] + k, starts[1]),
                kind: PositionKind::Robtarget,
                name: named.then_some(b"p10".as_slice()),
                line: line.wrapping_add(k),
                column,
                trans: [starts[0], starts[1], starts[2]],
                quaternion: [starts[3], starts[4], starts[5], starts[6]],
                quadrants: [starts[7], starts[8], starts[9], starts[10]],
                extax: &starts[11..starts.len() - k],
                values_pass_lints: pass,
            };
            let (mut staged, mut written) = (PositionList::new(), PositionList::new());
            for k in 0..2 {
                staged.push_read_again(&target(k));
                written.push_read_again_by_writer(&target(k));
            }
            prop_assert_eq!(&staged.bytes, &written.bytes);
            let bodies = |l: &PositionList| l.heads.iter().map(|h| h.body).collect::<Vec<_>>();
            prop_assert_eq!(bodies(&staged), bodies(&written));
        }
    }

    #[test]
    fn read_again_target_packs_what_push_packs_for_it() {
        let src = b"[[-1520.30,.5,9E+09],[0.707107,0,+12.5,2.69E-07],[0,0,-1,0],[5.,9E9]]";
        let starts: Vec<usize> = (1..src.len())
            .filter(|&i| {
                (src[i].is_ascii_digit() || matches!(src[i], b'.' | b'-' | b'+'))
                    && matches!(src[i - 1], b'[' | b',')
            })
            .collect();
        let field = |k: usize| NumField::read_at(src, starts[k]);
        let p = Position {
            name: Some(Name::from("p10")),
            kind: PositionKind::Robtarget,
            span: Span::new(0, src.len()),
            line: 7,
            column: 3,
            cartesian: Some(CartesianFields {
                trans: [field(0), field(1), field(2)],
                orient: Some(Orientation::Quaternion([
                    field(3),
                    field(4),
                    field(5),
                    field(6),
                ])),
            }),
            joints: Vec::new(),
            config: Config::Quadrants([field(7), field(8), field(9), field(10)]),
            extax: [field(11), field(12)].into_iter().collect(),
            usage: Usage::default(),
        };
        let mut general = PositionList::new();
        general.push_checking(p.clone(), src, false);
        let mut direct = PositionList::new();
        direct.push_read_again(&ReadAgainTarget {
            span: p.span,
            kind: p.kind,
            name: Some(b"p10"),
            line: 7,
            column: 3,
            trans: [starts[0], starts[1], starts[2]],
            quaternion: [starts[3], starts[4], starts[5], starts[6]],
            quadrants: [starts[7], starts[8], starts[9], starts[10]],
            extax: &starts[11..],
            values_pass_lints: crate::report::values_pass_lints(
                p.cartesian.as_ref().and_then(|c| c.orient.as_ref()),
                &p.config,
            ),
        });
        assert_eq!(starts.len(), 13);
        assert_eq!(direct.bytes, general.bytes);
        assert_eq!(direct.get(0, src), Some(p));
    }

    #[test]
    fn only_fields_the_source_spells_are_read_again() {
        // `9E+09` read again is one tag byte and one offset; a field the source does not
        // spell (here the literal of `0.707107` placed where `9E+09` is written) keeps its
        // value and style: 14 bytes more.
        let (src, spans) = source(&[3, 1]);
        let read = NumField::read_at(&src, spans[0].start);
        let moved = field(&src, &spans, 0, Some(1));
        assert_ne!(read, moved);
        let position = |f: Option<NumField>| Position {
            name: None,
            kind: PositionKind::Jointtarget,
            span: Span::new(1, src.len() - 1),
            line: 1,
            column: 2,
            cartesian: None,
            joints: vec![f],
            config: Config::None,
            extax: Axes::new(),
            usage: Usage::default(),
        };
        let mut list = PositionList::new();
        list.push(position(read), &src);
        let one = list.bytes.len();
        list.push(position(moved), &src);
        assert_eq!(list.bytes.len() - one, one + 12);
        assert_eq!(list.get(0, &src).unwrap().joints, vec![read]);
        assert_eq!(list.get(1, &src).unwrap().joints, vec![moved]);
    }

    #[test]
    fn usage_recorded_after_the_push_is_the_decoded_usage() {
        let src = b"[1,2]";
        let p = Position {
            name: Some(Name::from("p10")),
            kind: PositionKind::Jointtarget,
            span: Span::new(0, 5),
            line: 3,
            column: 4,
            cartesian: None,
            joints: vec![NumField::read_at(src, 1), NumField::read_at(src, 3)],
            config: Config::None,
            extax: Axes::new(),
            usage: Usage::default(),
        };
        let mut list = PositionList::packed([p.clone()], src);
        let shared = FrameName::from("wCar");
        list.usage_mut(0)
            .unwrap()
            .record_shared(Some(&shared), None, false, 12);
        let got = list.get(0, src).unwrap();
        assert_eq!(got.usage.wobj.as_deref(), Some("wCar"));
        assert_eq!(got.usage.lines, Lines::from(vec![12]));
        assert_eq!(
            Position {
                usage: got.usage.clone(),
                ..p
            },
            got
        );
        assert_eq!(list.name(0), Some("p10"));
        assert_eq!(list.span(0), Some(Span::new(0, 5)));
    }

    /// A source of literals from [`TEXTS`], each followed by a separator from `seps` (a
    /// field is taken from the memo only after a `,` or `]`), and each literal's span.
    fn separated(picks: &[(usize, usize)]) -> (Vec<u8>, Vec<Span>) {
        const SEPS: &[&str] = &[",", "]", " ,", ",\n", "]]", ";"];
        let mut src = b"[".to_vec();
        let mut spans = Vec::new();
        for &(t, sep) in picks {
            let text = TEXTS[t % TEXTS.len()].as_bytes();
            spans.push(Span::new(src.len(), src.len() + text.len()));
            src.extend_from_slice(text);
            src.extend_from_slice(SEPS[sep % SEPS.len()].as_bytes());
        }
        (src, spans)
    }

    proptest! {
        /// Decoding a run of positions with a memo ([`PositionList::decoded_with`], and
        /// [`PositionList::iter`]) gives each position as decoding it alone does, whole and
        /// for a track, whatever the texts repeat: literals spelled alike at other places,
        /// fields kept whole, other separators, quaternions, A B C and quadrants.
        #[test]
        fn a_memo_decodes_a_run_as_each_alone(
            lits in proptest::collection::vec((0usize..TEXTS.len(), 0usize..6), 1..30),
            targets in proptest::collection::vec(
                (0u8..4, picks(7), 0u8..2, picks(4), proptest::collection::vec(
                    proptest::option::weighted(0.9, (0usize..64, proptest::option::of(0usize..64))),
                    0..8,
                )),
                1..12,
            ),
        ) {
            let (src, spans) = separated(&lits);
            let f = |p: &Pick| p.and_then(|(k, moved)| field(&src, &spans, k, moved));
            let mut list = PositionList::new();
            for (cart, fields, config, quads, extax) in &targets {
                let all: Vec<Option<NumField>> = fields.iter().map(f).collect();
                list.push(Position {
                    name: None,
                    kind: PositionKind::Robtarget,
                    span: Span::new(0, src.len()),
                    line: 1,
                    column: 1,
                    cartesian: (*cart > 0).then(|| CartesianFields {
                        trans: [all[0], all[1], all[2]],
                        orient: match cart {
                            1 => None,
                            2 => Some(Orientation::Quaternion([all[3], all[4], all[5], all[6]])),
                            _ => Some(Orientation::Abc([all[3], all[4], all[5]])),
                        },
                    }),
                    joints: Vec::new(),
                    config: match config {
                        0 => Config::None,
                        _ => Config::Quadrants([f(&quads[0]), f(&quads[1]), f(&quads[2]), f(&quads[3])]),
                    },
                    extax: extax.iter().map(f).collect(),
                    usage: Usage::default(),
                }, &src);
            }
            let alone: Vec<Position> = (0..list.len()).map(|i| list.get(i, &src).unwrap()).collect();
            prop_assert_eq!(list.iter(&src).collect::<Vec<_>>(), alone.clone());
            let mut memo = DecodeMemo::default();
            for (i, want) in alone.iter().enumerate() {
                prop_assert_eq!(&list.decoded_with(i, &src, Reading::Whole, &mut memo), want);
            }
            for skid_axis in [0, 2, 7] {
                let reading = Reading::Track { skid_axis };
                // The memo left by the whole reading, then its own.
                for i in 0..list.len() {
                    let got = list.decoded_with(i, &src, reading, &mut memo);
                    prop_assert_eq!(got, list.get_reading(i, &src, reading).unwrap());
                }
            }
        }
    }
}
