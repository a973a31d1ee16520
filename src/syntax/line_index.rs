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
///
/// The pass that finds the line ends also notes the first control byte
/// ([`is_control_byte`](super::is_control_byte)): both look for the bytes below 0x20, and
/// `check`'s lint for control bytes then reads no byte of a large file a second time.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LineIndex {
    starts: Vec<u32>,
    len: usize,
    first_control: Option<u32>,
}

/// `offset` as a stored line start (see [`LineIndex`]).
fn narrow(offset: usize) -> u32 {
    u32::try_from(offset).unwrap_or(u32::MAX)
}

const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
const HIGH: u64 = 0x8080_8080_8080_8080;
const ONES: u64 = 0x0101_0101_0101_0101;

/// The high bit of each byte of word `x` that may end a line or be a control byte: every byte
/// below 0x20 and 0x7f, and besides them 0x80-0x9f and 0xff, which the caller passes over
/// (they are rare in a program, and letting them through saves four operations a word). Each
/// byte's sums stay below 0x100, so no carry reaches the next byte: the answer is exact for
/// every byte, not only the first.
fn line_end_or_control(x: u64) -> u64 {
    // `(b + 1) & 0x7f` is below 0x21 exactly for those bytes; adding 0x5f brings it to 0x80
    // exactly when it is not.
    let next = ((x & LOW7).wrapping_add(ONES)) & LOW7;
    !next.wrapping_add(0x5f5f_5f5f_5f5f_5f5f) & HIGH
}

/// Where [`LineIndex::line_col_from`] found the last offset asked: the line's index.
#[derive(Clone, Copy, Debug, Default)]
pub struct LineCursor(usize);

impl LineIndex {
    /// Indexes the line starts of `src` (LF, CRLF and lone CR each end a line), and notes its
    /// first control byte.
    pub fn new(src: &[u8]) -> LineIndex {
        // Eight bytes at a time: a word's bytes below 0x20 or equal to 0x7f are found with a
        // few integer operations ([`line_end_or_control`]), and only those are looked at, a
        // line end or two every few words. One pass for both: a control-byte scan of its own,
        // after the parse, read a large file from memory a second time.
        let mut starts = Vec::with_capacity(src.len() / 64 + 1);
        starts.push(0);
        let mut first_control = None;
        let mut visit = |at: usize, b: u8| match b {
            b'\n' => starts.push(narrow(at + 1)),
            // A `\r\n` is one terminator: the `\n` ends the line.
            b'\r' if src.get(at + 1) != Some(&b'\n') => starts.push(narrow(at + 1)),
            _ if first_control.is_none() && super::is_control_byte(b) => {
                first_control = Some(narrow(at));
            }
            _ => {}
        };
        // Four words at a time: most 32-byte blocks of a program hold no such byte at all.
        let blocks = src.chunks_exact(32);
        let tail = blocks.remainder();
        let mut base = 0;
        for block in blocks {
            let word = |i: usize| {
                let bytes = block.get(i * 8..i * 8 + 8).unwrap_or_default();
                line_end_or_control(u64::from_le_bytes(bytes.try_into().unwrap_or_default()))
            };
            let found = [word(0), word(1), word(2), word(3)];
            if found.iter().all(|&m| m == 0) {
                base += 32;
                continue;
            }
            for (i, &m) in found.iter().enumerate() {
                let mut m = m;
                while m != 0 {
                    let k = i * 8 + (m.trailing_zeros() / 8) as usize;
                    m &= m - 1;
                    visit(base + k, block.get(k).copied().unwrap_or_default());
                }
            }
            base += 32;
        }
        for (k, &b) in tail.iter().enumerate() {
            if b < 0x20 || b == 0x7f {
                visit(base + k, b);
            }
        }
        LineIndex {
            starts,
            len: src.len(),
            first_control,
        }
    }

    /// Offset of the first control byte of the source
    /// ([`is_control_byte`](super::is_control_byte)), if any.
    pub fn first_control_byte(&self) -> Option<usize> {
        self.first_control.map(|at| at as usize)
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
    fn every_byte_in_every_place_of_a_word() {
        let flagged = |c: u8| c < 0x20 || c == 0x7f || (0x80..=0x9f).contains(&c) || c == 0xff;
        for b in 0..=255u8 {
            for k in 0..8 {
                // The other bytes are each of a few neighbours of the thresholds.
                for fill in [0x00u8, 0x1f, 0x20, 0x7e, 0x7f, 0x80, 0x9f, 0xa0, 0xfe, 0xff] {
                    let mut w = [fill; 8];
                    w[k] = b;
                    let mask = line_end_or_control(u64::from_le_bytes(w));
                    for (j, &c) in w.iter().enumerate() {
                        let set = mask >> (8 * j + 7) & 1 == 1;
                        assert_eq!(set, flagged(c), "{w:02x?} byte {j}");
                    }
                    assert_eq!(mask & !HIGH, 0);
                }
            }
        }
    }

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
        fn first_control_byte_is_the_first_a_byte_scan_finds(
            src in proptest::collection::vec(
                proptest::sample::select(vec![
                    b'a', b'\r', b'\n', b'\t', 0x00, 0x0C, 0x1A, 0x1B, 0x1F, 0x20, 0x7E, 0x7F,
                    0x80, 0x9F, 0xA0, 0xFF,
                ]), 0..200),
            pad in 0usize..33,
        ) {
            // Spaces before it move the bytes across the words' and blocks' boundaries.
            let mut text = vec![b' '; pad];
            text.extend(&src);
            let expected = text.iter().position(|&b| crate::syntax::is_control_byte(b));
            let idx = LineIndex::new(&text);
            proptest::prop_assert_eq!(idx.first_control_byte(), expected);
            proptest::prop_assert_eq!(idx.starts, starts_by_bytes(&text));
        }

        #[test]
        fn same_lines_as_a_byte_scan(src in proptest::collection::vec(
            proptest::sample::select(vec![b'a', b'\r', b'\n', b' ']), 0..200)) {
            proptest::prop_assert_eq!(LineIndex::new(&src).starts, starts_by_bytes(&src));
        }
    }
}
