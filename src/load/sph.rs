//! SPH snapshots without a `--kernel`: the kernel and smoothing-length
//! convention of the code that wrote them (see `voxless_particles`'s SPH
//! kernel docs for the conversions).
//!
//! voxless's `h` puts a kernel's support at `R h` (R = 2 for the cubic
//! spline and the Wendland kernels, 2.5 for M5, 3 for M6, as PHANTOM). PySPH
//! writes that `h`. Gadget-4 writes the support radius `H`: `h = H / 2`
//! (the cubic spline, Gadget's kernel). SWIFT writes `h_S` with support
//! `γ h_S` and names its kernel in `HydroScheme/Kernel function`:
//! `h = γ h_S / R`.

use voxless_io::{ParticleTable, SphCode};
use voxless_particles::Kernel;

/// SWIFT's `kernel_gamma`: support over `h_S` (Dehnen & Aly 2012).
fn swift_gamma(k: Kernel) -> f64 {
    match k {
        Kernel::QuarticSpline => 2.018932,
        Kernel::QuinticSpline => 2.195775,
        Kernel::WendlandC2 => 1.936492,
        Kernel::WendlandC4 => 2.207940,
        Kernel::WendlandC6 => 2.449490,
        _ => 1.825742,
    }
}

/// The kernel a code's name for it means (SWIFT: "Cubic spline (M4)",
/// "Quintic spline (M6)", "Wendland C2", …), any case.
pub(crate) fn kernel_named(name: &str) -> Option<Kernel> {
    let n = name.to_ascii_lowercase();
    let has = |s: &str| n.contains(s);
    Some(if has("wendland") {
        if has("c2") {
            Kernel::WendlandC2
        } else if has("c4") {
            Kernel::WendlandC4
        } else if has("c6") {
            Kernel::WendlandC6
        } else {
            return None;
        }
    } else if has("quintic") || has("m6") {
        Kernel::QuinticSpline
    } else if has("quartic") || has("m5") {
        Kernel::QuarticSpline
    } else if has("cubic") || has("m4") {
        Kernel::CubicSpline
    } else {
        return None;
    })
}

/// The kernel for `table`'s SPH defaults, the factor from its smoothing
/// lengths to voxless's `h`, and what was assumed (for a note).
pub(crate) fn convention(table: &ParticleTable) -> (Kernel, f32, String) {
    let Some(sph) = &table.sph else {
        return (Kernel::CubicSpline, 1.0, "cubic-spline kernel".into());
    };
    match sph.code {
        SphCode::Gadget => (
            Kernel::CubicSpline,
            0.5,
            "cubic-spline kernel (Gadget and GIZMO write the support radius H = 2h)".into(),
        ),
        // No smoothing lengths: the radii come from the cell volumes.
        SphCode::Arepo => (Kernel::CubicSpline, 1.0, "cubic-spline kernel".into()),
        SphCode::Tipsy => (
            Kernel::CubicSpline,
            1.0,
            "cubic-spline kernel (Tipsy's hsmooth is h, support 2h)".into(),
        ),
        SphCode::Swift => {
            let (kernel, said) = match sph.kernel.as_deref() {
                Some(name) => match kernel_named(name) {
                    Some(k) => (k, format!("the file's kernel \"{name}\"")),
                    None => (
                        Kernel::CubicSpline,
                        format!(
                            "the file's kernel \"{name}\" is not one voxless knows: cubic spline"
                        ),
                    ),
                },
                None => (
                    Kernel::CubicSpline,
                    "no kernel in the file: cubic spline".into(),
                ),
            };
            let factor = swift_gamma(kernel) / kernel.support_factor() as f64;
            (
                kernel,
                factor as f32,
                format!(
                    "{said} ({}; SWIFT's h has support {:.6} h)",
                    kernel.name(),
                    swift_gamma(kernel)
                ),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxless_io::SphConvention;

    fn swift(kernel: Option<&str>) -> ParticleTable {
        ParticleTable {
            sph: Some(SphConvention {
                code: SphCode::Swift,
                kernel: kernel.map(str::to_string),
            }),
            ..Default::default()
        }
    }

    #[test]
    fn swift_smoothing_lengths_become_the_same_support() {
        // The support γ h_S must equal R h for every kernel SWIFT names.
        for (name, kernel) in [
            ("Cubic spline (M4)", Kernel::CubicSpline),
            ("Quartic spline (M5)", Kernel::QuarticSpline),
            ("Quintic spline (M6)", Kernel::QuinticSpline),
            ("Wendland C2", Kernel::WendlandC2),
            ("Wendland C4", Kernel::WendlandC4),
            ("Wendland C6", Kernel::WendlandC6),
        ] {
            let (k, f, _) = convention(&swift(Some(name)));
            assert_eq!(k, kernel, "{name}");
            let support = f as f64 * k.support_factor() as f64;
            assert!((support - swift_gamma(k)).abs() < 1e-6, "{name}");
        }
        assert!((convention(&swift(Some("Cubic spline (M4)"))).1 - 0.912871).abs() < 1e-6);
        assert!((convention(&swift(Some("Quintic spline (M6)"))).1 - 0.731925).abs() < 1e-6);
        // Unknown or absent: the cubic spline, said so.
        let (k, _, why) = convention(&swift(Some("Gaussian")));
        assert_eq!(k, Kernel::CubicSpline);
        assert!(why.contains("not one voxless knows"));
        let gadget = ParticleTable {
            sph: Some(SphConvention {
                code: SphCode::Gadget,
                kernel: None,
            }),
            ..Default::default()
        };
        assert_eq!(convention(&gadget).1, 0.5);
        assert_eq!(convention(&ParticleTable::default()).1, 1.0);
    }
}
