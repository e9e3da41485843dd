//! RBF kernels: the value, gradient, volume integral and line integral of
//! one particle's contribution, per unit weight.
//!
//! With `d` the distance from the particle centre, `r` the particle's radius
//! parameter and `w` its weight:
//!
//! | kernel | φ(d) | support |
//! |---|---|---|
//! | `gaussian3` | `w·exp(−½(3d/r)²)` | `d ≤ r` |
//! | `gaussian` | `κ·w·exp(−d²/2r²)` | `d ≤ σr` |
//! | `cubic-spline` | `w·M4(d/h)/(πh³)`, `h = r` | `d ≤ 2h` |
//! | `quartic-spline` | `w·M5(d/h)/(20πh³)`, `h = r` | `d ≤ 2.5h` |
//! | `quintic-spline` | `w·M6(d/h)/(120πh³)`, `h = r` | `d ≤ 3h` |
//! | `wendland-c2`, `-c4`, `-c6` | `w·σ·w(d/h)/h³`, `h = r` | `d ≤ 2h` |
//!
//! `M4(q) = 1 − 1.5q² + 0.75q³` for `q < 1`, `0.25(2 − q)³` for `1 ≤ q < 2`,
//! 0 beyond: the standard SPH cubic spline, normalised so that
//! `∫ M4(|x|/h)/(πh³) dx = 1`; with `w` = mass, `Φ = Σ m W` is the SPH
//! density estimate. The SPH kernels (the cubic spline and those of
//! [`sph`]: M5, M6, Wendland C2/C4/C6) all take the smoothing length `h` in
//! PHANTOM's convention as the radius and are normalised to 1 per unit
//! weight; [`sph`] gives their formulas and how to convert the smoothing
//! lengths of SWIFT, Gadget and GIZMO.
//!
//! `gaussian3` is the attribute-aware RBF paper's eq. 1–2 (a Gaussian of
//! standard deviation r/3 truncated at three deviations); `gaussian` is the
//! CPU RBF paper's eq. 2 (κ and σ default to 1 and 2). The gradient is the
//! exact derivative, `∇φ = φ'(d)·(x − c)/d`; for the Gaussians that is
//! `−φ·(x − c)/s²` with `s` the standard deviation (the CPU paper's eq. 4
//! drops the `1/s²` factor; we keep the exact form).

use voxless_core::Vec3;
use voxless_core::simd::Lanes;

pub mod area;
pub mod chords;
pub mod column_poly;
pub mod sph;

pub use sph::{Sph, SphFamily};

/// The kernel family and its global parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Kernel {
    #[default]
    Gaussian3,
    Gaussian {
        kappa: f32,
        sigma: f32,
    },
    CubicSpline,
    /// The M5 quartic B-spline (support 2.5h).
    QuarticSpline,
    /// The M6 quintic B-spline (support 3h).
    QuinticSpline,
    /// Wendland C2 (support 2h).
    WendlandC2,
    /// Wendland C4 (support 2h).
    WendlandC4,
    /// Wendland C6 (support 2h).
    WendlandC6,
}

/// Names accepted on the command line and in scenes.
pub const KERNEL_NAMES: &[&str] = &[
    "gaussian3",
    "gaussian",
    "cubic-spline",
    "quartic-spline",
    "quintic-spline",
    "wendland-c2",
    "wendland-c4",
    "wendland-c6",
];

/// `$body` with `$F` the [`Family`] type that evaluates `$kernel`: one
/// dispatch on the kernel, then a loop monomorphised per family.
macro_rules! with_family {
    ($kernel:expr, $F:ident => $body:expr) => {
        match $kernel {
            $crate::kernel::Kernel::CubicSpline => {
                type $F = $crate::kernel::CubicFamily;
                $body
            }
            $crate::kernel::Kernel::QuarticSpline => {
                type $F = $crate::kernel::SphFamily<$crate::kernel::sph::M5>;
                $body
            }
            $crate::kernel::Kernel::QuinticSpline => {
                type $F = $crate::kernel::SphFamily<$crate::kernel::sph::M6>;
                $body
            }
            $crate::kernel::Kernel::WendlandC2 => {
                type $F = $crate::kernel::SphFamily<$crate::kernel::sph::C2>;
                $body
            }
            $crate::kernel::Kernel::WendlandC4 => {
                type $F = $crate::kernel::SphFamily<$crate::kernel::sph::C4>;
                $body
            }
            $crate::kernel::Kernel::WendlandC6 => {
                type $F = $crate::kernel::SphFamily<$crate::kernel::sph::C6>;
                $body
            }
            $crate::kernel::Kernel::Gaussian3 | $crate::kernel::Kernel::Gaussian { .. } => {
                type $F = $crate::kernel::GaussianFamily;
                $body
            }
        }
    };
}
pub(crate) use with_family;

