//! The provenance stamp: the one line trackfix adds to a file it transforms.
//!
//! A comment right after the file's header (`MODULE`, KRL `DEF`/`DEFDAT`) in the language's own
//! comment syntax names the command, the robot, the profile (name and data hash) and trackfix's
//! version:
//!
//! ```text
//! MODULE spot_line
//! ! trackfix: correct robot=r1 profile="r1 track" sha256=0123456789ab version=0.1.0
//! ```
//!
//! It makes a second `correct` for the same robot detectable (a file corrected twice carries its
//! deviation twice), and a `zero` of a file never corrected. A later transform replaces the
//! line, so a file carries at most one stamp: the last transform applied to it.
//!
//! A transform writes a changed number with at least the house decimals of its kind (3 for mm,
//! 4 for degrees, 6 for quaternion components), so `-1200` corrected reads `-1200.873`. The
//! stamp then also records how the widened literals were first written, so that a later
//! transform that brings a value back can give back its text (`-1200.000` → `-1200`):
//!
//! ```text
//! ! trackfix: correct robot=r1 widened=3:0*12,3*4,1;6:0*8 version=0.1.0
//! ```
//!
//! `widened=` holds, for each house precision D that widened something (`3:`, `4:`, `6:`,
//! separated by `;`), a run-length list (`d*n` is `n` times `d`, `d` alone once) with one entry
//! per number literal of the file that resolves exactly D decimals, in file order (the stamp
//! line itself not counted): the precision it was first written with, D for one written so.
//! Trailing entries of D are left off. A literal's precision is its decimals minus its exponent:
//! `-1200.873` resolves 3, and so does `1.50123E+2`, a rewrite of `1.5E+2` (which resolves -1,
//! recorded as `3:-1`). See [`carry_precision`].
//!
//! `correct` also records the A of each KUKA target written at B = ±90° (`gimbal=0:0.0,5:30`,
//! by target index), whose split between A and C the corrected text no longer says; `zero`
//! writes the split that keeps it ([`LockSplits`]).
//!
//! A run that leaves refused targets as written (refused, and kept by the caller) lists them
//! (`kept=0:reach:p01;2:reach:j03`, [`Kept`]): the stamp then says what the file carries but
//! for those, and the transform that undoes it leaves them as written.

use crate::position::ParsedFile;
use crate::syntax::Span;
use crate::transform::refusal::RefusalKind;

/// The lowest first-written precision a `widened=` entry may hold (`1E+20` resolves -20; an
/// exponent literal keeps its exponent when rewritten only below 100).
const MIN_FIRST_PRECISION: i8 = -99;

/// What every stamp comment starts with after the comment mark.
const TAG: &str = "trackfix:";

/// What a stamp records.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Stamp {
    /// `correct`, `zero`, `mirror`, `transfer`.
    pub command: String,
    /// The robot whose track the file is now for (`transfer`: the robot transferred to).
    pub robot: Option<String>,
    /// The profile's name and the first 12 hex digits of its data hash.
    pub profile: Option<(String, String)>,
    /// How the literals this file's transforms widened were first written.
    #[serde(skip_serializing_if = "Widened::is_empty")]
    pub widened: Widened,
    /// The A of each target `correct` found at B = ±90° (see [`LockSplits`]).
    #[serde(skip_serializing_if = "LockSplits::is_empty")]
    pub gimbal: LockSplits,
    /// The targets the run left as written (see [`Kept`]).
    #[serde(skip_serializing_if = "Kept::is_empty")]
    pub kept: Kept,
    /// trackfix's version.
    pub version: String,
}

/// The decimal places house precisions write at least (`rewrite::{MM,DEG,QUAT}_DECIMALS`).
const HOUSE_DECIMALS: [usize; 3] = [
    super::rewrite::MM_DECIMALS,
    super::rewrite::DEG_DECIMALS,
    super::rewrite::QUAT_DECIMALS,
];

/// For each house precision D, the precision each literal that resolves exactly D decimals was
/// first written with, in file order (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Widened(pub std::collections::BTreeMap<usize, Vec<i8>>);

impl Widened {
    /// True when no literal is recorded as widened.
    pub fn is_empty(&self) -> bool {
        self.0
            .iter()
            .all(|(&d, list)| list.iter().all(|&e| e as i32 == d as i32))
    }

    /// The `widened=` value: `3:0*12,3*4,1;6:0*8`.
    fn text(&self) -> String {
        let mut parts = Vec::new();
        for (&d, list) in &self.0 {
            let keep = list
                .iter()
                .rposition(|&e| e as i32 != d as i32)
                .map_or(0, |i| i + 1);
            if keep == 0 {
                continue;
            }
            let mut runs: Vec<(i8, usize)> = Vec::new();
            for &e in &list[..keep] {
                match runs.last_mut() {
                    Some((v, n)) if *v == e => *n += 1,
                    _ => runs.push((e, 1)),
                }
            }
            let runs: Vec<String> = runs
                .iter()
                .map(|&(v, n)| {
                    if n == 1 {
                        v.to_string()
                    } else {
                        format!("{v}*{n}")
                    }
                })
                .collect();
            parts.push(format!("{d}:{}", runs.join(",")));
        }
        parts.join(";")
    }

    /// Reads a `widened=` value; `None` if it is malformed (then nothing is restored).
    /// At most `limit` entries in all (a file of `limit` bytes holds fewer literals), so a
    /// hostile stamp cannot make us allocate beyond the file's own size.
    fn parse(text: &str, limit: usize) -> Option<Widened> {
        let mut out = std::collections::BTreeMap::new();
        let mut total = 0usize;
        for part in text.split(';') {
            let (d, runs) = part.split_once(':')?;
            let d: usize = d.parse().ok()?;
            if !HOUSE_DECIMALS.contains(&d) {
                return None;
            }
            let mut list = Vec::new();
            for run in runs.split(',') {
                let (v, n) = match run.split_once('*') {
                    Some((v, n)) => (v.parse::<i8>().ok()?, n.parse::<usize>().ok()?),
                    None => (run.parse().ok()?, 1),
                };
                total += n;
                if v as i32 > d as i32 || v < MIN_FIRST_PRECISION || total > limit {
                    return None;
                }
                list.extend(std::iter::repeat_n(v, n));
            }
            out.insert(d, list);
        }
        Some(Widened(out))
    }

    /// The first-written precision of the `index`-th literal that resolves `d` decimals
    /// ([`carry_precision`] reads the lists by slot instead, once per literal).
    #[cfg(test)]
    fn of(&self, d: usize, index: usize) -> i32 {
        recorded(self.0.get(&d).map_or(&[][..], Vec::as_slice), index, d)
    }
}

/// The first-written precision entry `index` of a `d`-decimals list records: `d` itself where
/// the list has no entry (the literal was written at `d` from the start).
fn recorded(list: &[i8], index: usize, d: usize) -> i32 {
    list.get(index).map_or(d as i32, |&e| e as i32)
}

/// The A of each KUKA target written at B = ±90°, as written, by the target's index among the
/// file's targets (`gimbal=4:30,9:-12.5`).
///
/// At B = ±90° only A − C (B = 90°) or A + C (B = -90°) says the orientation; the split is the
/// file's own choice. `correct` moves such a target off the lock, where its angles have one
/// split only, so the corrected text no longer says which split the original had. `zero` reads
/// this record and, where its result is at B = ±90° again at the written places, writes the
/// split that keeps the recorded A (docs/design.md §5, round trip); never another orientation.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LockSplits(pub Vec<(usize, String)>);

impl LockSplits {
    /// True when no target is recorded.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The record of `file`: every Cartesian target with A, B, C literals whose B is ±90.
    /// Only each target's A, B and C are decoded ([`PositionList::abc_fields`]); debug builds
    /// hold the record to the one of decoding every target whole ([`LockSplits::of_decoded`]).
    ///
    /// [`PositionList::abc_fields`]: crate::position::PositionList::abc_fields
    pub fn of(file: &ParsedFile) -> LockSplits {
        let mut out = Vec::new();
        for i in 0..file.positions.len() {
            let Some([Some(a), Some(b), Some(_)]) = file.positions.abc_fields(i, &file.source)
            else {
                continue;
            };
            if super::rewrite::written_at_lock(&b) && a.value().is_finite() {
                out.push((i, crate::syntax::latin1(a.span().slice(&file.source))));
            }
        }
        let splits = LockSplits(out);
        debug_assert_eq!(splits, LockSplits::of_decoded(file));
        splits
    }

    /// [`LockSplits::of`] from each target decoded whole: what it is held to.
    fn of_decoded(file: &ParsedFile) -> LockSplits {
        use crate::position::Orientation;
        let mut out = Vec::new();
        // Only A, B, C targets are decoded: a RAPID module has none.
        let abc = (0..file.positions.len()).filter(|&i| file.positions.writes_abc(i));
        for (i, p) in abc.filter_map(|i| Some((i, file.position(i)?))) {
            let Some(Orientation::Abc([Some(a), Some(b), Some(_)])) =
                p.cartesian.as_ref().and_then(|c| c.orient.as_ref())
            else {
                continue;
            };
            if super::rewrite::written_at_lock(b) && a.value().is_finite() {
                out.push((i, crate::syntax::latin1(a.span().slice(&file.source))));
            }
        }
        LockSplits(out)
    }

    /// The recorded A of the target at `index`, if any.
    pub fn a_of(&self, index: usize) -> Option<f64> {
        let at = self.0.binary_search_by_key(&index, |(i, _)| *i).ok()?;
        self.0[at].1.parse().ok()
    }

    /// The `gimbal=` value: `4:30,9:-12.5`.
    fn text(&self) -> String {
        let parts: Vec<String> = self.0.iter().map(|(i, a)| format!("{i}:{a}")).collect();
        parts.join(",")
    }

    /// Reads a `gimbal=` value; `None` if it is malformed or not in target order (then nothing
    /// is kept). At most `limit` entries, as for `widened=`.
    fn parse(text: &str, limit: usize) -> Option<LockSplits> {
        let mut out: Vec<(usize, String)> = Vec::new();
        for part in text.split(',') {
            let (i, a) = part.split_once(':')?;
            let i: usize = i.parse().ok()?;
            let v: f64 = a.parse().ok()?;
            let ordered = out.last().is_none_or(|(last, _)| *last < i);
            if !v.is_finite() || !ordered || out.len() >= limit {
                return None;
            }
            out.push((i, a.to_owned()));
        }
        Some(LockSplits(out))
    }
}

/// The targets a run left as written, refused and kept by the caller (whole kinds of them), by
/// index among the file's targets (file order, as [`LockSplits`]), each with the kind of its
/// refusal and its name (`kept=0:reach:p01;2:reach:j03;7:skid-not-connected`; an inline target
/// has none).
///
/// The rest of the file carries the run's change and these do not, so a stamp without the list
/// would claim them too: a `zero` of a partly corrected file would take out of them a
/// correction they never had. The transform that undoes the stamp's leaves them as written
/// (docs/design.md §4, "Targets kept as written"). The name is there to tell a record out of
/// step with its file (a target added, removed or renamed since) from one in step.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Kept {
    /// The targets, in index order.
    pub targets: Vec<KeptTarget>,
    /// The record as written, when it cannot be read (a hand edit, a later version's kind):
    /// written back as it was, and nothing is known of which targets it lists.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unreadable: Option<String>,
}

/// Whether a transform reads what the provenance stamps of its input say of the targets they
/// list as kept as written ([`Kept`]; docs/design.md §4, "Targets kept as written"): the first
/// step of a chain does, the later ones do not (their input carries the first's stamp line, but
/// not what it says).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StampReading {
    /// The transform that undoes a stamp's leaves the targets it lists as written, saying so;
    /// any other refuses them (they lack what the rest of the file carries).
    Read,
    /// Every target is transformed alike.
    Ignore,
}

/// One target of a [`Kept`] record.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct KeptTarget {
    /// Its index among the file's targets.
    pub index: usize,
    /// Why the run refused it.
    pub kind: RefusalKind,
    /// Its name as declared; `None` for an inline target.
    pub name: Option<String>,
}

impl Kept {
    /// True when the record lists nothing and is not unreadable.
    pub fn is_empty(&self) -> bool {
        self.targets.is_empty() && self.unreadable.is_none()
    }

    /// A record of `targets` (sorted by index, one entry per index).
    pub fn of(mut targets: Vec<KeptTarget>) -> Kept {
        targets.sort_by_key(|t| t.index);
        targets.dedup_by_key(|t| t.index);
        Kept {
            targets,
            unreadable: None,
        }
    }

    /// The `kept=` value: `0:reach:p01;2:reach:j03;7:skid-not-connected`.
    fn text(&self) -> String {
        if let Some(raw) = &self.unreadable {
            return raw.clone();
        }
        let parts: Vec<String> = self
            .targets
            .iter()
            .map(|t| {
                let mut s = format!("{}:{}", t.index, kind_name(t.kind));
                if let Some(n) = &t.name {
                    s.push(':');
                    s.push_str(&escape_name(n));
                }
                s
            })
            .collect();
        parts.join(";")
    }

