//! Interpolation between two sRGB colours in the colour spaces ParaView
//! presets name: straight RGB, CIELAB, Moreland's diverging Msh space, HSV,
//! and steps. Colours in and out are sRGB components in `[0, 1]`; results
//! outside the gamut are clamped.

use std::f64::consts::PI;

/// How a colour map blends between two control points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// Linear interpolation of the sRGB components as given.
    Rgb,
    /// Linear interpolation in CIELAB (D65 white).
    Lab,
    /// Moreland's diverging interpolation in Msh (polar CIELAB), with a
    /// near-white midpoint between saturated colours of distant hues.
    Diverging,
    /// Linear interpolation in HSV along the shorter way round the hue circle.
    Hsv,
    /// Piecewise constant: each colour holds until the next control point.
    Step,
}

impl ColorSpace {
    /// Names as ParaView writes them (`ColorSpace`), case-insensitive.
    /// `Lab/CIEDE2000` is treated as `Lab`.
    pub fn parse(name: &str) -> Option<ColorSpace> {
        match name.to_ascii_lowercase().as_str() {
            "rgb" => Some(ColorSpace::Rgb),
            "lab" | "cielab" | "lab/ciede2000" => Some(ColorSpace::Lab),
            "diverging" | "msh" => Some(ColorSpace::Diverging),
            "hsv" => Some(ColorSpace::Hsv),
            "step" => Some(ColorSpace::Step),
            _ => None,
        }
    }

    pub const NAMES: &'static [&'static str] = &["RGB", "Lab", "Diverging", "HSV", "Step"];

    /// The sRGB colour a fraction `t` of the way from `a` to `b`.
    pub fn mix(self, a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
        let out = match self {
            ColorSpace::Rgb => lerp3(a, b, t),
            ColorSpace::Step => {
                if t < 1.0 {
                    a
                } else {
                    b
                }
            }
            ColorSpace::Lab => lab_to_srgb(lerp3(srgb_to_lab(a), srgb_to_lab(b), t)),
            ColorSpace::Diverging => msh_mix(a, b, t),
            ColorSpace::Hsv => hsv_mix(a, b, t),
        };
        out.map(|v| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
    }
}

fn lerp3(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]))
}

