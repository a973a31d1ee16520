//! Numeric literals that keep their original text and write new values in the same style.

use std::num::NonZeroU32;

use super::EditText;
use super::edit::INLINE;

/// A numeric literal as written: `12`, `-0.5`, `.5`, `9E9`, `9E+09`, `9e+9`, `2.69E-07`.
///
/// Like toml_edit's `Formatted<T>`, the value and the style of its text travel together: an
/// unchanged value keeps its original bytes (they stay in the source, found by the field's span),
/// a changed one is written with the original's decimals and style (no leading zero for `.5`,
/// the same exponent for `1.5E+2`). The text itself is not copied: a 50 MB module holds millions
/// of literals, and an allocation each would dominate parsing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NumLit {
    value: f64,
    /// Decimal places the text resolves: mantissa decimals minus the exponent
    /// (`9E+09` → -9, `2.69E-07` → 9, `1.50` → 2).
    /// (Saturated to ±32767: beyond 12 places every rewrite writes the same.)
    precision: i16,
    /// The exponent as written, if the text has one that a rewrite can keep.
    exponent: Option<Exponent>,
    /// [`PLUS`], [`LEADING_POINT`]: kept in one byte so that a literal stays 16 bytes (a 50 MB
    /// module holds millions).
    style: u8,
    /// Digits of the mantissa before the point (0 for `.5`; saturated at 255).
    int_digits: u8,
}

/// [`NumLit::style`]: the text starts with an explicit `+`.
const PLUS: u8 = 1;
/// [`NumLit::style`]: no digit before the point (`.5`, `-.25`).
const LEADING_POINT: u8 = 2;

/// The integer digits a rewritten mantissa may have and keep its literal's exponent: a value
/// that moved past 1000 times its original exponent is written plainly.
const EXPONENT_INT_DIGITS: usize = 3;

/// How a literal's exponent is spelled, so that a rewrite writes the same suffix.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Exponent {
    value: i8,
    /// `E` rather than `e`.
    upper: bool,
    /// The sign as written: `+`, `-` (also of `E-0`), or 0 for none.
    sign: u8,
    /// Digits written, leading zeros included (`E+09` → 2).
    digits: u8,
}

impl Exponent {
    /// Appends the suffix as written: `E+09`.
    fn write(self, out: &mut Digits) {
        out.push(if self.upper { b'E' } else { b'e' });
        if self.sign != 0 {
            out.push(self.sign);
        }
        // |value| < 100 (see `NumLit::parse`): one or two digits.
        let v = self.value.unsigned_abs();
        let len = if v >= 10 { 2 } else { 1 };
        for _ in len..self.digits as usize {
            out.push(b'0');
        }
        if v >= 10 {
            out.push(b'0' + v / 10 % 10);
        }
        out.push(b'0' + v % 10);
    }
}

/// A number's text built on the stack: a rewritten literal is at most a sign, 23 integer
/// digits, a point, 18 decimals and a 5-byte exponent suffix. Writing millions of literals
/// through `String`s was an allocation each.
struct Digits {
    bytes: [u8; 64],
    len: usize,
}

impl Digits {
    fn new() -> Digits {
        Digits {
            bytes: [0; 64],
            len: 0,
        }
    }

    fn push(&mut self, b: u8) {
        // Never full (see above); a byte past the end would be dropped, not a panic.
        if let Some(slot) = self.bytes.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }

    fn extend(&mut self, bytes: &[u8]) {
        // Never full (see above); what would not fit is dropped, not a panic.
        let end = (self.len + bytes.len()).min(self.bytes.len());
        let n = end - self.len;
        self.bytes[self.len..end].copy_from_slice(&bytes[..n]);
        self.len = end;
    }

    fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..self.len).unwrap_or(&[])
    }

    /// `0.512` → `.512`, `-0.512` → `-.512`: drops the integer `0` of a mantissa below 1.
    fn drop_leading_zero(&mut self) {
        let text = self.as_bytes();
        let Some(at) = text.iter().position(u8::is_ascii_digit) else {
            return;
        };
        if text.get(at..at + 2) == Some(b"0.") {
            self.bytes.copy_within(at + 1..self.len, at);
            self.len -= 1;
        }
    }

    fn as_string(&self) -> String {
        // Only ASCII was written.
        self.as_bytes().iter().map(|&b| b as char).collect()
    }
}

impl NumLit {
    /// Parses a whole literal; `None` if `bytes` is not exactly one number.
    pub fn parse(bytes: &[u8]) -> Option<NumLit> {
        match NumLit::parse_prefix(bytes)? {
            (lit, len) if len == bytes.len() => Some(lit),
            _ => None,
        }
    }

    /// Parses the decimal literal that `bytes` starts with, and its length: what [`parse`](Self::parse)
    /// gives for `&bytes[..len]`. `None` if `bytes` does not start with one, or if an exponent
    /// letter follows without digits (`1E`, which a lexer ends before the letter). A parser that
    /// scans its numbers with this hands the literal on instead of having it parsed again.
    #[inline]
    pub fn parse_prefix(bytes: &[u8]) -> Option<(NumLit, usize)> {
        match Plain::read(bytes) {
            Some(p) => Some((p.lit(), p.len)),
            None => NumLit::parse_general(bytes),
        }
    }

    /// The value and the packed literal ([`pack`](Self::pack) with its length) of what
    /// [`parse_prefix`](Self::parse_prefix) reads; `None` also where that does not pack. A
    /// packed list reads each field of a target again from the source so: through a
    /// [`NumLit`] and `pack`'s checks (which a literal from anywhere needs) the packing cost
    /// half as much again as the reading; what the fast path reads always packs, and its word
    /// is built from what was read. Inlined into the list's reading of each field, as
    /// `parse_prefix` is into the parser's.
    #[inline(always)]
    pub(crate) fn parse_packed(bytes: &[u8]) -> Option<(f64, PackedLit)> {
        match Plain::read(bytes) {
            Some(p) => Some((p.value, p.packed()?)),
            None => {
                let (lit, len) = NumLit::parse_general(bytes)?;
                Some((lit.value, lit.pack(len)?))
            }
        }
    }

    /// The fast path of [`parse_prefix`](Self::parse_prefix) alone ([`Plain::read`]).
    #[cfg(test)]
    fn parse_plain(bytes: &[u8]) -> Option<(NumLit, usize)> {
        Plain::read(bytes).map(|p| (p.lit(), p.len))
    }

    /// [`parse_prefix`](Self::parse_prefix) for every literal: any number of digits, any
    /// exponent (through `str::parse` where the fast path does not give the value exactly).
    #[inline(never)]
    fn parse_general(bytes: &[u8]) -> Option<(NumLit, usize)> {
        let mut i = 0;
        if matches!(bytes.first(), Some(b'+' | b'-')) {
            i += 1;
        }
        let int_start = i;
        // The digits as an integer, for the exact fast path below (valid up to 19 digits).
        let mut mantissa = 0u64;
        let mut push = |d: u8| mantissa = mantissa.wrapping_mul(10).wrapping_add((d - b'0') as u64);
        while let Some(&d) = bytes.get(i).filter(|d| d.is_ascii_digit()) {
            push(d);
            i += 1;
        }
        let int_digits = i - int_start;
        let mut digits = int_digits;
        let mut decimals = 0i32;
        let point = bytes.get(i) == Some(&b'.');
        if point {
            i += 1;
            let frac_start = i;
            while let Some(&d) = bytes.get(i).filter(|d| d.is_ascii_digit()) {
                push(d);
                i += 1;
            }
            decimals = (i - frac_start) as i32;
            digits += i - frac_start;
        }
        if digits == 0 {
            return None;
        }
        let mut exponent = 0i32;
        let mut style = None;
        if let Some(&letter @ (b'e' | b'E')) = bytes.get(i) {
            i += 1;
            let negative = bytes.get(i) == Some(&b'-');
            let sign = match bytes.get(i) {
                Some(&s @ (b'+' | b'-')) => {
                    i += 1;
                    s
                }
                _ => 0,
            };
            let exp_start = i;
            while bytes.get(i).is_some_and(u8::is_ascii_digit) {
                exponent = exponent
                    .saturating_mul(10)
                    .saturating_add((bytes[i] - b'0') as i32);
                i += 1;
            }
            if i == exp_start {
                return None;
            }
            if negative {
                exponent = -exponent;
            }
            style = Some((letter == b'E', sign, i - exp_start));
        }
        let len = i;
        let bytes = bytes.get(..len)?;
        let power = exponent.saturating_sub(decimals);
        let value = match exact_fast_path(mantissa, digits, power) {
            Some(v) if bytes.first() == Some(&b'-') => -v,
            Some(v) => v,
            None => {
                // Only ASCII digits, signs, '.', 'e' remain here, so the text is valid UTF-8.
                let text = std::str::from_utf8(bytes).ok()?;
                text.parse().ok()?
            }
        };
        if !value.is_finite() {
            return None;
        }
        // An exponent a rewrite can keep: small enough to spell again (|e| < 100, up to 3
        // digits as written).
        let exponent_style = style.and_then(|(upper, sign, digits)| {
            Some(Exponent {
                value: i8::try_from(exponent)
                    .ok()
                    .filter(|e| e.unsigned_abs() < 100)?,
                upper,
                sign,
                digits: u8::try_from(digits).ok().filter(|&d| d <= 3)?,
            })
        });
        Some((
            NumLit {
                value,
                precision: decimals
                    .saturating_sub(exponent)
                    .clamp(i16::MIN as i32, i16::MAX as i32) as i16,
                exponent: exponent_style,
                style: if bytes.first() == Some(&b'+') {
                    PLUS
                } else {
                    0
                } | if point && int_digits == 0 {
                    LEADING_POINT
                } else {
                    0
                },
                int_digits: int_digits.min(u8::MAX as usize) as u8,
            },
            len,
        ))
    }

    /// The literal as a float, for the math; the text itself stays in the tree.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// Decimal places the original text resolves (negative for `9E9`).
    pub fn precision(&self) -> i32 {
        self.precision as i32
    }

    /// The decimal places [`rewrite`](Self::rewrite) writes a new value with:
    /// `max(original decimals, min_decimals)` (at most 12).
    pub fn places(&self, min_decimals: usize) -> usize {
        (self.precision as i32)
            .clamp(0, 12)
            .max(min_decimals.min(12) as i32) as usize
    }

