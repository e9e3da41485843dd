//! Built-in demo particles: a two-armed spiral galaxy with a bulge, so the
//! main command works on a fresh machine with no data files.

use voxless_core::{SmallRng, Vec3};
use voxless_particles::ParticleData;

/// `n` particles: 20% in a Gaussian bulge, the rest along two logarithmic
/// spiral arms in a thin disc of radius ~1. The attribute is a "temperature"
/// that is high in the bulge and along the arm ridges.
pub fn galaxy(n: usize) -> ParticleData {
    let mut rng = SmallRng(0x5eed_1234_abcd_ef01);
    let mut positions = Vec::with_capacity(n);
    let mut attribute = Vec::with_capacity(n);
    for i in 0..n {
        if i % 5 == 0 {
            let p = Vec3::new(rng.normal(), rng.normal() * 0.6, rng.normal()) * 0.15;
            positions.push(p);
            attribute.push(1.0 - (p.length() / 0.5).min(1.0) * 0.5 + 0.1 * rng.normal());
        } else {
            let arm = (i % 2) as f32 * std::f32::consts::PI;
            let r = 0.1 + 0.9 * rng.f().sqrt();
            // Logarithmic spiral: angle grows with ln r; scatter off the ridge.
            let off = rng.normal() * 0.25;
            let theta = arm + 2.2 * (r / 0.1).ln() + off;
            let thickness = 0.03 + 0.02 * (1.0 - r);
            positions.push(Vec3::new(
                r * theta.cos() + rng.normal() * 0.02,
                rng.normal() * thickness,
                r * theta.sin() + rng.normal() * 0.02,
            ));
            attribute.push(0.7 * (-off * off * 20.0).exp() * (1.2 - r) + 0.05 * rng.normal());
        }
    }
    ParticleData {
        positions,
        radii: None,
        attribute: Some(attribute),
        weights: None,
    }
}
