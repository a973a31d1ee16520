//! Located messages about a source file, rendered the way compilers do.

use super::{LineIndex, Span};
use std::fmt::Write as _;

/// How serious a diagnostic is, least first. The parser's choice is a default: whoever renders
/// it (the CLI) may show it at another severity (`docs/design.md §8`, errors that render
/// themselves).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Information: nothing is wrong.
    Note,
    /// Something to check; the result is still complete.
    Warning,
    /// The input cannot be used as it is.
    Error,
}

impl Severity {
    /// The word the rendering prints (`note`, `warning`, `error`).
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Note => "note",
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
}

/// A message about the bytes `span` of one source, with an optional hint saying what to do.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Diagnostic {
    /// How serious it is.
    pub severity: Severity,
    /// The bytes of the source it is about (the caret covers them).
    pub span: Span,
    /// What is wrong, in one line.
    pub message: String,
    /// What to do about it (rendered as `= help: …`).
    pub hint: Option<String>,
    /// Whether it says what a transform takes the program to mean where that is not what is
    /// written (a frame's declaration stands for the value the program gives it): the
    /// transforms show it with their results, not only `check`.
    #[serde(skip)]
    pub shapes_transforms: bool,
}

impl Diagnostic {
    /// A diagnostic without a hint.
    pub fn new(severity: Severity, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity,
            span,
            message: message.into(),
            hint: None,
            shapes_transforms: false,
        }
    }

    /// An error without a hint.
    pub fn error(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Error, span, message)
    }

    /// A warning without a hint.
    pub fn warning(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Warning, span, message)
    }

    /// A note without a hint.
    pub fn note(span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Note, span, message)
    }

    /// The same diagnostic with `hint` as what to do.
    pub fn with_hint(mut self, hint: impl Into<String>) -> Diagnostic {
        self.hint = Some(hint.into());
        self
    }

    /// Marks it as one the transforms show ([`Diagnostic::shapes_transforms`]).
    pub fn shaping_transforms(mut self) -> Diagnostic {
        self.shapes_transforms = true;
        self
    }

    /// `path:line:column: severity: message`, the source line, a caret line and the hint, for a
    /// program file (Latin-1, see [`Encoding`]).
    ///
    /// Bytes are shown as Latin-1 so that a Windows-125x comment never breaks the caret's column;
    /// control characters (ESC, OSC, C0 and C1) are shown escaped (`\x1b`), never sent to the
    /// terminal; a long line is cut to a window of [`WINDOW`] characters around the span.
    pub fn render(&self, path: &str, src: &[u8], index: &LineIndex) -> String {
        self.render_in(path, src, index, Encoding::Latin1)
    }

    /// [`render`](Self::render) for a source whose text is in `encoding`.
    pub fn render_in(
        &self,
        path: &str,
        src: &[u8],
        index: &LineIndex,
        encoding: Encoding,
    ) -> String {
        let (line, col) = index.line_col(self.span.start);
        let text_span = index.line_span(src, line);
        let excerpt = Excerpt {
            line,
            column: col,
            text: text_span.slice(src),
            start: text_span.start,
            cut_before: false,
            cut_after: false,
            encoding,
        };
        self.render_excerpt(path, &excerpt)
    }

    /// [`render`](Self::render) from one line (or a piece of it) alone.
    pub fn render_excerpt(&self, path: &str, x: &Excerpt) -> String {
        let Excerpt {
            line,
            column: col,
            text,
            start: text_start,
            ..
        } = *x;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{}:{line}:{col}: {}: {}",
            printable(path),
            self.severity.as_str(),
            printable(&self.message)
        );
        let at = self.span.start.saturating_sub(text_start).min(text.len());
        let end = self
            .span
            .end
            .saturating_sub(text_start)
            .clamp(at, text.len());
        let (from, to) = window(text.len(), at, end);
        let gutter = line.to_string().len();
        let _ = writeln!(out, "{:gutter$} |", "");
        let mut shown = String::new();
        let mut pad = String::new();
        if from > 0 || x.cut_before {
            shown.push('…');
            pad.push(' ');
        }
        // The caret covers the characters of the span, however many bytes each takes.
        let mut caret_len = 0;
        for (offset, piece) in x.encoding.decode(&text[from..to]) {
            let width = push_piece(&mut shown, piece);
            let offset = from + offset;
            if offset < at {
                let fill = if piece == Piece::Char('\t') {
                    '\t'
                } else {
                    ' '
                };
                pad.extend(std::iter::repeat_n(fill, width));
            } else if offset < end {
                caret_len += 1;
            }
        }
        if to < text.len() || x.cut_after {
            shown.push('…');
        }
        let _ = writeln!(out, "{line} | {shown}");
        let caret_len = caret_len.max(1);
        let _ = writeln!(out, "{:gutter$} | {pad}{}", "", "^".repeat(caret_len));
        if let Some(hint) = &self.hint {
            let _ = writeln!(out, "{:gutter$} = help: {}", "", printable(hint));
        }
        out
    }
}

