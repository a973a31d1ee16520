//! The RAPID lexer: bytes in, tokens with byte spans out, trivia included.
//!
//! Every byte of the source belongs to exactly one token, so concatenating the tokens gives the
//! source back. Whitespace, each newline (`\n`, `\r\n`, bare `\r`), `!` comments, a BOM and
//! `%%%` header lines are tokens like any other; the parser skips them but the tree keeps them.
//!
//! The lexer streams: it keeps no token vector (a 50 MB module has ~20 M tokens, and a vector of
//! them would be larger than the file). It dispatches on the first byte by hand; identifiers
//! and based numbers are small nom 8 recognisers over bytes, decimal numbers a hand loop.

use nom::IResult;
use nom::Parser as _;
use nom::bytes::complete::{tag_no_case, take_while1};

use crate::syntax::BOM;

/// What a token is. Trivia kinds are listed first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TokenKind {
    /// Spaces, tabs, form feeds, a DOS end-of-file byte (0x1A).
    Whitespace,
    /// `\n`, `\r\n` or a bare `\r`.
    Newline,
    /// `!` up to (not including) the end of the line; any bytes, Latin-1 included.
    Comment,
    /// The UTF-8 byte order mark at offset 0.
    Bom,
    /// One line of a `%%%` header block, from the opening `%%%` line to the closing one.
    HeaderLine,
    /// Letters, digits and `_`, starting with a letter or `_`; keywords are identifiers too
    /// (RAPID keywords are case-insensitive and resolved by the parser).
    Ident,
    /// `12`, `-` excluded; `1.5`, `.5`, `1.`, `9E9`, `9E+09`, `2.69e-7`, `0xFF`, `0b101`, `0o17`.
    Number,
    /// `"..."` with `""` for a quote inside; any bytes.
    Str,
    /// A string without its closing quote before the end of the line.
    UnterminatedStr,
    /// An editor placeholder: `<SMT>`, `<EXP>`, `<ARG>`, `<ID>`, `<DN>`, ...
    Placeholder,
    /// `:=`
    Assign,
    /// `<=`, `>=`, `<>`
    Compare2,
    /// Any other single ASCII punctuation byte: `( ) [ ] { } , ; : = + - * / < > \ . % ? ^`.
    Punct,
    /// Bytes that cannot start any token (non-ASCII or control bytes outside comments/strings).
    Unknown,
    /// End of input (empty span).
    Eof,
}

impl TokenKind {
    /// Whitespace, newlines, comments, the BOM: what the parser steps over.
    pub fn is_trivia(self) -> bool {
        matches!(
            self,
            TokenKind::Whitespace | TokenKind::Newline | TokenKind::Comment | TokenKind::Bom
        )
    }
}

/// A token: its kind and the byte range `start..end` of the source (u32 keeps it 12 bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Token {
    /// What the token is.
    pub kind: TokenKind,
    /// An identifier spelled like a RAPID keyword (any case): the parser compares keyword text
    /// only for these, so ordinary names cost one flag test.
    pub keyword: bool,
    /// Its first byte in the source.
    pub start: u32,
    /// One past its last byte.
    pub end: u32,
}

impl Token {
    /// The empty end token at the source's start: what a parser holds before it lexes.
    pub(crate) const NONE: Token = Token {
        kind: TokenKind::Eof,
        keyword: false,
        start: 0,
        end: 0,
    };

    /// `start..end` as a [`crate::syntax::Span`].
    pub fn span(self) -> crate::syntax::Span {
        crate::syntax::Span::new(self.start as usize, self.end as usize)
    }

    /// The token's bytes (empty if the token does not fit `src`; never panics).
    pub fn text(self, src: &[u8]) -> &[u8] {
        src.get(self.start as usize..self.end as usize)
            .unwrap_or(&[])
    }

    /// The single punctuation byte of a [`TokenKind::Punct`] token, else 0.
    pub fn punct(self, src: &[u8]) -> u8 {
        if self.kind == TokenKind::Punct {
            src.get(self.start as usize).copied().unwrap_or(0)
        } else {
            0
        }
    }
}

/// Editor placeholders RobotStudio and the FlexPendant write into unfinished code.
const PLACEHOLDERS: &[&[u8]] = &[
    b"SMT", b"EXP", b"ARG", b"ID", b"DN", b"VAR", b"PAR", b"TDN", b"DDN", b"RDN", b"DIM", b"CSE",
    b"ALT", b"EIT", b"TYPE", b"ANY",
];

