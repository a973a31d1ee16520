//! The lossless syntax layer shared by RAPID and KRL.
//!
//! Sources are bytes (all syntax of both languages is ASCII; comments and strings may hold
//! Latin-1 or Windows-125x bytes, which are kept, never decoded). Parsers keep byte spans into
//! the source; printing is concatenation of those spans, and a transform is a list of [`Edit`]s
//! that replace only the numeric literals it changes.

mod diagnostic;
mod edit;
mod line_index;
mod number;
mod span;

pub use diagnostic::{Diagnostic, Excerpt, Severity, WINDOW, latin1, printable, window};
pub use edit::{Edit, EditError, apply_edits};
pub use line_index::LineIndex;
pub use number::{NumLit, fixed};
pub use span::Span;

/// The UTF-8 byte order mark some editors put in front of a module.
pub const BOM: &[u8] = b"\xEF\xBB\xBF";

/// True for bytes that are neither text nor the usual control characters: a NUL or most C0
/// codes mean an encrypted or binary file, which is reported and skipped, not parsed.
pub fn looks_binary(src: &[u8]) -> bool {
    let head = &src[..src.len().min(8192)];
    // A NUL never occurs in a program; a stray control byte in a comment does (and `check`
    // reports it): only a text made largely of control bytes is binary.
    let controls = head.iter().filter(|&&b| is_control_byte(b)).count();
    head.contains(&0) || controls * 10 > head.len()
}

/// A C0 control byte other than tab, line ends, form feed and the DOS end-of-file mark.
pub fn is_control_byte(b: u8) -> bool {
    b == 0x7f || (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0C | 0x1A))
}