    /// The text to write for `new`, or `None` when the original text already says it.
    ///
    /// `new` is written with [`places`](Self::places) decimals; if it rounds to the same text as
    /// the original value at that precision, the original text is kept (so `0` stays `0` and
    /// `9E+09` stays `9E+09`). The text keeps the original's style where it has one, so that a
    /// later transform that brings the value back can give back its text (docs/design.md §5): an
    /// explicit `+`; no leading zero below 1 for `.5` (`.512`); and the same exponent for
    /// `1.5E+2` (`1.50123E+2`, `15.00123E+2`) while the mantissa has at most 3 integer digits
    /// (or as many as the original's), else the plain form (`150012.300`).
    pub fn rewrite(&self, new: f64, min_decimals: usize) -> Option<String> {
        // Only ASCII is written.
        self.rewrite_text(new, min_decimals)
            .map(|t| t.iter().map(|&b| b as char).collect())
    }

    /// [`rewrite`](Self::rewrite) as the bytes of an edit: the common number is built on the
    /// stack and kept inline, without an allocation.
    pub fn rewrite_text(&self, new: f64, min_decimals: usize) -> Option<EditText> {
        self.rewrite_parts(new, min_decimals).map(|(text, _)| text)
    }

    /// [`rewrite_text`](Self::rewrite_text) and the value the text reads back as (what
    /// [`NumLit::parse`] of it gives; NaN if it did not parse, which our own text always does).
    pub fn rewrite_read(&self, new: f64, min_decimals: usize) -> Option<(EditText, f64)> {
        self.rewrite_parts(new, min_decimals).map(read_back)
    }

    /// The text, and its value when known without reading it back.
    fn rewrite_parts(&self, new: f64, min_decimals: usize) -> Option<(EditText, Option<f64>)> {
        let places = self.places(min_decimals);
        self.rewrite_at(new, places, Scaled::of(self.value, places))
    }

    /// [`rewrite_parts`](Self::rewrite_parts) at `places`, with `own`: the literal's value
    /// rounded there ([`Scaled::of`]).
    ///
    /// Inlined into its callers (a round-trip rewrite writes every field through
    /// [`Rounded::rewrite_read`]): through a call, its text and value went back through
    /// memory, and the registers it used were saved and restored each time.
    #[inline]
    fn rewrite_at(
        &self,
        new: f64,
        places: usize,
        own: Option<Scaled>,
    ) -> Option<(EditText, Option<f64>)> {
        // Compare the rounded values as integers first: most fields of a corrected program
        // change, but the ones that don't (zeros, 9E9, unchanged quaternions) cost no text.
        if let (Some(a), Some(b)) = (Scaled::of(new, places), own) {
            if a == b {
                return None;
            }
            let text = match self.exponent {
                None => a.inline_text(places, self.style),
                Some(_) => None,
            };
            let text = text.unwrap_or_else(|| self.text_by_digits(a, places));
            return Some((text, a.read_back(places)));
        }
        self.rewrite_by_format(new, places)
    }

    /// [`rewrite_at`](Self::rewrite_at) for values [`Scaled`] does not take (beyond 2^35 or
    /// 12 places), through `format!`. Apart: its strings kept out of the common path, whose
    /// every call set up their room.
    #[cold]
    #[inline(never)]
    fn rewrite_by_format(&self, new: f64, places: usize) -> Option<(EditText, Option<f64>)> {
        let written = fixed(new, places);
        if written == fixed(self.value, places) {
            return None;
        }
        if self.style & PLUS != 0 && !written.starts_with('-') {
            return Some((EditText::from(format!("+{written}").into_bytes()), None));
        }
        Some((EditText::from(written.into_bytes()), None))
    }

    /// The text of `a` at `places` in the literal's style, built in a [`Digits`]: every form
    /// [`rewrite_at`](Self::rewrite_at) writes, and the reference of [`Scaled::inline_text`].
    fn text_by_digits(&self, a: Scaled, places: usize) -> EditText {
        let mut text = Digits::new();
        if self.style & PLUS != 0 && !a.negative {
            text.push(b'+');
        }
        match self.exponent.map(|e| (e, places as i32 + e.value as i32)) {
            // The same digits with the point moved by the exponent: `150123` units of
            // 10^-3 are `1.50123E+2`.
            Some((e, decimals))
                if (0..=18).contains(&decimals)
                    && a.int_digits(decimals as usize)
                        <= (self.int_digits as usize).max(EXPONENT_INT_DIGITS) =>
            {
                a.write(decimals as usize, &mut text);
                e.write(&mut text);
            }
            _ => a.write(places, &mut text),
        }
        if self.style & LEADING_POINT != 0 && places > 0 {
            text.drop_leading_zero();
        }
        EditText::from_bytes(text.as_bytes())
    }

    /// The literal with its value rounded at the places a rewrite with `min_decimals` writes,
    /// for several rewrites and comparisons at those places ([`Rounded`]).
    ///
    /// Always inlined: a round-trip rewrite rounds every literal it writes, and as a call the
    /// rounding (which the compiler took out of line once `Scaled::of` changed) was 80
    /// instructions a field, its result going back through memory (5.7 M of correct on the
    /// 2 MB bench module).
    #[inline(always)]
    pub fn rounded(&self, min_decimals: usize) -> Rounded {
        let places = self.places(min_decimals);
        let own = Scaled::of(self.value, places);
        let signed_units = match own {
            Some(s) if s.units < 1 << 39 => {
                let units = s.units as u64 as f64;
                if s.negative { -units } else { units }
            }
            _ => f64::NAN,
        };
        Rounded {
            lit: *self,
            places,
            own,
            signed_units,
        }
    }

    /// The text to write for an integer field (`cf1`, Status), or `None` if unchanged.
    pub fn rewrite_integer(&self, new: i64) -> Option<String> {
        if self.value == new as f64 {
            None
        } else {
            Some(new.to_string())
        }
    }
}

/// A literal and its value rounded at the places a rewrite of it writes ([`NumLit::rounded`]),
/// computed once: a round-trip rewrite writes each literal and compares what the inverse gives
/// back with its value at those places ([`Rounded::same`]), and rounded the literal's own value
/// again for each.
#[derive(Clone, Copy, Debug)]
pub struct Rounded {
    lit: NumLit,
    places: usize,
    own: Option<Scaled>,
    /// `own`'s units with their sign, as an `f64`: below 2^39 they are exact in one, and so
    /// is their difference with a product near them ([`Rounded::same`]). NaN where there are
    /// none or they are 2^39 or more.
    signed_units: f64,
}

impl Rounded {
    /// A rounding of no literal, to fill an array before each slot gets its own: filled by
    /// copies of the first literal's, the array took as many stores again as the roundings.
    pub const PLACEHOLDER: Rounded = Rounded {
        lit: NumLit {
            value: 0.0,
            precision: 0,
            exponent: None,
            style: 0,
            int_digits: 1,
        },
        places: 0,
        own: None,
        signed_units: f64::NAN,
    };

    /// The places a rewrite writes ([`NumLit::places`]).
    pub fn places(&self) -> usize {
        self.places
    }

    /// The literal's value.
    pub fn value(&self) -> f64 {
        self.lit.value
    }

    /// [`NumLit::rewrite_read`] with the `min_decimals` the rounding was made for; inlined, as
    /// [`same`](Self::same), into the rewrite that makes it for every field it writes.
    #[inline]
    pub fn rewrite_read(&self, new: f64) -> Option<(EditText, f64)> {
        self.lit
            .rewrite_at(new, self.places, self.own)
            .map(read_back)
    }

    /// [`same_at`]`(v, value, places)`: whether `v` reads as the literal's value at the places.
    ///
    /// Always inlined into a rewrite's check of what the inverse gives back, which makes it
    /// for every field it writes: through a call it cost half again what it does, and the
    /// plain hint stopped being followed (1.8 M of correct on the 2 MB bench module).
    ///
    /// By the distance of `v` scaled to the units from the literal's own units, where that
    /// decides it: `v` reads as the literal exactly when its exact scaled value is within half
    /// a unit of them. Near them (below 2^40) the product is within 2^-13 of the exact one and
    /// their difference is exact, so a distance more than 2^-12 from one half settles it
    /// either way (as [`Scaled::by_float`] settles the rounding); ties, NaN and the values
    /// without such units take [`same_as_rounded`]. Scaling `v` and comparing its units as a
    /// [`Scaled`] was twice the instructions, for every field a rewrite checks.
    #[inline(always)]
    pub fn same(&self, v: f64) -> bool {
        let distance = (v * EXACT_POWERS[self.places.min(22)] - self.signed_units).abs();
        if distance < 0.5 - 1.0 / 4096.0 {
            return true;
        }
        if distance > 0.5 + 1.0 / 4096.0 {
            return false;
        }
        same_as_rounded(v, self.lit.value, self.own, self.places)
    }

    /// [`same`](Self::same) the plain way, its reference in the tests.
    #[cfg(test)]
    fn same_plainly(&self, v: f64) -> bool {
        same_as_rounded(v, self.lit.value, self.own, self.places)
    }
}

/// A [`NumLit`] without its value, and the length of its text, in four bytes: with the value
/// and a `u32` start a numeric field is 16 bytes (a 20 MB module holds 1.7 million of them).
///
/// Bits 0-7 hold the length (1..=255) and 8-15 the integer digits; bit 16 is [`PLUS`] (and
/// [`LEADING_POINT`] is no integer digits). Bit 17 says an exponent is kept; then bit 18 is
/// its letter's case, 19-20 its sign as written (none, `+`, `-`, which the exponent's value
/// has), 21-22 its digits and 23-29 its absolute value (below 100), and the precision is not
/// stored: the length less the sign, integer digits and suffix is the point and decimals, and
/// the precision is the decimals less the exponent. Without a kept exponent, bits 18-31 are the
/// precision (14-bit two's complement).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PackedLit(NonZeroU32);

/// [`PackedLit`]: the exponent's sign as written, by its 2-bit code.
const EXPONENT_SIGNS: [u8; 4] = [0, b'+', b'-', 0];

/// [`PackedLit`]: the precision range bits 18-31 hold.
const PACKED_PRECISION: std::ops::RangeInclusive<i16> = -(1 << 13)..=(1 << 13) - 1;

impl PackedLit {
    /// The length of the literal's text.
    pub(crate) fn len(self) -> usize {
        (self.0.get() & 0xff) as usize
    }

    /// The packed word, to be stored and given back to [`PackedLit::from_bits`].
    pub(crate) fn bits(self) -> u32 {
        self.0.get()
    }

    /// The literal a word from [`PackedLit::bits`] packs; `None` for zero, which no literal
    /// packs to.
    pub(crate) fn from_bits(bits: u32) -> Option<PackedLit> {
        NonZeroU32::new(bits).map(PackedLit)
    }
}

