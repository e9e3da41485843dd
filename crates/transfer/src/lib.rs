//! Transfer functions: how a normalised field value in `[0, 1]` becomes a
//! colour and an opacity.
//!
//! - [`Colormap`]: a named preset (exact published tables: viridis, inferno,
//!   magma, plasma, cividis, gray, ParaView's cool-warm) or sparse sRGB control
//!   points. Colours are given in sRGB, interpolated there (as ParaView and
//!   matplotlib do), and handed out in linear RGB for compositing.
//! - [`OpacityMap`]: sparse `(x, opacity)` control points, piecewise linear.
//! - [`TransferFunction`]: both baked into lookup tables, plus a table of the
//!   maximum opacity over any value range (the OSPRay approach). Integrators use
//!   it to skip intervals whose value range is invisible.
//! - [`ControlPoints`]: the sparse piecewise-linear map behind all of these,
//!   reused by particle radius and weight maps.
//! - [`read_colormap_file`]: colormaps from ParaView preset JSON or
//!   matplotlib-style colour lists (see the `import` module's notes).
//!
//! Invariant: `max_opacity(lo, hi)` is never below the opacity the lookup
//! tables return for any `x` in `[lo, hi]`, so skipping on it never drops a
//! visible sample.

mod colorspace;
mod import;
mod tables;

pub use import::{
    ColorSpace, ImportError, ImportedColormap, parse_colormap_json, read_colormap_file,
};

use voxless_core::{Lanes, Vec3, srgb_to_linear};

#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum TransferError {
    #[error("unknown colormap '{name}' (available: {})", COLORMAP_NAMES.join(", "))]
    UnknownColormap { name: String },
    #[error("unknown opacity preset '{name}' (available: {})", OPACITY_NAMES.join(", "))]
    UnknownOpacity { name: String },
    #[error("{what}: {message}")]
    BadControlPoints { what: String, message: String },
}

/// Names accepted by [`Colormap::preset`].
pub const COLORMAP_NAMES: &[&str] = &[
    "viridis",
    "inferno",
    "magma",
    "plasma",
    "cividis",
    "gray",
    "cool-warm",
];
/// Names accepted by [`OpacityMap::preset`].
pub const OPACITY_NAMES: &[&str] = &["linear", "constant", "ramp-high", "ramp-low"];

/// A sparse, sorted piecewise-linear map `x → y` (constant beyond the ends).
#[derive(Clone, Debug, PartialEq)]
pub struct ControlPoints {
    points: Vec<(f32, f32)>,
}

impl ControlPoints {
    /// `what` names the map in error messages ("opacity map", "radius map").
    /// Points need finite coordinates and strictly increasing `x` (equal `x`
    /// twice makes a step).
    pub fn new(what: &str, points: &[(f32, f32)]) -> Result<Self, TransferError> {
        let bad = |message: String| TransferError::BadControlPoints {
            what: what.to_string(),
            message,
        };
        if points.is_empty() {
            return Err(bad("needs at least one control point".into()));
        }
        for (i, &(x, y)) in points.iter().enumerate() {
            if !x.is_finite() || !y.is_finite() {
                return Err(bad(format!("point {i} ({x}, {y}) is not finite")));
            }
            if i > 0 && x < points[i - 1].0 {
                return Err(bad(format!(
                    "x must not decrease: point {i} has x = {x} after {}",
                    points[i - 1].0
                )));
            }
        }
        Ok(ControlPoints {
            points: points.to_vec(),
        })
    }

    pub fn points(&self) -> &[(f32, f32)] {
        &self.points
    }

    pub fn eval(&self, x: f32) -> f32 {
        let p = &self.points;
        let i = p.partition_point(|&(px, _)| px <= x);
        if i == 0 {
            return p[0].1;
        }
        if i == p.len() {
            return p[p.len() - 1].1;
        }
        let (x0, y0) = p[i - 1];
        let (x1, y1) = p[i];
        let s = if x1 > x0 { (x - x0) / (x1 - x0) } else { 1.0 };
        y0 + s * (y1 - y0)
    }
}

/// Colour control points in sRGB.
#[derive(Clone, Debug, PartialEq)]
pub struct Colormap {
    name: String,
    /// (x, sRGB) sorted by x.
    points: Vec<(f32, [f32; 3])>,
}

