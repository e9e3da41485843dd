//! Every data kind passes the same contract (`voxless_core::testing`):
//! intervals sorted and disjoint, samples inside their interval's value
//! range, the packet path equal to point samples, gradients against finite
//! differences, line integrals against quadrature, and renders and
//! projections that do not depend on the thread count. Raw volumes and
//! their prepared contexts both pass, and a context offers the hooks its
//! volume offers (fast paths, capabilities) but where it is said to differ.

use voxless::{
    AmrDesc, AnyVolume, Camera, ClassificationName, KernelName, MaterialDesc, ParticlesDesc,
    Range1, ReconstructionName, RenderSettings, Species, TetsDesc, TransferFunction, Vec3,
};
use voxless_core::testing::{Contract, Hook, assert_contract, assert_same_hooks};
use voxless_core::{Prepare, PrepareQuery};
use voxless_render::testing::assert_thread_independent;
use voxless_tets::testing::folded_sheet;
use voxless_transfer::{Colormap, OpacityMap};

mod fixtures;
use fixtures::{amr_cells, particles};

fn tf() -> TransferFunction {
    TransferFunction::new(
        Colormap::preset("viridis").unwrap(),
        OpacityMap::preset("ramp-high").unwrap(),
    )
}

/// Runs the contract on the raw volume and on a context prepared for a
/// transfer function that hides the lower half of the value range, checks
/// that the context answers every capability hook as the volume does but
/// those in `differ`, and runs the thread check.
fn check_kind<P: Prepare + voxless_core::Volume>(
    name: &str,
    v: &P,
    contract: &Contract,
    differ: &[Hook],
) {
    assert_contract(name, v, contract);
    let vr = v.value_range();
    let cut = vr.lo + 0.5 * vr.span();
    let visible = move |r: Range1| r.hi >= cut;
    let color = |a: f32| Vec3::splat(a.clamp(0.0, 1.0));
    let prepared = v.prepare(&PrepareQuery {
        is_visible: &visible,
        attribute_color: &color,
        event_budget: None,
        lod_pixels: None,
        simd: Default::default(),
    });
    // A prepared context hands out fewer intervals, never different samples
    // (and its intervals leave out what its transfer function hides, so its
    // quadrature is not the volume's line integral).
    let for_context = Contract {
        integral_tolerance: None,
        ..contract.clone()
    };
    assert_contract(&format!("{name} (prepared)"), &prepared, &for_context);
    assert_same_hooks(name, v, &prepared, differ);
    let b = v.bounds();
    let camera = Camera::framing(&b, 1.25);
    let settings = RenderSettings {
        spp: 2,
        ..RenderSettings::for_volume(v, 40, 32)
    };
    assert_thread_independent(name, v, &camera, &tf(), &settings);
}

#[test]
fn particles_of_every_kernel_pass() {
    for (kernel, classification) in [
        (KernelName::Gaussian3, ClassificationName::Post),
        (KernelName::Gaussian, ClassificationName::Pre),
        (KernelName::CubicSpline, ClassificationName::Post),
    ] {
        // Supports of about 0.2 (a few neighbours each): the quadrature
        // the contract compares line integrals with resolves them.
        let radius = if kernel == KernelName::Gaussian3 {
            0.2
        } else {
            0.1
        };
        let desc = ParticlesDesc {
            kernel: Some(kernel),
            classification: Some(classification),
            radius: Some(radius),
            ..Default::default()
        };
        let v = AnyVolume::from_particles(particles(600, 3), &desc)
            .unwrap()
            .volume;
        let AnyVolume::Particles(v) = v else {
            unreachable!()
        };
        check_kind(
            &format!("particles ({kernel})"),
            &*v,
            &Contract::default(),
            &[],
        );
    }
}

#[test]
fn multi_material_particles_pass() {
    let mat = |s: &str, colormap: &str| MaterialDesc {
        species: Species(s.into()),
        colormap: Some(colormap.into()),
        ..Default::default()
    };
    let desc = ParticlesDesc {
        materials: Some(vec![mat("1", "viridis"), mat("2", "inferno")]),
        ..Default::default()
    };
    let v = AnyVolume::from_particles(particles(800, 5), &desc)
        .unwrap()
        .volume;
    let AnyVolume::Materials(v) = v else {
        unreachable!()
    };
    // Classified samples: the blended opacity is not the derivative of a
    // field, so gradients are not compared.
    let c = Contract {
        gradient: None,
        integral_tolerance: None,
        ..Default::default()
    };
    check_kind("materials", &*v, &c, &[]);
}

#[test]
fn amr_cells_pass_with_every_reconstruction() {
    // Without a colour field, basis samples are plain values, which the
    // volume also gives eight at a time in lanes (checked too).
    for (reconstruction, color_field) in [
        (ReconstructionName::Basis, Some("energy")),
        (ReconstructionName::Basis, None),
        (ReconstructionName::Nearest, Some("energy")),
        (ReconstructionName::Octant, Some("energy")),
        (ReconstructionName::Octant, None),
    ] {
        let desc = AmrDesc {
            reconstruction: Some(reconstruction),
            color_field: color_field.map(String::from),
            ..Default::default()
        };
        let AnyVolume::Amr(v) = AnyVolume::from_amr(amr_cells(), &desc).unwrap().volume else {
            unreachable!()
        };
        let c = match reconstruction {
            // Tents are piecewise linear: differences across their kinks
            // disagree with the one-sided analytic gradient at few points.
            // Octant is piecewise trilinear: the same at its box faces.
            ReconstructionName::Basis | ReconstructionName::Octant => Contract::default(),
            // Nearest is piecewise constant: no gradient to compare, and
            // quadrature of its steps is only first order.
            ReconstructionName::Nearest => Contract {
                gradient: None,
                integral_tolerance: Some(2e-2),
                ..Default::default()
            },
        };
        // The context walks the region tree for a whole tile of rays at
        // once (its mask of visible regions is what makes that pay); the
        // bare volume has no tile view.
        let differ = [Hook::TileView];
        check_kind(
            &format!("AMR ({})", reconstruction.name()),
            &*v,
            &c,
            &differ,
        );
    }
}

#[test]
fn tessellations_pass() {
    let g = folded_sheet(6, 21);
    let v =
        AnyVolume::from_tessellation(g.positions.clone(), g.n, g.box_size, &TetsDesc::default())
            .unwrap();
    let AnyVolume::Tets(v) = v.volume else {
        unreachable!()
    };
    // The density is piecewise constant: its samples have no derivative to
    // compare (shading uses a smoothed gradient), and constant pieces make
    // quadrature exact.
    let c = Contract {
        gradient: None,
        integral_tolerance: Some(1e-4),
        constant_mismatch_share: 5e-3,
        ..Default::default()
    };
    check_kind("tessellation", &*v, &c, &[]);
}