impl Kernel {
    pub fn name(&self) -> &'static str {
        match self {
            Kernel::Gaussian3 => "gaussian3",
            Kernel::Gaussian { .. } => "gaussian",
            Kernel::CubicSpline => "cubic-spline",
            Kernel::QuarticSpline => "quartic-spline",
            Kernel::QuinticSpline => "quintic-spline",
            Kernel::WendlandC2 => "wendland-c2",
            Kernel::WendlandC4 => "wendland-c4",
            Kernel::WendlandC6 => "wendland-c6",
        }
    }

    /// The kernels of [`sph`] by value; `None` for the Gaussians and the
    /// cubic spline (which keeps its own, older code path).
    pub fn sph(&self) -> Option<Sph> {
        match self {
            Kernel::QuarticSpline => Some(Sph::M5),
            Kernel::QuinticSpline => Some(Sph::M6),
            Kernel::WendlandC2 => Some(Sph::C2),
            Kernel::WendlandC4 => Some(Sph::C4),
            Kernel::WendlandC6 => Some(Sph::C6),
            _ => None,
        }
    }

    /// An SPH kernel: radius = smoothing length, normalised to 1 per unit
    /// volume (so weights are masses and scale with the frame's volume).
    pub fn is_sph(&self) -> bool {
        *self == Kernel::CubicSpline || self.sph().is_some()
    }

    /// Support radius divided by the radius parameter.
    pub fn support_factor(&self) -> f32 {
        match *self {
            Kernel::Gaussian3 => 1.0,
            Kernel::Gaussian { sigma, .. } => sigma,
            Kernel::CubicSpline => 2.0,
            k => k.sph().map_or(1.0, |s| s.support() as f32),
        }
    }

    /// The packed per-particle constants `(shape, amplitude)` for radius `r`
    /// and weight `w`: Gaussians evaluate `amp·exp(−shape·d²)`, the cubic
    /// spline `amp·M4(d·shape)`, the other SPH kernels `amp·w(d·shape)`.
    pub fn pack(&self, r: f32, w: f32) -> (f32, f32) {
        match *self {
            Kernel::Gaussian3 => (4.5 / (r * r), w),
            Kernel::Gaussian { kappa, .. } => (0.5 / (r * r), kappa * w),
            Kernel::CubicSpline => (1.0 / r, w / (std::f32::consts::PI * r * r * r)),
            k => {
                // σ·w/h³ in f64, then rounded once.
                let sigma = k.sph().map_or(1.0, |s| s.sigma());
                let r = r as f64;
                (1.0 / r as f32, (sigma * w as f64 / (r * r * r)) as f32)
            }
        }
    }

    /// `∫ φ dV` over all space, per unit weight, for radius `r`.
    pub fn integral(&self, r: f64) -> f64 {
        match *self {
            Kernel::Gaussian3 => gaussian_ball_integral(r / 3.0, 3.0),
            Kernel::Gaussian { kappa, sigma } => {
                kappa as f64 * gaussian_ball_integral(r, sigma as f64)
            }
            // Normalised per unit weight by construction (tested).
            _ => 1.0,
        }
    }
}

/// Shape-parameterised evaluation, monomorphised per family in hot loops.
/// `d = x − c` and `d2 = |d|²`; the caller has checked the support.
pub trait Family: Copy + Send + Sync {
    /// φ for packed `(shape, amp)`.
    fn value(d: Vec3, d2: f32, shape: f32, amp: f32) -> f32;
    /// `(φ, g)` with `∇φ = g·d`.
    fn value_and_gradient_factor(d: Vec3, d2: f32, shape: f32, amp: f32) -> (f32, f32);
    /// [`Family::value`] for eight squared distances at once, in f32 (the
    /// packet path; within a few ulp of the scalar form, and the same bits
    /// on every lane type: written once over [`Lanes`]).
    fn value_simd<L: Lanes>(d2: L, shape: f32, amp: f32) -> L;
    /// [`Family::value_and_gradient_factor`] for eight points at once.
    fn value_and_gradient_factor_simd<L: Lanes>(d2: L, shape: f32, amp: f32) -> (L, L);
}

