//! KRL byte lexer: every byte of a source belongs to exactly one token, so printing the tokens
//! in order gives the source back (`grammars/krl.ebnf`, rule `token`).
//!
//! Tokens are `(kind, u32 span)`: no per-token allocation, which keeps a 50 MB `.dat` cheap.

use crate::syntax::Span;

/// What a token is. Trivia (whitespace, newlines, comments, the BOM) are tokens too.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TokenKind {
    /// The UTF-8 byte order mark at offset 0.
    Bom,
    /// Spaces, tabs, form feeds, DOS EOF (0x1A) and other stray control bytes.
    Whitespace,
    /// `\n`, `\r\n` or a bare `\r`.
    Newline,
    /// `;` to the end of the line (`;FOLD …`, `;ENDFOLD`, `;%{PE}%…` included).
    Comment,
    /// `&ACCESS RVP`, `&REL 3`, `&PARAM …`, `&COMMENT …`, `&USER …`: a whole header line.
    Header,
    /// Names and keywords: `[A-Za-z_$][A-Za-z0-9_$]*`.
    Ident,
    /// `12`, `1.5`, `.5`, `1.0E+02`: always unsigned (a sign is a [`TokenKind::Punct`]).
    Number,
    /// `"text"`.
    Str,
    /// `'B0101'`, `'H1F'`: bit and hex strings.
    Quoted,
    /// A string or quoted token missing its closing quote (runs to the end of the line).
    Unterminated,
    /// `#BASE`: an enum literal.
    Enum,
    /// Operators and punctuation; `==`, `<>`, `<=`, `>=` are one token.
    Punct,
    /// Bytes outside the ASCII syntax (Windows-125x or UTF-8 outside comments and strings).
    Unknown,
}

impl TokenKind {
    /// Tokens that carry no syntax.
    pub fn is_trivia(self) -> bool {
        matches!(
            self,
            TokenKind::Bom | TokenKind::Whitespace | TokenKind::Newline | TokenKind::Comment
        )
    }
}

/// One token: its kind and its byte range in the source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Token {
    /// What the token is.
    pub kind: TokenKind,
    /// Its first byte in the source.
    pub start: u32,
    /// One past its last byte.
    pub end: u32,
}

impl Token {
    /// `start..end` as a [`Span`].
    pub fn span(self) -> Span {
        Span::new(self.start as usize, self.end as usize)
    }

    /// The token's bytes in `src`.
    pub fn text(self, src: &[u8]) -> &[u8] {
        self.span().slice(src)
    }
}

pub(super) fn is_ident_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_' || b == b'$'
}

fn line_end(src: &[u8], i: usize) -> usize {
    run_end(src, i, |b| b != b'\n' && b != b'\r')
}

const fn byte_table(ident: bool) -> [bool; 256] {
    let mut t = [false; 256];
    let mut b = 0;
    while b < 256 {
        t[b] = if ident {
            is_ident_byte(b as u8)
        } else {
            is_space(b as u8)
        };
        b += 1;
    }
    t
}

const fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | 0x0B | 0x0C | 0x1A | 0x00..=0x08 | 0x0E..=0x19 | 0x1B..=0x1F | 0x7F)
}

const fn is_ident_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'$'
}

/// Byte classes by table: the lexer's inner loops are one load per byte.
static SPACE: [bool; 256] = byte_table(false);
pub(super) static IDENT: [bool; 256] = byte_table(true);

/// The end of the run of bytes from `i` on that satisfy `keep`.
#[inline]
fn run_end(src: &[u8], i: usize, keep: impl Fn(u8) -> bool) -> usize {
    let rest = src.get(i..).unwrap_or(&[]);
    i + rest.iter().position(|&b| !keep(b)).unwrap_or(rest.len())
}

/// Splits `src` into tokens covering every byte. Never fails: a byte the syntax does not know
/// becomes an [`TokenKind::Unknown`] token for the parser to report. Rules `token`, `bom`,
/// `whitespace`, `newline`, `comment`, `header`, `ident`, `number`, `exponent`, `string`,
/// `quoted`, `unterminated`, `enum`, `punct` and `unknown`.
///
/// Sources of 4 GiB or more do not fit `u32` spans; the caller refuses them before lexing.
pub fn lex(src: &[u8]) -> Vec<Token> {
    // Roughly one token per 4 bytes in position-heavy `.dat` files.
    let mut out = Vec::with_capacity(src.len() / 4 + 8);
    out.extend(Lexer::new(src));
    out
}