/// How many characters of a source line a diagnostic shows: a line of 2,000 targets renders
/// as a window around the span, so every rendered diagnostic stays small.
pub const WINDOW: usize = 200;

/// The byte range `[from, to)` of a line of `len` bytes shown for a span `[at, end)`: the whole
/// line when short, else [`WINDOW`] bytes starting a little before the span.
pub fn window(len: usize, at: usize, end: usize) -> (usize, usize) {
    if len <= WINDOW {
        return (0, len);
    }
    let lead = WINDOW / 4;
    let from = at.saturating_sub(lead).min(len.saturating_sub(WINDOW));
    let to = (from + WINDOW).max(end.min(from + 2 * WINDOW)).min(len);
    (from, to)
}

/// How a source's bytes are text. Program files (RAPID, KRL) are Latin-1, the controllers'
/// character set (and any byte is a char, so a Windows-125x comment never breaks a column);
/// TOML files (the cell file, a profile) are UTF-8 by the TOML specification, so a `·` in a
/// comment is one character, not the two `Â·` of its bytes read as Latin-1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// One byte, one char.
    #[default]
    Latin1,
    /// UTF-8; a byte that is no UTF-8 is shown escaped.
    Utf8,
}

/// One shown unit of a source line: a character, or a byte that is no character of the
/// encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Piece {
    Char(char),
    Byte(u8),
}

impl Encoding {
    /// The encoding of a text file that names none (a measurement table from a tracker's
    /// software): UTF-8 where every byte decodes so, which no Latin-1 text with a letter above
    /// ASCII does by chance; Latin-1 (Windows-1252's letters) otherwise.
    pub fn of_text(bytes: &[u8]) -> Encoding {
        match std::str::from_utf8(bytes) {
            Ok(_) => Encoding::Utf8,
            Err(_) => Encoding::Latin1,
        }
    }

    /// `bytes` as text in this encoding (a byte that is no UTF-8 becomes U+FFFD).
    pub fn text(self, bytes: &[u8]) -> String {
        match self {
            Encoding::Latin1 => latin1(bytes),
            Encoding::Utf8 => String::from_utf8_lossy(bytes).into_owned(),
        }
    }

    /// The pieces of `text` with the byte offset each starts at.
    fn decode(self, text: &[u8]) -> Vec<(usize, Piece)> {
        match self {
            Encoding::Latin1 => latin1_pieces(text),
            Encoding::Utf8 => utf8_pieces(text),
        }
    }
}

/// Latin-1: every byte is the char of the same number.
fn latin1_pieces(text: &[u8]) -> Vec<(usize, Piece)> {
    text.iter()
        .enumerate()
        .map(|(i, &b)| (i, Piece::Char(b as char)))
        .collect()
}

/// UTF-8: the chars of its valid runs, and each byte that is none on its own (a line cut inside
/// a character, or a Latin-1 byte in a UTF-8 file).
fn utf8_pieces(text: &[u8]) -> Vec<(usize, Piece)> {
    let mut out = Vec::with_capacity(text.len());
    let mut offset = 0;
    for chunk in text.utf8_chunks() {
        for (i, c) in chunk.valid().char_indices() {
            out.push((offset + i, Piece::Char(c)));
        }
        offset += chunk.valid().len();
        for &b in chunk.invalid() {
            out.push((offset, Piece::Byte(b)));
            offset += 1;
        }
    }
    out
}

/// One piece of a source line for the terminal: a control character or a stray byte escaped;
/// its width.
fn push_piece(out: &mut String, piece: Piece) -> usize {
    match piece {
        Piece::Char(c) if c == '\t' || !c.is_control() => {
            out.push(c);
            1
        }
        // Control characters (C0, DEL, C1) all are below U+0100: two hex digits say them.
        Piece::Char(c) => {
            let _ = write!(out, "\\x{:02x}", c as u32);
            4
        }
        Piece::Byte(b) => {
            let _ = write!(out, "\\x{b:02x}");
            4
        }
    }
}