    /// Reads a `kept=` value. Unlike the other records, one that cannot be read is kept as
    /// [`Kept::unreadable`], not dropped: an empty list would say that every target carries
    /// the run's change. At most `limit` entries, as for `widened=`.
    fn parse(text: &str, limit: usize) -> Kept {
        let read = || -> Option<Vec<KeptTarget>> {
            let mut out: Vec<KeptTarget> = Vec::new();
            for part in text.split(';') {
                let mut fields = part.splitn(3, ':');
                let index: usize = fields.next()?.parse().ok()?;
                let kind =
                    <RefusalKind as clap::ValueEnum>::from_str(fields.next()?, false).ok()?;
                let name = match fields.next() {
                    Some(text) => Some(unescape_name(text)?),
                    None => None,
                };
                let ordered = out.last().is_none_or(|last| last.index < index);
                if !ordered || out.len() >= limit || kind.is_note() {
                    return None;
                }
                out.push(KeptTarget { index, kind, name });
            }
            Some(out)
        };
        match read() {
            Some(targets) => Kept {
                targets,
                unreadable: None,
            },
            None => Kept {
                targets: Vec::new(),
                unreadable: Some(text.to_owned()),
            },
        }
    }

    /// Why the record does not fit `file`, if it does not: it cannot be read, or a target it
    /// lists is not where it says (another name there, or none). Such a record says nothing
    /// of which targets carry the run's change.
    pub fn out_of_step(&self, file: &ParsedFile) -> Option<String> {
        if let Some(raw) = &self.unreadable {
            return Some(format!("its kept= record `{raw}` cannot be read"));
        }
        for t in &self.targets {
            if t.index >= file.positions.len() {
                return Some(format!(
                    "its kept= record lists target index {} of a file of {} target(s)",
                    t.index,
                    file.positions.len()
                ));
            }
            let here = file.positions.name(t.index);
            let same = match (here, &t.name) {
                (Some(a), Some(b)) => crate::names::fold(a) == crate::names::fold(b),
                (None, None) => true,
                _ => false,
            };
            if !same {
                let said =
                    |n: Option<&str>| n.map_or("an inline target".to_owned(), |n| format!("`{n}`"));
                return Some(format!(
                    "its kept= record says target index {} is {}, and the file has {} there",
                    t.index,
                    said(t.name.as_deref()),
                    said(here)
                ));
            }
        }
        None
    }
}

/// A refusal kind by its kebab-case name (its `clap::ValueEnum` name).
pub(crate) fn kind_name(kind: RefusalKind) -> String {
    clap::ValueEnum::to_possible_value(&kind)
        .map_or_else(|| format!("{kind:?}"), |v| v.get_name().to_owned())
}

