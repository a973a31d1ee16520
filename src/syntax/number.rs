//! Numeric literals that keep their original text and write new values in the same style.

/// A numeric literal as written: `12`, `-0.5`, `.5`, `9E9`, `9E+09`, `9e+9`, `2.69E-07`.
///
/// Like toml_edit's `Formatted<T>`, the value and the style of its text travel together: an
/// unchanged value keeps its original bytes (they stay in the source, found by the field's span),
/// a changed one is written with the original's decimals. The text itself is not copied: a
/// 50 MB module holds millions of literals, and an allocation each would dominate parsing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NumLit {
    value: f64,
    /// Decimal places the text resolves: mantissa decimals minus the exponent
    /// (`9E+09` → -9, `2.69E-07` → 9, `1.50` → 2).
    precision: i32,
    /// The text starts with an explicit `+`.
    plus: bool,
}

impl NumLit {
    /// Parses a whole literal; `None` if `bytes` is not exactly one number.
    pub fn parse(bytes: &[u8]) -> Option<NumLit> {
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
        let mut digits = i - int_start;
        let mut decimals = 0i32;
        if bytes.get(i) == Some(&b'.') {
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
        if matches!(bytes.get(i), Some(b'e' | b'E')) {
            i += 1;
            let negative = bytes.get(i) == Some(&b'-');
            if matches!(bytes.get(i), Some(b'+' | b'-')) {
                i += 1;
            }
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
        }
        if i != bytes.len() {
            return None;
        }
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
        Some(NumLit {
            value,
            precision: decimals.saturating_sub(exponent),
            plus: bytes.first() == Some(&b'+'),
        })
    }

    /// The literal as a float, for the math; the text itself stays in the tree.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// Decimal places the original text resolves (negative for `9E9`).
    pub fn precision(&self) -> i32 {
        self.precision
    }

    /// Whether the text starts with an explicit `+`.
    pub fn plus(&self) -> bool {
        self.plus
    }

    /// The literal of these parts, as [`NumLit::parse`] gives them: a compact store (the
    /// position model's fields) keeps the parts and rebuilds the literal to rewrite it.
    pub(crate) fn from_parts(value: f64, precision: i32, plus: bool) -> NumLit {
        NumLit {
            value,
            precision,
            plus,
        }
    }

    /// The text to write for `new`, or `None` when the original text already says it.
    ///
    /// `new` is written with `max(original decimals, min_decimals)` places, never in exponent
    /// form; if it rounds to the same text as the original value at that precision, the original
    /// text is kept (so `0` stays `0` and `9E+09` stays `9E+09`).
    pub fn rewrite(&self, new: f64, min_decimals: usize) -> Option<String> {
        let places = self.precision.clamp(0, 12).max(min_decimals.min(12) as i32) as usize;
        // Compare the rounded values as integers first: most fields of a corrected program
        // change, but the ones that don't (zeros, 9E9, unchanged quaternions) cost no text.
        if let (Some(a), Some(b)) = (Scaled::of(new, places), Scaled::of(self.value, places)) {
            if a == b {
                return None;
            }
            let mut text = String::with_capacity(24);
            if self.plus && !a.negative {
                text.push('+');
            }
            a.write(places, &mut text);
            return Some(text);
        }
        let written = fixed(new, places);
        if written == fixed(self.value, places) {
            return None;
        }
        if self.plus && !written.starts_with('-') {
            return Some(format!("+{written}"));
        }
        Some(written)
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
        let mut text = String::with_capacity(24);
        scaled.write(places, &mut text);
        return text;
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
    fn of(value: f64, places: usize) -> Option<Scaled> {
        // 2^35 mm is 34,000 km: every coordinate, angle or quaternion a program holds.
        if !value.is_finite() || places > 12 || value.abs() >= 34_359_738_368.0 {
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
        let product = mantissa as u128 * 10u128.pow(places as u32);
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

    /// Appends the digits: `-`, the integer part, and `places` decimals after a `.`.
    ///
    /// By hand into a stack buffer: through `write!` the formatting machinery was most of the
    /// cost of a rewritten literal.
    fn write(self, places: usize, out: &mut String) {
        // Sign, 11 integer digits (< 2^35), '.', 12 decimals.
        let mut buf = [0u8; 32];
        let mut at = buf.len();
        // One 128-bit division; both parts fit in u64 (below 2^35 and 10^12).
        let scale = 10u128.pow(places as u32);
        let mut int = (self.units / scale) as u64;
        let mut frac = (self.units % scale) as u64;
        for _ in 0..places {
            at -= 1;
            buf[at] = b'0' + (frac % 10) as u8;
            frac /= 10;
        }
        if places > 0 {
            at -= 1;
            buf[at] = b'.';
        }
        // The integer part: at least one digit.
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
        // Only ASCII digits, '.' and '-' were written.
        out.extend(buf[at..].iter().map(|&b| b as char));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let mut text = String::new();
            scaled.write(places, &mut text);
            assert_eq!(text, by_format(value, places), "{value} .{places}");
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

    /// Mantissa in [0.5, 1) and exponent (the C `frexp`), for spreading random values.
    fn frexp(x: f64) -> (f64, i32) {
        if x == 0.0 {
            return (0.0, 0);
        }
        let e = x.abs().log2().floor() as i32 + 1;
        (x / 2f64.powi(e), e)
    }

    #[test]
    fn never_writes_exponent_noise() {
        let lit = NumLit::parse(b"1.5").unwrap();
        assert_eq!(lit.rewrite(1.0000000000002, 3).as_deref(), Some("1.000"));
        assert_eq!(lit.rewrite(1e-12, 3).as_deref(), Some("0.000"));
    }
}