/// The tokens of `src` one at a time, for the parser to consume a line at a time without
/// holding the tokens of the whole file (five times the size of a position-heavy `.dat`).
#[derive(Clone, Debug)]
pub(crate) struct Lexer<'a> {
    src: &'a [u8],
    i: usize,
    line_start: bool,
}

impl<'a> Lexer<'a> {
    pub(crate) fn new(src: &'a [u8]) -> Lexer<'a> {
        Lexer {
            src,
            i: 0,
            line_start: true,
        }
    }

    /// Byte offset of the next token.
    pub(crate) fn offset(&self) -> usize {
        self.i
    }

    /// Continues lexing at `i`, the start of a line (after a line the parser read itself).
    pub(super) fn resume_at_line(&mut self, i: usize) {
        self.i = i;
        self.line_start = true;
    }
}

impl Iterator for Lexer<'_> {
    type Item = Token;

    fn next(&mut self) -> Option<Token> {
        let src = self.src;
        let mut i = self.i;
        if i >= src.len() {
            return None;
        }
        if i == 0 && src.starts_with(crate::syntax::BOM) {
            self.i = 3;
            return Some(Token {
                kind: TokenKind::Bom,
                start: 0,
                end: 3,
            });
        }
        let line_start = self.line_start;
        let b = src[i];
        let start = i;
        let kind = match b {
            b'\n' => {
                i += 1;
                TokenKind::Newline
            }
            b'\r' => {
                i += if src.get(i + 1) == Some(&b'\n') { 2 } else { 1 };
                TokenKind::Newline
            }
            _ if SPACE[b as usize] => {
                i = run_end(src, i + 1, |c| SPACE[c as usize]);
                TokenKind::Whitespace
            }
            b';' => {
                i = line_end(src, i);
                TokenKind::Comment
            }
            b'&' if line_start => {
                i = line_end(src, i);
                TokenKind::Header
            }
            b'"' | b'\'' => {
                let j = run_end(src, i + 1, |c| c != b && c != b'\n' && c != b'\r');
                if src.get(j) == Some(&b) {
                    i = j + 1;
                    if b == b'"' {
                        TokenKind::Str
                    } else {
                        TokenKind::Quoted
                    }
                } else {
                    i = j;
                    TokenKind::Unterminated
                }
            }
            b'#' if src.get(i + 1).is_some_and(|&c| is_ident_start(c)) => {
                i = run_end(src, i + 2, |c| IDENT[c as usize]);
                TokenKind::Enum
            }
            b'0'..=b'9' => {
                i = number_end(src, i);
                TokenKind::Number
            }
            b'.' if src.get(i + 1).is_some_and(u8::is_ascii_digit) => {
                i = number_end(src, i);
                TokenKind::Number
            }
            _ if is_ident_start(b) => {
                i = run_end(src, i + 1, |c| IDENT[c as usize]);
                TokenKind::Ident
            }
            0x80..=0xFF => {
                i += 1;
                while i < src.len() && src[i] >= 0x80 {
                    i += 1;
                }
                TokenKind::Unknown
            }
            _ => {
                let two = matches!(
                    (b, src.get(i + 1)),
                    (b'=', Some(b'=')) | (b'<', Some(b'>' | b'=')) | (b'>', Some(b'='))
                );
                i += if two { 2 } else { 1 };
                TokenKind::Punct
            }
        };
        self.line_start = match kind {
            TokenKind::Newline => true,
            TokenKind::Whitespace => line_start,
            _ => false,
        };
        self.i = i;
        Some(Token {
            kind,
            start: start as u32,
            end: i as u32,
        })
    }
}

