//! Decimal text to f64 at memory speed where it is exact to do so.
//!
//! Simulation codes write numbers as `±d.dddE±dd` with up to 16 digits. Up
//! to 2⁵³ the digits are an exact f64, and so is a power of ten up to
//! 10²²: their product or quotient is one IEEE operation, correctly rounded
//! — Clinger's fast path, the bits `str::parse` gives. Everything else is
//! left to the general parser.

/// Powers of ten f64 holds exactly.
const EXACT_POWERS: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// A decimal `[±]digits[.digits][E|D[±]digits]` whose digits (without
/// leading zeros) fit 2⁵³ and whose power of ten is within ±22: the value
/// is then one exact integer times or over one exact power, a single
/// rounding — Clinger's fast path, the same bits as `str::parse`. Anything
/// else is `None`, for the general parser. AMRClaw writes 16 digits, so
/// nine values in ten take this path.
pub(crate) fn fast_decimal(t: &[u8]) -> Option<f64> {
    let (negative, mut i) = match t.first()? {
        b'-' => (true, 1),
        b'+' => (false, 1),
        _ => (false, 0),
    };
    let mut mantissa: u64 = 0;
    let (mut digits, mut scale, mut seen) = (0u32, 0i32, false);
    let mut dot = false;
    while let Some(&c) = t.get(i) {
        match c {
            b'0'..=b'9' => {
                seen = true;
                if mantissa != 0 || c != b'0' {
                    digits += 1;
                    if digits > 16 {
                        return None;
                    }
                }
                mantissa = mantissa * 10 + u64::from(c - b'0');
                scale -= i32::from(dot);
            }
            b'.' if !dot => dot = true,
            _ => break,
        }
        i += 1;
    }
    if !seen {
        return None;
    }
    if let Some(&c) = t.get(i) {
        if !matches!(c, b'e' | b'E' | b'd' | b'D') {
            return None;
        }
        i += 1;
        let sign = match t.get(i)? {
            b'-' => {
                i += 1;
                -1
            }
            b'+' => {
                i += 1;
                1
            }
            _ => 1,
        };
        let rest = t.get(i..).filter(|r| !r.is_empty() && r.len() <= 4)?;
        let mut e = 0i32;
        for &c in rest {
            if !c.is_ascii_digit() {
                return None;
            }
            e = e * 10 + i32::from(c - b'0');
        }
        scale += sign * e;
    }
    if mantissa >= 1 << 53 || scale.unsigned_abs() > 22 {
        return (mantissa == 0).then_some(if negative { -0.0 } else { 0.0 });
    }
    let m = mantissa as f64;
    let v = if scale >= 0 {
        m * EXACT_POWERS[scale as usize]
    } else {
        m / EXACT_POWERS[(-scale) as usize]
    };
    Some(if negative { -v } else { v })
}
