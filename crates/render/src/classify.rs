//! A packet pass's samples classified eight at a time: the transfer
//! function's colour and opacity at each sample's normalised value, and the
//! segment's opacity `1 − e^(−opacity · scale · len)` — the per-sample work
//! of emission–absorption compositing that does not depend on what lies in
//! front, so it need not wait for the ray's front-to-back order.
//!
//! The lanes do exactly the arithmetic of [`crate::march::RayState`]'s
//! scalar compositing (the same table position and lerp, tested in the
//! transfer crate; the same `exp`, [`voxless_core::simd::exp`]), so a ray
//! that takes its samples' colour and opacity from here composites the
//! bits it would have computed itself. Only the accumulation stays per
//! ray, in order.

use voxless_core::simd::{LANES, Lanes, Simd, WithLanes, dispatch};
use voxless_transfer::TransferFunction;

/// Per sample slot of a pass: colour by channel and the segment's opacity;
/// `alpha < 0` where the transfer function's opacity is not positive (the
/// scalar path adds nothing there).
#[derive(Default)]
pub(crate) struct Classified {
    pub rgb: [Vec<f32>; 3],
    pub alpha: Vec<f32>,
}

impl Classified {
    /// Classifies `x` (normalised values) of segments `len` long, opacity
    /// scaled by `scale`. Both inputs are padded here to a whole number of
    /// lane groups (the padding's results are never read).
    pub fn compute(
        &mut self,
        simd: Simd,
        tf: &TransferFunction,
        scale: f32,
        x: &mut Vec<f32>,
        len: &mut Vec<f32>,
    ) {
        let n = x.len().next_multiple_of(LANES);
        x.resize(n, 0.0);
        len.resize(n, 0.0);
        for v in self.rgb.iter_mut().chain([&mut self.alpha]) {
            v.resize(n, 0.0);
        }
        dispatch(
            simd,
            Job {
                tf,
                scale,
                x,
                len,
                out: self,
            },
        );
    }
}

struct Job<'a> {
    tf: &'a TransferFunction,
    scale: f32,
    x: &'a [f32],
    len: &'a [f32],
    out: &'a mut Classified,
}

impl WithLanes for Job<'_> {
    type Output = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let s = L::splat;
        // `(−opacity · scale) · len` as the scalar path computes it: a
        // product's sign is the operands' signs' xor, so negating the scale
        // instead of the opacity gives the same bits.
        let k = s(-self.scale);
        let Classified { rgb, alpha } = self.out;
        for at in (0..self.x.len()).step_by(LANES) {
            let ([r, g, b], o) = self.tf.color_and_opacity_lanes(L::load(self.x, at));
            let a = s(1.0) - ((o * k) * L::load(self.len, at)).exp();
            o.gt(s(0.0)).select(a, s(-1.0)).store(alpha, at);
            r.store(&mut rgb[0], at);
            g.store(&mut rgb[1], at);
            b.store(&mut rgb[2], at);
        }
    }
}
