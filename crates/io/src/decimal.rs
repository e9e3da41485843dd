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
/// nine values in ten take this path. The readers use
/// [`fast_decimal_prefix`], the same in one pass; this is its reference.
#[cfg(test)]
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
    exact(negative, mantissa, scale)
}

/// `±mantissa × 10^scale` when it is one correctly rounded operation
/// (digits below 2⁵³, a power of ten within ±22; zero at any scale).
fn exact(negative: bool, mantissa: u64, scale: i32) -> Option<f64> {
    let v = if mantissa == 0 {
        0.0
    } else if mantissa >= 1 << 53 || scale.unsigned_abs() > 22 {
        return None;
    } else if scale >= 0 {
        mantissa as f64 * EXACT_POWERS[scale as usize]
    } else {
        mantissa as f64 / EXACT_POWERS[(-scale) as usize]
    };
    Some(if negative { -v } else { v })
}

/// Eight ASCII digits at `t[i..i + 8]` as a number, when all eight are
/// digits: one load and three multiplies instead of eight steps.
#[inline]
fn eight_digits(t: &[u8], i: usize) -> Option<u64> {
    let bytes: [u8; 8] = t.get(i..i + 8)?.try_into().ok()?;
    let v = u64::from_le_bytes(bytes);
    // Every byte in '0'..='9': high nibble 3, and adding 6 keeps it 3.
    let digits = (v & 0xF0F0_F0F0_F0F0_F0F0) == 0x3030_3030_3030_3030
        && ((v.wrapping_add(0x0606_0606_0606_0606)) & 0xF0F0_F0F0_F0F0_F0F0)
            == 0x3030_3030_3030_3030;
    if !digits {
        return None;
    }
    // Pairs, then quads, then the eight (first byte most significant).
    let v = v - 0x3030_3030_3030_3030;
    let v = (v * 10 + (v >> 8)) & 0x00FF_00FF_00FF_00FF;
    let v = (v * 100 + (v >> 16)) & 0x0000_FFFF_0000_FFFF;
    Some((v * 10000 + (v >> 32)) & 0xFFFF_FFFF)
}

/// The number at the start of `t`, ending at ASCII whitespace or the end
/// of `t`, with the bytes it takes: [`fast_decimal`] of that token (the
/// same bits, the same `None`s) found in one pass, eight digits at a time
/// where they run that long. `None` leaves the token to the caller's scan
/// and the general parser.
pub(crate) fn fast_decimal_prefix(t: &[u8]) -> Option<(f64, usize)> {
    let (negative, mut i) = match t.first()? {
        b'-' => (true, 1),
        b'+' => (false, 1),
        _ => (false, 0),
    };
    let mut mantissa: u64 = 0;
    let (mut digits, mut scale, mut seen) = (0u32, 0i32, false);
    let mut dot = false;
    loop {
        if let Some(eight) = eight_digits(t, i) {
            // Significant digits: all eight once one was seen, else those
            // from the chunk's first non-zero digit.
            let sig = if mantissa != 0 {
                8
            } else {
                (1..=8).find(|&k| eight < 10u64.pow(k)).unwrap_or(8) * u32::from(eight != 0)
            };
            digits += sig;
            if digits > 16 {
                return None;
            }
            mantissa = mantissa * 100_000_000 + eight;
            seen = true;
            scale -= 8 * i32::from(dot);
            i += 8;
            continue;
        }
        match t.get(i) {
            Some(&c @ b'0'..=b'9') => {
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
            Some(b'.') if !dot => dot = true,
            _ => break,
        }
        i += 1;
    }
    if !seen {
        return None;
    }
    if let Some(&c) = t.get(i)
        && !c.is_ascii_whitespace()
    {
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
        let start = i;
        let mut e = 0i32;
        while let Some(&c) = t.get(i)
            && !c.is_ascii_whitespace()
        {
            if !c.is_ascii_digit() || i - start >= 4 {
                return None;
            }
            e = e * 10 + i32::from(c - b'0');
            i += 1;
        }
        if i == start {
            return None;
        }
        scale += sign * e;
    }
    exact(negative, mantissa, scale).map(|v| (v, i))
}
