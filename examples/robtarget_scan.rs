//! A floor for `trackfix check`'s time, timed beside it by `scripts/perf-compare.py`: the least
//! a program can do and still have read every robtarget of a module. It maps the file, walks
//! its lines, and for each line declaring a robtarget reads the name and the 17 numbers as
//! `f64` and keeps a small record of them. No syntax is checked, nothing round-trips, no name
//! is resolved, no number is read exactly (a digit run scaled by a power of ten): what is left
//! between this and `check` is the price of doing those.
//!
//! ```text
//! cargo build --release --example robtarget_scan
//! target/release/examples/robtarget_scan FILE.mod   # prints: LINES lines TARGETS robtargets
//! ```

use std::fs::File;

/// Powers of ten a decimal's digit run is scaled by.
const TENS: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// What is kept of a robtarget: where its name is and two of its values.
struct Record {
    name_start: u32,
    name_len: u32,
    x: f64,
    eax_a: f64,
}

/// The digits from `*at` on, advanced past them, as an integer and a count.
fn digits(b: &[u8], at: &mut usize, mantissa: &mut u64) -> i32 {
    let mut n = 0;
    while let Some(d) = b.get(*at).filter(|d| d.is_ascii_digit()) {
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d - b'0'));
        *at += 1;
        n += 1;
    }
    n
}

/// The decimal `[+-]digits[.digits][E[+-]digits]` at `*at`, advanced past it.
fn number(b: &[u8], at: &mut usize) -> f64 {
    let negative = b.get(*at) == Some(&b'-');
    if negative || b.get(*at) == Some(&b'+') {
        *at += 1;
    }
    let mut mantissa = 0;
    digits(b, at, &mut mantissa);
    let mut exponent = 0;
    if b.get(*at) == Some(&b'.') {
        *at += 1;
        exponent -= digits(b, at, &mut mantissa);
    }
    if matches!(b.get(*at), Some(b'E' | b'e')) {
        *at += 1;
        let below = b.get(*at) == Some(&b'-');
        if below || b.get(*at) == Some(&b'+') {
            *at += 1;
        }
        let mut e = 0;
        digits(b, at, &mut e);
        let e = i32::try_from(e).unwrap_or(i32::MAX);
        exponent = exponent.saturating_add(if below { -e } else { e });
    }
    let scale = TENS[exponent.unsigned_abs().min(22) as usize];
    let v = mantissa as f64;
    let v = if exponent >= 0 { v * scale } else { v / scale };
    if negative { -v } else { v }
}

/// The record of the robtarget declared on `line` (at `offset` in the file), if it declares one.
fn robtarget(line: &[u8], offset: usize) -> Option<Record> {
    let at = memchr::memmem::find(line, b"robtarget ")? + b"robtarget ".len();
    let name_len = memchr::memchr(b':', &line[at..])?;
    let mut values = [0.0; 17];
    let mut read = 0;
    let mut i = at + name_len;
    while read < values.len() && i < line.len() {
        if line[i].is_ascii_digit() || line[i] == b'-' {
            values[read] = number(line, &mut i);
            read += 1;
        } else {
            i += 1;
        }
    }
    Some(Record {
        name_start: u32::try_from(offset + at).ok()?,
        name_len: u32::try_from(name_len).ok()?,
        x: values[0],
        eax_a: values[11],
    })
}

fn main() -> std::io::Result<()> {
    let path = std::env::args_os()
        .nth(1)
        .ok_or(std::io::ErrorKind::InvalidInput)?;
    let file = File::open(path)?;
    // Mapped, as `check` maps a large input: the two pay the same for the file's pages.
    #[allow(unsafe_code)]
    // SAFETY: the file is only read, and nothing else writes it while this runs.
    let map = unsafe { memmap2::Mmap::map(&file)? };
    let bytes: &[u8] = &map;
    let mut records = Vec::new();
    let (mut lines, mut start) = (0usize, 0);
    for end in memchr::memchr_iter(b'\n', bytes).chain([bytes.len()]) {
        lines += 1;
        records.extend(robtarget(&bytes[start..end], start));
        start = end + 1;
    }
    // Every record is read once, so that none of the work above can be left out.
    let check: f64 = records
        .iter()
        .map(|r| r.x + r.eax_a + f64::from(r.name_start ^ r.name_len))
        .sum();
    use std::io::Write as _;
    writeln!(
        std::io::stdout().lock(),
        "{lines} lines {} robtargets (checksum {check:.3})",
        records.len()
    )
}