/// A streaming lexer. Cheap to copy, which is how the parser looks ahead.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lexer<'a> {
    src: &'a [u8],
    pos: usize,
    /// Inside a `%%%` header block (between the opening and closing `%%%` lines).
    in_header: bool,
    /// At the start of a line (only whitespace seen since the last newline).
    line_start: bool,
}

impl<'a> Lexer<'a> {
    /// Sources longer than `u32::MAX` bytes are not lexed (the parser reports them).
    pub(crate) fn new(src: &'a [u8]) -> Lexer<'a> {
        Lexer {
            src,
            pos: 0,
            in_header: false,
            line_start: true,
        }
    }

    /// Continues lexing at `pos`, which must be a token boundary in code (not at a line start,
    /// not in a header, comment or string): the parser's fast path skips what it read itself.
    pub(crate) fn seek(&mut self, pos: usize) {
        self.pos = pos.min(self.src.len());
        self.line_start = false;
    }

    /// Steps over the blanks and line ends at the place, which would lex as whitespace and
    /// newline tokens, without making a token of each: the parser drops them, and two or
    /// three per line (the line end and the indentation) were a fifth of its lexing. The
    /// lexer is left as those tokens leave it. Not inside a header, whose lines are read
    /// whole, blanks included.
    pub(crate) fn skip_blanks(&mut self) {
        if self.in_header {
            return;
        }
        let mut line_start = self.line_start;
        let mut i = self.pos;
        while let Some(&c) = self.src.get(i) {
            match c {
                b'\n' | b'\r' => line_start = true,
                b' ' | b'\t' | 0x0C | 0x1A => {}
                _ => break,
            }
            i += 1;
        }
        self.pos = i;
        self.line_start = line_start;
    }

    /// The identifier `text` at the place, as [`Lexer::next_token`] would lex it there, when
    /// the source spells it there whole: `text` is an identifier lexed before (its
    /// first byte a letter or `_`), and `keyword` what that token said of it. A statement
    /// mostly starts as the one before it did (`MoveL`, `CONST`): one compare of its bytes
    /// stands for the dispatch and the scan of the identifier. `None`, with nothing read,
    /// otherwise (inside a header too, whose lines are read whole).
    #[inline]
    pub(crate) fn ident_again(&mut self, text: &[u8], keyword: bool) -> Option<Token> {
        if self.in_header || text.is_empty() {
            return None;
        }
        let rest = self.src.get(self.pos..)?;
        let spelled = rest
            .get(..text.len())
            .is_some_and(|r| crate::names::same_bytes(r, text));
        if !spelled || rest.get(text.len()).is_some_and(|&c| is_ident_continue(c)) {
            return None;
        }
        // What `next_token` leaves: past the identifier, no longer at a line's start.
        self.line_start = false;
        let mut t = self.token(TokenKind::Ident, text.len());
        t.keyword = keyword;
        Some(t)
    }

    fn token(&mut self, kind: TokenKind, len: usize) -> Token {
        let start = self.pos;
        self.pos = (start + len).min(self.src.len());
        Token {
            kind,
            keyword: false,
            start: start as u32,
            end: self.pos as u32,
        }
    }

    fn ident_token(&mut self, rest: &[u8]) -> Token {
        let len = ident_len(rest);
        let mut t = self.token(TokenKind::Ident, len);
        t.keyword = rest.get(..len).is_some_and(is_keyword);
        t
    }

    /// The next token; [`TokenKind::Eof`] (empty) at the end, forever. Rules `newline`,
    /// `whitespace`, `comment`, `bom`, `header_line`, `string`, `placeholder`, `assign`,
    /// `compare2` and `punct`.
    pub(crate) fn next_token(&mut self) -> Token {
        let rest = self.src.get(self.pos..).unwrap_or(&[]);
        let Some(&b) = rest.first() else {
            return self.token(TokenKind::Eof, 0);
        };
        let at_line_start = self.line_start;
        self.line_start = false;
        if b == b'\n' || b == b'\r' {
            self.line_start = true;
            let len = if b == b'\r' && rest.get(1) == Some(&b'\n') {
                2
            } else {
                1
            };
            return self.token(TokenKind::Newline, len);
        }
        if self.in_header || (at_line_start && rest.starts_with(b"%%%")) {
            // A header line runs to the end of the line; the block closes at the second `%%%`.
            let len = line_len(rest);
            if self.in_header && rest.starts_with(b"%%%") {
                self.in_header = false;
            } else if !self.in_header {
                self.in_header = true;
            }
            return self.token(TokenKind::HeaderLine, len);
        }
        match b {
            b' ' | b'\t' | 0x0C | 0x1A => {
                self.line_start = at_line_start;
                let len = rest
                    .iter()
                    .position(|&c| !matches!(c, b' ' | b'\t' | 0x0C | 0x1A))
                    .unwrap_or(rest.len());
                self.token(TokenKind::Whitespace, len)
            }
            b'!' => self.token(TokenKind::Comment, line_len(rest)),
            b'"' => {
                let (kind, len) = string_len(rest);
                self.token(kind, len)
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => self.ident_token(rest),
            b'0'..=b'9' => self.token(TokenKind::Number, number_len(rest).max(1)),
            b'.' if rest.get(1).is_some_and(u8::is_ascii_digit) => {
                self.token(TokenKind::Number, number_len(rest).max(1))
            }
            b':' if rest.get(1) == Some(&b'=') => self.token(TokenKind::Assign, 2),
            b'<' | b'>' if matches!(rest.get(1), Some(b'=')) => self.token(TokenKind::Compare2, 2),
            b'<' if rest.get(1) == Some(&b'>') => self.token(TokenKind::Compare2, 2),
            b'<' => match placeholder_len(rest) {
                Some(len) => self.token(TokenKind::Placeholder, len),
                None => self.token(TokenKind::Punct, 1),
            },
            0xEF if self.pos == 0 && rest.starts_with(BOM) => {
                self.line_start = true;
                self.token(TokenKind::Bom, BOM.len())
            }
            0xC0..=0xFF if is_letter(b) => self.ident_token(rest),
            b'(' | b')' | b'[' | b']' | b'{' | b'}' | b',' | b';' | b':' | b'=' | b'+' | b'-'
            | b'*' | b'/' | b'>' | b'\\' | b'.' | b'%' | b'?' | b'^' | b'&' | b'#' | b'@'
            | b'$' | b'|' | b'\'' | b'~' | b'`' => self.token(TokenKind::Punct, 1),
            _ => {
                let len = rest
                    .iter()
                    .position(|&c| {
                        c.is_ascii_graphic() || matches!(c, b' ' | b'\t' | b'\n' | b'\r')
                    })
                    .unwrap_or(rest.len())
                    .max(1);
                self.token(TokenKind::Unknown, len)
            }
        }
    }
}

impl Iterator for Lexer<'_> {
    type Item = Token;

    fn next(&mut self) -> Option<Token> {
        let t = self.next_token();
        (t.kind != TokenKind::Eof).then_some(t)
    }
}

/// Every token of `src`, trivia included (for tests and tools; the parser streams instead).
pub fn tokenize(src: &[u8]) -> Vec<Token> {
    Lexer::new(src).collect()
}

fn line_len(rest: &[u8]) -> usize {
    rest.iter()
        .position(|&c| c == b'\n' || c == b'\r')
        .unwrap_or(rest.len())
}

/// A string up to its closing quote (`""` is a quote inside); unterminated at the line's end.
fn string_len(rest: &[u8]) -> (TokenKind, usize) {
    let mut i = 1;
    while let Some(&c) = rest.get(i) {
        match c {
            b'"' if rest.get(i + 1) == Some(&b'"') => i += 2,
            b'"' => return (TokenKind::Str, i + 1),
            b'\n' | b'\r' => return (TokenKind::UnterminatedStr, i),
            _ => i += 1,
        }
    }
    (TokenKind::UnterminatedStr, i)
}

fn placeholder_len(rest: &[u8]) -> Option<usize> {
    let close = rest.iter().take(7).position(|&c| c == b'>')?;
    let name = rest.get(1..close)?;
    PLACEHOLDERS.contains(&name).then_some(close + 1)
}

/// Rule `letter` (grammars/rapid.ebnf): RAPID's character set is ISO 8859-1, whose letters are the
/// ASCII ones and 0xC0-0xFF except × (0xD7) and ÷ (0xF7): `PROC Ñ()` is a routine name.
const fn is_letter(c: u8) -> bool {
    c.is_ascii_alphabetic() || (c >= 0xC0 && c != 0xD7 && c != 0xF7)
}

/// The bytes that continue an identifier, by table: identifiers are the lexer's most frequent
/// token, and the table keeps its loop at one load per byte with Latin-1 letters included.
static IDENT_CONTINUE: [bool; 256] = {
    let mut table = [false; 256];
    let mut b = 0;
    while b < 256 {
        let c = b as u8;
        table[b] = is_letter(c) || c.is_ascii_digit() || c == b'_';
        b += 1;
    }
    table
};

/// A byte that continues an identifier.
#[inline(always)]
pub(super) fn is_ident_continue(c: u8) -> bool {
    IDENT_CONTINUE[c as usize]
}

/// `ident = letter { letter | digit | "_" }` (grammars/rapid.ebnf): the length of the
/// identifier `rest` starts with (its first byte is a letter or `_`).
pub(super) fn ident_len(rest: &[u8]) -> usize {
    1 + rest
        .iter()
        .skip(1)
        .take_while(|&&c| IDENT_CONTINUE[c as usize])
        .count()
}

/// `number = based | decimal [ exponent ]` (grammars/rapid.ebnf), with rules `decimal` and
/// `exponent`. A trailing `E` without
/// digits is not part of the number (`1E` lexes as `1` then `E`). Decimal numbers are the
/// hottest path of a robtarget file, so they are scanned by hand.
fn number_len(rest: &[u8]) -> usize {
    if rest.first() == Some(&b'0')
        && rest
            .get(1)
            .is_some_and(|c| matches!(c | 0x20, b'x' | b'b' | b'o'))
        && let Ok((_, m)) = based(rest)
    {
        return m.len();
    }
    let digits = |mut i: usize| {
        while rest.get(i).is_some_and(u8::is_ascii_digit) {
            i += 1;
        }
        i
    };
    let mut i = digits(0);
    if rest.get(i) == Some(&b'.') {
        i = digits(i + 1);
    }
    if matches!(rest.get(i), Some(b'e' | b'E')) {
        let mut j = i + 1;
        if matches!(rest.get(j), Some(b'+' | b'-')) {
            j += 1;
        }
        let k = digits(j);
        if k > j {
            i = k;
        }
    }
    i
}

/// Declares [`KEYWORDS`] and the exact test for them from one list, so that the filter built
/// from the list and the test cannot disagree.
macro_rules! keywords {
    ($($k:literal),* $(,)?) => {
        /// Every word the parser treats as a keyword somewhere (reserved words, operators,
        /// `NOT`), upper case.
        const KEYWORDS: &[&[u8]] = &[$($k),*];

        /// Whether `upper` (upper case) is one of [`KEYWORDS`].
        fn is_keyword_upper(upper: &[u8]) -> bool {
            matches!(upper, $($k)|*)
        }
    };
}

keywords! {
    b"MODULE", b"ENDMODULE", b"PROC", b"ENDPROC", b"FUNC", b"ENDFUNC", b"TRAP", b"ENDTRAP",
    b"RECORD", b"ENDRECORD", b"CONST", b"PERS", b"VAR", b"ALIAS", b"LOCAL", b"TASK", b"INOUT",
    b"IF", b"THEN", b"ELSEIF", b"ELSE", b"ENDIF", b"FOR", b"FROM", b"TO", b"STEP", b"DO",
    b"ENDFOR", b"WHILE", b"ENDWHILE", b"TEST", b"CASE", b"DEFAULT", b"ENDTEST", b"GOTO",
    b"RETURN", b"RAISE", b"EXIT", b"RETRY", b"TRYNEXT", b"CONNECT", b"WITH", b"ERROR", b"UNDO",
    b"BACKWARD", b"DIV", b"MOD", b"AND", b"OR", b"XOR", b"NOT",
}

/// The shortest and longest keyword.
const KEYWORD_LEN: std::ops::RangeInclusive<usize> = 2..=9;

/// For each keyword length, a bit per (first letter, second letter) pair some keyword of that
/// length starts with (letters by their low 5 bits, so either case): most identifiers are
/// names (`p8169`, `MoveL`, `tGun`), and this tells them from keywords with two loads instead
/// of an upper-cased copy and a string match. Bytes other than letters may share a pair's bits;
/// they only pass on to the exact test.
static KEYWORD_PAIRS: [[u32; 32]; 10] = {
    let mut table = [[0u32; 32]; 10];
    let mut k = 0;
    while k < KEYWORDS.len() {
        let w = KEYWORDS[k];
        table[w.len()][(w[0] & 31) as usize] |= 1 << (w[1] & 31);
        k += 1;
    }
    table
};

/// Whether `text` is a keyword, in any case. The pair test is inlined into each caller (a
/// call for it, per name the lexer and the fast paths read, was 0.7 M instructions of `check`
/// on a 2 MB module); the exact test, for the few names it lets through, is not.
#[inline]
pub(super) fn is_keyword(text: &[u8]) -> bool {
    let &[first, second, ..] = text else {
        return false;
    };
    KEYWORD_LEN.contains(&text.len())
        && KEYWORD_PAIRS[text.len()][(first & 31) as usize] & 1 << (second & 31) != 0
        && is_keyword_exactly(text)
}

/// [`is_keyword`] once the pair test passed.
#[inline(never)]
fn is_keyword_exactly(text: &[u8]) -> bool {
    let mut buf = [0u8; 9];
    for (b, c) in buf.iter_mut().zip(text) {
        *b = c.to_ascii_uppercase();
    }
    is_keyword_upper(&buf[..text.len()])
}

/// `based = "0x" hexdigits | "0b" bits | "0o" octdigits`.
fn based(i: &[u8]) -> IResult<&[u8], &[u8]> {
    let (rest, prefix) =
        nom::branch::alt((tag_no_case("0x"), tag_no_case("0b"), tag_no_case("0o"))).parse(i)?;
    let radix = match prefix.get(1).map(u8::to_ascii_lowercase) {
        Some(b'x') => 16,
        Some(b'b') => 2,
        _ => 8,
    };
    let (rest, _) = take_while1(move |c: u8| (c as char).is_digit(radix)).parse(rest)?;
    Ok((rest, i.get(..i.len() - rest.len()).unwrap_or(i)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(src: &[u8]) -> Vec<(TokenKind, String)> {
        tokenize(src)
            .into_iter()
            .map(|t| (t.kind, crate::syntax::latin1(t.text(src))))
            .collect()
    }

    proptest::proptest! {
        /// An identifier taken again is the token lexing gives there, and leaves the lexer as
        /// lexing does; where the text is not the identifier there, nothing is read.
        #[test]
        fn an_identifier_taken_again_is_the_token_lexed(
            text in proptest::sample::select(vec!["MoveL", "CONST", "p1", "IF", "_x"]),
            after in proptest::sample::select(vec![
                "", " p1;", "\r\n", "L p1;", "0", "_", "\u{c4}", ";", "(", "\\", "!c",
            ]),
            before in proptest::sample::select(vec!["", "  ", "x", "\r\n  ", "%%%\r\n"]),
        ) {
            let text_bytes = text.as_bytes();
            let src: Vec<u8> = format!("{before}{text}{after}")
                .chars()
                .map(|c| c as u8)
                .collect();
            let mut lexed = Lexer::new(&src);
            // Up to where the text is written, as the parser would have read it (past it
            // when what comes before runs into it, as `x` does).
            while lexed.pos < before.len() {
                lexed.next_token();
            }
            let (mut again, at) = (lexed, lexed.pos);
            let want = lexed.next_token();
            let is_it = want.kind == TokenKind::Ident && want.text(&src) == text_bytes;
            match again.ident_again(text_bytes, is_keyword(text_bytes)) {
                Some(t) => {
                    proptest::prop_assert!(is_it);
                    proptest::prop_assert_eq!(t, want);
                    proptest::prop_assert_eq!(again.next_token(), lexed.next_token());
                }
                None => {
                    proptest::prop_assert!(!is_it || lexed.in_header);
                    proptest::prop_assert_eq!(again.pos, at);
                }
            }
        }

        /// The pair filter never turns a keyword away: `is_keyword` is a case-blind compare
        /// with every keyword, for names, keywords in any case, and keywords one byte off.
        #[test]
        fn keywords_are_what_the_list_says(
            word in "[A-Za-z_][A-Za-z0-9_\u{c0}-\u{ff}]{0,10}",
            k in 0..KEYWORDS.len(),
            flip in proptest::collection::vec(proptest::bool::ANY, 9),
            edit in proptest::option::of((0usize..9, proptest::sample::select(b"aZ_0\xc4".to_vec()))),
        ) {
            let oracle = |t: &[u8]| KEYWORDS.iter().any(|k| k.eq_ignore_ascii_case(t));
            // Latin-1: each char one byte.
            let word: Vec<u8> = word.chars().map(|c| c as u8).collect();
            proptest::prop_assert_eq!(is_keyword(&word), oracle(&word));
            let mut kw: Vec<u8> = KEYWORDS[k]
                .iter()
                .zip(&flip)
                .map(|(&c, &f)| if f { c.to_ascii_lowercase() } else { c })
                .collect();
            proptest::prop_assert!(is_keyword(&kw));
            if let Some((at, c)) = edit {
                let at = at.min(kw.len() - 1);
                kw[at] = c;
                proptest::prop_assert_eq!(is_keyword(&kw), oracle(&kw));
            }
        }
    }

    proptest::proptest! {
        /// Skipping blanks before each token gives the tokens other than blanks and line ends
        /// that lexing them one by one gives, headers and BOMs included.
        #[test]
        fn skipped_blanks_leave_the_other_tokens_as_they_were(
            parts in proptest::collection::vec(proptest::sample::select(vec![
                " ", "  ", "\t", "\r", "\n", "\r\n", "\x0c", "%%%", "  %%%", "VERSION:1",
                "a", "p10", "!c", "\"s\"", ";", ":=", "1.5", "\u{feff}", "x y",
            ]), 0..24),
        ) {
            let src = parts.concat().into_bytes();
            let significant = |skip: bool| {
                let mut lex = Lexer::new(&src);
                let mut out = Vec::new();
                loop {
                    if skip {
                        lex.skip_blanks();
                    }
                    let t = lex.next_token();
                    if t.kind == TokenKind::Eof {
                        break out;
                    }
                    if !matches!(t.kind, TokenKind::Whitespace | TokenKind::Newline) {
                        out.push(t);
                    }
                }
            };
            proptest::prop_assert_eq!(significant(true), significant(false));
        }
    }

    fn concat(src: &[u8]) -> Vec<u8> {
        tokenize(src)
            .into_iter()
            .flat_map(|t| t.text(src).to_vec())
            .collect()
    }

    #[test]
    fn every_newline_style_is_one_token() {
        use TokenKind::*;
        let src = b"a\r\nb\rc\nd";
        assert_eq!(
            kinds(src),
            vec![
                (Ident, "a".into()),
                (Newline, "\r\n".into()),
                (Ident, "b".into()),
                (Newline, "\r".into()),
                (Ident, "c".into()),
                (Newline, "\n".into()),
                (Ident, "d".into()),
            ]
        );
    }

    #[test]
    fn numbers_in_every_style() {
        for text in [
            "9E9", "9E+09", "9E+9", "9e9", ".5", "1.", "12", "1.25", "2.69E-07", "0xFF", "0b101",
            "0o17",
        ] {
            let toks = tokenize(text.as_bytes());
            assert_eq!(toks.len(), 1, "{text}");
            assert_eq!(toks[0].kind, TokenKind::Number, "{text}");
        }
        // `1E` is a number then an identifier: the exponent needs digits.
        let toks = tokenize(b"1E;");
        assert_eq!(toks[0].text(b"1E;"), b"1");
        assert_eq!(toks[1].kind, TokenKind::Ident);
    }

    #[test]
    fn strings_with_doubled_quotes_and_latin1() {
        let src = b"\"say \"\"hi\"\" \xE4\" x";
        let toks = tokenize(src);
        assert_eq!(toks[0].kind, TokenKind::Str);
        assert_eq!(toks[0].end as usize, src.len() - 2);
        let bad = b"\"open\r\nx";
        assert_eq!(tokenize(bad)[0].kind, TokenKind::UnterminatedStr);
        assert_eq!(tokenize(bad)[0].text(bad), b"\"open");
    }

    #[test]
    fn comments_keep_windows_1252_bytes() {
        let src = b"! Schwei\xDFpunkt \x80\r\nx";
        let toks = tokenize(src);
        assert_eq!(toks[0].kind, TokenKind::Comment);
        assert_eq!(toks[0].text(src), b"! Schwei\xDFpunkt \x80");
        assert_eq!(toks[1].kind, TokenKind::Newline);
    }

    #[test]
    fn bom_and_header_block() {
        let src = b"\xEF\xBB\xBF%%%\r\n  VERSION:1\r\n  LANGUAGE:ENGLISH\r\n%%%\r\n\r\nMODULE m";
        use TokenKind::*;
        let k: Vec<TokenKind> = tokenize(src).into_iter().map(|t| t.kind).collect();
        assert_eq!(
            k,
            vec![
                Bom, HeaderLine, Newline, HeaderLine, Newline, HeaderLine, Newline, HeaderLine,
                Newline, Newline, Ident, Whitespace, Ident
            ]
        );
        assert_eq!(concat(src), src);
    }

    #[test]
    fn percent_inside_code_is_late_binding_not_header() {
        let src = b"  %\"proc\"+\"1\"%;";
        let toks = tokenize(src);
        assert_eq!(toks[1].kind, TokenKind::Punct);
        assert_eq!(toks[1].text(src), b"%");
    }

    #[test]
    fn placeholders_and_operators() {
        use TokenKind::*;
        assert_eq!(
            kinds(b"<SMT> a<=b <> <EXP> x<y"),
            vec![
                (Placeholder, "<SMT>".into()),
                (Whitespace, " ".into()),
                (Ident, "a".into()),
                (Compare2, "<=".into()),
                (Ident, "b".into()),
                (Whitespace, " ".into()),
                (Compare2, "<>".into()),
                (Whitespace, " ".into()),
                (Placeholder, "<EXP>".into()),
                (Whitespace, " ".into()),
                (Ident, "x".into()),
                (Punct, "<".into()),
                (Ident, "y".into()),
            ]
        );
        assert_eq!(kinds(b":=")[0].0, Assign);
    }

    #[test]
    fn header_only_at_line_start_and_dos_eof_is_whitespace() {
        use TokenKind::*;
        // `%%%` after code is punctuation, not a header; indented `%%%` opens one.
        let k: Vec<TokenKind> = tokenize(b"a %%%\n  %%%\n x\n%%%\x1A\x0C")
            .into_iter()
            .map(|t| t.kind)
            .collect();
        assert_eq!(
            k,
            vec![
                Ident, Whitespace, Punct, Punct, Punct, Newline, Whitespace, HeaderLine, Newline,
                HeaderLine, Newline, HeaderLine
            ]
        );
        assert_eq!(kinds(b"\x1A\x0C\t ")[0].0, Whitespace);
        assert_eq!(tokenize(b"\x1A\x0C\t ").len(), 1);
    }

    #[test]
    fn keywords_are_flagged_in_any_case_names_are_not() {
        let src = b"EndProc moveL iF Tool0 elseif x";
        let flags: Vec<bool> = tokenize(src)
            .into_iter()
            .filter(|t| t.kind == TokenKind::Ident)
            .map(|t| t.keyword)
            .collect();
        assert_eq!(flags, vec![true, false, true, false, true, false]);
    }

    #[test]
    fn a_sign_is_its_own_token_and_exponents_need_digits() {
        let src = b"-1.5E-3 +.5 2e+ 7.";
        let texts: Vec<String> = tokenize(src)
            .into_iter()
            .filter(|t| t.kind != TokenKind::Whitespace)
            .map(|t| crate::syntax::latin1(t.text(src)))
            .collect();
        assert_eq!(texts, vec!["-", "1.5E-3", "+", ".5", "2", "e", "+", "7."]);
    }

    #[test]
    fn unknown_bytes_are_kept() {
        let src = b"a \xC3\xA9 \x01b";
        assert_eq!(concat(src), src);
        assert!(tokenize(src).iter().any(|t| t.kind == TokenKind::Unknown));
    }

    /// The editor placeholders the lexer knows are the grammar's.
    #[test]
    fn placeholders_are_the_grammar_terminals() {
        use crate::syntax::grammar_check::{read, terminals};
        let mut grammar = terminals(&read("grammars/rapid.ebnf"), "placeholder");
        assert!(grammar.remove("<") && grammar.remove(">"));
        let known = PLACEHOLDERS
            .iter()
            .map(|p| String::from_utf8_lossy(p).into_owned())
            .collect();
        assert_eq!(grammar, known);
    }
}