fn to_linear(v: f64) -> f64 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn to_srgb(v: f64) -> f64 {
    let v = v.max(0.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// D65 reference white.
const WHITE: [f64; 3] = [0.950_47, 1.0, 1.088_83];

fn srgb_to_lab(c: [f64; 3]) -> [f64; 3] {
    let [r, g, b] = c.map(to_linear);
    let xyz = [
        0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b,
        0.212_672_9 * r + 0.715_152_2 * g + 0.072_175_0 * b,
        0.019_333_9 * r + 0.119_192_0 * g + 0.950_304_1 * b,
    ];
    let f = |t: f64| {
        if t > 216.0 / 24389.0 {
            t.cbrt()
        } else {
            (24389.0 / 27.0 * t + 16.0) / 116.0
        }
    };
    let [fx, fy, fz] = [0, 1, 2].map(|k| f(xyz[k] / WHITE[k]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

fn lab_to_srgb(lab: [f64; 3]) -> [f64; 3] {
    let fy = (lab[0] + 16.0) / 116.0;
    let fx = fy + lab[1] / 500.0;
    let fz = fy - lab[2] / 200.0;
    let inv = |f: f64| {
        if f > 6.0 / 29.0 {
            f * f * f
        } else {
            (116.0 * f - 16.0) * 27.0 / 24389.0
        }
    };
    let (x, y, z) = (inv(fx) * WHITE[0], inv(fy) * WHITE[1], inv(fz) * WHITE[2]);
    let r = 3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z;
    let g = -0.969_266_0 * x + 1.876_010_8 * y + 0.041_556_0 * z;
    let b = 0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z;
    [r, g, b].map(to_srgb)
}

/// Polar CIELAB: magnitude M, saturation s (angle from the L axis), hue h.
fn lab_to_msh(lab: [f64; 3]) -> [f64; 3] {
    let m = (lab[0] * lab[0] + lab[1] * lab[1] + lab[2] * lab[2]).sqrt();
    if m == 0.0 {
        return [0.0; 3];
    }
    [
        m,
        (lab[0] / m).clamp(-1.0, 1.0).acos(),
        lab[2].atan2(lab[1]),
    ]
}

fn msh_to_lab(msh: [f64; 3]) -> [f64; 3] {
    let [m, s, h] = msh;
    [m * s.cos(), m * s.sin() * h.cos(), m * s.sin() * h.sin()]
}

/// Hue for an unsaturated end of a diverging segment: spin away from the
/// saturated end's hue so the path does not bend through an unrelated hue.
fn adjust_hue(saturated: [f64; 3], m_unsat: f64) -> f64 {
    let [m, s, h] = saturated;
    if m >= m_unsat || s.sin() == 0.0 {
        return h;
    }
    let spin = s * (m_unsat * m_unsat - m * m).sqrt() / (m * s.sin());
    if h > -PI / 3.0 { h + spin } else { h - spin }
}

fn msh_mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    let (mut p, mut q, mut t) = (lab_to_msh(srgb_to_lab(a)), lab_to_msh(srgb_to_lab(b)), t);
    let mut dh = (p[2] - q[2]).abs();
    if dh > PI {
        dh = 2.0 * PI - dh;
    }
    // Two saturated, distinct hues: pass through an unsaturated midpoint.
    if p[1] > 0.05 && q[1] > 0.05 && dh > PI / 3.0 {
        let mid = p[0].max(q[0]).max(88.0);
        if t < 0.5 {
            q = [mid, 0.0, 0.0];
            t *= 2.0;
        } else {
            p = [mid, 0.0, 0.0];
            t = 2.0 * t - 1.0;
        }
    }
    if p[1] < 0.05 && q[1] > 0.05 {
        p[2] = adjust_hue(q, p[0]);
    } else if q[1] < 0.05 && p[1] > 0.05 {
        q[2] = adjust_hue(p, q[0]);
    }
    lab_to_srgb(msh_to_lab(lerp3(p, q, t)))
}

/// (h in [0, 1), s, v).
fn rgb_to_hsv(c: [f64; 3]) -> [f64; 3] {
    let max = c[0].max(c[1]).max(c[2]);
    let min = c[0].min(c[1]).min(c[2]);
    let d = max - min;
    let s = if max > 0.0 { d / max } else { 0.0 };
    if d == 0.0 {
        return [0.0, s, max];
    }
    let h = if max == c[0] {
        (c[1] - c[2]) / d
    } else if max == c[1] {
        2.0 + (c[2] - c[0]) / d
    } else {
        4.0 + (c[0] - c[1]) / d
    };
    [(h / 6.0).rem_euclid(1.0), s, max]
}

fn hsv_to_rgb(hsv: [f64; 3]) -> [f64; 3] {
    let [h, s, v] = hsv;
    let h6 = h.rem_euclid(1.0) * 6.0;
    let sector = (h6.floor() as i32).clamp(0, 5);
    let f = h6 - sector as f64;
    let (p, q, r) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match sector {
        0 => [v, r, p],
        1 => [q, v, p],
        2 => [p, v, r],
        3 => [p, q, v],
        4 => [r, p, v],
        _ => [v, p, q],
    }
}

fn hsv_mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    let (mut p, mut q) = (rgb_to_hsv(a), rgb_to_hsv(b));
    // A grey end has no hue of its own: borrow the other end's.
    if p[1] == 0.0 {
        p[0] = q[0];
    } else if q[1] == 0.0 {
        q[0] = p[0];
    }
    if q[0] - p[0] > 0.5 {
        p[0] += 1.0;
    } else if p[0] - q[0] > 0.5 {
        q[0] += 1.0;
    }
    hsv_to_rgb(lerp3(p, q, t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_round_trip_and_ends_are_kept() {
        for c in [
            [0.2, 0.5, 0.9],
            [1.0, 1.0, 1.0],
            [0.0, 0.0, 0.0],
            [0.7, 0.02, 0.15],
        ] {
            let back = lab_to_srgb(srgb_to_lab(c));
            let hsv = hsv_to_rgb(rgb_to_hsv(c));
            for k in 0..3 {
                assert!((back[k] - c[k]).abs() < 1e-6, "{c:?} → {back:?}");
                assert!((hsv[k] - c[k]).abs() < 1e-12, "{c:?} → {hsv:?}");
            }
            for space in [ColorSpace::Lab, ColorSpace::Diverging, ColorSpace::Hsv] {
                let end = space.mix(c, [0.3, 0.3, 0.3], 0.0);
                assert!((0..3).all(|k| (end[k] - c[k]).abs() < 1e-6), "{space:?}");
            }
        }
        let hsv = ColorSpace::Hsv.mix([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.5);
        assert!((hsv[0] - 1.0).abs() < 1e-12 && hsv[1] == 0.0 && (hsv[2] - 1.0).abs() < 1e-12);
        assert_eq!(ColorSpace::Step.mix([0.1; 3], [0.9; 3], 0.99), [0.1; 3]);
    }
}
