//! Span-splice rewriting: replace only the bytes a transform changes.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::Span;
use super::packed::{Chunks, Place, VARINT_MAX, put_varint, read_varint, unzigzag, zigzag};

/// Replace the bytes of `span` in the original source with `text`.
///
/// 24 bytes: the span is kept as two `u32` offsets (trackfix reads no file of 4 GiB or more,
/// `output::MAX_INPUT_BYTES`; its parsers keep `u32` offsets too). A transform makes a few per
/// target and a file's [`EditList`] keeps them packed. A span that does not fit is kept as a
/// reversed one, which [`apply_edits`] refuses as [`EditError::OutOfBounds`]: never an edit at
/// another place.
#[derive(Clone, PartialEq, Eq)]
pub struct Edit {
    start: u32,
    end: u32,
    /// What the bytes of [`span`](Edit::span) become.
    pub text: EditText,
}

impl Edit {
    /// Replaces `span` with `text`.
    pub fn new(span: Span, text: impl Into<Vec<u8>>) -> Edit {
        Edit::with_text(span, EditText::from(text.into()))
    }

    /// Replaces `span` with `text`, already an [`EditText`].
    pub fn with_text(span: Span, text: EditText) -> Edit {
        let (start, end) = match (u32::try_from(span.start), u32::try_from(span.end)) {
            (Ok(start), Ok(end)) => (start, end),
            _ => (u32::MAX, 0),
        };
        Edit { start, end, text }
    }

    /// The bytes of the original source to replace (empty: insert at `span().start`).
    pub fn span(&self) -> Span {
        Span::new(self.start as usize, self.end as usize)
    }
}

/// With its span as a [`Span`]: `Edit { span: Span { start: 1, end: 4 }, text: [..] }`.
impl std::fmt::Debug for Edit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Edit")
            .field("span", &self.span())
            .field("text", &self.text)
            .finish()
    }
}

/// The bytes an [`Edit`] writes: up to 14 kept inline, longer ones on the heap.
///
/// Almost every edit is one number (`-1517.563`, `0.7071068`), written once per changed field:
/// 14 bytes hold every number trackfix writes at the precisions it reads, so writing one costs
/// no allocation; a longer text sits behind a thin pointer, so an `EditText` is 16 bytes and
/// an [`Edit`] 24. Reads as a byte slice (`Deref<Target = [u8]>`).
#[derive(Clone, PartialEq, Eq)]
pub struct EditText(TextRepr);

/// The longest text an [`EditText`] keeps inline.
pub(crate) const INLINE: usize = 14;

#[derive(Clone, PartialEq, Eq)]
enum TextRepr {
    Inline { len: u8, bytes: [u8; INLINE] },
    // Boxed twice: a thin pointer keeps the enum at 16 bytes.
    Heap(Box<Box<[u8]>>),
}

impl EditText {
    /// A copy of `text`: inline up to 14 bytes, so a written number costs no allocation.
    pub fn from_bytes(text: &[u8]) -> EditText {
        Self::inline(text).unwrap_or_else(|| EditText(TextRepr::Heap(Box::new(text.into()))))
    }

    /// `bytes[..len]` as an inline text, the array taken as it is: a number writer builds
    /// its text in place, and the copy [`from_bytes`](Self::from_bytes) makes (a call, its
    /// length not known until then) was a good part of writing one. The bytes past `len`
    /// must be zero, as [`from_bytes`](Self::from_bytes) leaves them, so that equal texts
    /// compare equal. `None` past 14 bytes.
    #[inline]
    pub(crate) fn inline_array(bytes: [u8; INLINE], len: usize) -> Option<EditText> {
        debug_assert!(bytes.iter().skip(len).all(|&b| b == 0));
        Some(EditText(TextRepr::Inline {
            len: u8::try_from(len).ok().filter(|&n| n as usize <= INLINE)?,
            bytes,
        }))
    }

    fn inline(text: &[u8]) -> Option<EditText> {
        let n = text.len();
        // The length check keeps the conversion in range: `len as u8` ≤ 14.
        if n > INLINE {
            return None;
        }
        let mut bytes = [0; INLINE];
        bytes.get_mut(..n)?.copy_from_slice(text);
        Some(EditText(TextRepr::Inline {
            len: n as u8,
            bytes,
        }))
    }
}

impl From<Vec<u8>> for EditText {
    fn from(text: Vec<u8>) -> EditText {
        Self::inline(&text)
            .unwrap_or_else(|| EditText(TextRepr::Heap(Box::new(text.into_boxed_slice()))))
    }
}

impl std::ops::Deref for EditText {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        match &self.0 {
            TextRepr::Inline { len, bytes } => bytes.get(..*len as usize).unwrap_or(&[]),
            TextRepr::Heap(b) => b,
        }
    }
}