#[derive(Clone, Copy)]
pub struct GaussianFamily;
#[derive(Clone, Copy)]
pub struct CubicFamily;

impl Family for GaussianFamily {
    #[inline(always)]
    fn value(_: Vec3, d2: f32, shape: f32, amp: f32) -> f32 {
        amp * (-shape * d2).exp()
    }
    #[inline(always)]
    fn value_and_gradient_factor(_: Vec3, d2: f32, shape: f32, amp: f32) -> (f32, f32) {
        let v = amp * (-shape * d2).exp();
        (v, -2.0 * shape * v)
    }
    #[inline(always)]
    fn value_simd<L: Lanes>(d2: L, shape: f32, amp: f32) -> L {
        // The polynomial `exp` of `Lanes`, the same on every backend.
        L::splat(amp) * (L::splat(-shape) * d2).exp()
    }
    #[inline(always)]
    fn value_and_gradient_factor_simd<L: Lanes>(d2: L, shape: f32, amp: f32) -> (L, L) {
        let v = Self::value_simd(d2, shape, amp);
        (v, L::splat(-2.0 * shape) * v)
    }
}

/// `q = |d|/h` in f64: near the support edge `2 − q` cancels, and an f32 `q`
/// would cost ~1e-5 relative accuracy there.
#[inline(always)]
pub(crate) fn cubic_q(d: Vec3, inv_h: f32) -> (f64, f64) {
    let dist = ((d.x as f64).powi(2) + (d.y as f64).powi(2) + (d.z as f64).powi(2)).sqrt();
    (dist, dist * inv_h as f64)
}

impl Family for CubicFamily {
    #[inline(always)]
    fn value(d: Vec3, _: f32, inv_h: f32, amp: f32) -> f32 {
        let (_, q) = cubic_q(d, inv_h);
        (amp as f64 * m4(q)) as f32
    }
    #[inline(always)]
    fn value_and_gradient_factor(d: Vec3, _: f32, inv_h: f32, amp: f32) -> (f32, f32) {
        let (dist, q) = cubic_q(d, inv_h);
        let (amp, inv_h) = (amp as f64, inv_h as f64);
        let v = amp * m4(q);
        // dφ/dd = amp·M4'(q)/h; ∇φ = dφ/dd·d/|d|. At d = 0, M4'(q)/q → −3.
        let g = if q > 0.0 {
            amp * m4_derivative(q) * inv_h / dist
        } else {
            -3.0 * amp * inv_h * inv_h
        };
        (v as f32, g as f32)
    }
    #[inline(always)]
    fn value_simd<L: Lanes>(d2: L, inv_h: f32, amp: f32) -> L {
        let q = d2.sqrt() * L::splat(inv_h);
        let (inner, outer, lt1, lt2) = cubic_parts(q);
        L::splat(amp) * lt1.select(inner, outer & lt2)
    }
    #[inline(always)]
    fn value_and_gradient_factor_simd<L: Lanes>(d2: L, inv_h: f32, amp: f32) -> (L, L) {
        let s = L::splat;
        let dist = d2.sqrt();
        let q = dist * s(inv_h);
        let (inner, outer, lt1, lt2) = cubic_parts(q);
        let a = s(amp);
        let v = a * lt1.select(inner, outer & lt2);
        // ∇φ = g·d. Inside q < 1, M4'(q)/q = −3 + 2.25q (no division, exact
        // at d = 0); outside, M4'(q) = −0.75(2 − q)² and |d| ≥ h.
        let ih = s(inv_h);
        let g_in = a * ih * ih * (s(2.25) * q - s(3.0));
        let t = s(2.0) - q;
        let g_out = a * ih * (s(-0.75) * t * t) / dist.max(s(f32::MIN_POSITIVE));
        let g = lt1.select(g_in, g_out & lt2);
        (v, g)
    }
}

/// The M4 pieces on eight lanes: (inner polynomial, outer polynomial,
/// q < 1, q < 2); zero beyond q = 2 comes from masking `outer` with `q < 2`.
#[inline(always)]
fn cubic_parts<L: Lanes>(q: L) -> (L, L, L, L) {
    let s = L::splat;
    let inner = s(1.0) + q * q * (s(0.75) * q - s(1.5));
    let t = s(2.0) - q;
    let outer = s(0.25) * t * t * t;
    (inner, outer, q.lt(s(1.0)), q.lt(s(2.0)))
}