impl NumLit {
    /// The literal without its value, with `len`, the length of its text; `None` if the text
    /// is empty or longer than 255 bytes, or the precision of a literal without a kept
    /// exponent is beyond ±8191 (`1E-9000`), or `len` is not what the text of this literal can
    /// be.
    #[inline]
    pub(crate) fn pack(&self, len: usize) -> Option<PackedLit> {
        // No literal is empty, and a length of at least 1 makes the word non-zero.
        let len = u8::try_from(len).ok().filter(|&l| l > 0)?;
        // The leading point is not stored: it is a literal without integer digits.
        let leading = if self.int_digits == 0 {
            LEADING_POINT
        } else {
            0
        };
        if self.style & !PLUS != leading {
            return None;
        }
        let plus = self.style & PLUS != 0;
        let mut bits = u32::from(len) | u32::from(self.int_digits) << 8 | u32::from(plus) << 16;
        match self.exponent {
            Some(e) => {
                let sign = EXPONENT_SIGNS.iter().position(|&s| s == e.sign)? as u32;
                let abs = e.value.unsigned_abs();
                // The exponent's sign is its written sign's; its precision follows from `len`.
                let signed = usize::from(plus || self.value.is_sign_negative());
                if e.digits > 3
                    || abs > 0x7f
                    || (e.value < 0 && e.sign != b'-')
                    || (e.value > 0 && e.sign == b'-')
                    || kept_precision(len, signed, self.int_digits, e) != self.precision
                {
                    return None;
                }
                bits |= 1 << 17
                    | u32::from(e.upper) << 18
                    | sign << 19
                    | u32::from(e.digits) << 21
                    | u32::from(abs) << 23;
            }
            None if PACKED_PRECISION.contains(&self.precision) => {
                bits |= (self.precision as u32 & 0x3fff) << 18;
            }
            None => return None,
        }
        NonZeroU32::new(bits).map(PackedLit)
    }

    /// The literal [`pack`](Self::pack) packed, with its value.
    #[inline]
    pub(crate) fn unpack(value: f64, packed: PackedLit) -> NumLit {
        let bits = packed.0.get();
        let int_digits = (bits >> 8) as u8;
        let plus = bits & 1 << 16 != 0;
        let style = if plus { PLUS } else { 0 } | if int_digits == 0 { LEADING_POINT } else { 0 };
        let (precision, exponent) = if bits & 1 << 17 != 0 {
            let sign = EXPONENT_SIGNS[(bits >> 19 & 3) as usize];
            let abs = (bits >> 23 & 0x7f) as i8;
            let e = Exponent {
                value: if sign == b'-' { -abs } else { abs },
                upper: bits & 1 << 18 != 0,
                sign,
                digits: (bits >> 21 & 3) as u8,
            };
            let signed = usize::from(plus || value.is_sign_negative());
            (kept_precision(bits as u8, signed, int_digits, e), Some(e))
        } else {
            // An arithmetic shift brings the 14-bit precision down with its sign.
            (((bits as i32) >> 18) as i16, None)
        };
        NumLit {
            value,
            precision,
            exponent,
            style,
            int_digits,
        }
    }
}

/// The precision of a literal with a kept exponent `e` whose text is `len` bytes: the text is a
/// sign (`signed`), `int_digits`, the point and decimals, and the suffix (`E`, sign, digits).
fn kept_precision(len: u8, signed: usize, int_digits: u8, e: Exponent) -> i16 {
    let suffix = 1 + usize::from(e.sign != 0) + e.digits as usize;
    let point_and_decimals = (len as usize).saturating_sub(signed + int_digits as usize + suffix);
    point_and_decimals.saturating_sub(1) as i16 - i16::from(e.value)
}

/// True when `a` and `b` read the same written with `places` decimals: the comparison
/// [`NumLit::rewrite`] makes before it keeps a literal's text.
pub fn same_at(a: f64, b: f64, places: usize) -> bool {
    same_as_rounded(a, b, Scaled::of(b, places), places)
}

/// [`same_at`] with `b` already rounded at `places` (`b_scaled`, [`Scaled::of`]).
#[inline]
fn same_as_rounded(a: f64, b: f64, b_scaled: Option<Scaled>, places: usize) -> bool {
    match (Scaled::of(a, places), b_scaled) {
        (Some(x), Some(y)) => x == y,
        _ => same_by_format(a, b, places),
    }
}

/// [`same_as_rounded`] for values [`Scaled`] does not take, by their texts; apart, as
/// [`NumLit::rewrite_by_format`].
#[cold]
#[inline(never)]
fn same_by_format(a: f64, b: f64, places: usize) -> bool {
    fixed(a, places) == fixed(b, places)
}

/// A rewrite's text with the value it reads back as: the one known from writing it, else
/// what [`NumLit::parse`] of the text gives (NaN if it did not parse, which our own text
/// always does).
///
/// Inlined into the rewrite that writes the text: there the value is nearly always known,
/// and through a call the text was moved in and out of it (1.1 M instructions of correct on
/// the 2 MB bench module); the parse is a call of its own.
#[inline]
fn read_back((text, read): (EditText, Option<f64>)) -> (EditText, f64) {
    let read = read
        .or_else(|| NumLit::parse(&text).map(|l| l.value()))
        .unwrap_or(f64::NAN);
    (text, read)
}

/// 10^0 … 10^19, the powers of ten a `u64` holds: what [`Scaled`] scales and splits by.
const POW10: [u64; 20] = {
    let mut p = [1u64; 20];
    let mut i = 1;
    while i < 20 {
        p[i] = p[i - 1] * 10;
        i += 1;
    }
    p
};

/// [`Scaled::by_float`]'s bound on the scaled value.
const TWO_TO_40: f64 = (1u64 << 40) as f64;

/// The `f64`s from 2^52 to 2^53 are the integers: [`Scaled::by_float`] rounds by adding it.
const TWO_TO_52: f64 = (1u64 << 52) as f64;

/// Powers of ten that are exact in an `f64`.
const EXACT_POWERS: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// `mantissa · 10^power` when one IEEE operation gives it exactly rounded (Clinger's fast
/// path: the mantissa and the power of ten are both exact doubles, so the single rounding of
/// the product or quotient is the correct one): every literal a robot program writes.
fn exact_fast_path(mantissa: u64, digits: usize, power: i32) -> Option<f64> {
    if digits > 19 || mantissa >= 1 << 53 {
        return None;
    }
    let m = mantissa as f64;
    match power {
        0..=22 => Some(m * EXACT_POWERS[power as usize]),
        -22..=-1 => Some(m / EXACT_POWERS[(-power) as usize]),
        _ => None,
    }
}

/// `value` with `places` decimals, without a negative zero.
pub fn fixed(value: f64, places: usize) -> String {
    if let Some(scaled) = Scaled::of(value, places) {
        let mut text = Digits::new();
        scaled.write(places, &mut text);
        return text.as_string();
    }
    let s = format!("{value:.places$}");
    if s.starts_with('-') && s[1..].bytes().all(|b| b == b'0' || b == b'.') {
        s[1..].to_owned()
    } else {
        s
    }
}

/// A value rounded to `places` decimals as an integer count of `10^-places`, computed exactly
/// from the binary value, the way `format!("{:.N}")` rounds (to nearest, ties to even); the
/// sign only if the rounded value is not zero. `None` outside the range this handles (more
/// than 12 places, |value| ≥ 2^35 or not finite), where the caller falls back to `format!`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Scaled {
    negative: bool,
    units: u128,
}

impl Scaled {
    #[inline]
    fn of(value: f64, places: usize) -> Option<Scaled> {
        // From 2 to 12 places a product below 2^40 is a value in range (below 2^40 / 100,
        // and finite): the range is asked only of what the multiplication leaves, and every
        // field a rewrite writes or compares (3 to 6 places) skips it.
        if (2..=12).contains(&places)
            && let Some(scaled) = Scaled::by_float(value, places)
        {
            return Some(scaled);
        }
        if !Scaled::in_range(value, places) {
            return None;
        }
        Scaled::by_float(value, places).or_else(|| Scaled::exactly(value, places))
    }

    /// [`of`](Self::of) without its shortcut from 2 places, its reference in the tests.
    #[cfg(test)]
    fn of_plainly(value: f64, places: usize) -> Option<Scaled> {
        if !Scaled::in_range(value, places) {
            return None;
        }
        Scaled::by_float(value, places).or_else(|| Scaled::exactly(value, places))
    }

    /// The values [`of`](Self::of) scales: finite, below 2^35 (34,000 km in mm: every
    /// coordinate, angle or quaternion a program holds) and at most 12 places.
    #[inline]
    fn in_range(value: f64, places: usize) -> bool {
        value.is_finite() && places <= 12 && value.abs() < 34_359_738_368.0
    }

    /// [`of`](Self::of) by one multiplication, where that decides the rounding: `None` when
    /// the scaled value is 2^40 or more, or within 2^-12 of a half unit, which
    /// [`exactly`](Self::exactly) settles. Below 2^40 the product of the value and the exact
    /// power of ten is within 2^-13 of the exact product (one rounding, 2^-53 relative), so a
    /// fraction further than that from one half rounds the same either way; the distance to
    /// the nearest integer is exact. Every rewrite and
    /// comparison scales a value (three a written field), and the exact path's 128-bit
    /// arithmetic was most of their cost.
    #[inline]
    fn by_float(value: f64, places: usize) -> Option<Scaled> {
        let x = value.abs() * EXACT_POWERS[places.min(22)];
        // Not below (or NaN): left to the exact path.
        if x.partial_cmp(&TWO_TO_40) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        // The nearest integer by adding 2^52, where a unit is 1: the sum rounds to it, its
        // low bits are it, and taking 2^52 off again is exact; so is the distance to it (the
        // two are within a factor 2 of each other, or the integer is 0), at most one half.
        // A conversion to an integer and back, with the checks `as` makes for its saturation,
        // was twice the instructions, and every written field scales two values.
        let big = x + TWO_TO_52;
        if (x - (big - TWO_TO_52)).abs() >= 0.5 - 1.0 / 4096.0 {
            return None;
        }
        let units = big.to_bits() - TWO_TO_52.to_bits();
        Some(Scaled {
            negative: value.is_sign_negative() && units != 0,
            units: u128::from(units),
        })
    }