/// One source line, or the window of it a diagnostic shows, with where it sits in its file.
#[derive(Clone, Copy, Debug)]
pub struct Excerpt<'a> {
    /// 1-based line of the diagnostic's span start.
    pub line: usize,
    /// 1-based column (bytes) of the span start.
    pub column: usize,
    /// The bytes shown (no line terminator).
    pub text: &'a [u8],
    /// Byte offset of `text` in the file (the span's offsets are file offsets).
    pub start: usize,
    /// Whether the line goes on before `text`.
    pub cut_before: bool,
    /// Whether the line goes on after `text`.
    pub cut_after: bool,
    /// How `text`'s bytes are characters.
    pub encoding: Encoding,
}

/// Bytes as Latin-1 text: every byte is one char, so columns stay columns.
pub fn latin1(bytes: &[u8]) -> String {
    // ASCII (names, nearly always) is the same text in one copy, not a char at a time.
    if bytes.is_ascii()
        && let Ok(text) = String::from_utf8(bytes.to_vec())
    {
        return text;
    }
    bytes.iter().map(|&b| b as char).collect()
}

/// `s` with control characters (ESC, OSC, BEL, C1, …; not tab or newline) escaped as `\x1b`,
/// safe to print to a terminal: file names, messages and source text can hold anything.
pub fn printable(s: &str) -> std::borrow::Cow<'_, str> {
    let unsafe_char = |c: char| c.is_control() && c != '\t' && c != '\n';
    if !s.chars().any(unsafe_char) {
        return std::borrow::Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if unsafe_char(c) {
            let _ = write!(out, "\\x{:02x}", c as u32);
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_location_line_and_caret() {
        let src = b"MODULE m\r\n  MoveL p1 v100;\r\nENDMODULE";
        let idx = LineIndex::new(src);
        let d = Diagnostic::error(Span::new(18, 20), "unknown target `p1`")
            .with_hint("declare it or check the spelling");
        let text = d.render("m.mod", src, &idx);
        assert_eq!(
            text,
            "m.mod:2:9: error: unknown target `p1`\n  |\n2 |   MoveL p1 v100;\n  |         ^^\n  = help: declare it or check the spelling\n"
        );
    }

    #[test]
    fn a_long_line_renders_a_window_around_the_span() {
        let mut src = vec![b'x'; 10_000];
        src[6000..6003].copy_from_slice(b"p42");
        let idx = LineIndex::new(&src);
        let d = Diagnostic::error(Span::new(6000, 6003), "here");
        let text = d.render("m.mod", &src, &idx);
        assert!(text.starts_with("m.mod:1:6001: error: here\n"), "{text}");
        let lines: Vec<&str> = text.lines().collect();
        // `…` + WINDOW bytes + `…`; the caret under `p42`.
        assert_eq!(lines[2].chars().count(), "1 | ".len() + WINDOW + 2);
        let shown = lines[2].find("p42").unwrap();
        assert_eq!(lines[3].find("^^^").unwrap(), shown - ("…".len() - 1));
    }

    #[test]
    fn control_characters_are_escaped_and_the_caret_follows() {
        let src = b"a \x1b]0;x\x07 p1";
        let idx = LineIndex::new(src);
        let d = Diagnostic::warning(Span::new(9, 11), "bad\x1b[2J");
        let text = d.render("m\x07.mod", src, &idx);
        assert_eq!(
            text,
            "m\\x07.mod:1:10: warning: bad\\x1b[2J\n  |\n1 | a \\x1b]0;x\\x07 p1\n  |                ^^\n"
        );
        assert_eq!(printable("tab\tok"), "tab\tok");
    }

    #[test]
    fn a_utf8_source_shows_characters_and_the_caret_counts_them() {
        // `é` and `·` are 2 bytes each in UTF-8; `p1` starts at byte 12, character 10.
        let src = "a é·b · p1 q".as_bytes();
        let idx = LineIndex::new(src);
        let d = Diagnostic::error(Span::new(12, 14), "here");
        let utf8 = d.render_in("c.toml", src, &idx, Encoding::Utf8);
        assert_eq!(
            utf8,
            "c.toml:1:13: error: here\n  |\n1 | a é·b · p1 q\n  |          ^^\n"
        );
        // The same bytes as Latin-1 (a program's convention): one character a byte.
        let latin1 = d.render("m.mod", src, &idx);
        assert!(
            latin1.contains("1 | a Ã©Â·b Â· p1 q\n  |             ^^\n"),
            "{latin1}"
        );
        // A byte that is no UTF-8 (a cut character, a Latin-1 byte) is shown escaped, its
        // width in the caret's padding.
        let src = b"\xe9 p1";
        let d = Diagnostic::error(Span::new(2, 4), "here");
        let text = d.render_in("c.toml", src, &LineIndex::new(src), Encoding::Utf8);
        assert!(text.contains("1 | \\xe9 p1\n  |      ^^\n"), "{text}");
    }
}
