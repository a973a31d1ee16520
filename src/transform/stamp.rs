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

use crate::position::ParsedFile;
use crate::syntax::Span;

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
    /// trackfix's version.
    pub version: String,
}

impl Stamp {
    /// A stamp of this version of trackfix.
    pub fn new(command: &str, robot: Option<&str>, profile: Option<(&str, &str)>) -> Stamp {
        Stamp {
            command: command.to_owned(),
            robot: robot.map(str::to_owned),
            profile: profile.map(|(n, h)| (n.to_owned(), h.chars().take(12).collect())),
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
        s.push_str(&format!(" version={}", self.version));
        s
    }

    /// Reads a stamp comment's text (after the comment mark); `None` if it is no stamp.
    fn parse(text: &str) -> Option<Stamp> {
        let rest = text.trim().strip_prefix(TAG)?;
        let mut words = split_tokens(rest).into_iter();
        let command = words.next()?;
        let mut stamp = Stamp {
            command,
            robot: None,
            profile: None,
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

fn find_in(src: &[u8], dialect: &dyn crate::dialect::Dialect) -> Option<(Stamp, Span)> {
    let mark = dialect.line_comment()?;
    let (_, after) = header(src, dialect.header_keywords())?;
    let (start, end, next) = lines(&src[after..]).next()?;
    let text = crate::syntax::latin1(&src[after + start..after + end]);
    let comment = text.trim_start().strip_prefix(mark)?;
    let stamp = Stamp::parse(comment)?;
    Some((stamp, Span::new(after + start, after + next)))
}

/// `src` with `stamp` as the line after its header: an existing stamp is replaced, else the line
/// is inserted, with the header line's own line end. `None` when the language has no line
/// comment or the file no header (nothing to put it after).
pub fn write(src: &[u8], dialect: &dyn crate::dialect::Dialect, stamp: &Stamp) -> Option<Vec<u8>> {
    let mark = dialect.line_comment()?;
    let (end, next) = header(src, dialect.header_keywords())?;
    let eol: &[u8] = if next > end { &src[end..next] } else { b"\n" };
    let mut line = format!("{mark} {}", stamp.text()).into_bytes();
    line.extend_from_slice(eol);
    let mut out = Vec::with_capacity(src.len() + line.len() + 1);
    match find_in(src, dialect) {
        Some((_, span)) => {
            out.extend_from_slice(&src[..span.start]);
            out.extend_from_slice(&line);
            out.extend_from_slice(&src[span.end..]);
        }
        None => {
            out.extend_from_slice(&src[..next]);
            if next == end {
                // The header is the file's last line, without a terminator.
                out.extend_from_slice(eol);
                line.truncate(line.len() - eol.len());
            }
            out.extend_from_slice(&line);
            out.extend_from_slice(&src[next..]);
        }
    }
    Some(out)
}

/// `src` without its stamp line (as it was before trackfix stamped it), if it has one.
pub fn strip(src: &[u8], dialect: &dyn crate::dialect::Dialect) -> Option<Vec<u8>> {
    let (_, span) = find_in(src, dialect)?;
    let mut out = src[..span.start].to_vec();
    out.extend_from_slice(&src[span.end..]);
    Some(out)
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
        // A file without a header (nothing to follow) is not stamped.
        assert_eq!(write(b"DECL INT i\n", &KRL, &stamp()), None);
        // An ordinary comment after the header is not a stamp.
        assert_eq!(find_in(b"DEF a()\n; trackfix is great\nEND\n", &KRL), None);
    }
}
