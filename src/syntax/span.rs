//! Byte ranges into a kept source buffer.

use std::ops::Range;

/// A half-open byte range `start..end` into the original source.
///
/// Every token, node and numeric field keeps one, so printing is a concatenation of source slices
/// and an edit replaces exactly the bytes it names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct Span {
    /// The first byte.
    pub start: usize,
    /// One past the last byte.
    pub end: usize,
}

impl Span {
    /// `start..end`.
    pub const fn new(start: usize, end: usize) -> Span {
        Span { start, end }
    }

    /// Bytes covered.
    pub const fn len(self) -> usize {
        self.end - self.start
    }

    /// Whether it covers no byte.
    pub const fn is_empty(self) -> bool {
        self.start == self.end
    }

    /// The smallest span covering both.
    pub fn cover(self, other: Span) -> Span {
        Span::new(self.start.min(other.start), self.end.max(other.end))
    }

    /// The span as a range, to slice the source with.
    pub fn range(self) -> Range<usize> {
        self.start..self.end
    }

    /// The bytes this span names; empty when it does not fit `src` (never panics).
    pub fn slice(self, src: &[u8]) -> &[u8] {
        src.get(self.start..self.end).unwrap_or(&[])
    }
}

/// A [`Span`] in two 32-bit offsets, for the records kept by the hundred thousand (call
/// records, Status/Turn fields, edits): inputs are at most
/// [`MAX_INPUT_BYTES`](crate::output::MAX_INPUT_BYTES) and the parsers' offsets are `u32`, so
/// every offset of a file trackfix reads fits. The end is kept plus one, never zero, so that an
/// `Option<Span32>` is eight bytes too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Span32 {
    start: u32,
    end_plus_one: std::num::NonZeroU32,
}

impl Span32 {
    /// `None` only for an offset past 4 GiB, which no input reaches (see the type). A reversed
    /// span is kept as it is.
    pub(crate) fn of(span: Span) -> Option<Span32> {
        Some(Span32 {
            start: u32::try_from(span.start).ok()?,
            end_plus_one: u32::try_from(span.end)
                .ok()?
                .checked_add(1)
                .and_then(std::num::NonZeroU32::new)?,
        })
    }

    /// The span as offsets.
    pub(crate) fn span(self) -> Span {
        Span::new(self.start as usize, (self.end_plus_one.get() - 1) as usize)
    }
}

impl From<Range<usize>> for Span {
    fn from(r: Range<usize>) -> Span {
        Span::new(r.start, r.end)
    }
}