/// End of `digits [. digits] [E [+-] digits]` (or `. digits …`) starting at `i`.
pub(super) fn number_end(src: &[u8], mut i: usize) -> usize {
    while i < src.len() && src[i].is_ascii_digit() {
        i += 1;
    }
    if src.get(i) == Some(&b'.') {
        i += 1;
        while i < src.len() && src[i].is_ascii_digit() {
            i += 1;
        }
    }
    if matches!(src.get(i), Some(b'e' | b'E')) {
        let mut j = i + 1;
        if matches!(src.get(j), Some(b'+' | b'-')) {
            j += 1;
        }
        if src.get(j).is_some_and(u8::is_ascii_digit) {
            while j < src.len() && src[j].is_ascii_digit() {
                j += 1;
            }
            i = j;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(src: &[u8]) -> Vec<(TokenKind, &[u8])> {
        lex(src)
            .into_iter()
            .map(|t| (t.kind, t.text(src)))
            .collect()
    }

    fn covers(src: &[u8]) {
        let toks = lex(src);
        let mut pos = 0u32;
        for t in &toks {
            assert_eq!(t.start, pos);
            assert!(t.end > t.start);
            pos = t.end;
        }
        assert_eq!(pos as usize, src.len());
    }

    #[test]
    fn bom_then_header() {
        let src = b"\xEF\xBB\xBF&ACCESS RVP\r\nDEF a()";
        use TokenKind::*;
        assert_eq!(
            kinds(src)[..3],
            [
                (Bom, &b"\xEF\xBB\xBF"[..]),
                (Header, b"&ACCESS RVP"),
                (Newline, b"\r\n")
            ]
        );
        covers(src);
    }

    #[test]
    fn mixed_newlines_are_one_token_each() {
        let src = b"a\r\nb\rc\nd";
        let nl: Vec<_> = kinds(src)
            .into_iter()
            .filter(|(k, _)| *k == TokenKind::Newline)
            .map(|(_, t)| t)
            .collect();
        assert_eq!(nl, [&b"\r\n"[..], b"\r", b"\n"]);
    }

    #[test]
    fn fold_line_is_one_comment() {
        let src = b";FOLD LIN P1 Vel=2 m/s CPDAT1 Tool[1]:gun;%{PE}%R 8.3.31,%MKUKATPBASIS,%P 1:LIN\nLIN XP1";
        let k = kinds(src);
        assert_eq!(k[0].0, TokenKind::Comment);
        assert_eq!(
            k[0].1,
            &src[..src.iter().position(|&b| b == b'\n').unwrap()]
        );
    }

    #[test]
    fn bit_strings_enums_and_numbers() {
        use TokenKind::*;
        let src = b"S 'B010',T 'H1F' #BASE 1.0E+02 .5 7";
        let k: Vec<_> = kinds(src)
            .into_iter()
            .filter(|(k, _)| *k != Whitespace)
            .collect();
        assert_eq!(
            k,
            [
                (Ident, &b"S"[..]),
                (Quoted, b"'B010'"),
                (Punct, b","),
                (Ident, b"T"),
                (Quoted, b"'H1F'"),
                (Enum, b"#BASE"),
                (Number, b"1.0E+02"),
                (Number, b".5"),
                (Number, b"7"),
            ]
        );
    }

    #[test]
    fn cp1252_in_comment_stays_in_comment_and_outside_is_unknown() {
        let src = b"; Schwei\xDFpunkt\nX\xE4=1";
        let k = kinds(src);
        assert_eq!(k[0], (TokenKind::Comment, &b"; Schwei\xDFpunkt"[..]));
        assert!(k.contains(&(TokenKind::Unknown, &b"\xE4"[..])));
        covers(src);
    }

    #[test]
    fn unterminated_string_stops_at_line_end() {
        let src = b"A=\"abc\nB=1";
        let k = kinds(src);
        assert_eq!(k[2], (TokenKind::Unterminated, &b"\"abc"[..]));
        assert_eq!(k[3].0, TokenKind::Newline);
    }

    #[test]
    fn ampersand_only_starts_a_header_at_line_start() {
        let k = kinds(b"  &REL 3\nA=B&C");
        assert_eq!(k[1], (TokenKind::Header, &b"&REL 3"[..]));
        assert!(k.contains(&(TokenKind::Punct, &b"&"[..])));
    }

    #[test]
    fn two_char_operators() {
        let k = kinds(b"a==b<>c<=d>=e");
        let ops: Vec<_> = k
            .iter()
            .filter(|(k, _)| *k == TokenKind::Punct)
            .map(|(_, t)| *t)
            .collect();
        assert_eq!(ops, [&b"=="[..], b"<>", b"<=", b">="]);
    }

    #[test]
    fn arbitrary_bytes_are_covered() {
        covers(b"\x00\xff'\"#1e+;&\r\r\n.");
        covers(b"1.e5 1E 1e-");
    }
}