impl Colormap {
    pub fn preset(name: &str) -> Result<Colormap, TransferError> {
        let key = name.to_ascii_lowercase().replace('_', "-");
        let table: &[[f32; 3]; 256] = match key.as_str() {
            "viridis" => &tables::VIRIDIS,
            "inferno" => &tables::INFERNO,
            "magma" => &tables::MAGMA,
            "plasma" => &tables::PLASMA,
            "cividis" => &tables::CIVIDIS,
            "gray" | "grey" | "greys" => &tables::GRAY,
            "cool-warm" | "coolwarm" | "cool-to-warm" => &tables::COOL_WARM,
            _ => {
                return Err(TransferError::UnknownColormap {
                    name: name.to_string(),
                });
            }
        };
        Ok(Colormap {
            name: key,
            points: table
                .iter()
                .enumerate()
                .map(|(i, c)| (i as f32 / 255.0, *c))
                .collect(),
        })
    }

    /// Sparse sRGB control points `(x, [r, g, b])`, components in [0, 1].
    pub fn from_points(points: &[(f32, [f32; 3])]) -> Result<Colormap, TransferError> {
        for c in 0..3 {
            let ch: Vec<(f32, f32)> = points.iter().map(|p| (p.0, p.1[c])).collect();
            ControlPoints::new("colormap", &ch)?;
        }
        if let Some(p) = points
            .iter()
            .find(|p| p.1.iter().any(|v| !(0.0..=1.0).contains(v)))
        {
            return Err(TransferError::BadControlPoints {
                what: "colormap".into(),
                message: format!("colour {:?} at x = {} is outside [0, 1]", p.1, p.0),
            });
        }
        Ok(Colormap {
            name: "custom".into(),
            points: points.to_vec(),
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// sRGB colour at `x` (clamped to the ends).
    pub fn srgb(&self, x: f32) -> [f32; 3] {
        let p = &self.points;
        let i = p.partition_point(|q| q.0 <= x);
        if i == 0 {
            return p[0].1;
        }
        if i == p.len() {
            return p[p.len() - 1].1;
        }
        let (x0, c0) = p[i - 1];
        let (x1, c1) = p[i];
        let s = if x1 > x0 { (x - x0) / (x1 - x0) } else { 1.0 };
        [0, 1, 2].map(|k| c0[k] + s * (c1[k] - c0[k]))
    }

    /// Linear-RGB colour at `x`.
    pub fn linear(&self, x: f32) -> Vec3 {
        let c = self.srgb(x);
        Vec3::new(
            srgb_to_linear(c[0]),
            srgb_to_linear(c[1]),
            srgb_to_linear(c[2]),
        )
    }
}

/// Opacity control points over the normalised value.
#[derive(Clone, Debug, PartialEq)]
pub struct OpacityMap(pub ControlPoints);

impl OpacityMap {
    pub fn preset(name: &str) -> Result<OpacityMap, TransferError> {
        let pts: &[(f32, f32)] = match name.to_ascii_lowercase().as_str() {
            "linear" | "ramp" => &[(0.0, 0.0), (1.0, 1.0)],
            "constant" | "flat" => &[(0.0, 1.0), (1.0, 1.0)],
            "ramp-high" => &[(0.0, 0.0), (0.5, 0.0), (1.0, 1.0)],
            "ramp-low" => &[(0.0, 1.0), (1.0, 0.0)],
            _ => {
                return Err(TransferError::UnknownOpacity {
                    name: name.to_string(),
                });
            }
        };
        Self::from_points(pts)
    }

    /// Opacities must lie in [0, 1].
    pub fn from_points(points: &[(f32, f32)]) -> Result<OpacityMap, TransferError> {
        let cp = ControlPoints::new("opacity map", points)?;
        if let Some(p) = points.iter().find(|p| !(0.0..=1.0).contains(&p.1)) {
            return Err(TransferError::BadControlPoints {
                what: "opacity map".into(),
                message: format!("opacity {} at x = {} is outside [0, 1]", p.1, p.0),
            });
        }
        Ok(OpacityMap(cp))
    }
}

/// Entries in the colour and opacity lookup tables.
const LUT: usize = 1024;

/// `2^23`: adding and subtracting it rounds a float in `[0, 2^23)` to an
/// integer.
const ROUND: f32 = 8_388_608.0;

/// `t[i]·w0 + t[i1]·w1` per lane (a function, not a closure: lane kernels
/// inline into their SIMD entry).
#[inline(always)]
fn lerp<L: Lanes>(t: &[f32], (i, i1, w0, w1): (L, L, L, L)) -> L {
    L::gather(t, i) * w0 + L::gather(t, i1) * w1
}

/// A colormap and opacity map baked for fast lookup.
#[derive(Clone, Debug)]
pub struct TransferFunction {
    colormap: Colormap,
    opacity_map: OpacityMap,
    /// The colour table by channel (lanes gather from each).
    color_lut: [Vec<f32>; 3],
    opacity_lut: Vec<f32>,
    /// `max_table[level][i]` = max of `opacity_lut[i .. i + 2^level]`.
    max_table: Vec<Vec<f32>>,
}

impl TransferFunction {
    pub fn new(colormap: Colormap, opacity_map: OpacityMap) -> Self {
        let at = |i: usize| i as f32 / (LUT - 1) as f32;
        let colors: Vec<Vec3> = (0..LUT).map(|i| colormap.linear(at(i))).collect();
        let color_lut = [0, 1, 2].map(|c| colors.iter().map(|v| v[c]).collect());
        let opacity_lut: Vec<f32> = (0..LUT).map(|i| opacity_map.0.eval(at(i))).collect();
        // A sparse table over the LUT's knots: the maximum of any run of
        // them is two overlapping power-of-two windows.
        let mut max_table = vec![opacity_lut.clone()];
        let mut width = 1;
        while width * 2 <= LUT {
            let prev = max_table.last().unwrap();
            let next: Vec<f32> = (0..=LUT - 2 * width)
                .map(|i| prev[i].max(prev[i + width]))
                .collect();
            max_table.push(next);
            width *= 2;
        }
        TransferFunction {
            colormap,
            opacity_map,
            color_lut,
            opacity_lut,
            max_table,
        }
    }

    /// Viridis with a linear opacity ramp.
    pub fn default_for_density() -> Self {
        TransferFunction::new(
            Colormap::preset("viridis").unwrap(),
            OpacityMap::preset("linear").unwrap(),
        )
    }

    pub fn colormap(&self) -> &Colormap {
        &self.colormap
    }
    pub fn opacity_map(&self) -> &OpacityMap {
        &self.opacity_map
    }

    #[inline]
    fn lut_pos(x: f32) -> (usize, f32) {
        let f = x.clamp(0.0, 1.0) * (LUT - 1) as f32;
        // NaN clamps to NaN; `as i32` maps it to 0. (Through `i32`, not
        // `usize`: a float-to-`u64` conversion is a dozen instructions on
        // x86-64, and this runs twice per sample.)
        let i = (f as i32 as usize).min(LUT - 2);
        (i, (f - i as f32).clamp(0.0, 1.0))
    }

    /// Knot `i` of the colour table.
    #[inline(always)]
    fn knot(&self, i: usize) -> Vec3 {
        let [r, g, b] = &self.color_lut;
        Vec3::new(r[i], g[i], b[i])
    }

    /// The tables every lookup interpolates: `(r, g, b, opacity)` at the
    /// knots `i / (n − 1)` (a device integrator uploads them and reads them
    /// as [`TransferFunction::color_and_opacity`] does).
    pub fn knots(&self) -> Vec<[f32; 4]> {
        let [r, g, b] = &self.color_lut;
        (0..LUT)
            .map(|i| [r[i], g[i], b[i], self.opacity_lut[i]])
            .collect()
    }

    /// Linear-RGB colour at normalised `x`.
    #[inline]
    pub fn color(&self, x: f32) -> Vec3 {
        let (i, s) = Self::lut_pos(x);
        self.knot(i) * (1.0 - s) + self.knot(i + 1) * s
    }

    /// [`TransferFunction::color`] and [`TransferFunction::opacity`] at
    /// normalised `x`, the same bits, with one LUT position for both.
    #[inline]
    pub fn color_and_opacity(&self, x: f32) -> (Vec3, f32) {
        let (i, s) = Self::lut_pos(x);
        (
            self.knot(i) * (1.0 - s) + self.knot(i + 1) * s,
            self.opacity_lut[i] * (1.0 - s) + self.opacity_lut[i + 1] * s,
        )
    }

    /// [`TransferFunction::color_and_opacity`] of eight values at once,
    /// the same bits in every lane where `x` is not NaN (NaN lanes give
    /// NaN opacity there and here, colours unspecified): the table position
    /// with the same arithmetic (the integer part by rounding and
    /// correcting, which is the truncation for `f` in `[0, LUT)`), the
    /// knots by gathers from the colour table's channels.
    #[inline(always)]
    pub fn color_and_opacity_lanes<L: Lanes>(&self, x: L) -> ([L; 3], L) {
        let s = L::splat;
        // `clamp(0, 1)` as `f32::clamp` does it, NaN passing through.
        let f = s(1.0).min(s(0.0).max(x)) * s((LUT - 1) as f32);
        // Round to the nearest integer (f < 2^23), then one down where
        // that rounded up: floor, which is truncation for f ≥ 0.
        let r = (f + s(ROUND)) - s(ROUND);
        let i = r - r.gt(f).select(s(1.0), s(0.0));
        let i = i.lt(s((LUT - 2) as f32)).select(i, s((LUT - 2) as f32));
        let w = s(1.0).min(s(0.0).max(f - i));
        let at = (i, i + s(1.0), s(1.0) - w, w);
        let [r, g, b] = &self.color_lut;
        (
            [lerp(r, at), lerp(g, at), lerp(b, at)],
            lerp(&self.opacity_lut, at),
        )
    }

    /// Opacity in [0, 1] at normalised `x`.
    #[inline]
    pub fn opacity(&self, x: f32) -> f32 {
        let (i, s) = Self::lut_pos(x);
        self.opacity_lut[i] * (1.0 - s) + self.opacity_lut[i + 1] * s
    }

    /// Whether `opacity(x)` is non-zero anywhere in `[lo, hi]`: exactly
    /// `max_opacity(lo, hi) > 0`, answered from the ends alone when they
    /// settle it (space skipping asks once per interval).
    #[inline]
    pub fn any_opacity(&self, lo: f32, hi: f32) -> bool {
        lo <= hi && (self.opacity(hi) > 0.0 || self.max_opacity(lo, hi) > 0.0)
    }

    /// The maximum of `opacity(x)` over normalised `x` in `[lo, hi]` (up to
    /// rounding in `opacity`'s interpolation). `opacity` is piecewise
    /// linear between the LUT's knots, so the maximum lies at an end or at
    /// a knot inside: exact, so a range the map gives no opacity anywhere
    /// is recognised as invisible even where it ends at the foot of a ramp
    /// (a conservative bound over coarser bins would call it visible).
    pub fn max_opacity(&self, lo: f32, hi: f32) -> f32 {
        if !(lo <= hi) {
            return 0.0;
        }
        let ends = self.opacity(lo).max(self.opacity(hi));
        let pos = |x: f32| x.clamp(0.0, 1.0) * (LUT - 1) as f32;
        // Knots strictly between the ends.
        let a = pos(lo).floor() as usize + 1;
        let b = (pos(hi).ceil() as usize).saturating_sub(1);
        if a > b {
            return ends;
        }
        // Sparse-table range maximum: two overlapping power-of-two windows.
        let len = b - a + 1;
        let level = (usize::BITS - 1 - len.leading_zeros()) as usize;
        let w = 1 << level;
        ends.max(self.max_table[level][a].max(self.max_table[level][b + 1 - w]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_published_endpoints() {
        let v = Colormap::preset("viridis").unwrap();
        assert_eq!(v.srgb(0.0), [0.267004, 0.004874, 0.329415]);
        assert_eq!(v.srgb(1.0), [0.993248, 0.906157, 0.143936]);
        let cw = Colormap::preset("cool-warm").unwrap();
        let mid = cw.srgb(0.5);
        assert!(mid.iter().all(|c| (c - 0.865).abs() < 0.01), "{mid:?}");
        for name in COLORMAP_NAMES {
            Colormap::preset(name).unwrap();
        }
        let err = Colormap::preset("jet").unwrap_err().to_string();
        assert!(err.contains("jet") && err.contains("viridis"), "{err}");
    }

    #[test]
    fn max_opacity_bounds_every_lookup() {
        let op =
            OpacityMap::from_points(&[(0.0, 0.0), (0.3, 0.0), (0.31, 0.8), (0.6, 0.1), (1.0, 0.5)])
                .unwrap();
        let tf = TransferFunction::new(Colormap::preset("gray").unwrap(), op);
        let mut seed = 1u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1 << 24) as f32
        };
        for _ in 0..2000 {
            let (a, b) = (rnd(), rnd());
            let (lo, hi) = (a.min(b), a.max(b));
            let m = tf.max_opacity(lo, hi);
            for k in 0..=50 {
                let x = lo + (hi - lo) * k as f32 / 50.0;
                assert!(
                    tf.opacity(x) <= m + 1e-7,
                    "x {x} in [{lo}, {hi}]: {} > {m}",
                    tf.opacity(x)
                );
            }
        }
        // The zero-opacity region is recognised as invisible (away from the kink).
        assert_eq!(tf.max_opacity(0.0, 0.29), 0.0);
        // And the maximum is the maximum, not a bound over a coarser grid.
        for _ in 0..2000 {
            let (a, b) = (rnd(), rnd());
            let (lo, hi) = (a.min(b), a.max(b));
            let brute = (0..=20_000)
                .map(|k| tf.opacity(lo + (hi - lo) * k as f32 / 20_000.0))
                .fold(0.0, f32::max);
            let m = tf.max_opacity(lo, hi);
            assert!(
                m >= brute - 1e-7 && m <= brute + 1e-3,
                "[{lo}, {hi}]: {m} vs {brute}"
            );
        }
        // The foot of a ramp: values at or below the range's low end are
        // invisible under the linear map.
        let linear = TransferFunction::default_for_density();
        assert_eq!(linear.max_opacity(0.0, 0.0), 0.0);
        assert!(linear.max_opacity(0.0, 1e-3) > 0.0);
        for _ in 0..2000 {
            let (a, b) = (rnd(), rnd());
            let (lo, hi) = (a.min(b) * 0.4, a.max(b) * 0.4);
            assert_eq!(tf.any_opacity(lo, hi), tf.max_opacity(lo, hi) > 0.0);
        }
    }

    #[test]
    fn control_points_interpolate_and_validate() {
        let cp = ControlPoints::new("radius map", &[(0.0, 1.0), (1.0, 0.5)]).unwrap();
        assert_eq!(cp.eval(0.5), 0.75);
        assert_eq!(cp.eval(-1.0), 1.0);
        assert_eq!(cp.eval(2.0), 0.5);
        assert!(ControlPoints::new("radius map", &[(0.5, 1.0), (0.1, 0.5)]).is_err());
        assert!(ControlPoints::new("radius map", &[(f32::NAN, 1.0)]).is_err());
        assert!(OpacityMap::from_points(&[(0.0, 2.0)]).is_err());
    }
}

#[cfg(test)]
mod lane_tests {
    use super::*;
    use voxless_core::simd::{LANES, Simd, WithLanes, dispatch};

    /// Colour and opacity of `x`, eight at a time.
    struct Lookup<'a>(&'a TransferFunction, &'a [f32]);

    impl WithLanes for Lookup<'_> {
        type Output = Vec<(Vec3, f32)>;
        #[inline(always)]
        fn run<L: Lanes>(self) -> Self::Output {
            let mut out = Vec::new();
            for at in (0..self.1.len()).step_by(LANES) {
                let ([r, g, b], o) = self.0.color_and_opacity_lanes(L::load(self.1, at));
                let (r, g, b, o) = (r.to_array(), g.to_array(), b.to_array(), o.to_array());
                out.extend((0..LANES).map(|k| (Vec3::new(r[k], g[k], b[k]), o[k])));
            }
            out
        }
    }

    #[test]
    fn lane_lookups_give_the_bits_of_scalar_lookups() {
        let tf = TransferFunction::new(
            Colormap::preset("inferno").unwrap(),
            OpacityMap::from_points(&[(0.0, 0.0), (0.3, 0.7), (0.31, 0.1), (1.0, 1.0)]).unwrap(),
        );
        // Every knot, between knots, the ends, outside [0, 1], and NaN.
        let mut xs: Vec<f32> = (0..=40_000).map(|k| k as f32 / 40_000.0).collect();
        xs.extend((0..LUT).map(|i| i as f32 / (LUT - 1) as f32));
        xs.extend([
            -1.0,
            -0.0,
            1.0,
            1.0 + 1e-7,
            7.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ]);
        xs.extend([f32::NAN, f32::MIN_POSITIVE, 1.0 - f32::EPSILON]);
        xs.resize(xs.len().next_multiple_of(LANES), 0.5);
        for simd in Simd::ALL.into_iter().filter(|s| s.available()) {
            let lanes = dispatch(simd, Lookup(&tf, &xs));
            for (&x, &(c, o)) in xs.iter().zip(&lanes) {
                let (cs, os) = tf.color_and_opacity(x);
                if x.is_nan() {
                    assert!(o.is_nan() && os.is_nan(), "{simd:?}: NaN opacity");
                    continue;
                }
                let same = (0..3).all(|k| c[k].to_bits() == cs[k].to_bits())
                    && o.to_bits() == os.to_bits();
                assert!(
                    same,
                    "{simd:?}, x = {x}: lanes {c:?} {o}, scalar {cs:?} {os}"
                );
            }
        }
    }
}