    /// [`of`](Self::of) from the binary value exactly.
    #[inline(never)]
    fn exactly(value: f64, places: usize) -> Option<Scaled> {
        if !Scaled::in_range(value, places) {
            return None;
        }
        // value = mantissa · 2^exp exactly; below 2^35 with a 53-bit mantissa, exp < -17.
        let bits = value.to_bits();
        let biased = ((bits >> 52) & 0x7ff) as i32;
        let fraction = bits & ((1u64 << 52) - 1);
        let (mantissa, exp) = if biased == 0 {
            (fraction, -1074)
        } else {
            (fraction | (1u64 << 52), biased - 1075)
        };
        let shift = u32::try_from(-exp).ok().filter(|&s| s > 0)?;
        // mantissa < 2^53 and 10^places < 2^40: the product fits with 35 bits to spare.
        let product = mantissa as u128 * POW10[places] as u128;
        let units = if shift >= 128 {
            // product < 2^93, so the value is below half a unit.
            0
        } else {
            let quotient = product >> shift;
            let rest = product & ((1u128 << shift) - 1);
            let half = 1u128 << (shift - 1);
            if rest > half || (rest == half && quotient & 1 == 1) {
                quotient + 1
            } else {
                quotient
            }
        };
        Some(Scaled {
            negative: value.is_sign_negative() && units != 0,
            units,
        })
    }

    /// What [`NumLit::parse`] reads from these units written with `places` decimals, in any of
    /// the forms a rewrite writes (the digits are the units whichever way the point and the
    /// exponent move them): the same single division of its exact fast path, when that applies.
    fn read_back(self, places: usize) -> Option<f64> {
        if self.units >= 1 << 53 || places > 22 {
            return None;
        }
        // Below 2^53 the units are a u64 (a u128 conversion is a call), exactly an f64.
        let v = self.units as u64 as f64 / EXACT_POWERS[places];
        Some(if self.negative { -v } else { v })
    }

    /// [`NumLit::text_by_digits`] for a literal without an exponent and of `style`, written
    /// straight into the bytes of an inline [`EditText`]: its length known first, the digits
    /// from the last one back. `None` where the text is longer than an inline one or the
    /// units pass a `u64`. Nearly every written number is one of these (`-1520.873`), and the
    /// copies through the stack buffers, each a call, were most of the cost of writing it.
    ///
    /// A text of at most 7 digits and 1 to 7 decimals (every quaternion and coordinate below
    /// 10 m a program writes at its places) is put together in one word ([`by_word`]), not
    /// digit pair by digit pair: the division into the integer and the decimals, the count
    /// of the integer digits, the two loops and their bounds checks were 120 of the 235
    /// instructions a field of a corrected target took to write, by the word 80.
    ///
    /// [`by_word`]: Self::inline_by_word
    #[inline]
    fn inline_text(self, places: usize, style: u8) -> Option<EditText> {
        let units = u64::try_from(self.units).ok()?;
        if units < POW10[8]
            && let Some(text) = Scaled::inline_by_word(self.negative, units, places, style)
        {
            return Some(text);
        }
        let scale = *POW10.get(places)?;
        let (int, frac) = (units / scale, units % scale);
        let signed = self.negative || style & PLUS != 0;
        // `.512`: no integer `0` below 1 where the literal was written so.
        let int_len = if int == 0 && places > 0 && style & LEADING_POINT != 0 {
            0
        } else {
            1 + POW10[1..].iter().take_while(|&&p| int >= p).count()
        };
        let point = usize::from(places > 0);
        let len = usize::from(signed) + int_len + point + places;
        if len > INLINE {
            return None;
        }
        let mut bytes = [0u8; INLINE];
        put_digits(&mut bytes, len, frac, places);
        let int_end = len - point - places;
        if point > 0
            && let Some(slot) = bytes.get_mut(int_end)
        {
            *slot = b'.';
        }
        put_digits(&mut bytes, int_end, int, int_len);
        if signed {
            bytes[0] = if self.negative { b'-' } else { b'+' };
        }
        EditText::inline_array(bytes, len)
    }

    /// [`inline_text`](Self::inline_text) for `units` below 10^8 whose digits, the point
    /// left out, are at most 7 (with the integer `0` of a value below 1) and `places` 1 or
    /// more, else `None`. The units' 8 digits are one word ([`ascii_digits`]); the ones
    /// written are its last, from the first that is not a leading `0` or the integer digit
    /// (none for `.512`, where the literal was written so); the point goes in between by two
    /// shifts, and the sign before it all. Little-endian: a word's first byte is its lowest.
    #[inline(always)]
    fn inline_by_word(negative: bool, units: u64, places: usize, style: u8) -> Option<EditText> {
        let digits = ascii_digits(units);
        // How many digits the units have (0 for 0): the leading `0`s are the low bytes.
        let significant = 8 - ((digits ^ ZEROS).trailing_zeros() / 8) as usize;
        let int_len = if significant > places {
            significant - places
        } else {
            usize::from(style & LEADING_POINT == 0)
        };
        let n = int_len + places;
        if !(places >= 1 && n <= 7) {
            return None;
        }
        // The last `n` digits moved to the front, then the decimals one byte on for the
        // point: 8 bytes at most.
        let written = digits >> (8 * (8 - n));
        let int = written & ((1 << (8 * int_len)) - 1);
        let body = int
            | u64::from(b'.') << (8 * int_len)
            | (written >> (8 * int_len)) << (8 * int_len + 8);
        let signed = usize::from(negative || style & PLUS != 0);
        let mut bytes = [0u8; INLINE];
        bytes[0] = if negative { b'-' } else { b'+' };
        // Over the sign when there is none.
        bytes[signed..signed + 8].copy_from_slice(&body.to_le_bytes());
        EditText::inline_array(bytes, signed + n + 1)
    }

    /// Digits before the point when the units are written with `places` decimals (at least 1).
    fn int_digits(self, places: usize) -> usize {
        // By u64 where the units fit (a u128 division is a call).
        let Ok(units) = u64::try_from(self.units) else {
            let mut int = self.units / POW10[places] as u128;
            let mut n = 1;
            while int >= 10 {
                int /= 10;
                n += 1;
            }
            return n;
        };
        let int = units / POW10[places];
        1 + POW10[1..].iter().take_while(|&&p| int >= p).count()
    }

    /// Appends the digits: `-`, the integer part, and `places` (at most 18) decimals after a
    /// `.` — the value's own places, or more for the mantissa of an exponent form.
    ///
    /// By hand into a stack buffer: through `write!` the formatting machinery was most of the
    /// cost of a rewritten literal.
    fn write(self, places: usize, out: &mut Digits) {
        // Sign, 23 integer digits (units < 2^75, written with no decimals), '.', 18 decimals.
        let mut buf = [0u8; 48];
        let mut at = buf.len();
        // The decimals fit in u64 (below 10^18), and so does the integer part of every value
        // but the largest with the most places (units < 2^75): then one 128-bit division.
        let scale = POW10[places];
        let (mut int, mut frac) = match u64::try_from(self.units) {
            Ok(units) => ((units / scale) as u128, units % scale),
            Err(_) => (
                self.units / scale as u128,
                (self.units % scale as u128) as u64,
            ),
        };
        for _ in 0..places {
            at -= 1;
            buf[at] = b'0' + (frac % 10) as u8;
            frac /= 10;
        }
        if places > 0 {
            at -= 1;
            buf[at] = b'.';
        }
        // The integer part: at least one digit; by u64 where it fits (a u128 `%` is a call).
        while int > u64::MAX as u128 {
            at -= 1;
            buf[at] = b'0' + (int % 10) as u8;
            int /= 10;
        }
        let mut int = int as u64;
        loop {
            at -= 1;
            buf[at] = b'0' + (int % 10) as u8;
            int /= 10;
            if int == 0 {
                break;
            }
        }
        if self.negative {
            at -= 1;
            buf[at] = b'-';
        }
        out.extend(buf.get(at..).unwrap_or(&[]));
    }
}

/// `00` … `99`, for [`put_digits`].
static DIGIT_PAIRS: [u8; 200] = {
    let mut table = [0u8; 200];
    let mut i = 0;
    while i < 100 {
        table[2 * i] = b'0' + (i / 10) as u8;
        table[2 * i + 1] = b'0' + (i % 10) as u8;
        i += 1;
    }
    table
};

/// Writes the last `n` decimal digits of `v` into `bytes`, ending before `end` (at least `n`),
/// two at a time: one division a pair (a digit a division was most of writing a number).
#[inline(always)]
fn put_digits(bytes: &mut [u8], end: usize, mut v: u64, n: usize) {
    let mut at = end;
    let mut left = n;
    while left >= 2 {
        at -= 2;
        let pair = (v % 100) as usize * 2;
        v /= 100;
        if let (Some(slot), Some(digits)) =
            (bytes.get_mut(at..at + 2), DIGIT_PAIRS.get(pair..pair + 2))
        {
            slot.copy_from_slice(digits);
        }
        left -= 2;
    }
    if left == 1
        && let Some(slot) = bytes.get_mut(at - 1)
    {
        *slot = b'0' + (v % 10) as u8;
    }
}

/// The 8 decimal digits of `n` (below 10^8, with leading zeros) as ASCII in one word, the
/// first digit in its lowest byte, as they lie in memory: split into halves of 4 digits, 2
/// and 1 by lanes of the word, each division by multiplying (exact below 10^4 and 100:
/// `x · 10486 >> 20` is `x / 100`, `x · 103 >> 10` is `x / 10`; a test checks every lane).
#[inline(always)]
fn ascii_digits(n: u64) -> u64 {
    let x = (n / 10_000) | ((n % 10_000) << 32);
    let q = ((x * 10_486) >> 20) & 0x0000_007F_0000_007F;
    let x = q | (x - q * 100) << 16;
    let q = ((x * 103) >> 10) & 0x000F_000F_000F_000F;
    (q | (x - q * 10) << 8) | ZEROS
}

/// Appends the decimal digits of `bytes` from `*i` on to `mantissa` (wrapping: the caller
/// refuses more digits than a `u64` holds), and moves `*i` past them.
#[inline]
fn take_digits(bytes: &[u8], i: &mut usize, mantissa: &mut u64) {
    while let Some(d) = bytes
        .get(*i)
        .map(|b| b.wrapping_sub(b'0'))
        .filter(|&d| d <= 9)
    {
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d));
        *i += 1;
    }
}

/// A literal as the fast path of [`NumLit::parse_prefix`] reads it, which the literal and its
/// packed word ([`PackedLit`]) are built from: at most 19 digits, no exponent or one of at most
/// 2 digits, and a value Clinger's fast path gives exactly (see [`exact_fast_path`]).
#[derive(Clone, Copy)]
struct Plain {
    /// The value, with its sign.
    value: f64,
    /// The length of the text.
    len: usize,
    /// `+`, `-`, or 0 for none.
    sign: u8,
    int_digits: u8,
    point: bool,
    decimals: u8,
    exponent: Option<Exponent>,
}