/// As a byte vector prints: `[49, 46, 53]`.
impl std::fmt::Debug for EditText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// Why a set of edits cannot be applied. Either is a bug of the transform that made the edits,
/// not of the input.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EditError {
    /// Two edits touch the same bytes.
    #[error("edits overlap at bytes {first:?} and {second:?}")]
    Overlap {
        /// The span of the earlier edit.
        first: Span,
        /// The span of the edit that overlaps it.
        second: Span,
    },
    /// An edit's span is reversed or ends past the source.
    #[error("edit at bytes {0:?} lies outside the source")]
    OutOfBounds(Span),
}

/// Applies non-overlapping edits to `src`; everything outside their spans is copied unchanged.
///
/// Edits may come in any order. Two edits of the same span with the same text count as one (a
/// target referenced twice is rewritten once); any other overlap is an error rather than a guess.
/// The same as collecting them into an [`EditList`] and [`applying`](EditList::apply) it.
pub fn apply_edits(src: &[u8], edits: &[Edit]) -> Result<Vec<u8>, EditError> {
    let mut list = EditList::default();
    for e in edits {
        list.push(e);
    }
    list.apply(src)
}

/// The edits of one file, packed: what a transform holds from its first target until the
/// output is built.
///
/// A `correct` of a 20 MB module makes 700,000 edits; as [`Edit`]s in a vector grown by
/// doubling they took 22 MB, and sorting them for [`apply_edits`] 5.6 MB of references more,
/// next to the source and the output being built. Here an edit is its offset from the edit
/// before it, its length and its text, in bytes (about 12 for a written number; see
/// `syntax::packed`), and the edits are not sorted: they are kept as the runs in which they came
/// in order (a transform's edits come in file order, target by target, so a file has a few runs:
/// its targets, its offset calls, its declarations), and [`apply`](EditList::apply) merges
/// the runs.
#[derive(Clone, Default)]
pub struct EditList {
    log: Chunks,
    runs: Vec<Run>,
    len: usize,
    /// How much the edits lengthen the source (shorten it, below zero), duplicates included.
    growth: isize,
    /// The span of the last edit added: the next one continues its run unless it sorts before.
    last: (u32, u32),
}

/// Edits that came in order: where the first one starts in the log, and how many there are.
#[derive(Clone, Copy, Debug)]
struct Run {
    place: Place,
    count: usize,
}

impl EditList {
    /// No edits.
    pub fn new() -> EditList {
        EditList::default()
    }

    /// Adds `edit` (a copy of its text).
    #[inline]
    pub fn push(&mut self, edit: &Edit) {
        let key = (edit.start, edit.end);
        let prev_start = match self.runs.last_mut() {
            Some(run) if key >= self.last => {
                run.count += 1;
                self.last.0
            }
            _ => {
                self.runs.push(Run {
                    place: self.log.end(),
                    count: 1,
                });
                0
            }
        };
        let text: &[u8] = &edit.text;
        let delta = edit.start - prev_start;
        let len = zigzag(i64::from(edit.end) - i64::from(edit.start));
        match &edit.text.0 {
            // A number a few bytes after the edit before (the next field of a target): its
            // three numbers take a byte each, written with its text as one block of fixed
            // size, cut to what they take.
            TextRepr::Inline { len: n, bytes } if delta < 0x80 && len < 0x80 => {
                let mut block = [0; 3 + INLINE];
                block[0] = delta as u8;
                block[1] = len as u8;
                block[2] = *n;
                block[3..].copy_from_slice(bytes);
                let out = self.log.room(block.len());
                let end = out.len() + 3 + usize::from(*n);
                out.extend_from_slice(&block);
                out.truncate(end);
            }
            _ => self.push_record(u64::from(delta), len, &edit.text),
        }
        // One saturating sum, not two: the text's length and the span's are far from the
        // bounds of an `isize`, and so is their difference.
        let removed = edit.end.saturating_sub(edit.start) as isize;
        self.growth = self.growth.saturating_add(text.len() as isize - removed);
        self.last = key;
        self.len += 1;
    }

    /// [`push`](Self::push)'s record of any size: the offset from the start of the edit before
    /// in its run, the length (zigzagged), then the text's length and the text.
    fn push_record(&mut self, delta: u64, len: u64, edit_text: &EditText) {
        let text: &[u8] = edit_text;
        // Within a run starts never decrease; an edit kept reversed (`Edit::with_text`) has
        // a negative length.
        let mut head = [0; 3 * VARINT_MAX + INLINE];
        let mut n = 0;
        put_varint(&mut head, &mut n, delta);
        put_varint(&mut head, &mut n, len);
        put_varint(&mut head, &mut n, text.len() as u64);
        match &edit_text.0 {
            // A number: its head and its inline bytes go in as one block of fixed size (no
            // copy of a length known only here), then the block is cut to what they take.
            TextRepr::Inline { bytes, .. } => {
                head[n..n + INLINE].copy_from_slice(bytes);
                let out = self.log.room(head.len());
                let end = out.len() + n + text.len();
                out.extend_from_slice(&head);
                out.truncate(end);
            }
            TextRepr::Heap(_) => {
                let out = self.log.room(n + text.len());
                out.extend_from_slice(&head[..n]);
                out.extend_from_slice(text);
            }
        }
    }

