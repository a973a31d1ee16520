//! The lossless syntax layer shared by RAPID and KRL.
//!
//! Sources are bytes (all syntax of both languages is ASCII; comments and strings may hold
//! Latin-1 or Windows-125x bytes, which are kept, never decoded). Parsers keep byte spans into
//! the source; printing is concatenation of those spans, and a transform is a list of [`Edit`]s
//! that replace only the numeric literals it changes.
//!
#![doc = include_str!("lossless_example.md")]

mod diagnostic;
mod edit;
#[cfg(test)]
pub(crate) mod grammar_check;
mod line_index;
mod number;
pub(crate) mod packed;
mod span;
mod tree;

pub use diagnostic::{Diagnostic, Encoding, Excerpt, Severity, WINDOW, latin1, printable, window};
pub use edit::{Edit, EditError, EditList, EditText, apply_edits};
pub use line_index::{LineCursor, LineIndex};
pub use number::{NumLit, Rounded, fixed, same_at};
pub(crate) use number::{PackedLit, ShortLit};
pub use span::Span;
pub(crate) use span::Span32;
pub(crate) use tree::language;
pub use tree::{Language, NoSink, Node, Sink, Tree};
pub(crate) use tree::{TreeBuilder, refused_tree, too_large};

/// The UTF-8 byte order mark some editors put in front of a module.
pub const BOM: &[u8] = b"\xEF\xBB\xBF";

/// True for a file that is not text: a NUL byte, or C0 control codes (other than tab, line
/// ends, form feed and DOS end-of-file) in more than 1 of 32 bytes of its first 8 KiB (and more
/// than 8 of them), mean
/// an encrypted or binary file, which is reported and skipped, not parsed. A stray control
/// byte in a comment (0x05, 0x1C: editors and pendants leave them) does not.
pub fn looks_binary(src: &[u8]) -> bool {
    let head = &src[..src.len().min(8192)];
    // A NUL never occurs in a program; a stray control byte in a comment does (and `check`
    // reports it): only a text made largely of control bytes is binary.
    let controls = head.iter().filter(|&&b| is_control_byte(b)).count();
    head.contains(&0) || controls * 10 > head.len()
}

/// How many bytes `a` and `b` start with alike, 16 at a time: most of a transformed file is the
/// same on both sides in stretches of tens of bytes between its changed numbers, and a call
/// statement is mostly the one before it.
#[inline]
pub(crate) fn common_len(a: &[u8], b: &[u8]) -> usize {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let (chunks_a, _) = a.as_chunks::<16>();
    let (chunks_b, _) = b.as_chunks::<16>();
    for (k, (x, y)) in chunks_a.iter().zip(chunks_b).enumerate() {
        let diff = u128::from_le_bytes(*x) ^ u128::from_le_bytes(*y);
        if diff != 0 {
            return k * 16 + (diff.trailing_zeros() / 8) as usize;
        }
    }
    let done = chunks_a.len() * 16;
    done + a[done..]
        .iter()
        .zip(&b[done..])
        .take_while(|(x, y)| x == y)
        .count()
}

/// A C0 control byte other than tab, line ends, form feed and the DOS end-of-file mark.
pub fn is_control_byte(b: u8) -> bool {
    b == 0x7f || (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0C | 0x1A))
}

#[cfg(test)]
mod tests {
    use super::{common_len, looks_binary};

    #[test]
    fn common_len_is_where_the_bytes_first_differ() {
        let a: Vec<u8> = (0..40u8).collect();
        for len_b in [0, 1, 15, 16, 17, 33, 40] {
            for at in 0..=len_b {
                let mut b = a[..len_b].to_vec();
                if let Some(x) = b.get_mut(at) {
                    *x ^= 0x80;
                }
                let plain = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
                assert_eq!(common_len(&a, &b), plain, "{len_b} {at}");
                assert_eq!(common_len(&b, &a), plain, "{len_b} {at}");
            }
        }
    }

    #[test]
    fn a_control_byte_in_a_comment_is_still_text() {
        assert!(!looks_binary(
            b"MODULE m\r\n  ! moved \x05 here \x1C\r\nENDMODULE\r\n"
        ));
        assert!(!looks_binary(b";\x05\r\nDEF a()\r\nEND\r\n"));
        assert!(looks_binary(b"MODULE m\x00"));
        assert!(looks_binary(
            &[0x17, 0x9a, 0x01, 0x02, 0x03, 0x04].repeat(20)
        ));
        // One control byte on every line of a long file is still text.
        let every_line = b"  ! moved \x05 here, see the cell drawing\r\n".repeat(200);
        assert!(!looks_binary(&every_line));
        assert!(!looks_binary(b""));
    }
}