impl Plain {
    /// The literal nearly every program writes (see the type), in one pass over the bytes:
    /// `None` for anything else, which [`NumLit::parse_general`] reads (and also for what no
    /// path reads, such as `1E`). The general path spent most of `check`'s number reading on
    /// the cases this leaves to it; inlined into the parser's loop, the call's own cost goes
    /// too.
    #[inline(always)]
    fn read(bytes: &[u8]) -> Option<Plain> {
        let (sign, int_start) = match bytes.first() {
            Some(&s @ (b'+' | b'-')) => (s, 1),
            _ => (0, 0),
        };
        let m = Mantissa::read(bytes, int_start);
        let digits = m.int_digits + m.decimals;
        // The sum wrapped past 19 digits: refused before it is used.
        if digits == 0 || digits > 19 || m.value >= 1 << 53 {
            return None;
        }
        let mut i = m.end;
        let mut exponent = None;
        if let Some(&letter @ (b'e' | b'E')) = bytes.get(i) {
            i += 1;
            let exp_sign = match bytes.get(i) {
                Some(&s @ (b'+' | b'-')) => {
                    i += 1;
                    s
                }
                _ => 0,
            };
            let exp_start = i;
            // One digit or two; a third is the general path's.
            let mut value = digit(bytes, i)?;
            i += 1;
            if let Some(d) = digit(bytes, i) {
                value = value * 10 + d;
                i += 1;
                if digit(bytes, i).is_some() {
                    return None;
                }
            }
            // Below 100.
            let value = value as i8;
            exponent = Some(Exponent {
                value: if exp_sign == b'-' { -value } else { value },
                upper: letter == b'E',
                sign: exp_sign,
                digits: (i - exp_start) as u8,
            });
        }
        let e = exponent.map_or(0, |e| i32::from(e.value));
        let mantissa = m.value as f64;
        let power = e - m.decimals as i32;
        let value = match power {
            0..=22 => mantissa * EXACT_POWERS[power as usize],
            -22..=-1 => mantissa / EXACT_POWERS[(-power) as usize],
            _ => return None,
        };
        Some(Plain {
            value: if sign == b'-' { -value } else { value },
            len: i,
            sign,
            // At most 19 each.
            int_digits: m.int_digits as u8,
            point: m.point,
            decimals: m.decimals as u8,
            exponent,
        })
    }

    fn lit(self) -> NumLit {
        NumLit {
            value: self.value,
            // |decimals| ≤ 19 and |e| ≤ 99.
            precision: (i16::from(self.decimals) - self.exponent.map_or(0, |e| i16::from(e.value))),
            exponent: self.exponent,
            style: if self.sign == b'+' { PLUS } else { 0 }
                | if self.point && self.int_digits == 0 {
                    LEADING_POINT
                } else {
                    0
                },
            int_digits: self.int_digits,
        }
    }

    /// `self.lit().pack(self.len)`, which packs every literal read so: its text is at most 25
    /// bytes, it has a leading point exactly when it has no integer digits (it has digits), and
    /// its exponent, of at most 2 digits, has the sign as written (`-` for `-0` too), and its
    /// precision is the decimals less it, which is what the length gives back. Built straight
    /// from the parts, without those checks.
    #[inline(always)]
    fn packed(self) -> Option<PackedLit> {
        let mut bits =
            self.len as u32 | u32::from(self.int_digits) << 8 | u32::from(self.sign == b'+') << 16;
        bits |= match self.exponent {
            Some(e) => {
                let sign = match e.sign {
                    b'+' => 1,
                    b'-' => 2,
                    _ => 0,
                };
                1 << 17
                    | u32::from(e.upper) << 18
                    | sign << 19
                    | u32::from(e.digits) << 21
                    | u32::from(e.value.unsigned_abs()) << 23
            }
            // The precision is the decimals, 0 to 19.
            None => u32::from(self.decimals) << 18,
        };
        NonZeroU32::new(bits).map(PackedLit)
    }
}

/// A literal of at most seven digits either side of its point, and an exponent of one or two
/// digits, as [`ShortLit::read`] finds it: where it ends and what its value is made of, the
/// value decoded only when asked for ([`ShortLit::value`]). A robtarget's translation and
/// external axes are only located when a file is read (their values are read again from the
/// source where a target is decoded), and its orientation and configuration mostly taken from
/// the target before: decoding every value as it was read was a tenth of `check`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShortLit {
    /// The index after the literal, and the byte there.
    pub end: usize,
    pub next: u8,
    /// The words the integer digits and the decimals start (only their first
    /// `int_digits`/`decimals` bytes are the literal's).
    int: u64,
    int_digits: u32,
    frac: u64,
    decimals: u32,
    /// The exponent less the decimals (-22 to 22).
    power: i32,
    negative: bool,
}

/// `b'0'` in every byte of a word.
const ZEROS: u64 = 0x3030_3030_3030_3030;

/// The eight bytes at `at`, little-endian (the first byte lowest); `None` past the end.
#[inline(always)]
fn word_at(bytes: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(*bytes.get(at..)?.first_chunk::<8>()?))
}

/// How many of the word's bytes are ASCII digits before the first that is not (8 if all are),
/// in a few operations for the whole word: a byte is a digit when its `b'0'` offset is at most
/// 9, which adding 0x76 carries into its top bit. A byte carries into the next only when its
/// offset is 0x8a or more, no digit: what it changes lies past the first byte that is not one.
#[inline(always)]
fn digit_run(word: u64) -> u32 {
    let t = word ^ ZEROS;
    let not_digit = (t.wrapping_add(0x7676_7676_7676_7676) | t) & 0x8080_8080_8080_8080;
    not_digit.trailing_zeros() / 8
}

/// The number the first `n` bytes of `word` (digits, `n` at most 8) spell: the digits moved
/// to the word's top, below them zeros, and pairs, fours and eights of digits joined by three
/// multiplications (Lemire's eight-digit parse).
#[inline(always)]
fn digits_value(word: u64, n: u32) -> u64 {
    if n == 0 {
        return 0;
    }
    let v = (word ^ ZEROS) << (8 * (8 - n.min(8)));
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    let low = (v & 0x0000_00ff_0000_00ff).wrapping_mul(100 + (1_000_000 << 32));
    let high = ((v >> 16) & 0x0000_00ff_0000_00ff).wrapping_mul(1 + (10_000 << 32));
    low.wrapping_add(high) >> 32
}

/// Powers of ten up to 10^7, as integers: a short literal's integer digits are scaled by its
/// decimals' count.
const INT_POWERS: [u64; 8] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000];

impl ShortLit {
    /// The literal at `bytes[i]` when it is short (see the type) and the bytes hold eight
    /// past each of its digit runs' starts; `None` for anything else, which
    /// [`NumLit::parse_prefix`] reads (or refuses). What it reads, `parse_prefix` reads to the
    /// same end, with the same value, as a literal that packs ([`NumLit::pack`]): the short
    /// literals are a part of [`Plain`]'s, found by words where `Plain` steps byte by byte.
    #[inline(always)]
    pub(crate) fn read(bytes: &[u8], i: usize) -> Option<ShortLit> {
        let first = *bytes.get(i)?;
        let negative = first == b'-';
        let at = i + usize::from(negative || first == b'+');
        let int = word_at(bytes, at)?;
        let int_digits = digit_run(int);
        if int_digits == 8 {
            return None;
        }
        let mut end = at + int_digits as usize;
        let mut next = (int >> (8 * int_digits)) as u8;
        let (mut frac, mut decimals) = (0, 0);
        if next == b'.' {
            frac = word_at(bytes, end + 1)?;
            decimals = digit_run(frac);
            if decimals == 8 {
                return None;
            }
            end += 1 + decimals as usize;
            next = (frac >> (8 * decimals)) as u8;
        }
        if int_digits + decimals == 0 {
            return None;
        }
        let mut power = -(decimals as i32);
        if next | 0x20 == b'e' {
            let mut k = end + 1;
            let sign = *bytes.get(k)?;
            let exp_negative = sign == b'-';
            k += usize::from(exp_negative || sign == b'+');
            // One digit or two; a third is the general path's.
            let mut e = i32::from(digit(bytes, k)?);
            k += 1;
            if let Some(d) = digit(bytes, k) {
                e = e * 10 + i32::from(d);
                k += 1;
                if digit(bytes, k).is_some() {
                    return None;
                }
            }
            power += if exp_negative { -e } else { e };
            end = k;
            next = *bytes.get(k)?;
        }
        if !(-22..=22).contains(&power) {
            return None;
        }
        Some(ShortLit {
            end,
            next,
            int,
            int_digits,
            frac,
            decimals,
            power,
            negative,
        })
    }

    /// The literal's value: what [`NumLit::parse_prefix`] gives it, bit for bit (the same
    /// mantissa and the same one operation with the same power of ten as [`Plain::read`]).
    #[inline(always)]
    pub(crate) fn value(&self) -> f64 {
        let scale = INT_POWERS.get(self.decimals as usize).copied().unwrap_or(0);
        let mantissa = digits_value(self.int, self.int_digits) * scale
            + digits_value(self.frac, self.decimals);
        let m = mantissa as f64;
        let value = match self.power {
            0..=22 => m * EXACT_POWERS[self.power as usize],
            -22..=-1 => m / EXACT_POWERS[(-self.power) as usize],
            _ => f64::NAN,
        };
        if self.negative { -value } else { value }
    }
}

/// The digit at `bytes[i]`, if there is one.
#[inline(always)]
fn digit(bytes: &[u8], i: usize) -> Option<u8> {
    bytes
        .get(i)
        .map(|b| b.wrapping_sub(b'0'))
        .filter(|&d| d <= 9)
}

/// A literal's mantissa, `int[.frac]`, as [`Plain::read`] reads it.
struct Mantissa {
    /// The digits as one integer (wrapping: past 19 digits the caller refuses it).
    value: u64,
    int_digits: usize,
    /// A point follows the integer digits.
    point: bool,
    decimals: usize,
    /// Where it ends.
    end: usize,
}