    /// How many edits were added (identical duplicates included).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no edit was added.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The edits, in the order they were added.
    pub fn iter(&self) -> impl Iterator<Item = Edit> + '_ {
        let log = &self.log;
        self.runs.iter().flat_map(move |run| {
            let mut cursor = Cursor::of(*run);
            std::iter::from_fn(move || cursor.next(log))
                .map(|r| Edit::with_text(r.span(), EditText::from_bytes(r.text(log))))
        })
    }

    /// `src` with the edits spliced in (see [`apply_edits`]), in one pass over the edits.
    ///
    /// The output is sized exactly: the output of a large program is as large as its source,
    /// and room to spare would be held for the rest of the run. The size is summed as the edits
    /// come in; only an identical duplicate in another run (dropped here) makes it differ, and
    /// then the output is fitted at the end. An edit out of bounds or overlapping another ends
    /// the pass with the error, and what was written is dropped.
    ///
    /// The list is consumed: each chunk of its log is freed once every run has read past it,
    /// so the edits shrink as the output grows (on a 20 MB module they were 7.9 MB of
    /// `correct`'s peak, held beside the whole output).
    ///
    /// The output is written into a buffer of that size, zeroed (fresh pages from the system,
    /// not written first) and filled in order, not grown by `extend_from_slice`: nearly every
    /// piece is short (a written number, the `,` between two), and each was a call into
    /// `memcpy`, 5.7 M instructions of `correct` on the 2 MB bench module. See [`Out`]; the
    /// tests hold it to the splice by sorting, which copies each piece as it is.
    pub fn apply(self, src: &[u8]) -> Result<Vec<u8>, EditError> {
        self.apply_by(src, true, |_, _, _| {})
    }

    /// [`apply`](Self::apply), handing `seen` each edit as it is spliced in, in the order of
    /// the output (by span; an identical duplicate left out): its span in `src`, its text and,
    /// where the list has them, 16 bytes that start with the text.
    /// What a caller learns of the output from the edits is learnt without reading it again.
    pub fn apply_seen(
        self,
        src: &[u8],
        seen: impl FnMut(Span, &[u8], Option<&[u8; 16]>),
    ) -> Result<Vec<u8>, EditError> {
        self.apply_by(src, true, seen)
    }

    /// [`apply`](Self::apply); with `straight`, the edits of a list of one run are read
    /// straight from the log's chunks ([`splice_run`](Self::splice_run)), else through the
    /// merge: what the tests compare the straight reading with.
    fn apply_by<S: FnMut(Span, &[u8], Option<&[u8; 16]>)>(
        mut self,
        src: &[u8],
        straight: bool,
        seen: S,
    ) -> Result<Vec<u8>, EditError> {
        let size = src.len().saturating_add_signed(self.growth);
        let mut splice = Splice {
            out: Out {
                bytes: vec![0; size],
                len: 0,
            },
            pos: 0,
            prev: None,
            seen,
        };
        match self.runs[..] {
            [run] if straight => self.splice_run(run, src, &mut splice)?,
            _ => {
                let mut merge = self.sorted();
                let mut released = 0;
                while let Some(e) = merge.next(&self.log) {
                    let text = self.log.get(e.text, e.len);
                    let window = self.log.get(e.text, 16).first_chunk();
                    splice.edit(src, e.span(), text, window)?;
                    if e.text.chunk > released {
                        released = merge.lowest_chunk().min(e.text.chunk);
                        self.log.release_before(released);
                    }
                }
            }
        }
        splice.out.put(&src[splice.pos..], None);
        let mut out = splice.out.bytes_written();
        if out.capacity() != out.len() {
            out.shrink_to_fit();
        }
        Ok(out)
    }

    /// The splice of the edits of `run`, the list's only one, read in place chunk by chunk:
    /// each record where it lies, its text beside it, without a [`Cursor`]'s place and the
    /// [`Merge`]'s copy of each record between (the two were half of `apply`'s 12.6 M
    /// instructions on the 2 MB bench module's 71,000 edits). As the merge does, an identical
    /// duplicate of the edit before is left out, a record that does not read back ends the
    /// run, and each chunk is freed once the run has read past it and the last edit given
    /// does not lie in it.
    fn splice_run<S: FnMut(Span, &[u8], Option<&[u8; 16]>)>(
        &mut self,
        run: Run,
        src: &[u8],
        splice: &mut Splice<S>,
    ) -> Result<(), EditError> {
        let mut place = run.place;
        let mut left = run.count;
        let mut prev_start = 0;
        let mut last: Option<Record> = None;
        while left > 0 {
            let bytes = self.log.rest(&mut place);
            let mut at = 0;
            let mut ended = bytes.is_empty();
            while left > 0 && at < bytes.len() {
                let Some((start, end, head, n)) = decode(&bytes[at..], prev_start) else {
                    ended = true;
                    break;
                };
                let from = at + head;
                let text = &bytes[from..from + n];
                let record = Record {
                    start,
                    end,
                    text: Place {
                        at: place.at + from,
                        ..place
                    },
                    len: n,
                };
                at = from + n;
                left -= 1;
                prev_start = start;
                if last.is_some_and(|l| {
                    (l.start, l.end) == (start, end) && self.log.get(l.text, l.len) == text
                }) {
                    continue;
                }
                let window = bytes.get(from..).and_then(|b| b.first_chunk());
                splice.edit(src, record.span(), text, window)?;
                last = Some(record);
            }
            place.at += at;
            if ended {
                break;
            }
            let keep = last.map_or(place.chunk, |l| l.text.chunk.min(place.chunk));
            self.log.release_before(keep);
        }
        Ok(())
    }

    /// The edits by span (a stable order: equal spans as they were added), each identical
    /// duplicate of the edit before it left out.
    fn sorted(&self) -> Merge {
        match self.runs[..] {
            // The edits came in order (a transform's targets in file order, then its offset
            // calls after them): read straight from the run, without the merge's heap and
            // its bookkeeping per edit.
            [run] => Merge {
                runs: Runs::One(Cursor::of(run)),
                last: None,
            },
            _ => Merge {
                runs: Runs::Many(self.merged()),
                last: None,
            },
        }
    }

    /// [`sorted`](Self::sorted) for edits in several runs.
    fn merged(&self) -> Sorted {
        let mut cursors: Vec<Cursor> = self.runs.iter().map(|r| Cursor::of(*r)).collect();
        let mut heads: Vec<Option<Record>> =
            cursors.iter_mut().map(|c| c.next(&self.log)).collect();
        let heap = heads
            .iter()
            .enumerate()
            .skip(1)
            .filter_map(|(i, h)| h.map(|h| Reverse((h.start, h.end, i))))
            .collect();
        let head = heads.first_mut().and_then(Option::take);
        Sorted {
            cursors,
            heads,
            heap,
            run: 0,
            head,
        }
    }
}