/// A target's name as one word of the record: `%`, `;`, `"`, blanks and anything outside
/// printable ASCII as `%XX` (of its UTF-8 bytes).
fn escape_name(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for b in name.bytes() {
        if b.is_ascii_graphic() && !matches!(b, b'%' | b';' | b'"') {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// [`escape_name`] undone; `None` for a malformed escape.
fn unescape_name(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok().filter(|s| !s.is_empty())
}

impl Stamp {
    /// A stamp of this version of trackfix.
    pub fn new(command: &str, robot: Option<&str>, profile: Option<(&str, &str)>) -> Stamp {
        Stamp {
            command: command.to_owned(),
            robot: robot.map(str::to_owned),
            profile: profile.map(|(n, h)| (n.to_owned(), h.chars().take(12).collect())),
            widened: Widened::default(),
            gimbal: LockSplits::default(),
            kept: Kept::default(),
            version: env!("CARGO_PKG_VERSION").to_owned(),
        }
    }

    /// The comment text after the comment mark (no line end).
    pub fn text(&self) -> String {
        let mut s = format!("{TAG} {}", self.command);
        if let Some(r) = &self.robot {
            s.push_str(&format!(" robot={}", token(r)));
        }
        if let Some((name, hash)) = &self.profile {
            s.push_str(&format!(" profile={} sha256={hash}", token(name)));
        }
        if !self.widened.is_empty() {
            s.push_str(&format!(" widened={}", self.widened.text()));
        }
        if !self.gimbal.is_empty() {
            s.push_str(&format!(" gimbal={}", self.gimbal.text()));
        }
        if !self.kept.is_empty() {
            s.push_str(&format!(" kept={}", self.kept.text()));
        }
        s.push_str(&format!(" version={}", self.version));
        s
    }

    /// Reads a stamp comment's text (after the comment mark); `None` if it is no stamp.
    fn parse(text: &str, limit: usize) -> Option<Stamp> {
        let rest = text.trim().strip_prefix(TAG)?;
        let mut words = split_tokens(rest).into_iter();
        let command = words.next()?;
        let mut stamp = Stamp {
            command,
            robot: None,
            profile: None,
            widened: Widened::default(),
            gimbal: LockSplits::default(),
            kept: Kept::default(),
            version: String::new(),
        };
        let mut name = None;
        for w in words {
            match w.split_once('=') {
                Some(("robot", v)) => stamp.robot = Some(v.to_owned()),
                Some(("profile", v)) => name = Some(v.to_owned()),
                Some(("sha256", v)) => {
                    stamp.profile = Some((name.take().unwrap_or_default(), v.to_owned()));
                }
                Some(("widened", v)) => {
                    stamp.widened = Widened::parse(v, limit).unwrap_or_default()
                }
                Some(("gimbal", v)) => {
                    stamp.gimbal = LockSplits::parse(v, limit).unwrap_or_default()
                }
                Some(("kept", v)) => stamp.kept = Kept::parse(v, limit),
                Some(("version", v)) => stamp.version = v.to_owned(),
                _ => {}
            }
        }
        Some(stamp)
    }

    /// True for a stamp that says the file is corrected for `robot`'s track (a `correct` for it,
    /// or a `transfer` to it).
    pub fn corrected_for(&self, robot: &str) -> bool {
        matches!(self.command.as_str(), "correct" | "transfer")
            && self.robot.as_deref() == Some(robot)
    }
}

/// A value as one word: quoted when it holds blanks or quotes.
fn token(s: &str) -> String {
    if s.is_empty() || s.contains(|c: char| c.is_whitespace() || c == '"') {
        format!("\"{}\"", s.replace('"', "'"))
    } else {
        s.to_owned()
    }
}

/// Blank-separated words; `key="a b"` is one word `key=a b`.
fn split_tokens(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut quoted = false;
    for c in s.chars() {
        match c {
            '"' => quoted = !quoted,
            c if c.is_whitespace() && !quoted => {
                if !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
            }
            c => word.push(c),
        }
    }
    if !word.is_empty() {
        out.push(word);
    }
    out
}

/// The lines of `src` with their terminators: `(start, end without terminator, end)`.
fn lines(src: &[u8]) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
    let mut start = 0;
    std::iter::from_fn(move || {
        if start >= src.len() {
            return None;
        }
        let mut end = start;
        while end < src.len() && src[end] != b'\n' && src[end] != b'\r' {
            end += 1;
        }
        let mut next = end;
        if next < src.len() && src[next] == b'\r' {
            next += 1;
        }
        if next < src.len() && src[next] == b'\n' && (next == end || src[end] == b'\r') {
            next += 1;
        }
        let line = (start, end, next);
        start = next;
        Some(line)
    })
}

/// Where the header line is: its content end and the end of its terminator.
fn header(src: &[u8], keywords: &[&str]) -> Option<(usize, usize)> {
    header_name(src, keywords).map(|h| (h.end, h.next))
}

/// The header line of a file and the name it declares.
pub(crate) struct Header {
    /// The span of the declared name (`spot_line` in `DEF spot_line( )`).
    pub name: Span,
    /// Content end and terminator end of the header line.
    pub end: usize,
    pub next: usize,
}

/// The first line that opens with one of `keywords` (ASCII case ignored, after blanks and a
/// BOM), and the name after the keyword.
pub(crate) fn header_name(src: &[u8], keywords: &[&str]) -> Option<Header> {
    for (start, end, next) in lines(src) {
        let text = &src[start..end];
        let mut at = text
            .iter()
            .take_while(|b| matches!(b, b' ' | b'\t'))
            .count();
        if text[at..].starts_with(b"\xEF\xBB\xBF") {
            at += 3;
        }
        let body = &text[at..];
        // The longest keyword that matches (`DEFDAT` before `DEF`).
        let keyword = keywords
            .iter()
            .filter(|k| {
                body.len() >= k.len()
                    && body[..k.len()].eq_ignore_ascii_case(k.as_bytes())
                    && body
                        .get(k.len())
                        .is_none_or(|b| matches!(b, b' ' | b'\t' | b'('))
            })
            .max_by_key(|k| k.len());
        if let Some(k) = keyword {
            let rest = &body[k.len()..];
            let blanks = rest
                .iter()
                .take_while(|b| matches!(b, b' ' | b'\t'))
                .count();
            let len = rest[blanks..]
                .iter()
                .take_while(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'$'))
                .count();
            let name_start = start + at + k.len() + blanks;
            return Some(Header {
                name: Span::new(name_start, name_start + len),
                end,
                next,
            });
        }
    }
    None
}

/// The stamp of `file` and the span of its whole line (terminator included), if it has one.
pub fn find(file: &ParsedFile) -> Option<(Stamp, Span)> {
    find_in(&file.source, file.language.dialect())
}

/// The stamp of the bytes `src` in `dialect` and the span of its line, if it has one.
pub fn find_stamp(src: &[u8], dialect: &dyn crate::dialect::Dialect) -> Option<(Stamp, Span)> {
    find_in(src, dialect)
}

fn find_in(src: &[u8], dialect: &dyn crate::dialect::Dialect) -> Option<(Stamp, Span)> {
    let mark = dialect.line_comment()?;
    let (_, after) = header(src, dialect.header_keywords())?;
    let (start, end, next) = lines(&src[after..]).next()?;
    let text = crate::syntax::latin1(&src[after + start..after + end]);
    let comment = text.trim_start().strip_prefix(mark)?;
    let stamp = Stamp::parse(comment, src.len())?;
    Some((stamp, Span::new(after + start, after + next)))
}

/// `src` with `stamp` as the line after its header: an existing stamp is replaced, else the line
/// is inserted, with the header line's own line end. `None` when the language has no line
/// comment or the file no header (nothing to put it after).
pub fn write(src: &[u8], dialect: &dyn crate::dialect::Dialect, stamp: &Stamp) -> Option<Vec<u8>> {
    let mut out = src.to_vec();
    write_in_place(&mut out, dialect, stamp).then_some(out)
}

/// [`write()`] into `src` itself: the bytes after the stamp line move, the file is not copied
/// (it is a transform's whole output). `false`, and `src` unchanged, where [`write()`] gives
/// `None`.
pub fn write_in_place(
    src: &mut Vec<u8>,
    dialect: &dyn crate::dialect::Dialect,
    stamp: &Stamp,
) -> bool {
    let Some(mark) = dialect.line_comment() else {
        return false;
    };
    let Some((end, next)) = header(src, dialect.header_keywords()) else {
        return false;
    };
    let eol = if next > end { &src[end..next] } else { b"\n" };
    let mut line = format!("{mark} {}", stamp.text()).into_bytes();
    let (at, replaced) = match find_in(src, dialect) {
        Some((_, span)) => {
            line.extend_from_slice(eol);
            (span.start, span.end - span.start)
        }
        // The header is the file's last line, without a terminator: the stamp line gets the
        // terminator before it instead of after.
        None if next == end => {
            line.splice(0..0, eol.iter().copied());
            (next, 0)
        }
        None => {
            line.extend_from_slice(eol);
            (next, 0)
        }
    };
    splice(src, at, replaced, &line);
    true
}

/// Replaces `len` bytes at `at` with `with`, growing the buffer by exactly what it needs.
fn splice(src: &mut Vec<u8>, at: usize, len: usize, with: &[u8]) {
    src.reserve_exact(with.len().saturating_sub(len));
    src.splice(at..at + len, with.iter().copied());
}

/// `src` without its stamp line (as it was before trackfix stamped it), if it has one.
pub fn strip(src: &[u8], dialect: &dyn crate::dialect::Dialect) -> Option<Vec<u8>> {
    let mut out = src.to_vec();
    strip_in_place(&mut out, dialect).then_some(out)
}

/// [`strip`] from `src` itself; `false`, and `src` unchanged, when it has no stamp.
pub fn strip_in_place(src: &mut Vec<u8>, dialect: &dyn crate::dialect::Dialect) -> bool {
    let Some((_, span)) = find_in(src, dialect) else {
        return false;
    };
    src.drain(span.start..span.end);
    true
}

/// A number literal's place in a file: its byte span, decimals after the point, where the
/// mantissa ends and the precision it resolves.
#[derive(Clone, Copy, Debug)]
struct NumberToken {
    start: usize,
    end: usize,
    /// Digits after the point (of the mantissa).
    decimals: u32,
    /// Bytes of the exponent suffix (`E+2` → 3; 0 without one).
    exponent_len: u32,
    /// [`NumberToken::precision`], worked out once as the literal is read: the carry tests it
    /// up to three times a literal.
    precision: i32,
}

impl NumberToken {
    /// A literal of `decimals` and `exponent` (0 without one) with its suffix of
    /// `exponent_len` bytes.
    fn new(start: usize, end: usize, decimals: u32, exponent: i32, exponent_len: u32) -> Self {
        NumberToken {
            start,
            end,
            decimals,
            exponent_len,
            precision: (decimals as i32).saturating_sub(exponent),
        }
    }

    /// Decimal places the literal resolves: its decimals minus its exponent (`1.50123E+2` → 3).
    fn precision(&self) -> i32 {
        self.precision
    }

    /// Whether it resolves exactly a house precision (the literals `widened=` lists).
    fn house(&self) -> bool {
        usize::try_from(self.precision()).is_ok_and(|p| HOUSE_DECIMALS.contains(&p))
    }

    /// The end of the mantissa (before any exponent).
    fn mantissa_end(&self) -> usize {
        self.end - self.exponent_len as usize
    }
}

/// Every number literal of `src` outside `skip`, in file order: a digit run with an optional
/// `.` and digits and an optional exponent, not part of a name (`p10`, `$X1`) and not followed
/// by a letter. Signs are not part of it. Dialect-free on purpose: the same scan of the same
/// bytes gives the same list, comments and strings included, on both sides of a transform.
fn number_tokens(skip: Option<Span>) -> NumberTokens {
    NumberTokens { skip, i: 0 }
}

/// The number literals of a file, in order (see [`number_tokens`]): scanned as they are asked
/// for, so that two files' literals can be paired without a list of millions of each.
///
/// The scanner keeps only its place; each step is given the bytes. A step reads nothing before
/// the end of the token it last returned (that token is followed by a byte outside words), so
/// the bytes before it may be rewritten between steps: [`carry_precision`] narrows literals in
/// the buffer it scans.
#[derive(Clone)]
struct NumberTokens {
    skip: Option<Span>,
    i: usize,
}

/// The bytes that belong to a word for [`number_tokens`] (letters, digits, `_ $ . #`), by
/// table: the scan looks at every byte of two files, and one load per byte keeps it cheap.
static WORD: [bool; 256] = {
    let mut table = [false; 256];
    let mut b = 0;
    while b < 256 {
        let c = b as u8;
        table[b] = c.is_ascii_alphanumeric() || matches!(c, b'_' | b'$' | b'.' | b'#');
        b += 1;
    }
    table
};

/// Each byte's low seven bits (`0x7f` in every byte of a word).
const LOW7: u64 = u64::from_le_bytes([0x7f; 8]);

/// The high bit of each byte of `x` that is an ASCII byte in `lo..hi` (`lo` ≥ 1, `hi` ≤ 128),
/// eight bytes at once: no byte's sum carries into the next one.
#[inline(always)]
fn bytes_in(x: u64, lo: u8, hi: u8) -> u64 {
    let ones = u64::from_le_bytes([1; 8]);
    let low = x & LOW7;
    let from_lo = low + ones * u64::from(0x80 - lo);
    let from_hi = low + ones * u64::from(0x80 - hi);
    from_lo & !from_hi & !x & !LOW7
}

/// The place after the digits at `src[i..]`, eight bytes at a time: a literal's digit runs are
/// a few bytes, and one test of a word for them costs what the tests of two bytes did.
#[inline(always)]
fn after_digits(src: &[u8], mut i: usize) -> usize {
    while let Some(block) = src.get(i..).and_then(|s| s.first_chunk::<8>()) {
        let others = !bytes_in(u64::from_le_bytes(*block), b'0', b'9' + 1) & !LOW7;
        if others != 0 {
            return i + (others.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    while src.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    i
}

/// The end and decimals of the literal at `start` when it has no exponent, its digits
/// before the point are fewer than 8 and so are those after it (`1520.652,`, `0.000427]`): the
/// non-digits of the word at the start and of the one after the point give both digit runs in
/// a line, without [`after_digits`]'s loops and the tests between them. `None` for any other
/// literal, and for bytes that are no literal (a word byte after the digits):
/// [`NumberTokens::next`] reads those as it did.
#[inline(always)]
fn short_literal(src: &[u8], start: usize) -> Option<(usize, u32)> {
    // The word at `at` and the place of its first non-digit, if it has one.
    let digits = |at: usize| {
        let word = *src.get(at..)?.first_chunk::<8>()?;
        let others = !bytes_in(u64::from_le_bytes(word), b'0', b'9' + 1) & !LOW7;
        (others != 0).then(|| (word, (others.trailing_zeros() / 8) as usize & 7))
    };
    let (word, n) = digits(start)?;
    let (end, decimals, after) = match word[n] {
        b'.' => {
            let (word, d) = digits(start + n + 1)?;
            (start + n + 1 + d, d as u32, word[d])
        }
        b => (start + n, 0, b),
    };
    // An exponent's `E` is a word byte: left to the byte-wise scan.
    (!WORD[after as usize]).then_some((end, decimals))
}

impl NumberTokens {
    /// The next literal of `src` (the same bytes at and after the place as at the last step).
    #[inline(always)]
    fn next(&mut self, src: &[u8]) -> Option<NumberToken> {
        let skip = self.skip;
        let word = |b: u8| WORD[b as usize];
        let mut i = self.i;
        loop {
            // Bytes outside words start nothing: run over them in a tight loop, stopping at
            // the skipped span's start while the scan may still land on it.
            let limit = match skip {
                Some(s) if i <= s.start => s.start.min(src.len()),
                _ => src.len(),
            };
            let from = i;
            while i < limit && !word(src[i]) {
                i += 1;
            }
            if i >= src.len() {
                break;
            }
            if let Some(s) = skip
                && i == s.start
            {
                i = s.end.max(i + 1);
                continue;
            }
            let b = src[i];
            let starts =
                b.is_ascii_digit() || (b == b'.' && src.get(i + 1).is_some_and(u8::is_ascii_digit));
            // The byte before is outside words where the loop above ran over it.
            if !starts || (i == from && i > 0 && word(src[i - 1])) {
                // Skip the rest of a word so `p10` gives no token (`b` is a word byte here).
                while i < src.len() && word(src[i]) {
                    i += 1;
                }
                continue;
            }
            let start = i;
            if let Some((end, decimals)) = short_literal(src, start) {
                self.i = end;
                return Some(NumberToken::new(start, end, decimals, 0, 0));
            }
            i = after_digits(src, i);
            let mut decimals = 0;
            if src.get(i) == Some(&b'.') {
                let f = i + 1;
                i = after_digits(src, f);
                decimals = i - f;
            }
            let (mut exponent, mut exponent_len) = (0, 0);
            if i < src.len() && matches!(src[i], b'e' | b'E') {
                let mut j = i + 1;
                let negative = j < src.len() && src[j] == b'-';
                if j < src.len() && matches!(src[j], b'+' | b'-') {
                    j += 1;
                }
                if j < src.len() && src[j].is_ascii_digit() {
                    let mut e = 0i32;
                    while j < src.len() && src[j].is_ascii_digit() {
                        e = e.saturating_mul(10).saturating_add((src[j] - b'0') as i32);
                        j += 1;
                    }
                    exponent = if negative { -e } else { e };
                    exponent_len = (j - i) as u32;
                    i = j;
                }
            }
            if i < src.len() && word(src[i]) {
                // `1.2.3`, `12abc`: no number; skip the whole word.
                while i < src.len() && word(src[i]) {
                    i += 1;
                }
                continue;
            }
            self.i = i;
            let decimals = u32::try_from(decimals).unwrap_or(u32::MAX);
            return Some(NumberToken::new(start, i, decimals, exponent, exponent_len));
        }
        self.i = i;
        None
    }
}

/// A stretch of the original that the output holds unchanged, `delta` bytes further on (the
/// transform's edits before it changed the length by that much): `original[start..end]` equals
/// `output[start + delta..end + delta]`, and `end` is the first byte where they differ (or the
/// end of either file).
///
/// [`carry_precision`] scans both files' literals, but a transform leaves most of a file as it
/// was (the words, the separators, the literals it did not change): there the output's next
/// literal is the original's, moved by `delta`, and need not be scanned again.
#[derive(Clone, Copy, Default)]
struct Alike {
    delta: isize,
    start: usize,
    end: usize,
    /// The stretch runs to the end of both files.
    to_the_end: bool,
}

impl Alike {
    /// The stretch the original from `b_from` and the output from `a_from` hold alike, from the
    /// byte before those places (the scanner reads it); `None` at the start of just one of the
    /// files, where there is no byte before to compare.
    #[inline]
    fn at(b_from: usize, a_from: usize, original: &[u8], output: &[u8]) -> Option<Alike> {
        if (b_from == 0) != (a_from == 0) {
            return None;
        }
        let (lo, lo_out) = (b_from.saturating_sub(1), a_from.saturating_sub(1));
        let len = crate::syntax::common_len(
            original.get(lo..).unwrap_or(&[]),
            output.get(lo_out..).unwrap_or(&[]),
        );
        Some(Alike {
            delta: lo_out as isize - lo as isize,
            start: lo,
            end: lo + len,
            to_the_end: lo + len == original.len() && lo_out + len == output.len(),
        })
    }

    /// The output's next literal (or its end, `Some(None)`) when the scan of the original that
    /// went from `b_from` to `b` read only bytes the output holds the same from `a_from` on:
    /// the scanner keeps nothing but its place, and reads from the byte before its place up to
    /// the byte after the literal it returns (see [`NumberTokens`]), so the same bytes give the
    /// same literal. `None` when that is not known: then the output is scanned.
    fn output_token(
        &mut self,
        b: Option<NumberToken>,
        b_from: usize,
        a_from: usize,
        original: &[u8],
        output: &[u8],
    ) -> Option<Option<NumberToken>> {
        // At the very start there is no byte before the place to compare.
        if (b_from == 0) != (a_from == 0) {
            return None;
        }
        let (lo, lo_out) = (b_from.saturating_sub(1), a_from.saturating_sub(1));
        let delta = lo_out as isize - lo as isize;
        // A stretch found from an earlier place with the same delta ends where it ended.
        if delta != self.delta || lo < self.start || lo >= self.end {
            *self = Alike::at(b_from, a_from, original, output)?;
        }
        let moved = |t: NumberToken| NumberToken {
            start: t.start.wrapping_add_signed(delta),
            end: t.end.wrapping_add_signed(delta),
            ..t
        };
        match b {
            // The byte after the literal (which ends it) is read too, where there is one.
            Some(t) if t.end < self.end || (self.to_the_end && t.end == self.end) => {
                Some(Some(moved(t)))
            }
            None if self.to_the_end => Some(None),
            _ => None,
        }
    }
}

/// The place of house precision `p` in [`HOUSE_DECIMALS`], if it is one.
/// By table, one test for every literal's precision instead of one for each house precision.
fn house_slot(p: i32) -> Option<usize> {
    const SLOTS: [Option<usize>; 8] = {
        let mut slots = [None; 8];
        let mut h = 0;
        while h < HOUSE_DECIMALS.len() {
            slots[HOUSE_DECIMALS[h]] = Some(h);
            h += 1;
        }
        slots
    };
    SLOTS.get(usize::try_from(p).ok()?).copied().flatten()
}

/// What [`carry_precision`] made of a transform's output.
#[derive(Clone, Debug, PartialEq)]
pub struct CarriedPrecision {
    /// The output, with each value the transform brought back to its first-written decimals
    /// written with them again.
    pub output: Vec<u8>,
    /// How the output's widened literals were first written: for the output's stamp.
    pub widened: Widened,
}

/// Carries literal precision across a transform from `original` (stamped or not) to `output`
/// (the transform's result, its stamp line not yet replaced).
///
/// The two files' number literals are paired in order (a transform replaces literals with
/// literals; if the counts differ nothing is carried and `output` is returned as is). A literal
/// the transform rewrote whose original was recorded as widened from precision `d` by
/// `original`'s stamp, and whose new text at the widened precision D ends in D − d zeros (of
/// the mantissa, for an exponent literal), is written with precision `d` (`-1200.000` →
/// `-1200`, `1.50000E+2` → `1.5E+2`, `.500` → `.5`): only zeros are dropped, so a stamp out of
/// step with the file can never change a value. Then every output literal that resolves exactly
/// a house precision D gets its first-written precision: a rewritten one's original precision
/// (or the earlier stamp's record of it), an unchanged one's record carried over, a narrowed one
/// its own.
///
/// `output` is taken and given back, not copied: narrowing only drops bytes, so it is done in
/// place, and an output with nothing to narrow (every `correct`) is returned untouched. A copy
/// of a large program's output here was as large as the file, next to its original and output.
pub fn carry_precision(
    original: &[u8],
    output: Vec<u8>,
    dialect: &dyn crate::dialect::Dialect,
) -> CarriedPrecision {
    carry(original, output, dialect, true)
}

/// [`carry_precision`] with the record an [`EditCarry`] worked out from the edits that made
/// `output` (`None` where it could not): taken as it is when neither file has a stamp, which is
/// when it is what [`carry_precision`] would build; otherwise [`carry_precision`].
pub fn carry_precision_known(
    original: &[u8],
    output: Vec<u8>,
    dialect: &dyn crate::dialect::Dialect,
    known: Option<Widened>,
) -> CarriedPrecision {
    match known {
        Some(widened)
            if find_in(original, dialect).is_none() && find_in(&output, dialect).is_none() =>
        {
            debug_assert_eq!(widened, carry_unstamped(original, output.clone()).widened);
            CarriedPrecision { output, widened }
        }
        _ => carry_precision(original, output, dialect),
    }
}

/// [`carry_unstamped`]'s record worked out from the edits as they are spliced in
/// ([`EditList::apply_seen`](crate::syntax::EditList::apply_seen)), without scanning the
/// output: the literals between the edits are the original's, counted by their marks
/// ([`count_house`]), and an edit's literals are paired with those of its text.
///
/// That pairs the two files' literals as the scan of both does only where each edit is clean:
/// the scan comes to its span from a stop of the original (a sign or two between allowed), the
/// byte after it is a stop (or the end), and its text has as many literals as the span: then
/// the scan of either file finds the same literals between the edits, and in the edits the
/// literals of the span and of the text. Any other edit makes the record unknown
/// ([`EditCarry::finish`] gives `None`) and [`carry_precision`] scans the files. Every
/// transform's edits of number literals are clean. On the 2 MB bench module `correct`'s
/// carry was 24 M instructions, most of them scanning each rewritten literal and its
/// neighbourhood on both sides; worked out here, about 19 M.
#[derive(Default)]
pub struct EditCarry {
    /// The original up to here is accounted for: the end of the last edit's span.
    pos: usize,
    count: [usize; 3],
    lists: [Vec<i8>; 3],
    /// An edit was not clean: the record is unknown.
    unknown: bool,
}

/// The most literals of an edit paired here; an edit of more is not clean.
const EDIT_LITERALS: usize = 4;

/// The precisions of the literals [`number_tokens`] finds in `bytes` (scanned on their own),
/// how many, `None` beyond [`EDIT_LITERALS`]. A plain literal (a sign, digits, a point among
/// or after them: nearly every edit of a transform) is read in one pass without the scan.
/// `window`, where given, is 16 bytes that start with `bytes`.
#[inline(always)]
fn precisions(bytes: &[u8], window: Option<&[u8; 16]>) -> Option<([i32; EDIT_LITERALS], usize)> {
    let mut found = [0i32; EDIT_LITERALS];
    let plain = match window {
        Some(w) if bytes.len() <= 16 => {
            plain_precision_in(w, bytes.len()).or_else(|| plain_precision(bytes))
        }
        _ => plain_precision(bytes),
    };
    if let Some(p) = plain {
        found[0] = p;
        return Some((found, 1));
    }
    let mut scan = number_tokens(None);
    let mut n = 0;
    while let Some(t) = scan.next(bytes) {
        *found.get_mut(n)? = t.precision();
        n += 1;
    }
    Some((found, n))
}

/// [`plain_precision`] of the first `n` (at most 16) bytes of `window` whose digits and point
/// after the sign are eight bytes or fewer (`-1520.652`, `0.707333`: most literals), by one
/// word: its bytes that are no digit must be one point at most, after the first.
#[inline(always)]
fn plain_precision_in(window: &[u8; 16], n: usize) -> Option<i32> {
    let sign = usize::from(matches!(window[0], b'-' | b'+'));
    let len = n.checked_sub(sign).filter(|&l| (1..=8).contains(&l))?;
    let word = u64::from_le_bytes(*window[sign..].first_chunk::<8>()?);
    let high = u64::from_le_bytes([0x80; 8]);
    let within = match len {
        8 => high,
        _ => high & ((1u64 << (8 * len)) - 1),
    };
    let others = within & !bytes_in(word, b'0', b'9' + 1);
    if others == 0 {
        return Some(0);
    }
    let at = (others.trailing_zeros() / 8) as usize;
    let point = word.to_le_bytes()[at] == b'.';
    (others & (others - 1) == 0 && point && at > 0).then(|| (len - 1 - at) as i32)
}

/// The precision of `bytes` when they are one sign or none, then digits with at most one
/// point among or after them (`-1520.652`, `12.`): the one literal the scan finds in them,
/// of as many decimals as follow the point. `None` for anything else.
#[inline(always)]
fn plain_precision(bytes: &[u8]) -> Option<i32> {
    let digits = match bytes {
        [b'-' | b'+', rest @ ..] => rest,
        _ => bytes,
    };
    if !digits.first()?.is_ascii_digit() {
        return None;
    }
    let mut point = None;
    for (i, &b) in digits.iter().enumerate() {
        match b {
            b'0'..=b'9' => {}
            b'.' if point.is_none() => point = Some(i),
            _ => return None,
        }
    }
    Some(point.map_or(0, |p| (digits.len() - p - 1) as i32))
}

impl EditCarry {
    /// Nothing seen yet.
    pub fn new() -> EditCarry {
        EditCarry::default()
    }

    /// The edit of `span` of `original` writing `text`, after those before it in the output.
    /// `window`, where given, is 16 bytes that start with `text`.
    #[inline]
    pub fn edit(&mut self, original: &[u8], span: Span, text: &[u8], window: Option<&[u8; 16]>) {
        if self.unknown || !self.seen(original, span, text, window) {
            self.unknown = true;
        }
    }

    #[inline(always)]
    fn seen(
        &mut self,
        original: &[u8],
        span: Span,
        text: &[u8],
        window: Option<&[u8; 16]>,
    ) -> bool {
        let (s, e) = (span.start, span.end);
        if s < self.pos || e < s || e > original.len() {
            return false;
        }
        // The stop the scan comes to the span from: signs may stand between.
        let mut k = s;
        while k > self.pos && matches!(original[k - 1], b'+' | b'-') {
            k -= 1;
        }
        let to = match k {
            0 => 0,
            _ if k > self.pos && is_stop(original[k - 1]) => k - 1,
            _ => return false,
        };
        if original.get(e).is_some_and(|&b| !is_stop(b)) {
            return false;
        }
        // Gaps of a separator or two between a target's fields (most of them) hold no literal
        // of a house precision: that has a mark `count_house` looks for (a point or a minus).
        if to > self.pos
            && original[self.pos..to]
                .iter()
                .any(|&b| b.wrapping_sub(b'-') < 2)
        {
            count_house(original, self.pos, to, &mut self.count);
        }
        // A plain literal for a plain literal (nearly every edit) is read by words.
        let at_s = original.get(s..).and_then(|o| o.first_chunk());
        let plain = match (at_s, window) {
            (Some(o), Some(t)) if e - s <= 16 && text.len() <= 16 => {
                plain_precision_in(o, e - s).zip(plain_precision_in(t, text.len()))
            }
            _ => None,
        };
        if let Some((b, a)) = plain {
            self.pair(b, a);
        } else {
            let (Some((b, nb)), Some((a, na))) =
                (precisions(&original[s..e], at_s), precisions(text, window))
            else {
                return false;
            };
            if nb != na {
                return false;
            }
            for (&b, &a) in b.iter().zip(&a).take(na) {
                self.pair(b, a);
            }
        }
        self.pos = e;
        true
    }

    /// A literal of precision `b` written as one of precision `a`: paired as `carry_unstamped`
    /// pairs a literal it finds changed.
    #[inline(always)]
    fn pair(&mut self, b: i32, a: i32) {
        if let Some(h) = house_slot(a) {
            let entry = b.min(a);
            if entry != a {
                let entry = entry.max(MIN_FIRST_PRECISION as i32) as i8;
                if self.lists[h].len() < self.count[h] {
                    self.lists[h].resize(self.count[h], HOUSE_DECIMALS[h] as i8);
                }
                self.lists[h].push(entry);
            }
            self.count[h] += 1;
        }
    }

    /// The record for the output of the edits seen, `None` if one was not clean.
    pub fn finish(mut self, original: &[u8]) -> Option<Widened> {
        if self.unknown {
            return None;
        }
        count_house(original, self.pos, original.len(), &mut self.count);
        Some(filled(self.lists, self.count))
    }
}

/// [`carry_precision`]; with `shortcut`, the output's literals in stretches it holds unchanged
/// are taken from the original's scan instead of scanned again (see [`Alike`]). Without it
/// both files are scanned throughout: what the tests compare the shortcut with.
fn carry(
    original: &[u8],
    mut output: Vec<u8>,
    dialect: &dyn crate::dialect::Dialect,
    shortcut: bool,
) -> CarriedPrecision {
    let old = find_in(original, dialect);
    if shortcut && old.is_none() && find_in(&output, dialect).is_none() {
        return carry_unstamped(original, output);
    }
    let old_widened = old
        .as_ref()
        .map(|(s, _)| s.widened.clone())
        .unwrap_or_default();
    let skip_in = old.as_ref().map(|(_, span)| *span);
    let skip_out = find_in(&output, dialect).map(|(_, span)| span);
    let mut before = number_tokens(skip_in);
    let mut after = number_tokens(skip_out);
    // Per house precision, by its place in HOUSE_DECIMALS (arrays, not maps: this runs once per
    // literal of the file): the earlier stamp's record, how many of the original's literals
    // resolve it so far (indexing that record), and the output's new record.
    let old_lists: [&[i8]; 3] =
        HOUSE_DECIMALS.map(|d| old_widened.0.get(&d).map_or(&[][..], Vec::as_slice));
    let mut seen = [0usize; 3];
    let mut lists: [Vec<i8>; 3] = Default::default();
    // The narrowing, in place: `output[..kept]` is final, `output[at..]` not yet looked at (the
    // scan reads only there); the bytes between are moved down once a literal is narrowed,
    // never before, so an output without one is not moved at all.
    let mut kept = 0;
    let mut at = 0;
    // Whether the two files are known to hold as many literals (checked before the first byte
    // moves, so that an output is never left half narrowed).
    let mut in_step = false;
    let mut alike = Alike::default();
    loop {
        let (b_from, a_from) = (before.i, after.i);
        let b = before.next(original);
        // The skipped spans (the stamp lines, at the head) are behind both scans.
        let past_skips =
            skip_in.is_none_or(|s| b_from > s.start) && skip_out.is_none_or(|s| a_from > s.start);
        let same = match shortcut && past_skips {
            true => alike.output_token(b, b_from, a_from, original, &output),
            false => None,
        };
        let a = match same {
            Some(a) => {
                after.i = a.map_or(output.len(), |a| a.end);
                a
            }
            None => after.next(&output),
        };
        let (b, a) = match (b, a) {
            (Some(b), Some(a)) => (b, a),
            (None, None) => break,
            _ => {
                return CarriedPrecision {
                    output,
                    widened: Widened::default(),
                };
            }
        };
        let d = match house_slot(b.precision()) {
            Some(h) => {
                let d = recorded(old_lists[h], seen[h], HOUSE_DECIMALS[h]);
                seen[h] += 1;
                d
            }
            None => b.precision(),
        };
        // A literal whose sign alone the transform flipped (`mirror`) was rewritten too: the
        // scan's literal starts after its sign.
        let unchanged = same.is_some()
            || (original[b.start..b.end] == output[a.start..a.end]
                && negated(original, b.start) == negated(&output, a.start));
        // The written text as a head of the new mantissa and the exponent: how many bytes
        // of the literal are dropped before its exponent (none: written as it is).
        let mut cut = 0;
        let mut precision = a.precision();
        let first_precision = if unchanged { d } else { d.min(precision) };
        // Only a literal the earlier stamp records as widened is narrowed again.
        let recorded = d < b.precision();
        if !unchanged && a.house() && recorded && first_precision < precision {
            let drop = (precision - first_precision) as usize;
            let mantissa = &output[a.start..a.mantissa_end()];
            let int_digits = mantissa.iter().take_while(|c| c.is_ascii_digit()).count();
            // Dropping all decimals drops the point too, unless nothing would be left of
            // the mantissa (`.500`).
            let decimals = a.decimals as usize;
            let zeros = drop <= decimals
                && mantissa[mantissa.len() - drop..].iter().all(|&c| c == b'0')
                && (drop < decimals || int_digits > 0);
            if zeros {
                cut = if drop == decimals { drop + 1 } else { drop };
                precision = first_precision;
            }
        }
        let narrowed = cut > 0;
        // Every output literal of a house precision has an entry: a narrowed one too (it may
        // have landed on another house precision, `0.123000` → `0.123`), so that the lists
        // stay in step with the file.
        if let Some(h) = house_slot(precision) {
            let entry = if narrowed { precision } else { first_precision };
            let entry = entry.max(MIN_FIRST_PRECISION as i32) as i8;
            lists[h].push(entry);
        }
        if narrowed {
            if !in_step {
                let (mut b2, mut a2) = (before.clone(), after.clone());
                loop {
                    match (b2.next(original), a2.next(&output)) {
                        (Some(_), Some(_)) => {}
                        (None, None) => break,
                        _ => {
                            return CarriedPrecision {
                                output,
                                widened: Widened::default(),
                            };
                        }
                    }
                }
                in_step = true;
            }
            // Up to the cut, then the exponent after it: both move down, never up.
            let head = a.mantissa_end() - cut;
            output.copy_within(at..head, kept);
            kept += head - at;
            output.copy_within(a.mantissa_end()..a.end, kept);
            kept += a.end - a.mantissa_end();
            at = a.end;
        }
    }
    if at > kept {
        let len = output.len();
        output.copy_within(at..len, kept);
        output.truncate(kept + len - at);
    }
    let mut widened = Widened::default();
    for (d, list) in HOUSE_DECIMALS.into_iter().zip(lists) {
        if !list.is_empty() {
            widened.0.insert(d, list);
        }
    }
    CarriedPrecision { output, widened }
}

/// Whether the literal at `start` is written with a minus sign right before it.
fn negated(src: &[u8], start: usize) -> bool {
    start.checked_sub(1).and_then(|i| src.get(i)) == Some(&b'-')
}

/// [`carry`] for an original without a stamp (the usual input of `correct`), whose output
/// has none yet either: nothing is recorded as widened, so nothing is narrowed and the output
/// is given back as it is; only the record is built.
///
/// Without an earlier record a literal's first precision is its own, so a pair's entry is the
/// lower of the two literals' precisions (an unchanged literal's is its own), and an entry of
/// the literal's own house precision D is the one a list holds anyway where it has none: only
/// the output's count of D-literals is kept for those, and a list is filled up to it where a
/// literal first written with fewer decimals comes. In the stretches the output holds
/// unchanged (see [`Alike`]) the original's literals are only counted, not paired: 51.6 M
/// instructions on the 2 MB bench module, where [`carry`]'s pairing of every literal was 73.5 M;
/// and counted by their marks ([`count_house`]) rather than scanned byte by byte: 27.5 M where
/// the scan was 48.4 M. What is left is the pairing of the literals the transform rewrote.
fn carry_unstamped(original: &[u8], output: Vec<u8>) -> CarriedPrecision {
    let unpaired = |output| CarriedPrecision {
        output,
        widened: Widened::default(),
    };
    let mut before = number_tokens(None);
    let mut after = number_tokens(None);
    // The output's literals of each house precision so far, and the lists up to the last entry
    // that is not the precision itself.
    let mut count = [0usize; 3];
    let mut lists: [Vec<i8>; 3] = Default::default();
    loop {
        let (b_from, a_from) = (before.i, after.i);
        // The stretch the two scans are alike in from here on (none at the start of just one
        // of the files).
        let lo = b_from.saturating_sub(1);
        let (end, to_the_end) = match (original.get(lo), output.get(a_from.saturating_sub(1))) {
            // Differing at once (after a literal the transform rewrote, its last digits):
            // what `Alike::at` finds, without comparing a stretch.
            (Some(x), Some(y)) if x != y => (lo, false),
            _ => Alike::at(b_from, a_from, original, &output)
                .map_or((lo, false), |a| (a.end, a.to_the_end)),
        };
        // The original's literals that end inside it (with the byte after them) are the
        // output's too: counted only, the bulk of them up to the stretch's last stop by marks
        // (see [`count_house`]), the last few by the scan.
        if to_the_end {
            count_house(original, b_from, original.len(), &mut count);
            return CarriedPrecision {
                output,
                widened: filled(lists, count),
            };
        }
        let mut from = b_from;
        // A stretch of a few bytes (within a target's fields, the start of a rewritten literal)
        // is scanned: searching it would cost its set-up for a block or less.
        let stop = (end > b_from + 16).then(|| last_stop(original, b_from, end));
        if let Some(stop) = stop.flatten() {
            count_house(original, b_from, stop, &mut count);
            (before.i, from) = (stop, stop);
        }
        let b = loop {
            let b = before.next(original);
            match b {
                Some(t) if t.end < end || (to_the_end && t.end == end) => {
                    if let Some(h) = house_slot(t.precision()) {
                        count[h] += 1;
                    }
                    from = t.end;
                }
                None if to_the_end => {
                    // The output ends alike: no literal left on either side.
                    return CarriedPrecision {
                        output,
                        widened: filled(lists, count),
                    };
                }
                _ => break b,
            }
        };
        // The first literal that is not known alike: scanned on both sides, from the places
        // after the last literal counted.
        after.i = from.wrapping_add_signed(a_from as isize - b_from as isize);
        let a = after.next(&output);
        let (b, a) = match (b, a) {
            (Some(b), Some(a)) => (b, a),
            (None, None) => {
                return CarriedPrecision {
                    output,
                    widened: filled(lists, count),
                };
            }
            _ => return unpaired(output),
        };
        if let Some(h) = house_slot(a.precision()) {
            let entry = b.precision().min(a.precision());
            if entry != a.precision() {
                let entry = entry.max(MIN_FIRST_PRECISION as i32) as i8;
                // Most entries follow one another (every literal rewritten): only a run of
                // unchanged ones since the last is filled in, and without a call otherwise.
                if lists[h].len() < count[h] {
                    lists[h].resize(count[h], HOUSE_DECIMALS[h] as i8);
                }
                lists[h].push(entry);
            }
            count[h] += 1;
        }
    }
}

/// Whether the scan of literals stops on byte `b` whatever came before it: every byte outside
/// words but a sign, which an exponent's digits may follow (`1.5E-3`: the scan reads past the
/// `-`). A scan from any place before such a byte comes to it, and what it finds after depends
/// only on the bytes from there on.
fn is_stop(b: u8) -> bool {
    !WORD[b as usize] && !matches!(b, b'+' | b'-')
}

/// The last [`is_stop`] byte of `src[from..to]`, if one is there.
fn last_stop(src: &[u8], from: usize, to: usize) -> Option<usize> {
    let at = src.get(from..to)?.iter().rposition(|&b| is_stop(b))?;
    Some(from + at)
}

/// Adds to `count` the house-precision literals the scan of `src` from its place `from` finds
/// before `to`, a stop of the scan ([`is_stop`]) or the end of `src`: no literal runs across
/// either, so the scan of `src[..to]` finds the same ones.
///
/// A literal resolves 3 decimals or more only with 3 digits after its point or with a negative
/// exponent (`5E-3`), so the bytes are not scanned one by one but searched for those marks
/// (`.` and `-`, 16 bytes at a time), and only a mark that has them (digits after
/// the point, a letter `E` before the sign) is scanned, from the last stop before it: what the
/// scan from `from` would find there. The literals between are none of a house precision. In
/// a transformed file's unchanged stretches (a target's configuration and external axes,
/// names, keywords) such marks are rare: about 20,000 of the 2 MB bench module's stretches'
/// 1.2 MB. `count_house_plain` in the tests is the scan it replaces.
fn count_house(src: &[u8], from: usize, to: usize, count: &mut [usize; 3]) {
    let Some(hay) = src.get(..to) else {
        return;
    };
    // The scan's place: the house literals before it are counted.
    let mut at = from;
    let rest = hay.get(from..).unwrap_or_default();
    let (blocks, tail) = rest.as_chunks::<16>();
    // The last few bytes are the end of a block that ends with them, its bytes before them
    // left out (a range of fewer than 16 bytes is read byte by byte).
    let last = match rest.last_chunk::<16>() {
        Some(block) if !tail.is_empty() => Some((to - 16, block, 16 - tail.len())),
        _ => None,
    };
    let whole = blocks
        .iter()
        .enumerate()
        .map(|(k, b)| (from + 16 * k, b, 0));
    for (block_at, block, skip) in whole.chain(last) {
        // One test of the block (compared as a vector), then one mask of its marks, built
        // eight bytes at a time.
        if !block
            .iter()
            .fold(false, |any, &b| any | (b.wrapping_sub(b'-') < 2))
        {
            continue;
        }
        // `-` and `.` are 0x2d and 0x2e.
        let marks = |half: &[u8]| {
            bytes_in(
                u64::from_le_bytes(half.try_into().unwrap_or_default()),
                b'-',
                b'.' + 1,
            )
        };
        let (lo, hi) = block.split_at(8);
        let mut marks = u128::from(marks(lo)) | u128::from(marks(hi)) << 64;
        while marks != 0 {
            let j = (marks.trailing_zeros() / 8) as usize;
            marks &= marks - 1;
            if j >= skip && !count_at(hay, block_at + j, &mut at, count) {
                return;
            }
        }
    }
    if rest.len() < 16 {
        for (j, &b) in rest.iter().enumerate() {
            if b.wrapping_sub(b'-') < 2 && !count_at(hay, from + j, &mut at, count) {
                return;
            }
        }
    }
}

/// [`count_house`] at the mark `m` of `hay`, the scan at `at`: if the mark is one a house
/// literal may have, the literals from the last stop before it (or `at`) up to the one past
/// it are scanned and counted, and `at` moves after them. `false` once the scan finds no
/// literal left in `hay`.
#[inline(always)]
fn count_at(hay: &[u8], m: usize, at: &mut usize, count: &mut [usize; 3]) -> bool {
    let digit = |i: usize| hay.get(i).is_some_and(u8::is_ascii_digit);
    let marked = m >= *at
        && match hay[m] {
            b'.' => digit(m + 1) && digit(m + 2) && digit(m + 3),
            _ => m > 0 && matches!(hay[m - 1], b'e' | b'E'),
        };
    if !marked {
        return true;
    }
    let stop = hay[*at..m].iter().rposition(|&b| is_stop(b));
    let mut scan = number_tokens(None);
    scan.i = stop.map_or(*at, |s| *at + s);
    while scan.i <= m {
        let Some(t) = scan.next(hay) else {
            return false;
        };
        if let Some(h) = house_slot(t.precision()) {
            count[h] += 1;
        }
    }
    *at = scan.i;
    true
}

/// The record of [`carry_unstamped`]'s lists, each filled up to its count of literals with
/// the house precision itself.
fn filled(lists: [Vec<i8>; 3], count: [usize; 3]) -> Widened {
    let mut widened = Widened::default();
    for (h, mut list) in lists.into_iter().enumerate() {
        list.resize(count[h], HOUSE_DECIMALS[h] as i8);
        if !list.is_empty() {
            widened.0.insert(HOUSE_DECIMALS[h], list);
        }
    }
    widened
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dialect::{krl::Krl as KRL, rapid::Rapid as RAPID};

    fn stamp() -> Stamp {
        Stamp {
            command: "correct".into(),
            robot: Some("r1".into()),
            profile: Some(("r1 track".into(), "0123456789ab".into())),
            widened: Widened::default(),
            gimbal: LockSplits::default(),
            kept: Kept::default(),
            version: "9.9.9".into(),
        }
    }

    #[test]
    fn goes_after_the_header_in_the_languages_comment_and_line_end() {
        let src = b"%%%\r\nMODULE m\r\n  CONST robtarget p:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\r\nENDMODULE\r\n";
        let out = write(src, &RAPID, &stamp()).unwrap();
        let text = String::from_utf8(out.clone()).unwrap();
        let line = "! trackfix: correct robot=r1 profile=\"r1 track\" sha256=0123456789ab version=9.9.9\r\n";
        assert!(
            text.starts_with(&format!("%%%\r\nMODULE m\r\n{line}  CONST")),
            "{text}"
        );
        assert_eq!(out.len(), src.len() + line.len());
        // Stamping again replaces the line; stripping gives the input back.
        let again = write(&out, &RAPID, &Stamp::new("zero", Some("r1"), None)).unwrap();
        assert_eq!(again.iter().filter(|&&b| b == b'\n').count(), 5);
        assert!(String::from_utf8_lossy(&again).contains("! trackfix: zero robot=r1 version="));
        assert_eq!(strip(&out, &RAPID).unwrap(), src);
        assert_eq!(strip(&again, &RAPID).unwrap(), src);
    }

    #[test]
    fn stamps_and_strips_in_place_as_the_copying_forms_do() {
        let src = b"&ACCESS RVP\r\nDEFDAT spot\r\nDECL E6POS XP1={X 1}\r\nENDDAT\r\n".to_vec();
        let mut buf = src.clone();
        assert!(write_in_place(&mut buf, &KRL, &stamp()));
        assert_eq!(Some(&buf), write(&src, &KRL, &stamp()).as_ref());
        // Replacing the stamp with a longer and a shorter one moves only what follows it.
        let mut long = stamp();
        long.robot = Some("a_much_longer_robot_name".into());
        assert!(write_in_place(&mut buf, &KRL, &long));
        assert_eq!(find_in(&buf, &KRL).unwrap().0, long);
        assert!(buf.ends_with(b"\r\nDECL E6POS XP1={X 1}\r\nENDDAT\r\n"));
        assert!(write_in_place(&mut buf, &KRL, &stamp()));
        assert_eq!(Some(&buf), write(&src, &KRL, &stamp()).as_ref());
        assert!(strip_in_place(&mut buf, &KRL));
        assert_eq!(buf, src);
        // Nothing to strip, nothing to stamp after: the bytes are left alone.
        assert!(!strip_in_place(&mut buf, &KRL));
        assert_eq!(buf, src);
        let mut headless = b"DECL INT i\n".to_vec();
        assert!(!write_in_place(&mut headless, &KRL, &stamp()));
        assert_eq!(headless, b"DECL INT i\n");
    }

    #[test]
    fn an_output_with_nothing_to_narrow_is_given_back_unmoved() {
        let src = b"MODULE m\n  x := [12.250, 13.250];\nENDMODULE\n";
        let out = b"MODULE m\n  x := [12.500, 13.000];\nENDMODULE\n".to_vec();
        let (at, capacity) = (out.as_ptr(), out.capacity());
        let c = carry_precision(src, out, &RAPID);
        // The same buffer, not a copy of it (no stamp: nothing was widened before).
        assert_eq!((c.output.as_ptr(), c.output.capacity()), (at, capacity));
        assert_eq!(c.output, b"MODULE m\n  x := [12.500, 13.000];\nENDMODULE\n");
        assert!(c.widened.is_empty(), "{:?}", c.widened);
    }

    #[test]
    fn krl_stamps_def_and_defdat_and_reads_back() {
        let dat = b"&ACCESS RVP\nDEFDAT  spot\nDECL E6POS XP1={X 1}\nENDDAT\n";
        let out = write(dat, &KRL, &stamp()).unwrap();
        let text = String::from_utf8(out.clone()).unwrap();
        assert_eq!(
            text.lines().nth(2).unwrap(),
            "; trackfix: correct robot=r1 profile=\"r1 track\" sha256=0123456789ab version=9.9.9"
        );
        let (read, _) = find_in(&out, &KRL).unwrap();
        assert_eq!(read, stamp());
        assert!(read.corrected_for("r1") && !read.corrected_for("r2"));
        let src = b"DEF spot( )\nEND";
        let out = write(src, &KRL, &stamp()).unwrap();
        assert!(out.starts_with(b"DEF spot( )\n; trackfix: correct"));
        // A header that ends the file gets the line end before the stamp, none after.
        let out = write(b"DEF spot( )", &KRL, &stamp()).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "DEF spot( )\n; trackfix: correct robot=r1 profile=\"r1 track\" sha256=0123456789ab version=9.9.9"
        );
        // A file without a header (nothing to follow) is not stamped.
        assert_eq!(write(b"DECL INT i\n", &KRL, &stamp()), None);
        // An ordinary comment after the header is not a stamp.
        assert_eq!(find_in(b"DEF a()\n; trackfix is great\nEND\n", &KRL), None);
    }
    /// `kept=` reads back what it wrote, names with the record's separators and non-ASCII
    /// included; a stamp without it (an earlier version's) reads as listing nothing; one that
    /// cannot be read is kept as written, never read as an empty list.
    #[test]
    fn kept_records_each_target_left_as_written_and_reads_back() {
        let target = |index, kind, name: Option<&str>| KeptTarget {
            index,
            kind,
            name: name.map(str::to_owned),
        };
        let kept = Kept::of(vec![
            target(7, RefusalKind::SkidNotConnected, None),
            target(0, RefusalKind::Reach, Some("p01")),
            target(2, RefusalKind::JointTarget, Some("pGrid{1,2}")),
            target(3, RefusalKind::Reach, Some("a;b c%\"Ä:")),
        ]);
        assert_eq!(
            kept.text(),
            "0:reach:p01;2:joint-target:pGrid{1,2};3:reach:a%3Bb%20c%25%22%C3%84:;7:skid-not-connected"
        );
        let mut s = stamp();
        s.kept = kept.clone();
        let out = write(b"MODULE m\nENDMODULE\n", &RAPID, &s).unwrap();
        let (read, _) = find_in(&out, &RAPID).unwrap();
        assert_eq!(read, s);
        assert_eq!(read.kept.targets[2].name.as_deref(), Some("a;b c%\"Ä:"));
        // Written by a version without the record: nothing listed.
        let old = b"MODULE m\n! trackfix: correct robot=r1 widened=3:0 version=0.1.0\nENDMODULE\n";
        let (read, _) = find_in(old, &RAPID).unwrap();
        assert!(read.kept.is_empty() && !read.widened.is_empty(), "{read:?}");
        // Unreadable: unknown kind, a note's kind, out of order, a bad escape, beyond the
        // file's size. Kept as written, and written back as it was.
        for bad in [
            "0:rich:p01",
            "0:kept-as-written:p01",
            "2:reach;1:reach",
            "0:reach:p%G1",
            "0:reach;1:reach;2:reach",
        ] {
            let k = Kept::parse(bad, 2);
            assert_eq!(
                (k.targets.len(), k.unreadable.as_deref()),
                (0, Some(bad)),
                "{bad}"
            );
            assert!(!k.is_empty());
            assert_eq!(k.text(), bad);
        }
    }

    /// A record is in step with its file when each target it lists is where it says, by name
    /// (any case) or as an inline one.
    #[test]
    fn a_kept_record_out_of_step_says_where() {
        let src = "MODULE m\n  CONST robtarget p01:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], v100, fine, tool0;\n    MoveL p01, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n";
        let f = crate::rapid::parse_file(std::path::Path::new("m.mod"), src.as_bytes().to_vec());
        assert_eq!(f.positions.len(), 2);
        let of = |text: &str| Kept::parse(text, 100).out_of_step(&f);
        assert_eq!(of("0:reach:P01;1:reach"), None);
        assert_eq!(
            of("0:reach:p02").as_deref(),
            Some("its kept= record says target index 0 is `p02`, and the file has `p01` there")
        );
        assert_eq!(
            of("1:reach:p01").as_deref(),
            Some(
                "its kept= record says target index 1 is `p01`, and the file has an inline target there"
            )
        );
        assert_eq!(
            of("2:reach").as_deref(),
            Some("its kept= record lists target index 2 of a file of 2 target(s)")
        );
        assert!(of("x").unwrap().contains("cannot be read"));
    }

    #[test]
    fn gimbal_records_the_a_of_each_target_at_the_lock_and_reads_back() {
        let src = "{X 1,Y 2,Z 3,A 30,B 45,C 10,S 2,T 35,E1 0}\n\
                   {X 1,Y 2,Z 3,A 15.0,B 90,C 10,S 2,T 35,E1 0}\n\
                   {X 1,Y 2,Z 3,A -12.5,B -90.0,C 10,S 2,T 35,E1 0}\n";
        let p = crate::transform::test_support::krl(src, "b");
        let splits = LockSplits::of(&p.files[0]);
        // The first target is off the lock; the others' A as written, by target index.
        assert_eq!(splits.text(), "1:15.0,2:-12.5");
        assert_eq!(
            (splits.a_of(0), splits.a_of(1), splits.a_of(2)),
            (None, Some(15.0), Some(-12.5))
        );
        let mut s = stamp();
        s.gimbal = splits.clone();
        let dat = b"DEFDAT spot\nENDDAT\n";
        let out = write(dat, &KRL, &s).unwrap();
        assert!(String::from_utf8_lossy(&out).contains(" gimbal=1:15.0,2:-12.5 version="));
        assert_eq!(find_in(&out, &KRL).unwrap().0, s);
        // Only A, B and C decoded, the record of decoding every target whole, and each
        // target's A, B and C as decoding it gives them: the samples, and targets on and off
        // the lock among axis targets, frames, odd literals and a missing orientation.
        let mixed = "DEFDAT b\n\
                     DECL E6POS XP1={X 1,Y 2,Z 3,A 15.0,B 90,C 10,S 2,T 35,E1 0}\n\
                     DECL E6POS XP2={X 1E4,Y -2,Z 3,A -7,B -90,C 1,S 2,T 35}\n\
                     DECL POS XP3={X 1,Y 2,Z 3,A 15.0,B 90.00,C 1.5E+1}\n\
                     DECL FRAME F4={X 0,Y 0,Z 0,A 9,B 90,C 1}\n\
                     DECL E6AXIS XA={A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}\n\
                     DECL E6POS XP5={X 1,Y 2,Z 3,A 30,B 45,C 10,S 2,T 35,E1 0}\n\
                     DECL E6POS XP6={X 1,Y 2,Z 3}\n\
                     ENDDAT\n";
        let mut files = vec![("mixed.dat".to_owned(), mixed.as_bytes().to_vec())];
        for file in ["spot_line", "pallet", "glue_tcp", "two_bases"] {
            let path = format!("{}/samples/krl/{file}.dat", env!("CARGO_MANIFEST_DIR"));
            files.push((path.clone(), std::fs::read(&path).unwrap()));
        }
        let mut at_lock = 0;
        for (path, bytes) in files {
            let f = crate::krl::parse_file(std::path::Path::new(&path), bytes);
            let splits = LockSplits::of(&f);
            assert_eq!(splits, LockSplits::of_decoded(&f), "{path}");
            at_lock += splits.0.len();
            for i in 0..f.positions.len() {
                let whole = f.position(i).and_then(|p| match p.cartesian?.orient? {
                    crate::position::Orientation::Abc(abc) => Some(abc),
                    _ => None,
                });
                assert_eq!(f.positions.abc_fields(i, &f.source), whole, "{path} {i}");
            }
        }
        assert!(at_lock >= 2, "{at_lock}");
        // Malformed, out of target order or beyond the file's size: nothing is kept.
        for bad in ["1:x", "2:1,1:1", "1:inf", "1", "1:1,2:2,3:3"] {
            assert_eq!(
                LockSplits::parse(bad, 2).unwrap_or_default(),
                LockSplits::default(),
                "{bad}"
            );
        }
    }
}

#[cfg(test)]
mod precision_tests {
    use super::*;
    use crate::dialect::rapid::Rapid as RAPID;
    use crate::syntax::NumLit;

    /// A module with one robtarget of the given literal texts (3 mm, 4 quaternion components).
    fn module(mm: &[String], q: &[String]) -> Vec<u8> {
        format!(
            "MODULE m\n  ! p10 is 1.5 mm off\n  CONST robtarget p10:=[[{}],[{}],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n",
            mm.join(","),
            q.join(",")
        )
        .into_bytes()
    }

    /// `text` (one literal) rewritten for `new` the way a transform writes it.
    fn rewrite(text: &str, new: f64, house: usize) -> String {
        NumLit::parse(text.as_bytes())
            .unwrap()
            .rewrite(new, house)
            .unwrap_or_else(|| text.to_owned())
    }

    /// A literal with `decimals` places for `units · 10^-decimals`.
    fn literal(units: i64, decimals: usize) -> String {
        crate::syntax::fixed(units as f64 / 10f64.powi(decimals as i32), decimals)
    }

    #[test]
    fn widened_round_trips_through_the_stamp_text() {
        let mut w = Widened::default();
        w.0.insert(3, vec![0, 0, 0, 3, 1, 3, 3]);
        w.0.insert(6, vec![6, 6]);
        assert_eq!(w.text(), "3:0*3,3,1");
        let back = Widened::parse(&w.text(), 100).unwrap();
        assert_eq!(back.of(3, 4), 1);
        assert_eq!(
            back.of(3, 6),
            3,
            "a left-off trailing entry reads as written so"
        );
        assert_eq!(Widened::parse("3:0*2;6:1", 100), {
            let mut x = Widened::default();
            x.0.insert(3, vec![0, 0]);
            x.0.insert(6, vec![1]);
            Some(x)
        });
        for bad in [
            "",
            "3:",
            "5:0",
            "3:4",
            "3:0*x",
            "3:0*999999999999",
            "3:0*60,1*41",
        ] {
            assert_eq!(Widened::parse(bad, 100), None, "{bad}");
        }
    }

    #[test]
    fn a_stamp_out_of_step_only_drops_zeros() {
        // The stamp says the first 3-decimal literal was written with 0 decimals, but the file
        // was edited since: `12.500` stays, `13.000` loses only its zeros.
        let src = b"MODULE m\n! trackfix: correct widened=3:0*2 version=0\n  x := [12.250, 13.250];\nENDMODULE\n";
        let out = b"MODULE m\n! trackfix: correct widened=3:0*2 version=0\n  x := [12.500, 13.000];\nENDMODULE\n";
        let c = carry_precision(src, out.to_vec(), &RAPID);
        assert_eq!(
            String::from_utf8(c.output).unwrap(),
            "MODULE m\n! trackfix: correct widened=3:0*2 version=0\n  x := [12.500, 13];\nENDMODULE\n"
        );
        assert_eq!(c.widened.text(), "3:0");
        // Numbers in names are none; an exponent literal resolves its decimals minus the
        // exponent (`1.5E+2` -1, `1.50123E+2` 3, `2.5e-1` 2).
        let text = b"p10 1.5E+2 $x1 .5 7.250 1.50123E+2 2.5e-1";
        let mut scan = number_tokens(None);
        let t: Vec<_> = std::iter::from_fn(|| scan.next(text))
            .map(|t| (t.decimals, t.precision(), t.house()))
            .collect();
        assert_eq!(
            t,
            [
                (1, -1, false),
                (1, 1, false),
                (3, 3, true),
                (5, 3, true),
                (1, 2, false)
            ]
        );
    }

    #[test]
    fn exponent_and_leading_point_literals_narrow_back() {
        // `correct` keeps each literal's style (NumLit::rewrite) and records its first
        // precision: `1.5E+2` resolves -1, `.5` 1, `2.5e1` 0.
        let src = b"MODULE m\n  x := [1.5E+2, .5, 2.5e1, 7.125];\nENDMODULE\n";
        let corrected = b"MODULE m\n  x := [1.50123E+2, .512, 2.5123e1, 7.250];\nENDMODULE\n";
        let c = carry_precision(src, corrected.to_vec(), &RAPID);
        assert_eq!(c.output, corrected);
        assert_eq!(c.widened.text(), "3:-1,1,0");
        let mut stamp = Stamp::new("correct", Some("r1"), None);
        stamp.widened = c.widened;
        let stamped = write(&c.output, &RAPID, &stamp).unwrap();
        assert!(String::from_utf8_lossy(&stamped).contains(" widened=3:-1,1,0 "));
        // `zero` wrote the values back at the widened precision: only zeros are dropped, of the
        // mantissa before an exponent, and `.500` keeps its point.
        let zeroed = b"MODULE m\n  x := [1.50000E+2, .500, 2.5000e1, 7.125];\nENDMODULE\n";
        let zeroed = write(zeroed, &RAPID, &stamp).unwrap();
        let back = carry_precision(&stamped, zeroed.clone(), &RAPID);
        assert!(back.widened.is_empty(), "{:?}", back.widened);
        assert_eq!(
            String::from_utf8(strip(&back.output, &RAPID).unwrap()).unwrap(),
            String::from_utf8(src.to_vec()).unwrap()
        );
        // A widened exponent literal zero does not land on keeps its record.
        let off = write(
            b"MODULE m\n  x := [1.50001E+2, .500, 2.5000e1, 7.125];\nENDMODULE\n",
            &RAPID,
            &stamp,
        )
        .unwrap();
        assert_eq!(
            carry_precision(&stamped, off, &RAPID).widened.text(),
            "3:-1"
        );
    }

    #[test]
    fn a_narrowed_literal_keeps_the_lists_in_step() {
        // `0.123000` (a 3-decimal quaternion component widened to 6) narrows to `0.123`, a
        // 3-decimal literal: it has its own entry in the 3-list, so the `12.500` after it keeps
        // its record (0) in the next run.
        let src = b"MODULE m\n! trackfix: correct widened=6:3;3:3,0 version=0\n  x := [0.123457, 0.000, 12.500];\nENDMODULE\n";
        let out = b"MODULE m\n! trackfix: correct widened=6:3;3:3,0 version=0\n  x := [0.123000, 0.000, 12.750];\nENDMODULE\n";
        let c = carry_precision(src, out.to_vec(), &RAPID);
        assert!(String::from_utf8_lossy(&c.output).contains("[0.123, 0.000, 12.750]"));
        assert_eq!(c.widened.0.get(&3), Some(&vec![3, 3, 0]));
    }

    #[test]
    fn literal_counts_that_differ_carry_nothing() {
        // Without the extra literal `13.000` would become `13` (as above); with one more literal
        // on either side the files cannot be paired, and the output is kept as it is.
        let src = b"MODULE m\n! trackfix: correct widened=3:0*2 version=0\n  x := [12.250, 13.250];\nENDMODULE\n";
        let out: &[u8] = b"MODULE m\n! trackfix: correct widened=3:0*2 version=0\n  x := [12.500, 13.000, 1];\nENDMODULE\n";
        let c = carry_precision(src, out.to_vec(), &RAPID);
        assert_eq!(c.output, out);
        assert!(c.widened.is_empty());
        let fewer: &[u8] =
            b"MODULE m\n! trackfix: correct widened=3:0*2 version=0\n  x := [13.000];\nENDMODULE\n";
        let c = carry_precision(src, fewer.to_vec(), &RAPID);
        assert_eq!(c.output, fewer);
        assert!(c.widened.is_empty());
        // The last literal of the longer side is what tells: 2 against 3 and 3 against 2.
        let c = carry_precision(out, src.to_vec(), &RAPID);
        assert_eq!(c.output, src);
    }

    #[test]
    fn a_literal_ended_differently_in_the_output_is_scanned_there() {
        // `1]` became `1x`: the byte that ends the literal changed, and the output has one
        // literal less, so nothing may be carried (`12.000` stays). Were the output's literals
        // taken from the original's up to the changed byte, `12.000` would lose its zeros.
        let src = b"MODULE m\n! trackfix: correct widened=3:0 version=0\n  x := [12.250, 1];\nENDMODULE\n";
        let out = b"MODULE m\n! trackfix: correct widened=3:0 version=0\n  x := [12.000, 1x;\nENDMODULE\n";
        let c = carry_precision(src, out.to_vec(), &RAPID);
        assert_eq!(c.output, out);
        // And the byte before it: `[5` became `p5`, a name.
        let src = b"MODULE m\n! trackfix: correct widened=3:0 version=0\n  x := [12.250, [5];\nENDMODULE\n";
        let out = b"MODULE m\n! trackfix: correct widened=3:0 version=0\n  x := [12.000, p5];\nENDMODULE\n";
        assert_eq!(carry_precision(src, out.to_vec(), &RAPID).output, out);
        // The same edits with the literal count kept: `12.000` narrows.
        let out = b"MODULE m\n! trackfix: correct widened=3:0 version=0\n  x := [12.000, [6];\nENDMODULE\n";
        let c = carry_precision(src, out.to_vec(), &RAPID);
        assert!(String::from_utf8_lossy(&c.output).contains("[12, [6]"));
    }

    /// Pieces of a program text for the shortcut's proptest: literals of every precision and
    /// style, names with digits, separators, and the bytes that end or extend a literal.
    const PIECES: [&str; 30] = [
        "12",
        "1.250",
        "0.5",
        "-700.00",
        "1.5E+2",
        ".5",
        "9E9",
        "12.000",
        "0.123000",
        "7.",
        "p10",
        "$x1",
        "e",
        "E+",
        ", ",
        "[",
        "]",
        "\n",
        " ",
        "\r\n",
        ".",
        "x",
        "5E-3",
        "1.25e-1",
        "1.23456E+2",
        "-",
        "E-",
        "1.2.345",
        "0.7071",
        "9E+09",
    ];

    /// What [`count_house`] counts, by the scan itself: the house literals from `from` that
    /// end by `to`, scanned in the whole of `src`.
    fn count_house_plain(src: &[u8], from: usize, to: usize) -> [usize; 3] {
        let mut scan = number_tokens(None);
        scan.i = from;
        let mut count = [0; 3];
        while let Some(t) = scan.next(src).filter(|t| t.end <= to) {
            if let Some(h) = house_slot(t.precision()) {
                count[h] += 1;
            }
        }
        count
    }

    /// A module of robtargets, `Offs` calls and a tooldata with the given literals, in turn.
    fn program(literals: &[String]) -> String {
        let mut out = String::from("MODULE m\r\n");
        let mut next = literals.iter().map(String::as_str).cycle();
        let mut lit = || next.next().unwrap_or("0");
        for i in 0..literals.len().div_ceil(12) {
            out.push_str(&format!(
                "  CONST robtarget p{i}:=[[{},{},{}],[{},{},{},{}],[0,0,-1,0],[{},9E+09,9E+09,9E+09,9E+09,9E+09]];\r\n",
                lit(), lit(), lit(), lit(), lit(), lit(), lit(), lit()
            ));
            out.push_str(&format!(
                "  MoveL Offs(p{i},{},0,{}),v100,z1,tGun;\r\n",
                lit(),
                lit()
            ));
            out.push_str(&format!(
                "  ! tool {i}\r\n  PERS tooldata t{i}:=[TRUE,[[{},-3.2,{}],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\r\n",
                lit(), lit()
            ));
        }
        out.push_str("ENDMODULE\r\n");
        out
    }

    /// The program text of `pieces` after `head`.
    fn text(head: &str, pieces: &[usize]) -> Vec<u8> {
        let mut t = head.to_owned();
        for &i in pieces {
            t.push_str(PIECES[i]);
        }
        t.push_str("\nENDMODULE\n");
        t.into_bytes()
    }

    /// `pieces` with `edits` applied: `(at, piece, insert)` replaces or inserts a piece, or
    /// removes one (no piece).
    fn edited(pieces: &[usize], edits: &[(usize, Option<usize>, bool)]) -> Vec<usize> {
        let mut changed = pieces.to_vec();
        for &(at, with, insert) in edits {
            let at = at.min(changed.len());
            match with {
                Some(w) if insert || at == changed.len() => changed.insert(at, w),
                Some(w) => changed[at] = w,
                None if at < changed.len() => {
                    changed.remove(at);
                }
                None => {}
            }
        }
        changed
    }

    proptest::proptest! {
        /// Taking the output's literals from the original's scan where the output holds the
        /// same bytes changes nothing: the result is the one of scanning both files throughout,
        /// whatever was edited (literals rewritten longer or shorter, bytes that end a literal
        /// or join it to a name, inserted and deleted pieces). Without a stamp that is
        /// [`carry_unstamped`]'s result.
        #[test]
        fn the_shortcut_changes_no_result(
            pieces in proptest::collection::vec(0..PIECES.len(), 0..60),
            edits in proptest::collection::vec((0usize..60, proptest::option::of(0..PIECES.len()), proptest::bool::ANY), 0..8),
            widened in proptest::sample::select(vec!["", "3:0*3,1,0", "3:2,0;6:3*2", "4:0;3:1*4"]),
        ) {
            let head = if widened.is_empty() {
                "MODULE m\n".to_owned()
            } else {
                format!("MODULE m\n! trackfix: correct widened={widened} version=0\n")
            };
            let original = text(&head, &pieces);
            let output = text(&head, &edited(&pieces, &edits));
            let fast = carry(&original, output.clone(), &RAPID, true);
            let full = carry(&original, output, &RAPID, false);
            proptest::prop_assert_eq!(fast, full);
        }

        /// Counting instead of pairing the literals of an unstamped file where the output holds
        /// them unchanged gives the record of pairing them all, and the output untouched.
        #[test]
        fn the_unstamped_record_is_the_plain_one(
            pieces in proptest::collection::vec(0..PIECES.len(), 0..80),
            edits in proptest::collection::vec((0usize..80, proptest::option::of(0..PIECES.len()), proptest::bool::ANY), 0..12),
        ) {
            let original = text("MODULE m\n", &pieces);
            let output = text("MODULE m\n", &edited(&pieces, &edits));
            let fast = carry_unstamped(&original, output.clone());
            proptest::prop_assert_eq!(&fast.output, &output);
            proptest::prop_assert_eq!(fast, carry(&original, output, &RAPID, false));
        }
    }

    /// `text("MODULE m\n", pieces)` with `edits` made as one list of edits on its spans (at most
    /// one a piece: `(at, piece, insert)` replaces the piece at `at`, inserts one before it,
    /// or removes it), applied while an [`EditCarry`] sees them: the output and its record.
    fn carried_by_edits(
        pieces: &[usize],
        edits: &[(usize, Option<usize>, bool)],
        reversed: bool,
    ) -> (Vec<u8>, Vec<u8>, Option<Widened>) {
        use crate::syntax::Edit;
        let head = "MODULE m\n";
        let original = text(head, pieces);
        let mut starts = vec![head.len()];
        for &i in pieces {
            starts.push(starts.last().unwrap() + PIECES[i].len());
        }
        let mut by_place = std::collections::BTreeMap::new();
        for &(at, with, insert) in edits {
            let at = at.min(pieces.len());
            let (start, end) = (
                starts[at],
                starts.get(at + 1).copied().unwrap_or(starts[at]),
            );
            let edit = match with {
                Some(w) if insert || at == pieces.len() => {
                    Edit::new(Span::new(start, start), PIECES[w])
                }
                Some(w) => Edit::new(Span::new(start, end), PIECES[w]),
                None => Edit::new(Span::new(start, end), ""),
            };
            by_place.insert(at, edit);
        }
        let mut list: Vec<Edit> = by_place.into_values().collect();
        // Out of order, the list is merged: the edits reach the carry in order all the same.
        if reversed {
            list.reverse();
        }
        let list: crate::syntax::EditList = list.into_iter().collect();
        let mut carry = EditCarry::new();
        let output = list
            .apply_seen(&original, |span, t, w| carry.edit(&original, span, t, w))
            .unwrap();
        let widened = carry.finish(&original);
        (original, output, widened)
    }

    proptest::proptest! {
        /// A plain literal's precision, read in one pass, is that of the one literal the scan
        /// finds in its bytes.
        #[test]
        fn a_plain_literal_is_what_the_scan_finds(text in "[-+]?[0-9.eE+-]{0,18}") {
            let bytes = text.as_bytes();
            let mut window = [b'x'; 16];
            let n = bytes.len().min(16);
            window[..n].copy_from_slice(&bytes[..n]);
            if let Some(p) = plain_precision_in(&window, n).filter(|_| bytes.len() <= 16) {
                proptest::prop_assert_eq!(Some(p), plain_precision(bytes));
            }
            if let Some(p) = plain_precision(bytes) {
                let mut scan = number_tokens(None);
                let t = scan.next(bytes);
                proptest::prop_assert_eq!(t.map(|t| t.precision()), Some(p));
                proptest::prop_assert!(scan.next(bytes).is_none());
            }
        }

        /// The record worked out from the edits, where they let it be known, is the one of
        /// scanning both files, whatever the edits (literals for literals, for words,
        /// separators, signs, pieces inserted and removed, next to one another).
        #[test]
        fn the_record_from_the_edits_is_the_scanned_one(
            pieces in proptest::collection::vec(0..PIECES.len(), 0..80),
            edits in proptest::collection::vec((0usize..80, proptest::option::of(0..PIECES.len()), proptest::bool::ANY), 0..12),
            reversed in proptest::bool::ANY,
        ) {
            let (original, output, known) = carried_by_edits(&pieces, &edits, reversed);
            if let Some(widened) = known {
                proptest::prop_assert_eq!(widened, carry_unstamped(&original, output.clone()).widened);
            }
        }

        /// Literals between separators rewritten as literals (what the transforms write) always
        /// give the record, and it is the scanned one.
        #[test]
        fn literals_rewritten_give_the_record(
            literals in proptest::collection::vec(proptest::sample::select(vec![0usize, 1, 2, 3, 4, 5, 6, 7, 8, 9, 22, 23, 24, 28, 29]), 1..40),
            seps in proptest::collection::vec(proptest::sample::select(vec![14usize, 15, 16, 17, 18, 19]), 40),
            edits in proptest::collection::vec((0usize..40, proptest::sample::select(vec![0usize, 1, 2, 3, 4, 5, 6, 7, 8, 9, 22, 23, 24, 28, 29])), 0..12),
        ) {
            let mut pieces = Vec::new();
            for (&l, &s) in literals.iter().zip(&seps) {
                pieces.push(s);
                pieces.push(l);
            }
            pieces.push(14);
            let edits: Vec<_> = edits
                .iter()
                .map(|&(at, w)| (2 * (at % literals.len()) + 1, Some(w), false))
                .collect();
            let (original, output, known) = carried_by_edits(&pieces, &edits, false);
            proptest::prop_assert_eq!(known, Some(carry_unstamped(&original, output).widened));
        }
    }

    /// The scan of [`number_tokens`] byte by byte, without its words of digits and its
    /// short-literal path: what they are held to. Each literal as (start, end, decimals,
    /// precision, exponent bytes).
    fn plain_tokens(src: &[u8]) -> Vec<(usize, usize, u32, i32, u32)> {
        let word = |b: u8| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'$' | b'.' | b'#');
        let digit = |i: usize| src.get(i).is_some_and(u8::is_ascii_digit);
        let mut out = Vec::new();
        let mut i = 0;
        while i < src.len() {
            if !word(src[i]) {
                i += 1;
                continue;
            }
            let starts = digit(i) || (src[i] == b'.' && digit(i + 1));
            if !starts || (i > 0 && word(src[i - 1])) {
                while i < src.len() && word(src[i]) {
                    i += 1;
                }
                continue;
            }
            let start = i;
            while digit(i) {
                i += 1;
            }
            let mut decimals = 0;
            if src.get(i) == Some(&b'.') {
                i += 1;
                while digit(i) {
                    (i, decimals) = (i + 1, decimals + 1);
                }
            }
            let (mut exponent, mut exponent_len) = (0i32, 0u32);
            if matches!(src.get(i), Some(b'e' | b'E')) {
                let mut j = i + 1;
                let negative = src.get(j) == Some(&b'-');
                if matches!(src.get(j), Some(b'+' | b'-')) {
                    j += 1;
                }
                if digit(j) {
                    let mut e = 0i32;
                    while digit(j) {
                        e = e
                            .saturating_mul(10)
                            .saturating_add(i32::from(src[j] - b'0'));
                        j += 1;
                    }
                    exponent = if negative { -e } else { e };
                    exponent_len = (j - i) as u32;
                    i = j;
                }
            }
            if src.get(i).is_some_and(|&b| word(b)) {
                while i < src.len() && word(src[i]) {
                    i += 1;
                }
                continue;
            }
            let precision = (decimals as i32).saturating_sub(exponent);
            out.push((start, i, decimals, precision, exponent_len));
        }
        out
    }

    proptest::proptest! {
        /// The scan reads the literals the byte-wise scan does, digit runs of any length
        /// against the ends of the words it reads and of the file among them, exponents, words
        /// that join digits to names and Latin-1 bytes whose low seven bits are digits or marks.
        #[test]
        fn the_scan_is_the_byte_wise_one(
            bytes in proptest::collection::vec(
                proptest::sample::select(b"0123456789000111..eE+-,;[ x_#\xb0\xb9\xae\xad".to_vec()),
                0..120,
            ),
        ) {
            let mut scan = number_tokens(None);
            let mut found = Vec::new();
            while let Some(t) = scan.next(&bytes) {
                found.push((t.start, t.end, t.decimals, t.precision(), t.exponent_len));
            }
            proptest::prop_assert_eq!(found, plain_tokens(&bytes));
        }
    }

    #[test]
    fn digit_runs_read_eight_bytes_at_once_end_where_the_bytes_do() {
        // Latin-1 bytes whose low seven bits are digits (`°` is 0xb0) or marks end a run and
        // mark nothing.
        let text = b"1234567890123456789.5\xb0\xb9 7\xae\xad 12345678-.";
        for i in 0..text.len() {
            let plain = i + text[i..].iter().take_while(|b| b.is_ascii_digit()).count();
            assert_eq!(after_digits(text, i), plain, "at {i}");
        }
        let marks: Vec<usize> = (0..text.len())
            .filter(|&i| matches!(text[i], b'-' | b'.'))
            .collect();
        let mut found = Vec::new();
        for (k, block) in text.chunks(8).enumerate() {
            let mut word = [0; 8];
            word[..block.len()].copy_from_slice(block);
            let mut m = bytes_in(u64::from_le_bytes(word), b'-', b'.' + 1);
            while m != 0 {
                found.push(8 * k + (m.trailing_zeros() / 8) as usize);
                m &= m - 1;
            }
        }
        assert_eq!(found, marks);
    }

    proptest::proptest! {
        /// Searching for the marks a house literal has counts what the scan counts, from any
        /// place of the scan to any stop after it (or the end).
        #[test]
        fn counting_by_marks_is_the_scan(
            pieces in proptest::collection::vec(0..PIECES.len(), 0..80),
            skip in 0usize..20,
            to in 0usize..1000,
        ) {
            let src = text("", &pieces);
            let mut scan = number_tokens(None);
            for _ in 0..skip {
                scan.next(&src);
            }
            let from = scan.i.min(src.len());
            let stops: Vec<usize> = (from..src.len()).filter(|&i| is_stop(src[i])).chain([src.len()]).collect();
            let to = stops[to % stops.len()];
            let mut count = [0; 3];
            count_house(&src, from, to, &mut count);
            proptest::prop_assert_eq!(count, count_house_plain(&src, from, to));
        }

        /// A program corrected as `correct` does (some literals rewritten at the house
        /// precision of their field, longer or shorter, exponent literals among them, the edits
        /// ending where the literals end), with and without an earlier stamp: the shortcuts give
        /// the plain scan's result.
        #[test]
        fn a_corrected_program_carries_as_the_plain_scan(
            literals in proptest::collection::vec((-2_000_000i64..2_000_000, 0usize..=6, 0u8..8), 1..60),
            moved in proptest::collection::vec(proptest::option::of(-3.0f64..3.0), 1..60),
            widened in proptest::sample::select(vec!["", "3:0*3,1,0", "3:2,0;6:3*2"]),
        ) {
            let written: Vec<String> = literals
                .iter()
                .map(|&(u, d, style)| match style {
                    0 => format!("{}E-3", u / 1000),
                    1 => format!("{}E+2", literal(u, d)),
                    _ => literal(u, d),
                })
                .collect();
            let corrected: Vec<String> = written
                .iter()
                .zip(moved.iter().cycle())
                .enumerate()
                .map(|(i, (t, m))| match m {
                    Some(m) => {
                        let v = NumLit::parse(t.as_bytes()).unwrap().value();
                        rewrite(t, v + m, if i % 12 < 3 { 3 } else { 6 })
                    }
                    None => t.clone(),
                })
                .collect();
            let head = match widened {
                "" => String::new(),
                w => format!("! trackfix: correct widened={w} version=0\r\n"),
            };
            let with_head = |p: String| p.replacen("MODULE m\r\n", &format!("MODULE m\r\n{head}"), 1).into_bytes();
            let original = with_head(program(&written));
            let output = with_head(program(&corrected));
            let fast = carry(&original, output.clone(), &RAPID, true);
            let plain = carry(&original, output, &RAPID, false);
            proptest::prop_assert_eq!(fast, plain);
        }
    }

    proptest::proptest! {
        /// zero(correct(x)) == x byte for byte, with the stamp: a synthetic correction moves each
        /// value by `delta` and writes it as a transform does (at least the house decimals); the
        /// inverse writes the exact original value back. Original literals of 0–6 decimals.
        #[test]
        fn correct_then_zero_gives_back_the_bytes(
            mm in proptest::collection::vec((-2_000_000i64..2_000_000, 0usize..=6), 3),
            q in proptest::collection::vec((-1_000_000i64..1_000_000, 0usize..=6), 4),
            delta in -3.0f64..3.0,
        ) {
            let mm_text: Vec<String> = mm.iter().map(|&(u, d)| literal(u, d)).collect();
            let q_text: Vec<String> = q.iter().map(|&(u, d)| literal(u, d)).collect();
            let original = module(&mm_text, &q_text);
            let value = |t: &String| NumLit::parse(t.as_bytes()).unwrap().value();
            let c_mm: Vec<String> = mm_text.iter().map(|t| rewrite(t, value(t) + delta, 3)).collect();
            let c_q: Vec<String> = q_text.iter().map(|t| rewrite(t, value(t) + delta * 1e-3, 6)).collect();
            let corrected = carry_precision(&original, module(&c_mm, &c_q), &RAPID);
            let mut stamp = Stamp::new("correct", Some("r1"), None);
            stamp.widened = corrected.widened;
            let stamped = write(&corrected.output, &RAPID, &stamp).unwrap();
            // The inverse: each corrected literal rewritten for its original value.
            let z_mm: Vec<String> = c_mm.iter().zip(&mm_text).map(|(c, o)| rewrite(c, value(o), 3)).collect();
            let z_q: Vec<String> = c_q.iter().zip(&q_text).map(|(c, o)| rewrite(c, value(o), 6)).collect();
            let zeroed = write(&module(&z_mm, &z_q), &RAPID, &stamp).unwrap();
            let back = carry_precision(&stamped, zeroed.clone(), &RAPID);
            proptest::prop_assert!(back.widened.is_empty(), "{:?}", back.widened);
            proptest::prop_assert_eq!(
                String::from_utf8(strip(&back.output, &RAPID).unwrap()).unwrap(),
                String::from_utf8(original).unwrap()
            );
        }
    }
}
