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
        while bytes.get(i).is_some_and(u8::is_ascii_digit) {
            i += 1;
        }
        let mut digits = i - int_start;
        let mut decimals = 0i32;
        if bytes.get(i) == Some(&b'.') {
            i += 1;
            let frac_start = i;
            while bytes.get(i).is_some_and(u8::is_ascii_digit) {
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
        // Only ASCII digits, signs, '.', 'e' remain here, so the text is valid UTF-8.
        let text = std::str::from_utf8(bytes).ok()?;
        let value: f64 = text.parse().ok()?;
        if !value.is_finite() {
            return None;
        }
        Some(NumLit {
            value,
            precision: decimals.saturating_sub(exponent),
            plus: bytes.first() == Some(&b'+'),
        })
    }

    pub fn value(&self) -> f64 {
        self.value
    }

    /// Decimal places the original text resolves (negative for `9E9`).
    pub fn precision(&self) -> i32 {
        self.precision
    }

    /// The text to write for `new`, or `None` when the original text already says it.
    ///
    /// `new` is written with `max(original decimals, min_decimals)` places, never in exponent
    /// form; if it rounds to the same text as the original value at that precision, the original
    /// text is kept (so `0` stays `0` and `9E+09` stays `9E+09`).
    pub fn rewrite(&self, new: f64, min_decimals: usize) -> Option<String> {
        let places = self.precision.clamp(0, 12).max(min_decimals.min(12) as i32) as usize;
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

/// `value` with `places` decimals, without a negative zero.
pub fn fixed(value: f64, places: usize) -> String {
    let s = format!("{value:.places$}");
    if s.starts_with('-') && s[1..].bytes().all(|b| b == b'0' || b == b'.') {
        s[1..].to_owned()
    } else {
        s
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

    #[test]
    fn never_writes_exponent_noise() {
        let lit = NumLit::parse(b"1.5").unwrap();
        assert_eq!(lit.rewrite(1.0000000000002, 3).as_deref(), Some("1.000"));
        assert_eq!(lit.rewrite(1e-12, 3).as_deref(), Some("0.000"));
    }
}