impl Extend<Edit> for EditList {
    #[inline]
    fn extend<I: IntoIterator<Item = Edit>>(&mut self, edits: I) {
        for e in edits {
            self.push(&e);
        }
    }
}

impl FromIterator<Edit> for EditList {
    fn from_iter<I: IntoIterator<Item = Edit>>(edits: I) -> EditList {
        let mut list = EditList::default();
        list.extend(edits);
        list
    }
}

/// As the list of its edits, in the order they were added.
impl std::fmt::Debug for EditList {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// The 16 bytes of `bytes` from `at`, where it has them.
#[inline(always)]
fn window(bytes: &[u8], at: usize) -> Option<&[u8; 16]> {
    bytes.get(at..)?.first_chunk()
}

/// [`EditList::apply`]'s output: `bytes[..len]` written, the rest zeros still to be written.
struct Out {
    bytes: Vec<u8>,
    len: usize,
}

impl Out {
    /// Appends `piece`. `window`, when given, is 16 bytes that start with it: a piece of 16
    /// bytes or fewer is then written as those 16, one fixed copy of two moves, where the
    /// buffer has room for them. The bytes past the piece are written over by the pieces
    /// after it (each byte's last writer is the piece it belongs to), or cut off at the end.
    #[inline(always)]
    fn put(&mut self, piece: &[u8], window: Option<&[u8; 16]>) {
        let n = piece.len();
        let room = self
            .bytes
            .get_mut(self.len..)
            .and_then(|r| r.first_chunk_mut::<16>());
        match (window, room) {
            (Some(window), Some(room)) if n <= 16 => *room = *window,
            _ => self.put_slice(piece),
        }
        self.len += n;
    }

    /// [`put`](Self::put) for a long piece, or near the end: copied as it is, the buffer
    /// grown where it is short (its size was summed as the edits came in, so it is not).
    fn put_slice(&mut self, piece: &[u8]) {
        let end = self.len + piece.len();
        if self.bytes.len() < end {
            self.bytes.resize(end, 0);
        }
        self.bytes[self.len..end].copy_from_slice(piece);
    }