impl Mantissa {
    /// The mantissa from `start`, byte by byte with the digits summed as they go.
    ///
    /// Eight bytes at a time (the digits found by their top bits, the value in three
    /// multiplies) cost more on a robot program: most of its literals have one digit (`0`,
    /// `-1`, `9E+09`), where a word's reading costs twice a byte's, and the longer ones
    /// (`-1520.30`, `0.707107`) no more than six or seven digits, which a word saved too little
    /// on (`rcheck` 190.9 M by bytes, 194.2 M by words). A robtarget's declaration reads
    /// its literals by words all the same ([`ShortLit`]): there the value is mostly not
    /// decoded, and no literal is built.
    #[inline(always)]
    fn read(bytes: &[u8], start: usize) -> Mantissa {
        let mut i = start;
        let mut value = 0;
        take_digits(bytes, &mut i, &mut value);
        let int_digits = i - start;
        let point = bytes.get(i) == Some(&b'.');
        let mut decimals = 0;
        if point {
            i += 1;
            let frac_start = i;
            take_digits(bytes, &mut i, &mut value);
            decimals = i - frac_start;
        }
        Mantissa {
            value,
            int_digits,
            point,
            decimals,
            end: i,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast path as it read a literal in one function, before its reading was shared by
    /// `parse_prefix` and `parse_packed` (`Plain::read`, `Mantissa::read`): the reference the
    /// shared reading is held to.
    fn plain_bytewise(bytes: &[u8]) -> Option<(NumLit, usize)> {
        let (sign, mut i) = match bytes.first() {
            Some(&s @ (b'+' | b'-')) => (s, 1),
            _ => (0, 0),
        };
        let int_start = i;
        let mut mantissa = 0u64;
        // Wrapping: more than 19 digits are refused below, before the sum is used.
        take_digits(bytes, &mut i, &mut mantissa);
        let int_digits = i - int_start;
        let point = bytes.get(i) == Some(&b'.');
        let mut decimals = 0;
        if point {
            i += 1;
            let frac_start = i;
            take_digits(bytes, &mut i, &mut mantissa);
            decimals = i - frac_start;
        }
        let digits = int_digits + decimals;
        if digits == 0 || digits > 19 || mantissa >= 1 << 53 {
            return None;
        }
        let mut exponent = None;
        if let Some(&letter @ (b'e' | b'E')) = bytes.get(i) {
            i += 1;
            let exp_sign = match bytes.get(i) {
                Some(&s @ (b'+' | b'-')) => {
                    i += 1;
                    s
                }
                _ => 0,
            };
            let exp_start = i;
            let mut value = 0i8;
            while let Some(d) = bytes
                .get(i)
                .map(|b| b.wrapping_sub(b'0'))
                .filter(|&d| d <= 9)
            {
                if i - exp_start == 2 {
                    return None;
                }
                value = value * 10 + d as i8;
                i += 1;
            }
            if i == exp_start {
                return None;
            }
            exponent = Some(Exponent {
                value: if exp_sign == b'-' { -value } else { value },
                upper: letter == b'E',
                sign: exp_sign,
                digits: (i - exp_start) as u8,
            });
        }
        let e = exponent.map_or(0, |e| i32::from(e.value));
        let decimals = decimals as i32;
        let m = mantissa as f64;
        let power = e - decimals;
        let value = match power {
            0..=22 => m * EXACT_POWERS[power as usize],
            -22..=-1 => m / EXACT_POWERS[(-power) as usize],
            _ => return None,
        };
        Some((
            NumLit {
                value: if sign == b'-' { -value } else { value },
                // |decimals| ≤ 19 and |e| ≤ 99.
                precision: (decimals - e) as i16,
                exponent,
                style: if sign == b'+' { PLUS } else { 0 }
                    | if point && int_digits == 0 {
                        LEADING_POINT
                    } else {
                        0
                    },
                int_digits: int_digits as u8,
            },
            i,
        ))
    }

    #[test]
    fn parses_every_style() {
        for (text, value, precision) in [
            ("12", 12.0, 0),
            ("-0.5", -0.5, 1),
            (".5", 0.5, 1),
            ("5.", 5.0, 0),
            ("9E9", 9e9, -9),
            ("9E+09", 9e9, -9),
            ("9e+9", 9e9, -9),
            ("2.69E-07", 2.69e-7, 9),
            ("+1.250", 1.25, 3),
        ] {
            let lit = NumLit::parse(text.as_bytes()).unwrap();
            assert_eq!(lit.value(), value, "{text}");
            assert_eq!(lit.precision(), precision, "{text}");
        }
        for bad in ["", "-", ".", "1e", "1.2.3", "abc", "1x", "1e+"] {
            assert!(NumLit::parse(bad.as_bytes()).is_none(), "{bad}");
        }
    }

    #[test]
    fn keeps_text_below_written_precision() {
        let zero = NumLit::parse(b"0").unwrap();
        assert_eq!(zero.rewrite(0.0004, 3), None);
        assert_eq!(zero.rewrite(-0.0004, 3), None);
        assert_eq!(zero.rewrite(0.3, 3).as_deref(), Some("0.300"));
        let big = NumLit::parse(b"9E+09").unwrap();
        assert_eq!(big.rewrite(9e9, 3), None);
        let q = NumLit::parse(b"0.123457").unwrap();
        assert_eq!(q.rewrite(0.1234568, 6), None);
        assert_eq!(q.rewrite(-0.1234568, 6).as_deref(), Some("-0.123457"));
        let mm = NumLit::parse(b"1234.56789").unwrap();
        assert_eq!(mm.rewrite(1234.5, 3).as_deref(), Some("1234.50000"));
        let plus = NumLit::parse(b"+1.5").unwrap();
        assert_eq!(plus.rewrite(2.0, 3).as_deref(), Some("+2.000"));
        assert_eq!(plus.rewrite(-2.0, 3).as_deref(), Some("-2.000"));
    }

    proptest::proptest! {
        #[test]
        fn parse_equals_std(
            int in "[0-9]{0,12}",
            frac in proptest::option::of("[0-9]{0,12}"),
            exp in proptest::option::of(-30i32..30),
            sign in proptest::sample::select(vec!["", "-", "+"]),
        ) {
            let mut text = format!("{sign}{int}");
            if let Some(f) = &frac {
                text.push('.');
                text.push_str(f);
            }
            if let Some(e) = exp {
                text.push_str(&format!("E{e}"));
            }
            let std: Option<f64> = text.parse().ok();
            let ours = NumLit::parse(text.as_bytes()).map(|l| l.value());
            if int.is_empty() && frac.as_deref().is_none_or(str::is_empty) {
                proptest::prop_assert_eq!(ours, None);
            } else {
                proptest::prop_assert_eq!(ours.map(f64::to_bits), std.map(f64::to_bits), "{}", text);
            }
        }
    }

    /// A literal's text as programs and hostile inputs write it: a sign, integer digits, a point
    /// and decimals (up to 25 digits each, past the 19 the fast path takes), an exponent in
    /// either case with or without a sign and with leading zeros (`9E+09`, `2.5e-001`).
    fn literal_text() -> impl proptest::strategy::Strategy<Value = String> {
        use proptest::prelude::*;
        (
            proptest::sample::select(vec!["", "-", "+"]),
            "[0-9]{0,25}",
            proptest::option::of("[0-9]{0,25}"),
            proptest::option::of((
                proptest::sample::select(vec!["E", "e"]),
                proptest::sample::select(vec!["", "+", "-"]),
                "[0-9]{1,3}",
            )),
        )
            .prop_map(|(sign, int, frac, exp)| {
                let mut text = format!("{sign}{int}");
                if let Some(f) = frac {
                    text.push('.');
                    text.push_str(&f);
                }
                if let Some((e, s, d)) = exp {
                    text.push_str(&format!("{e}{s}{d}"));
                }
                text
            })
    }

    #[test]
    fn the_common_literals_take_the_fast_path() {
        // What a robtarget holds: if these fell back, the proptest below would test nothing.
        for text in [
            "-1520.30", "0.707107", "0", "+12.5", ".5", "5.", "9E+09", "9E9", "2.69E-07",
        ] {
            let plain = NumLit::parse_plain(text.as_bytes());
            assert_eq!(plain, NumLit::parse_general(text.as_bytes()), "{text}");
            assert!(plain.is_some(), "{text}");
        }
        // Past 19 digits, 2^53, 10^±22 or a 2-digit exponent: the general path.
        for text in [
            "12345678901234567890",
            "9007199254740993",
            "1E23",
            "1e-23",
            "1.5E+009",
        ] {
            assert_eq!(NumLit::parse_plain(text.as_bytes()), None, "{text}");
            assert!(NumLit::parse_general(text.as_bytes()).is_some(), "{text}");
        }
    }

    proptest::proptest! {
        /// Whichever path reads it, a literal's value is the correctly rounded one `str::parse`
        /// (an independent reader) gives, bit for bit; and the fast path reads the same literal
        /// as the general one, style and precision included. (What follows is no exponent
        /// letter: `1.5E` is no literal at all.)
        #[test]
        fn both_paths_read_what_std_reads(text in literal_text(), tail in "[ ,\\]a-dx;]?") {
            let std: Option<f64> = text.parse().ok();
            let whole = format!("{text}{tail}");
            let ours = NumLit::parse_prefix(whole.as_bytes());
            match ours {
                Some((lit, len)) => {
                    proptest::prop_assert_eq!(len, text.len(), "{}", whole);
                    proptest::prop_assert_eq!(Some(lit.value().to_bits()), std.map(f64::to_bits), "{}", text);
                }
                // Only a text without digits in its mantissa (or, beyond f64, an infinity).
                None => proptest::prop_assert!(
                    std.is_none_or(|v| v.is_infinite()),
                    "{} reads as {:?}", text, std
                ),
            }
            if let Some(plain) = NumLit::parse_plain(whole.as_bytes()) {
                proptest::prop_assert_eq!(Some(plain), NumLit::parse_general(whole.as_bytes()), "{}", whole);
            }
        }
    }

    /// Literals at the fast path's edges: leading zeros, 15 to 20 digits, 2^53 either side,
    /// no digits on one side of the point, signs, exponents of one to three digits and
    /// 10^±22 either side.
    const PLAIN_EDGES: &[&str] = &[
        "0",
        "-0",
        "+0",
        "007",
        "-0.000",
        ".5",
        "-.25",
        "+.5",
        "5.",
        "-5.",
        ".",
        "-",
        "+",
        "-.",
        "123456789012345",
        "1234567890123456",
        "12345678901234567",
        "1234567890123456789",
        "12345678901234567890",
        "9007199254740991",
        "9007199254740992",
        "0.9007199254740993",
        "1.234567890123456789",
        "000000000000000000001",
        "9E+09",
        "9E9",
        "9e-9",
        "2.69E-07",
        ".0e-0",
        "1E+22",
        "1E22",
        "1E23",
        "1e-22",
        "1e-23",
        "1.5E+009",
        "1E",
        "1E+",
        "1e-",
        "0.0000000000000000000001",
        "123.456e+21",
    ];

    #[test]
    fn the_plain_path_reads_the_edges_as_before() {
        for text in PLAIN_EDGES {
            // Alone (the end of the slice right after it) and followed as in a program.
            for tail in ["", ",", "]", "x", ".5", "e5", "E+1"] {
                let whole = format!("{text}{tail}");
                let bytes = whole.as_bytes();
                assert_eq!(NumLit::parse_plain(bytes), plain_bytewise(bytes), "{whole}");
                let packed = NumLit::parse_packed(bytes).map(|(v, p)| (v.to_bits(), p));
                let by_lit = NumLit::parse_prefix(bytes)
                    .and_then(|(lit, len)| Some((lit.value.to_bits(), lit.pack(len)?)));
                assert_eq!(packed, by_lit, "{whole}");
            }
        }
    }

    proptest::proptest! {
        /// The fast path reads what it read byte by byte with a literal's parts in one pass
        /// (literals, and any text of a literal's bytes); and a literal read packed is the
        /// literal `parse_prefix` reads, packed with its length, bit for bit.
        #[test]
        fn the_plain_path_reads_as_before_and_packs_as_pack(
            text in proptest::prop_oneof![literal_text(), "[-+0-9.eE]{0,30}"],
            tail in proptest::option::of("[ ,\\]a-dx;.eE0-9+-]{1,3}"),
        ) {
            let whole = format!("{text}{}", tail.unwrap_or_default());
            let bytes = whole.as_bytes();
            proptest::prop_assert_eq!(NumLit::parse_plain(bytes), plain_bytewise(bytes), "{}", whole);
            let packed = NumLit::parse_packed(bytes).map(|(v, p)| (v.to_bits(), p));
            let by_lit = NumLit::parse_prefix(bytes)
                .and_then(|(lit, len)| Some((lit.value.to_bits(), lit.pack(len)?)));
            proptest::prop_assert_eq!(packed, by_lit, "{}", whole);
        }
    }

    /// What [`ShortLit::read`] stands in for: where it reads a literal at `i`, `parse_prefix`
    /// reads one to the same end that packs, with the same value bit for bit, and the byte
    /// after it is the one it gives. `Ok(true)` where it read one.
    fn short_as_prefix(bytes: &[u8], i: usize) -> Result<bool, String> {
        let Some(short) = ShortLit::read(bytes, i) else {
            return Ok(false);
        };
        let text = String::from_utf8_lossy(bytes);
        let (lit, len) = NumLit::parse_prefix(&bytes[i..])
            .ok_or_else(|| format!("{text:?} at {i}: short, but no literal"))?;
        if i + len != short.end || lit.pack(len).is_none() {
            return Err(format!(
                "{text:?} at {i}: {len} bytes, packs: {:?}",
                lit.pack(len)
            ));
        }
        if lit.value().to_bits() != short.value().to_bits()
            || bytes.get(short.end) != Some(&short.next)
        {
            return Err(format!(
                "{text:?} at {i}: {} / {}",
                lit.value(),
                short.value()
            ));
        }
        Ok(true)
    }

    /// `digit_run` counts the digits a byte loop counts, and `digits_value` gives their value,
    /// for every byte value after runs of every length, and after it bytes of every kind.
    #[test]
    fn a_word_s_digit_run_and_value_are_its_bytes_read_one_by_one() {
        for run in 0..=8usize {
            for b in 0..=255u8 {
                for after in [0u8, b'9', 0xff, 0x8a, b'.'] {
                    let mut bytes = [after; 8];
                    for (k, d) in bytes.iter_mut().enumerate().take(run) {
                        *d = b'0' + ((k * 7 + 3) % 10) as u8;
                    }
                    if run < 8 {
                        bytes[run] = b;
                    }
                    let word = u64::from_le_bytes(bytes);
                    let by_bytes = bytes.iter().take_while(|c| c.is_ascii_digit()).count();
                    assert_eq!(digit_run(word) as usize, by_bytes, "{bytes:?}");
                    let value = bytes[..by_bytes]
                        .iter()
                        .fold(0u64, |v, d| v * 10 + u64::from(d - b'0'));
                    assert_eq!(digits_value(word, by_bytes as u32), value, "{bytes:?}");
                }
            }
        }
    }

    #[test]
    fn the_common_literals_are_read_short_as_parse_prefix_reads_them() {
        // What a robtarget holds, followed as in a program: if these were not read short, the
        // proptest below would test little.
        for text in [
            "-1520.30",
            "0.707107",
            "0",
            "-1",
            "+12.5",
            ".5",
            "-.25",
            "5.",
            "9E+09",
            "9E9",
            "9e+9",
            "9E09",
            "2.69E-07",
            "1.50E+2",
            "0000000",
            "-9999999.9999999",
            "1E22",
            "1e-15",
        ] {
            for tail in [",", "]", ",9E+09,9E+09]];"] {
                let whole = format!("{text}{tail}        ");
                assert_eq!(short_as_prefix(whole.as_bytes(), 0), Ok(true), "{whole}");
            }
        }
        // Eight digits on a side, a third exponent digit, 10^±23, no digits, or fewer than
        // eight bytes to read: for `parse_prefix` alone.
        for text in [
            "12345678",
            "0.12345678",
            "9e+009",
            "9.0E+009",
            "1E23",
            "1e-23",
            "1.5e-22",
            ".",
            "-",
            "+-1",
            "-.",
            "1E",
            "1E+",
            "x1",
        ] {
            let whole = format!("{text},        ");
            assert_eq!(short_as_prefix(whole.as_bytes(), 0), Ok(false), "{whole}");
        }
        assert_eq!(short_as_prefix(b"[1,2]", 1), Ok(false));
        assert_eq!(short_as_prefix(b"1.5", 0), Ok(false));
    }

    #[test]
    fn the_edges_read_short_as_parse_prefix_reads_them() {
        for text in PLAIN_EDGES {
            for tail in [
                "",
                ",",
                "]",
                "x",
                ".5",
                "e5",
                "E+1",
                ",        ",
                "\u{e4}        ",
            ] {
                for lead in ["", "[", "\u{c4}"] {
                    let whole = format!("{lead}{text}{tail}");
                    assert!(
                        short_as_prefix(whole.as_bytes(), lead.len()).is_ok(),
                        "{whole}"
                    );
                }
            }
        }
    }

    proptest::proptest! {
        /// Wherever [`ShortLit::read`] reads a literal, `parse_prefix` reads the same one, as
        /// a literal that packs, with the same value: literals of every spelling, any text of
        /// a literal's bytes, with what a program has around them and Latin-1 bytes.
        #[test]
        fn a_short_literal_is_the_literal_parse_prefix_reads(
            lead in "[\\[,]?",
            text in proptest::prop_oneof![
                literal_text(),
                "[-+]?[0-9]{0,9}(\\.[0-9]{0,9})?([eE][-+]?[0-9]{0,3})?",
                "[-+0-9.eE]{0,20}",
            ],
            tail in "[ ,\\]a-dx;.eE0-9+\u{e4}-]{0,12}",
        ) {
            let whole = format!("{lead}{text}{tail}");
            let read = short_as_prefix(whole.as_bytes(), lead.len());
            proptest::prop_assert!(read.is_ok(), "{:?}", read);
        }
    }

    /// `format!` with the negative zero dropped: the reference the fixed-point writer must equal.
    fn by_format(value: f64, places: usize) -> String {
        let s = format!("{value:.places$}");
        match s.strip_prefix('-') {
            Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_owned(),
            _ => s,
        }
    }

    #[test]
    fn fixed_point_ties_and_edges() {
        for (value, places) in [
            (0.5, 0),
            (1.5, 0),
            (2.5, 0),
            (0.125, 2),
            (0.375, 2),
            (-0.0625, 3),
            (-0.0004, 3),
            (1e-300, 6),
            (5e-324, 12),
            (1234.56789, 5),
            (9e9, 3),
            (34359738367.9, 3),
            (0.1 + 0.2, 12),
        ] {
            let scaled = Scaled::of(value, places).unwrap();
            let mut text = Digits::new();
            scaled.write(places, &mut text);
            assert_eq!(
                text.as_string(),
                by_format(value, places),
                "{value} .{places}"
            );
        }
        assert_eq!(Scaled::of(1e20, 3), None);
        assert_eq!(Scaled::of(1.0, 13), None);
        assert_eq!(fixed(1e20, 1), "100000000000000000000.0");
    }

    proptest::proptest! {
        #[test]
        fn fixed_point_equals_format(
            value in proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO,
            scale in -15i32..12,
            places in 0usize..=12,
        ) {
            // Spread the values over the magnitudes programs hold (1e-15 … 1e11).
            let (m, _) = frexp(value);
            let v = m * 10f64.powi(scale);
            proptest::prop_assert_eq!(fixed(v, places), by_format(v, places));
        }

        #[test]
        fn fixed_point_on_written_decimals(
            units in -10_000_000_000i64..10_000_000_000,
            places in 0usize..=9,
            nudge in -2i32..=2,
        ) {
            // Values just beside a decimal written with `places + 1` digits: the rounding edge.
            let v = units as f64 / 10f64.powi(places as i32 + 1);
            let v = f64::from_bits((v.to_bits() as i64 + nudge as i64) as u64);
            proptest::prop_assert_eq!(fixed(v, places), by_format(v, places));
        }
    }

    proptest::proptest! {
        /// The scaling by one multiplication gives what the exact scaling gives, or leaves the
        /// value to it: values of every magnitude, and values just beside a half unit (the
        /// ties and their neighbours, where the product's rounding could tip the result).
        #[test]
        fn scaling_by_float_is_the_exact_scaling(
            value in proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO,
            scale in -15i32..12,
            units in -10_000_000_000i64..10_000_000_000,
            nudge in -3i64..=3,
            places in 0usize..=13,
        ) {
            let (m, _) = frexp(value);
            let spread = m * 10f64.powi(scale);
            let half = (units as f64 + 0.5) / 10f64.powi(places as i32);
            let half = f64::from_bits((half.to_bits() as i64 + nudge) as u64);
            for v in [value, spread, half, -half, f64::NAN, f64::NEG_INFINITY] {
                proptest::prop_assert_eq!(Scaled::of(v, places), Scaled::exactly(v, places), "{} .{}", v, places);
                if let Some(fast) = Scaled::by_float(v, places).filter(|_| Scaled::in_range(v, places)) {
                    proptest::prop_assert_eq!(Some(fast), Scaled::exactly(v, places), "{} .{}", v, places);
                }
            }
        }

        /// The text written in place is the one built in the stack buffer, in every plain
        /// style (`+`, a leading point, both, neither), wherever it fits inline.
        #[test]
        fn the_inline_text_is_the_digits_text(
            units in 0u64..100_000_000_000_000,
            digits_off in 0usize..=14,
            negative in proptest::bool::ANY,
            places in 0usize..=12,
            style in proptest::sample::select(vec!["1.5", "+1.5", ".5", "+.5"]),
        ) {
            // Of every length: a uniform draw is nearly always 13 or 14 digits long.
            let units = units / POW10[digits_off];
            let lit = NumLit::parse(style.as_bytes()).unwrap();
            let a = Scaled { negative: negative && units != 0, units: u128::from(units) };
            let by_digits = lit.text_by_digits(a, places);
            match a.inline_text(places, lit.style) {
                Some(inline) => proptest::prop_assert_eq!(inline, by_digits),
                None => proptest::prop_assert!(by_digits.len() > INLINE, "{:?}", by_digits),
            }
        }
    }

    #[test]
    fn the_digit_word_s_lanes_divide_exactly() {
        assert!((0..10_000u64).all(|x| (x * 10_486) >> 20 == x / 100));
        assert!((0..100u64).all(|x| (x * 103) >> 10 == x / 10));
        for n in [
            0, 1, 9, 10, 99, 100, 1234, 9999, 10_000, 12_345_678, 99_999_999,
        ] {
            let text = format!("{n:08}");
            assert_eq!(ascii_digits(n).to_le_bytes(), text.as_bytes(), "{n}");
        }
    }

    #[test]
    fn the_inline_text_by_word_at_its_edges() {
        for style in ["1.5", "+1.5", ".5", "+.5"] {
            let lit = NumLit::parse(style.as_bytes()).unwrap();
            for (places, &scale) in POW10.iter().enumerate().take(9).skip(1) {
                for int in [0, 1, 9, 10, 99_999, 9_999_999, 99_999_999] {
                    for frac in [0, 1, scale / 2, scale - 1] {
                        for negative in [false, true] {
                            let units = int * scale + frac;
                            let a = Scaled {
                                negative: negative && units != 0,
                                units: u128::from(units),
                            };
                            let by_digits = lit.text_by_digits(a, places);
                            match a.inline_text(places, lit.style) {
                                Some(inline) => assert_eq!(inline, by_digits),
                                None => assert!(by_digits.len() > INLINE, "{by_digits:?}"),
                            }
                        }
                    }
                }
            }
        }
    }

    /// Mantissa in [0.5, 1) and exponent (the C `frexp`), for spreading random values.
    fn frexp(x: f64) -> (f64, i32) {
        if x == 0.0 {
            return (0.0, 0);
        }
        let e = x.abs().log2().floor() as i32 + 1;
        (x / 2f64.powi(e), e)
    }

    #[test]
    fn a_literal_is_16_bytes() {
        // Millions per large module: the style costs no size.
        assert_eq!(std::mem::size_of::<NumLit>(), 16);
    }

    #[test]
    fn rewrites_keep_the_literals_style() {
        let r = |text: &str, new: f64, house: usize| {
            NumLit::parse(text.as_bytes())
                .unwrap()
                .rewrite(new, house)
                .unwrap()
        };
        // No leading zero below 1, as written; from 1 on there is no other way.
        assert_eq!(r(".5", 0.5123, 3), ".512");
        assert_eq!(r("-.5", -0.25, 3), "-.250");
        assert_eq!(r(".5", 1.75, 3), "1.750");
        // The same exponent, its letter, sign and padding: the digits at the precision the
        // literal resolves (at least the house decimals), the point moved.
        assert_eq!(r("1.5E+2", 150.123, 3), "1.50123E+2");
        assert_eq!(r("1.5E+2", -1500.5, 3), "-15.00500E+2");
        assert_eq!(r("2.5e-001", 0.2512, 3), "2.51e-001");
        assert_eq!(r("1.04259E-05", 1.0412e-5, 6), "1.04120E-05");
        assert_eq!(r("1.04259E-05", -1.916148e-4, 6), "-19.16148E-05");
        assert_eq!(r("+.5E+1", 5.1234, 3), "+.5123E+1");
        // The exponent's sign as written, `-0` too.
        assert_eq!(r(".0e-0", -335.069, 3), "-335.069e-0");
        // Beyond the exact writer's range (2^35) a value is written plainly.
        assert_eq!(r("10.0E10", 0.0, 3), "0.000");
        // A mantissa past 3 integer digits: plain form.
        assert_eq!(r("1.5E+2", 150000.5, 3), "150000.500");
        // What the rewrite wrote reads back at the precision it wrote.
        for text in ["1.50123E+2", "-15.00500E+2", "2.51e-001", ".512"] {
            let lit = NumLit::parse(text.as_bytes()).unwrap();
            assert_eq!(lit.places(3), 3, "{text}");
        }
        assert!(same_at(0.0004, 0.0, 3) && !same_at(0.0006, 0.0, 3));
        assert!(same_at(-0.0000001, 0.0, 6));
    }

    proptest::proptest! {
        /// A rewrite in any style says the new value at the places it writes, reads back with
        /// that precision, and keeps the style where it can: an exponent literal its exponent
        /// suffix (while the mantissa stays within 3 integer digits), a leading-point literal no
        /// leading zero below 1.
        #[test]
        fn rewrites_say_the_value_in_the_style(
            int in "[0-9]{0,3}",
            frac in "[0-9]{1,4}",
            exp in proptest::option::of((proptest::sample::select(vec!["E", "e", "E+", "e-", "E-0"]), 0u8..12)),
            sign in proptest::sample::select(vec!["", "-", "+"]),
            new in -5000.0f64..5000.0,
            house in proptest::sample::select(vec![3usize, 4, 6]),
        ) {
            let mut text = format!("{sign}{int}.{frac}");
            if let Some((e, n)) = &exp {
                text.push_str(&format!("{e}{n}"));
            }
            let lit = NumLit::parse(text.as_bytes()).unwrap();
            // The value a rewrite reports is the one its text reads back as, bit for bit.
            if let Some((t, read)) = lit.rewrite_read(new, house) {
                let parsed = NumLit::parse(&t).map(|l| l.value().to_bits());
                proptest::prop_assert_eq!(Some(read.to_bits()), parsed, "{} → {:?}", text, t);
            }
            let Some(out) = lit.rewrite(new, house) else {
                proptest::prop_assert!(same_at(new, lit.value(), lit.places(house)));
                return Ok(());
            };
            let back = NumLit::parse(out.as_bytes());
            proptest::prop_assert!(back.is_some(), "{} → {}", text, out);
            let back = back.unwrap();
            let places = lit.places(house);
            proptest::prop_assert_eq!(back.places(house), places, "{} → {}", text, out);
            proptest::prop_assert!(same_at(back.value(), new, places), "{} → {} for {}", text, out, new);
            match &exp {
                Some((e, n)) if out.contains(['e', 'E']) => {
                    proptest::prop_assert!(out.ends_with(&format!("{e}{n}")), "{} → {}", text, out);
                }
                Some((e, n)) => {
                    // Plain only when the mantissa would pass 3 integer digits, or need more
                    // than 18 decimals, or the original is beyond the exact writer's range
                    // (2^35: a written `10.0E10`).
                    let e = if e.contains('-') { -(*n as i32) } else { *n as i32 };
                    let mantissa = new.abs() / 10f64.powi(e);
                    proptest::prop_assert!(
                        mantissa >= 999.0
                            || places as i32 + e > 18
                            || lit.value().abs() >= 34_359_738_368.0,
                        "{} → {}", text, out
                    );
                }
                None => proptest::prop_assert!(!out.contains(['e', 'E']), "{} → {}", text, out),
            }
            if int.is_empty() && exp.is_none() && new.abs() < 0.5 {
                proptest::prop_assert!(!out.trim_start_matches(['-', '+']).starts_with('0'), "{} → {}", text, out);
            }
        }
    }

    proptest::proptest! {
        /// A literal rounded once rewrites and compares as the literal does each time.
        #[test]
        fn a_rounded_literal_rewrites_and_compares_as_the_literal(
            text in literal_text(),
            new in proptest::prop_oneof![-5000.0f64..5000.0, -1.0f64..1.0, proptest::num::f64::ANY],
            near in proptest::option::of(-4i32..=4),
            house in proptest::sample::select(vec![0usize, 3, 4, 6, 12, 14]),
        ) {
            let Some(lit) = NumLit::parse(text.as_bytes()) else {
                return Ok(());
            };
            // Also values a half unit, a unit or two of the last place from the literal's own
            // (the half units at the bound of `same`'s shortcut).
            let new = match near {
                Some(k) => lit.value() + k as f64 / 2.0 * 10f64.powi(-(lit.places(house) as i32)),
                None => new,
            };
            let r = lit.rounded(house);
            proptest::prop_assert_eq!(r.places(), lit.places(house));
            let bits = |x: Option<(EditText, f64)>| x.map(|(t, v)| (t, v.to_bits()));
            proptest::prop_assert_eq!(bits(r.rewrite_read(new)), bits(lit.rewrite_read(new, house)), "{} {}", text, new);
            proptest::prop_assert_eq!(r.same(new), same_at(new, lit.value(), lit.places(house)), "{} {}", text, new);
            proptest::prop_assert_eq!(r.same(new), r.same_plainly(new), "{} {}", text, new);
        }
    }

    proptest::proptest! {
        /// `Scaled::of`'s shortcut from 2 places scales as the plain path does, also at the
        /// bounds of the range (2^35, and products near 2^40) and for values that are no number.
        #[test]
        fn scaling_by_the_shortcut_is_the_plain_scaling(
            value in proptest::prop_oneof![
                -5000.0f64..5000.0,
                proptest::num::f64::ANY,
                proptest::strategy::Strategy::prop_map(0.9f64..1.1, |f| f * 34_359_738_368.0),
                proptest::strategy::Strategy::prop_map(
                    (0.9f64..1.1, 0i32..=12),
                    |(f, p)| f * (1u64 << 40) as f64 / 10f64.powi(p),
                ),
            ],
            places in 0usize..=14,
        ) {
            proptest::prop_assert_eq!(Scaled::of(value, places), Scaled::of_plainly(value, places), "{} {}", value, places);
        }
    }

    #[test]
    fn never_writes_exponent_noise() {
        let lit = NumLit::parse(b"1.5").unwrap();
        assert_eq!(lit.rewrite(1.0000000000002, 3).as_deref(), Some("1.000"));
        assert_eq!(lit.rewrite(1e-12, 3).as_deref(), Some("0.000"));
    }
}