/// The M4 cubic spline shape (without the 1/(πh³) normalisation).
#[inline(always)]
pub fn m4(q: f64) -> f64 {
    if q < 1.0 {
        1.0 - 1.5 * q * q + 0.75 * q * q * q
    } else if q < 2.0 {
        let t = 2.0 - q;
        0.25 * t * t * t
    } else {
        0.0
    }
}

#[inline(always)]
fn m4_derivative(q: f64) -> f64 {
    if q < 1.0 {
        -3.0 * q + 2.25 * q * q
    } else if q < 2.0 {
        let t = 2.0 - q;
        -0.75 * t * t
    } else {
        0.0
    }
}

/// `∫ exp(−|x|²/2s²) dx` over the ball of radius `a·s`:
/// `(2π)^{3/2} s³ · P(a)` with `P(a) = erf(a/√2) − √(2/π)·a·e^{−a²/2}`
/// (the χ₃ distribution function).
pub fn gaussian_ball_integral(s: f64, a: f64) -> f64 {
    let p = libm::erf(a / std::f64::consts::SQRT_2)
        - (2.0 / std::f64::consts::PI).sqrt() * a * (-0.5 * a * a).exp();
    (2.0 * std::f64::consts::PI).powf(1.5) * s * s * s * p
}

impl Kernel {
    /// `∫ φ(√(b² + u²)) du` over `u ∈ [u0, u1]` (clipped to the support), per
    /// unit weight, for a line at squared distance `b2` from the centre.
    /// Closed form for the Gaussians; for the SPH kernels, a tabulated full
    /// chord or Simpson's rule on a partial one (see
    /// [`Kernel::chord_integral_tabled`] for the fast one projections take).
    pub fn chord_integral(&self, b2: f64, r: f64, u0: f64, u1: f64) -> f64 {
        let support = self.support_factor() as f64 * r;
        let l2 = support * support - b2;
        if l2 <= 0.0 {
            return 0.0;
        }
        let l = l2.sqrt();
        let (a, b) = (u0.max(-l), u1.min(l));
        if a >= b {
            return 0.0;
        }
        match *self {
            Kernel::Gaussian3 => gaussian_chord(b2, r / 3.0, 1.0, a, b),
            Kernel::Gaussian { kappa, .. } => gaussian_chord(b2, r, kappa as f64, a, b),
            Kernel::CubicSpline => {
                let norm = 1.0 / (std::f64::consts::PI * r * r * r);
                if a <= -l && b >= l {
                    // Full chord: the projected kernel F(b/h)·h (u in units of h).
                    norm * r * projected_m4((b2.sqrt() / r) as f32) as f64
                } else {
                    let f = |u: f64| m4((b2 + u * u).sqrt() / r);
                    norm * voxless_core::simpson(f, a, b, 256)
                }
            }
            k => {
                let Some(s) = k.sph() else { return 0.0 };
                let norm = s.sigma() / (r * r * r);
                if a <= -l && b >= l {
                    // Full chord: σ/h² · F(b/h) from the kernel's table.
                    norm * r * s.projected(b2 / (r * r))
                } else {
                    let f = |u: f64| s.w((b2 + u * u).sqrt() / r);
                    norm * voxless_core::simpson(f, a, b, 256)
                }
            }
        }
    }
}

impl Kernel {
    /// [`Kernel::chord_integral`] with the SPH kernels' partial chords read
    /// from the table of cumulative chords ([`chords`]: within 3·10⁻⁶ of
    /// the peak column, and parts of one chord add up to the whole): what
    /// a projection pays per pixel for a kernel cut by a periodic face.
    pub fn chord_integral_tabled(&self, b2: f64, r: f64, u0: f64, u1: f64) -> f64 {
        match self.partial_norm(r) {
            Some(nr) => self.partial_chord(nr, b2, r, u0, u1),
            None => self.chord_integral(b2, r, u0, u1),
        }
    }

    /// An SPH kernel's `norm · r` for partial chords of radius `r` (`None`
    /// for the Gaussians, whose chords are closed forms).
    #[inline]
    fn partial_norm(&self, r: f64) -> Option<f64> {
        let norm = match (*self, self.sph()) {
            (Kernel::CubicSpline, _) => 1.0 / (std::f64::consts::PI * r * r * r),
            (_, Some(s)) => s.sigma() / (r * r * r),
            _ => return None,
        };
        Some(norm * r)
    }