    /// The bytes written.
    fn bytes_written(mut self) -> Vec<u8> {
        self.bytes.truncate(self.len);
        self.bytes
    }
}

/// The record at the head of `bytes`, the edit before it in its run starting at
/// `prev_start`: its span, the bytes of its head and of its text (which follows the head).
/// `None` where it does not read back whole.
#[inline(always)]
fn decode(bytes: &[u8], prev_start: u32) -> Option<(u32, u32, usize, usize)> {
    let (start, len, n, at) = match *bytes {
        // Nearly every record's three numbers take a byte each (the offset from the edit
        // before within a target, a number's length, its text's): read at once.
        [delta, len, n, ..] if (delta | len | n) < 0x80 => (
            prev_start.checked_add(u32::from(delta))?,
            unzigzag(u64::from(len)),
            usize::from(n),
            3,
        ),
        _ => {
            let mut at = 0;
            let start = u64::from(prev_start).checked_add(read_varint(bytes, &mut at)?)?;
            let start = u32::try_from(start).ok()?;
            let len = unzigzag(read_varint(bytes, &mut at)?);
            let n = usize::try_from(read_varint(bytes, &mut at)?).ok()?;
            (start, len, n, at)
        }
    };
    let end = u32::try_from(i64::from(start).checked_add(len)?).ok()?;
    bytes.get(at..at.checked_add(n)?)?;
    Some((start, end, at, n))
}

/// [`EditList::apply`]'s splice so far: the output, the place in the source after the last
/// edit, and that edit's span.
struct Splice<S> {
    out: Out,
    pos: usize,
    prev: Option<Span>,
    /// Told of each edit spliced in (see [`EditList::apply_seen`]).
    seen: S,
}

impl<S: FnMut(Span, &[u8], Option<&[u8; 16]>)> Splice<S> {
    /// Splices in the edit of `span` writing `text` (`window`: 16 bytes that start with it,
    /// where the log has them), after the source up to it; an edit out of bounds or
    /// overlapping the one before is the error.
    #[inline(always)]
    fn edit(
        &mut self,
        src: &[u8],
        span: Span,
        text: &[u8],
        window: Option<&[u8; 16]>,
    ) -> Result<(), EditError> {
        if span.start > span.end || span.end > src.len() {
            return Err(EditError::OutOfBounds(span));
        }
        if span.start < self.pos {
            return Err(EditError::Overlap {
                first: self.prev.unwrap_or(span),
                second: span,
            });
        }
        self.out
            .put(&src[self.pos..span.start], self::window(src, self.pos));
        self.out.put(text, window);
        self.pos = span.end;
        self.prev = Some(span);
        (self.seen)(span, text, window);
        Ok(())
    }
}

/// One edit read back from the log: its span, and where its text is (a place, not a borrow,
/// so that [`EditList::apply`] can free the chunks it has read past).
#[derive(Clone, Copy, PartialEq, Eq)]
struct Record {
    start: u32,
    end: u32,
    text: Place,
    len: usize,
}

impl Record {
    fn span(&self) -> Span {
        Span::new(self.start as usize, self.end as usize)
    }

    fn text<'a>(&self, log: &'a Chunks) -> &'a [u8] {
        log.get(self.text, self.len)
    }

    /// The same edit: span and text.
    fn same(&self, other: &Record, log: &Chunks) -> bool {
        (self.start, self.end) == (other.start, other.end) && self.text(log) == other.text(log)
    }
}

/// Reads one run back.
struct Cursor {
    place: Place,
    left: usize,
    prev_start: u32,
}

impl Cursor {
    fn of(run: Run) -> Cursor {
        Cursor {
            place: run.place,
            left: run.count,
            prev_start: 0,
        }
    }

    /// The chunk of the log its next edit is in (`usize::MAX` once it has none).
    fn lowest_chunk(&self) -> usize {
        if self.left > 0 {
            self.place.chunk
        } else {
            usize::MAX
        }
    }

    /// The run's next edit. The log holds what [`EditList::push`] wrote, so every record reads
    /// back whole; one that did not would end the run.
    #[inline(always)]
    fn next(&mut self, log: &Chunks) -> Option<Record> {
        if self.left == 0 {
            return None;
        }
        let bytes = log.rest(&mut self.place);
        let (start, end, at, n) = decode(bytes, self.prev_start)?;
        let text = Place {
            at: self.place.at + at,
            ..self.place
        };
        self.place.at += at + n;
        self.left -= 1;
        self.prev_start = start;
        Some(Record {
            start,
            end,
            text,
            len: n,
        })
    }
}

/// [`EditList::sorted`]: the edits of one run read as they are, or of several merged, each
/// identical duplicate of the edit before it left out.
struct Merge {
    runs: Runs,
    /// The last edit given (the next is compared with it).
    last: Option<Record>,
}

