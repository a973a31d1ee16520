//! Byte offset → line and column, for diagnostics.

use super::Span;

/// Start offsets of every line of a source.
///
/// A line ends at `\n`, `\r\n` or a bare `\r`: robot controllers and old editors write all three,
/// sometimes in one file, and a diagnostic must point at the line a user sees in their editor.
///
/// The starts are `u32`: a 20 MB module has 220,000 lines, and every page of the index is a
/// fresh one the kernel clears (0.9 MB less at `usize`'s half). No input reaches 4 GiB
/// ([`MAX_INPUT_BYTES`](crate::output::MAX_INPUT_BYTES)); past it a start is clamped, so an
/// offset there is placed on a wrong line, never a panic.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LineIndex {
    starts: Vec<u32>,
    len: usize,
}

/// `offset` as a stored line start (see [`LineIndex`]).
fn narrow(offset: usize) -> u32 {
    u32::try_from(offset).unwrap_or(u32::MAX)
}

/// Where [`LineIndex::line_col_from`] found the last offset asked: the line's index.
#[derive(Clone, Copy, Debug, Default)]
pub struct LineCursor(usize);

impl LineIndex {
    /// Indexes the line starts of `src` (LF, CRLF and lone CR each end a line).
    pub fn new(src: &[u8]) -> LineIndex {
        let mut starts = vec![0];
        // memchr2 scans a word at a time; a byte loop spent ~9 instructions per byte here. A
        // `\r\n` is one terminator and is stepped over whole: a search per byte of it cost
        // as much again in a CRLF file, where the lines are short.
        let mut at = 0;
        while let Some(found) = src
            .get(at..)
            .and_then(|rest| memchr::memchr2(b'\n', b'\r', rest))
        {
            let i = at + found;
            let end = if src[i] == b'\r' && src.get(i + 1) == Some(&b'\n') {
                i + 2
            } else {
                i + 1
            };
            starts.push(narrow(end));
            at = end;
        }
        LineIndex {
            starts,
            len: src.len(),
        }
    }

    /// Number of lines (a final newline opens an empty last line).
    pub fn line_count(&self) -> usize {
        self.starts.len()
    }

    /// 1-based line and 1-based byte column of `offset` (clamped to the source).
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.len);
        // The first start is 0, so the partition point is at least 1.
        let line = self
            .starts
            .partition_point(|&s| s as usize <= offset)
            .saturating_sub(1);
        (line + 1, offset - self.start(line) + 1)
    }

    /// Where line `line` (0-based) starts; 0 for one past the end.
    fn start(&self, line: usize) -> usize {
        self.starts.get(line).map_or(0, |&s| s as usize)
    }

    /// [`LineIndex::line_col`] found from `cursor`, the line of the offset asked before: a
    /// reader asking in file order (a parser's statements, one or two a line) steps forward a
    /// line or two where a search took about 17 steps. Any order gives the same answers.
    pub fn line_col_from(&self, cursor: &mut LineCursor, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.len);
        let mut line = cursor.0;
        if self.starts.get(line).is_some_and(|&s| s as usize <= offset) {
            for _ in 0..4 {
                match self.starts.get(line + 1) {
                    Some(&next) if next as usize <= offset => line += 1,
                    _ => {
                        cursor.0 = line;
                        return (line + 1, offset - self.start(line) + 1);
                    }
                }
            }
        }
        let (l, c) = self.line_col(offset);
        cursor.0 = l - 1;
        (l, c)
    }

    /// 1-based line of `offset`.
    pub fn line(&self, offset: usize) -> usize {
        self.line_col(offset).0
    }

    /// The span of 1-based `line` without its terminator; empty past the end.
    pub fn line_span(&self, src: &[u8], line: usize) -> Span {
        let Some(&start) = self.starts.get(line.wrapping_sub(1)) else {
            return Span::new(self.len, self.len);
        };
        let start = start as usize;
        let mut end = self.starts.get(line).map_or(self.len, |&s| s as usize);
        while end > start && matches!(src.get(end - 1), Some(b'\n' | b'\r')) {
            end -= 1;
        }
        Span::new(start, end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mixed_terminators() {
        let src = b"a\r\nbb\rccc\nd";
        let idx = LineIndex::new(src);
        assert_eq!(idx.line_count(), 4);
        assert_eq!(idx.line_col(0), (1, 1));
        assert_eq!(idx.line_col(3), (2, 1));
        assert_eq!(idx.line_col(6), (3, 1));
        assert_eq!(idx.line_col(8), (3, 3));
        assert_eq!(idx.line_col(10), (4, 1));
        assert_eq!(idx.line_span(src, 2).slice(src), b"bb");
        assert_eq!(idx.line_span(src, 4).slice(src), b"d");
        assert_eq!(idx.line_span(src, 9).slice(src), b"");
    }

    /// The byte-at-a-time rule the index implements, written out independently.
    fn starts_by_bytes(src: &[u8]) -> Vec<u32> {
        let mut starts = vec![0];
        let mut i = 0;
        while i < src.len() {
            if src[i] == b'\n' || (src[i] == b'\r' && src.get(i + 1) != Some(&b'\n')) {
                starts.push(i as u32 + 1);
            }
            i += 1;
        }
        starts
    }

    proptest::proptest! {
        #[test]
        fn a_cursor_finds_what_the_search_finds(
            src in proptest::collection::vec(
                proptest::sample::select(vec![b'a', b'\r', b'\n', b' ']), 0..200),
            offsets in proptest::collection::vec(0usize..220, 0..40),
            sorted in proptest::bool::ANY,
        ) {
            let idx = LineIndex::new(&src);
            let mut offsets = offsets;
            if sorted {
                offsets.sort_unstable();
            }
            let mut cursor = LineCursor::default();
            for o in offsets {
                proptest::prop_assert_eq!(idx.line_col_from(&mut cursor, o), idx.line_col(o));
            }
        }

        #[test]
        fn same_lines_as_a_byte_scan(src in proptest::collection::vec(
            proptest::sample::select(vec![b'a', b'\r', b'\n', b' ']), 0..200)) {
            proptest::prop_assert_eq!(LineIndex::new(&src).starts, starts_by_bytes(&src));
        }
    }
}
