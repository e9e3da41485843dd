//! A tiny deterministic generator for demo data, benchmarks and tests.
//!
//! Not for rendering: integrators draw from a stream keyed by (pixel, sample,
//! dimension) so that any pixel can be re-rendered alone. This one is a plain
//! sequence (Knuth's 64-bit LCG, top 24 bits), the same on every machine.

use crate::math::Vec3;

#[derive(Clone, Debug)]
pub struct SmallRng(pub u64);

impl SmallRng {
    /// Uniform in `[0, 1)`.
    pub fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }

    /// Uniform in the unit cube.
    pub fn v(&mut self) -> Vec3 {
        Vec3::new(self.f(), self.f(), self.f())
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f32 {
        let (a, b) = (self.f().max(f32::MIN_POSITIVE), self.f());
        (-2.0 * a.ln()).sqrt() * (std::f32::consts::TAU * b).cos()
    }
}