/// Where [`Merge`] reads the edits from, in order by span.
enum Runs {
    One(Cursor),
    Many(Sorted),
}

impl Merge {
    /// The next edit by span, read from `log`.
    #[inline]
    fn next(&mut self, log: &Chunks) -> Option<Record> {
        loop {
            let head = match &mut self.runs {
                Runs::One(cursor) => cursor.next(log)?,
                Runs::Many(sorted) => sorted.next(log)?,
            };
            if self.last.is_some_and(|l| l.same(&head, log)) {
                continue;
            }
            self.last = Some(head);
            return Some(head);
        }
    }

    /// The first chunk of the log still to be read: what the runs have not given yet, and the
    /// last edit given.
    fn lowest_chunk(&self) -> usize {
        let runs = match &self.runs {
            Runs::One(cursor) => cursor.lowest_chunk(),
            Runs::Many(sorted) => sorted.lowest_chunk(),
        };
        runs.min(self.last.map_or(usize::MAX, |r| r.text.chunk))
    }
}

/// [`EditList::merged`]: the runs merged by span. The run taken from stays the same while
/// its next edit sorts before every other run's (all of them, for a file of one run): only a
/// change of run goes through the heap.
struct Sorted {
    cursors: Vec<Cursor>,
    /// The next edit of each run but the current one, not yet given.
    heads: Vec<Option<Record>>,
    /// Those heads by (start, end, run): equal spans in the order of their runs.
    heap: BinaryHeap<Reverse<(u32, u32, usize)>>,
    /// The run taken from, and its next edit.
    run: usize,
    head: Option<Record>,
}

impl Sorted {
    /// The next edit by span, read from `log`.
    #[inline]
    fn next(&mut self, log: &Chunks) -> Option<Record> {
        let key = self.head.map(|h| (h.start, h.end, self.run));
        match (key, self.heap.peek()) {
            (Some(key), Some(&Reverse(top))) if top < key => {
                // Another run's edit comes first: the current one waits in the heap.
                self.heads[self.run] = self.head.take();
                self.heap.push(Reverse(key));
                self.take_top();
            }
            (None, Some(_)) => self.take_top(),
            (None, None) => return None,
            _ => {}
        }
        let head = self.head?;
        self.head = self.cursors.get_mut(self.run)?.next(log);
        Some(head)
    }

    /// Makes the run of the heap's first edit the current one.
    fn take_top(&mut self) {
        if let Some(Reverse((_, _, run))) = self.heap.pop() {
            self.run = run;
            self.head = self.heads.get_mut(run).and_then(Option::take);
        }
    }

