//! The SPH kernels' own definitions: their normalisation by quadrature and
//! their projected-column tables against direct quadrature along z of the
//! independently written reference forms in [`crate::tests`].

use crate::tests::{KERNELS, reference_kernel};
use crate::{ParticleData, ParticleSettings, ParticleVolume};
use voxless_core::Vec3;

/// The crate's own SPH forms (σ·w(q) of [`crate::kernel::sph`]) integrate
/// to 1 over space: radial quadrature split at every kink, relative 1e-6.
#[test]
fn sph_kernels_integrate_to_one() {
    for kernel in KERNELS.into_iter().filter(|k| k.sph().is_some()) {
        let s = kernel.sph().unwrap();
        let f = |q: f64| 4.0 * std::f64::consts::PI * q * q * s.sigma() * s.w(q);
        let q = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0];
        let total: f64 = q
            .windows(2)
            .filter(|p| p[0] < s.support())
            .map(|p| voxless_core::simpson(f, p[0], p[1].min(s.support()), 2000))
            .sum();
        assert!((total - 1.0).abs() < 1e-6, "{kernel:?}: ∫W dV = {total}");
        // And the volume's packed constants and evaluation: Φ of one
        // particle of weight 2, radius 0.3, summed over a radial line.
        let vol = ParticleVolume::new(
            ParticleData {
                positions: vec![Vec3::ZERO],
                radii: Some(vec![0.3]),
                weights: Some(vec![2.0]),
                attribute: None,
            },
            ParticleSettings {
                kernel,
                ..Default::default()
            },
        )
        .unwrap();
        let g = |d: f64| {
            4.0 * std::f64::consts::PI * d * d * vol.density(Vec3::new(d as f32, 0.0, 0.0)) as f64
        };
        let reach = kernel.support_factor() as f64 * 0.3;
        let m = voxless_core::simpson(g, 0.0, reach, 20_000);
        assert!((m - 2.0).abs() < 2e-5, "{kernel:?}: ∫Φ dV = {m}");
    }
}

/// Each SPH kernel's column table against direct quadrature of the
/// reference W (written independently, above) along z, for impact
/// parameters across the support: within 1e-6 of the peak column (f32
/// table entries and linear interpolation in q², spacing (Q/h)²/8192).
#[test]
fn column_tables_match_quadrature_along_z() {
    for kernel in KERNELS.into_iter().filter(|k| k.is_sph()) {
        let h = 0.37;
        let column = kernel.column(h);
        let support = kernel.support_factor() as f64 * h;
        let direct = |b: f64| {
            let l = (support * support - b * b).max(0.0).sqrt();
            let f = |z: f64| reference_kernel(kernel, (b * b + z * z).sqrt(), h, 1.0).0;
            voxless_core::simpson(f, -l, l, 20_000)
        };
        let peak = direct(0.0);
        let mut worst = 0.0f64;
        for i in 0..=300 {
            // Uneven steps, so samples fall between table entries.
            let b = support * (i as f64 / 300.0).powf(1.1) * 0.999_999;
            let err = (column.at(b * b) - direct(b)).abs();
            worst = worst.max(err);
        }
        assert!(
            worst <= 1e-6 * peak,
            "{kernel:?}: worst {worst:e} vs peak {peak}"
        );
    }
}
