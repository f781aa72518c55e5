//! Python `repr` formatting, so the CLI and the app print the lab's tuples
//! character for character.

/// `repr(float(x))`: the shortest round-trip digits, fixed notation when
/// the decimal exponent is in [-4, 16), scientific (`1e-05`, `1.5e+16`)
/// otherwise, always with a `.0` or fraction in fixed notation.
pub fn py_float(x: f64) -> String {
    if x.is_nan() {
        return "nan".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if x == 0.0 {
        return if x.is_sign_negative() { "-0.0".into() } else { "0.0".into() };
    }
    // `{:e}` finds how many digits the shortest round-trip form needs; when
    // two digit strings of that length both round-trip, Python (David Gay's
    // dtoa) takes the one nearer the exact value, ties to even, so the digits
    // are then produced by exact rounding at that precision.
    let shortest = format!("{x:e}");
    let n = shortest.split_once('e').map_or(1, |(m, _)| m.chars().filter(|c| c.is_ascii_digit()).count());
    let sci = format!("{:.*e}", n.saturating_sub(1), x);
    let (mant, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let neg = mant.starts_with('-');
    let digits: String = mant.chars().filter(|c| c.is_ascii_digit()).collect();
    let sign = if neg { "-" } else { "" };
    if (-4..16).contains(&exp) {
        let n = digits.len() as i32;
        let s = if exp >= 0 {
            if n <= exp + 1 {
                format!("{digits}{}.0", "0".repeat((exp + 1 - n) as usize))
            } else {
                format!("{}.{}", &digits[..(exp + 1) as usize], &digits[(exp + 1) as usize..])
            }
        } else {
            format!("0.{}{digits}", "0".repeat((-exp - 1) as usize))
        };
        format!("{sign}{s}")
    } else {
        let m = if digits.len() > 1 { format!("{}.{}", &digits[..1], &digits[1..]) } else { digits };
        let es = if exp < 0 { '-' } else { '+' };
        format!("{sign}{m}e{es}{:02}", exp.abs())
    }
}

/// `repr` of an f32 value as Python sees it after widening to float.
pub fn py_f32(x: f32) -> String {
    py_float(x as f64)
}

/// `repr` of a Python str holding ASCII/UTF-8 text: single quotes unless the
/// text contains a single quote and no double quote.
pub fn py_str(s: &str) -> String {
    let quote = if s.contains('\'') && !s.contains('"') { '"' } else { '\'' };
    let mut out = String::with_capacity(s.len() + 2);
    out.push(quote);
    for ch in s.chars() {
        match ch {
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c == quote => {
                out.push('\\');
                out.push(c);
            }
            c if (c as u32) < 0x20 || c as u32 == 0x7f => out.push_str(&format!("\\x{:02x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push(quote);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_like_python() {
        assert_eq!(py_float(100.0), "100.0");
        assert_eq!(py_float(105.0), "105.0");
        assert_eq!(py_f32(61.4), "61.400001525878906");
        assert_eq!(py_f32(72.02083), "72.02082824707031");
        assert_eq!(py_float(0.8), "0.8");
        assert_eq!(py_float(0.0001), "0.0001");
        assert_eq!(py_float(0.00001), "1e-05");
        assert_eq!(py_float(1.5e16), "1.5e+16");
        assert_eq!(py_float(1e22), "1e+22");
        assert_eq!(py_float(123456789012345.6), "123456789012345.6");
        assert_eq!(py_float(-2.5), "-2.5");
        assert_eq!(py_float(0.0), "0.0");
        // Two 16-digit strings round-trip; Python picks the nearer (a tie here: even).
        // The literal is the f32 value exactly, every digit of it on purpose.
        #[allow(clippy::excessive_precision)]
        let exact = 66.618316650390625;
        assert_eq!(py_float(exact), "66.61831665039062");
    }

    #[test]
    fn strings_like_python() {
        assert_eq!(py_str("/home/u/MyKITTI"), "'/home/u/MyKITTI'");
        assert_eq!(py_str("it's"), "\"it's\"");
        assert_eq!(py_str("a\\b"), "'a\\\\b'");
    }
}