    /// [`Kernel::chord_integral_tabled`] of an SPH kernel with its
    /// [`Kernel::partial_norm`] `nr` given.
    #[inline]
    fn partial_chord(&self, nr: f64, b2: f64, r: f64, u0: f64, u1: f64) -> f64 {
        let support = self.support_factor() as f64;
        let l2 = (support * r).powi(2) - b2;
        if l2 <= 0.0 {
            return 0.0;
        }
        let l = l2.sqrt();
        if u0 <= -l && u1 >= l {
            return self.chord_integral(b2, r, u0, u1);
        }
        let table = match self.sph() {
            Some(s) => chords::partial_chords(s as usize, |q| s.w(q), support),
            None => chords::partial_chords(5, m4, support),
        };
        nr * table.chord(b2 / (r * r), u0 / r, u1 / r)
    }
}

/// One particle's full column, `∫ φ(√(b² + u²)) du` over the whole line at
/// squared distance `b²` from its centre, per unit weight, with the
/// particle's constants computed once: for projections that add a particle
/// to many pixels. Equals [`Kernel::chord_integral`] over the full chord to
/// ~1e-7 of the peak: the SPH kernels' projected kernel is read from a
/// table in `q² = b²/h²` (no square root per pixel); the cubic spline's is
/// sampled from the table in `q` that `chord_integral` reads, the others'
/// are [`Sph::column_table`], which `chord_integral` reads too.
#[derive(Clone, Copy, Debug)]
pub struct Column {
    kernel: Kernel,
    r: f64,
    support2: f64,
    /// SPH kernels: `σ/h²` (`1/(πh²)` for the cubic spline), the table's
    /// scale, and `(N − 1)/(Q h)²` with `Q` the support factor, which maps
    /// `b²` to a table position.
    scale: f64,
    to_index: f64,
    /// SPH kernels: `norm · r` of their partial chords.
    partial_norm: Option<f64>,
}

/// Entries of the projected-M4 table over `q² ∈ [0, 4]`.
const PROJ_Q2_TABLE: usize = sph::COLUMN_TABLE;

/// [`projected_m4`] tabulated over `q²` (linear interpolation in `q²`).
fn projected_m4_q2_table() -> &'static [f32; PROJ_Q2_TABLE] {
    use std::sync::OnceLock;
    static TABLE: OnceLock<Box<[f32; PROJ_Q2_TABLE]>> = OnceLock::new();
    TABLE.get_or_init(|| {
        Box::new(std::array::from_fn(|i| {
            projected_m4((4.0 * i as f64 / (PROJ_Q2_TABLE - 1) as f64).sqrt() as f32)
        }))
    })
}

/// The table of the kernels that read none.
static NO_TABLE: [f32; PROJ_Q2_TABLE] = [0.0; PROJ_Q2_TABLE];

impl Kernel {
    /// The projected-kernel table an SPH kernel's [`Column`] reads (over
    /// `q² ∈ [0, Q²]`, `Q` the support factor); `None` for the Gaussians.
    pub fn sph_table(&self) -> Option<&'static [f32]> {
        self.is_sph().then(|| &self.table()[..])
    }

    /// [`Kernel::sph_table`], or zeros for the Gaussians (built on first
    /// use).
    #[inline]
    fn table(&self) -> &'static [f32; PROJ_Q2_TABLE] {
        match self.sph() {
            _ if *self == Kernel::CubicSpline => projected_m4_q2_table(),
            Some(s) => s.column_table(),
            None => &NO_TABLE,
        }
    }

    /// The full column of a particle of radius `r` (see [`Column`]).
    pub fn column(&self, r: f64) -> Column {
        let factor = self.support_factor() as f64;
        let support = factor * r;
        // (The table is looked up where it is read, not here: the lanes'
        // splats never read it, and building it took ~4 ms of both cores
        // at the start of every projection.)
        let scale = match self.sph() {
            _ if *self == Kernel::CubicSpline => 1.0 / (std::f64::consts::PI * r * r),
            Some(s) => s.sigma() / (r * r),
            None => 0.0,
        };
        Column {
            kernel: *self,
            r,
            support2: support * support,
            scale,
            // For the cubic spline (N − 1)/4 is exact, as before.
            to_index: 1.0 / (r * r) * ((PROJ_Q2_TABLE - 1) as f64 / (factor * factor)),
            partial_norm: self.partial_norm(r),
        }
    }
}

impl Column {
    /// Whether the column is read from the SPH table ([`Kernel::sph_table`]).
    #[inline]
    pub fn is_sph(&self) -> bool {
        self.kernel.is_sph()
    }