    /// The first chunk of the log still to be read: what the runs have not read yet and the
    /// edits read ahead.
    fn lowest_chunk(&self) -> usize {
        let unread = self.cursors.iter().map(Cursor::lowest_chunk);
        let read_ahead = self
            .heads
            .iter()
            .chain([&self.head])
            .flatten()
            .map(|r| r.text.chunk);
        unread.chain(read_ahead).min().unwrap_or(usize::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_text_reads_back_inline_and_on_the_heap() {
        assert_eq!(std::mem::size_of::<EditText>(), 16);
        assert_eq!(std::mem::size_of::<Edit>(), 24);
        for n in [0, 1, 13, 14, 15, 22, 23, 64] {
            let bytes: Vec<u8> = (0..n).map(|i| b'0' + (i % 10) as u8).collect();
            let t = EditText::from(bytes.clone());
            assert_eq!(&*t, bytes.as_slice(), "{n} bytes");
            assert_eq!(
                matches!(t.0, TextRepr::Inline { .. }),
                n <= INLINE,
                "{n} bytes"
            );
            assert_eq!(format!("{t:?}"), format!("{bytes:?}"));
        }
        // Equal texts are equal whatever they were built from.
        assert_eq!(
            Edit::new(Span::new(0, 1), "1.5"),
            Edit::new(Span::new(0, 1), b"1.5".to_vec())
        );
        assert_eq!(
            EditText::from_bytes(b"1.5"),
            EditText::from(b"1.5".to_vec())
        );
        let long = [b'7'; 40];
        assert_eq!(&*EditText::from_bytes(&long), &long[..]);
        assert_ne!(
            EditText::from(b"1.5".to_vec()),
            EditText::from(b"1.50".to_vec())
        );
    }

    #[test]
    fn splices_in_any_order() {
        let src = b"[1,2,3]";
        let out = apply_edits(
            src,
            &[
                Edit::new(Span::new(5, 6), "30.000"),
                Edit::new(Span::new(1, 2), "-1"),
            ],
        )
        .unwrap();
        assert_eq!(out, b"[-1,2,30.000]");
    }

    #[test]
    fn rejects_overlap_and_out_of_bounds() {
        let src = b"abcdef";
        assert!(matches!(
            apply_edits(
                src,
                &[
                    Edit::new(Span::new(0, 3), "x"),
                    Edit::new(Span::new(2, 4), "y")
                ]
            ),
            Err(EditError::Overlap { .. })
        ));
        assert!(matches!(
            apply_edits(src, &[Edit::new(Span::new(4, 9), "x")]),
            Err(EditError::OutOfBounds(_))
        ));
    }

    #[test]
    fn spans_read_back_and_one_past_u32_is_refused_not_moved() {
        let e = Edit::new(Span::new(7, 12), "1.5");
        assert_eq!(e.span(), Span::new(7, 12));
        assert_eq!(
            format!("{e:?}"),
            "Edit { span: Span { start: 7, end: 12 }, text: [49, 46, 53] }"
        );
        let top = u32::MAX as usize;
        assert_eq!(
            Edit::new(Span::new(top, top), "x").span(),
            Span::new(top, top)
        );
        if let Some(past) = top.checked_add(1) {
            let e = Edit::new(Span::new(past, past), "x");
            assert!(e.span().start > e.span().end);
            assert_eq!(
                apply_edits(b"ab", &[e]),
                Err(EditError::OutOfBounds(Span::new(top, 0)))
            );
        }
    }

    /// The splice as it was written before the edits were packed: sort (stable) by span, drop
    /// each identical duplicate of the edit kept before it, check, copy.
    fn splice_by_sorting(src: &[u8], edits: &[Edit]) -> Result<Vec<u8>, EditError> {
        let mut order: Vec<&Edit> = edits.iter().collect();
        order.sort_by_key(|e| (e.start, e.end));
        order.dedup_by(|b, a| (a.start, a.end) == (b.start, b.end) && a.text == b.text);
        let mut out = Vec::new();
        let mut pos = 0;
        let mut prev: Option<Span> = None;
        for e in order {
            let span = e.span();
            if span.start > span.end || span.end > src.len() {
                return Err(EditError::OutOfBounds(span));
            }
            if span.start < pos {
                return Err(EditError::Overlap {
                    first: prev.unwrap_or(span),
                    second: span,
                });
            }
            out.extend_from_slice(&src[pos..span.start]);
            out.extend_from_slice(&e.text);
            pos = span.end;
            prev = Some(span);
        }
        out.extend_from_slice(&src[pos..]);
        Ok(out)
    }

    proptest::proptest! {
        /// Any edits in any order (in runs, shuffled, duplicated, overlapping, out of bounds,
        /// texts inline and on the heap): the packed list splices as sorting did, its output is
        /// sized exactly, and it reads back as it was given.
        #[test]
        fn the_packed_list_splices_as_sorting_did(
            src_len in 0usize..60,
            spans in proptest::collection::vec((0usize..64, 0usize..6, 0usize..20), 0..40),
            dups in proptest::collection::vec(0usize..40, 0..6),
            shuffle in proptest::collection::vec(0usize..40, 0..20),
        ) {
            let src: Vec<u8> = (0..src_len).map(|i| b'a' + (i % 26) as u8).collect();
            let mut edits: Vec<Edit> = spans
                .iter()
                .map(|&(start, len, text)| {
                    let text: Vec<u8> = (0..text).map(|i| b'0' + (i % 10) as u8).collect();
                    Edit::new(Span::new(start, start + len), text)
                })
                .collect();
            // Mostly in order (as a transform makes them), with a few moved and repeated.
            edits.sort_by_key(|e| e.span().start);
            for (i, &k) in shuffle.iter().enumerate() {
                if !edits.is_empty() {
                    let n = edits.len();
                    edits.swap(i % n, k % n);
                }
            }
            for &d in &dups {
                if let Some(e) = edits.get(d).cloned() {
                    edits.insert(d, e);
                }
            }
            let list: EditList = edits.iter().cloned().collect();
            proptest::prop_assert_eq!(list.len(), edits.len());
            proptest::prop_assert_eq!(list.iter().collect::<Vec<_>>(), edits.clone());
            let merged = list.clone().apply_by(&src, false, |_, _, _| {});
            let packed = list.apply(&src);
            proptest::prop_assert_eq!(&packed, &splice_by_sorting(&src, &edits));
            proptest::prop_assert_eq!(&packed, &merged);
            if let Ok(out) = packed {
                proptest::prop_assert_eq!(out.capacity(), out.len());
            }
        }
    }

    #[test]
    fn edits_in_order_make_one_run_and_reversed_ones_one_each() {
        let e = |at: usize, text: &str| Edit::new(Span::new(at, at + 1), text);
        let forward: EditList = (0..10).map(|i| e(2 * i, "xy")).collect();
        assert_eq!(forward.runs.len(), 1);
        // Equal spans continue the run (a target rewritten twice).
        let mut again = forward.clone();
        again.push(&e(18, "xy"));
        assert_eq!(again.runs.len(), 1);
        let backward: EditList = (0..10).rev().map(|i| e(2 * i, "xy")).collect();
        assert_eq!(backward.runs.len(), 10);
        let src = b"abcdefghijklmnopqrst";
        let want = apply_edits(src, &forward.iter().collect::<Vec<_>>()).unwrap();
        assert_eq!(want, b"xybxydxyfxyhxyjxylxynxypxyrxyt");
        assert_eq!(backward.apply(src).unwrap(), want);
        assert_eq!(again.apply(src).unwrap(), want);
        assert_eq!(
            format!("{:?}", EditList::from_iter([e(3, "1")])),
            "[Edit { span: Span { start: 3, end: 4 }, text: [49] }]"
        );
        assert!(EditList::new().is_empty());
        assert_eq!(EditList::new().apply(b"ab").unwrap(), b"ab");
    }

    /// Runs that interleave over many chunks of the log, with duplicates across runs: `apply`
    /// frees each chunk once every run has read past it, and must not free one an edit read
    /// ahead (a run waiting in the merge) or the last edit given still points into.
    #[test]
    fn runs_merged_over_many_chunks_splice_as_sorting_did() {
        let src: Vec<u8> = (0..60_000).map(|i| b'a' + (i % 26) as u8).collect();
        let e = |at: usize, text: &str| Edit::new(Span::new(at, at + 1), text);
        // Pushed first and written last: a run of one, read ahead at the start, whose text
        // sits in the first chunk while every other run reads past it.
        let mut edits = vec![e(59_001, "first pushed, last written")];
        // The first half's even bytes, the second half's, then the first half's odd bytes
        // (a second run interleaving with the first over every one of its chunks), then
        // some of the first run again (identical: dropped) and a heap-sized text.
        edits.extend((0..15_000).map(|i| e(2 * i, "even")));
        edits.extend((15_000..30_000).map(|i| e(2 * i, "late")));
        edits.extend((0..15_000).map(|i| e(2 * i + 1, "odd")));
        edits.extend((0..15_000).step_by(7).map(|i| e(2 * i, "even")));
        edits.push(e(59_999, &"long text on the heap ".repeat(4)));
        let list: EditList = edits.iter().cloned().collect();
        assert!(list.runs.len() >= 3);
        assert!(list.log.chunks_len() > 10, "the edits fit in few chunks");
        assert_eq!(list.apply(&src), splice_by_sorting(&src, &edits));
    }

    /// One run over many chunks of the log, read straight from them: identical duplicates
    /// (one across a chunk's end among them) left out, heap texts and long offsets, an
    /// overlap found as the merge finds it.
    #[test]
    fn one_run_over_many_chunks_splices_as_the_merge_does() {
        let src: Vec<u8> = (0..200_000).map(|i| b'a' + (i % 26) as u8).collect();
        let mut edits = Vec::new();
        for i in 0..40_000usize {
            let at = 4 * i + (i % 3);
            let text = match i % 500 {
                0 => "a text too long to be kept inline".to_owned(),
                _ => format!("{}.{:03}", i, i % 1000),
            };
            edits.push(Edit::new(Span::new(at, at + 1 + i % 2), text));
            if i % 7 == 0 {
                edits.push(edits[edits.len() - 1].clone());
            }
        }
        edits.push(Edit::new(Span::new(199_990, 199_990), "inserted"));
        let list: EditList = edits.iter().cloned().collect();
        assert_eq!(list.runs.len(), 1);
        assert!(list.log.chunks_len() > 10, "the edits fit in few chunks");
        let want = splice_by_sorting(&src, &edits);
        assert_eq!(list.clone().apply_by(&src, false, |_, _, _| {}), want);
        assert_eq!(list.apply(&src), want);
        // The same span again with another text: an overlap, reported with the edit before.
        let mut clash = edits[..9].to_vec();
        clash.push(Edit::new(edits[8].span(), "other"));
        let list: EditList = clash.iter().cloned().collect();
        assert_eq!(list.runs.len(), 1);
        let want = splice_by_sorting(&src, &clash);
        assert!(matches!(want, Err(EditError::Overlap { .. })));
        assert_eq!(list.clone().apply_by(&src, false, |_, _, _| {}), want);
        assert_eq!(list.apply(&src), want);
    }

    #[test]
    fn identical_duplicates_collapse() {
        let e = Edit::new(Span::new(0, 1), "z");
        assert_eq!(apply_edits(b"ab", &[e.clone(), e]).unwrap(), b"zb");
    }
}