    /// The table position per unit `b²` (SPH kernels).
    #[inline]
    pub fn to_index(&self) -> f64 {
        self.to_index
    }

    /// The factor of the table's values (SPH kernels): the column is
    /// `scale ×` the interpolated table value.
    #[inline]
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The Gaussians' standard deviation and amplitude per unit weight
    /// (their column is a closed form); `None` for the SPH kernels.
    pub fn gaussian(&self) -> Option<(f64, f64)> {
        match self.kernel {
            Kernel::Gaussian3 => Some((self.r / 3.0, 1.0)),
            Kernel::Gaussian { kappa, .. } => Some((self.r, kappa as f64)),
            _ => None,
        }
    }

    /// The squared support radius.
    #[inline]
    pub fn support2(&self) -> f64 {
        self.support2
    }

    /// `∫ column dA` per unit weight: the kernel's whole mass.
    pub fn mass(&self) -> f64 {
        self.kernel.integral(self.r)
    }

    /// The integral along the line at squared distance `b2` from the centre
    /// over the line parameter `u0..u1` (0 at the closest point).
    #[inline]
    pub fn chord(&self, b2: f64, u0: f64, u1: f64) -> f64 {
        match self.partial_norm {
            Some(nr) => self.kernel.partial_chord(nr, b2, self.r, u0, u1),
            None => self.kernel.chord_integral(b2, self.r, u0, u1),
        }
    }

    /// An SPH kernel's column at `b2` inside the support, from the table.
    #[inline(always)]
    fn tabled(&self, b2: f64) -> f64 {
        // (b2 / (Qh)²).min(1) · (N − 1), with the constant factors folded
        // into one.
        const LAST: f64 = (PROJ_Q2_TABLE - 1) as f64;
        let x = (b2 * self.to_index).min(LAST);
        let i = (x as usize).min(PROJ_Q2_TABLE - 2);
        let s = (x - i as f64) as f32;
        let table = self.kernel.table();
        let f = table[i] * (1.0 - s) + table[i + 1] * s;
        self.scale * f as f64
    }

    /// The column at squared distance `b2` from the centre (0 outside the
    /// support).
    #[inline]
    pub fn at(&self, b2: f64) -> f64 {
        if b2 >= self.support2 {
            return 0.0;
        }
        if self.kernel.is_sph() {
            self.tabled(b2)
        } else {
            self.kernel
                .chord_integral(b2, self.r, f64::NEG_INFINITY, f64::INFINITY)
        }
    }
}

fn gaussian_chord(b2: f64, s: f64, amp: f64, a: f64, b: f64) -> f64 {
    let k = std::f64::consts::SQRT_2 * s;
    amp * (-b2 / (2.0 * s * s)).exp()
        * s
        * (std::f64::consts::PI / 2.0).sqrt()
        * (libm::erf(b / k) - libm::erf(a / k))
}

/// `F(q_b)` for M4 by Simpson's rule, split at the `q = 1` kink.
pub(crate) fn projected_m4_quadrature(qb: f64) -> f64 {
    let f = |v: f64| m4((qb * qb + v * v).sqrt());
    let vmax = (4.0 - qb * qb).max(0.0).sqrt();
    let vkink = (1.0 - qb * qb).max(0.0).sqrt();
    let inner = if vkink > 0.0 {
        voxless_core::simpson(f, 0.0, vkink, 400)
    } else {
        0.0
    };
    2.0 * (inner + voxless_core::simpson(f, vkink, vmax, 400))
}

/// Entries of the projected-M4 table over `q_b ∈ [0, 2]`.
const PROJ_TABLE: usize = 2049;

/// `F(q_b) = ∫ M4(√(q_b² + v²)) dv` over all `v` (the M4 column through a
/// unit-h kernel at impact parameter `q_b`), tabulated once with Simpson's rule
/// split at the `q = 1` kink, then linearly interpolated.
fn projected_m4(qb: f32) -> f32 {
    use std::sync::OnceLock;
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..PROJ_TABLE)
            .map(|i| projected_m4_quadrature(2.0 * i as f64 / (PROJ_TABLE - 1) as f64) as f32)
            .collect()
    });
    let x = (qb / 2.0).clamp(0.0, 1.0) * (PROJ_TABLE - 1) as f32;
    let i = (x as usize).min(PROJ_TABLE - 2);
    let s = x - i as f32;
    table[i] * (1.0 - s) + table[i + 1] * s
}
