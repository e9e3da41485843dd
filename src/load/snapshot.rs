//! Cosmological snapshots (SWIFT, Gadget, AREPO, GIZMO, Tipsy): which part
//! of the file to read (particle type, region), which columns are the
//! smoothing lengths and masses, and what the file says about its units
//! and epoch.
//!
//! A region keeps the particles within a margin of it, so that kernels
//! reaching in from outside still count: the support of `radius` when one
//! is given, else a tenth of the region's longest side.

use voxless_io::{ParticleTable, Region, SphCode};
use voxless_scene::ParticlesDesc;

use super::formats::{ParticleFormat, TableOptions};
use super::table::{Selection, Source};

use super::periodic;
use crate::SceneError;

/// The region's margin without a radius, as a fraction of its longest side.
const REGION_MARGIN: f64 = 0.1;

/// What to read of the particle file `p` names: its PySPH group, snapshot
/// type and region, and share `share` of the rows.
pub(crate) fn selection(p: &ParticlesDesc, share: Option<(usize, usize)>) -> Selection<'_> {
    Selection {
        options: TableOptions {
            group: p.group.clone(),
            part_type: None,
            share,
            region: region(p),
            no_file_box: p.periodic == Some(false),
        },
        species: p.species.as_ref().map(|s| s.0.as_str()),
        part_type: p.part_type.as_ref().map(|s| s.0.as_str()),
    }
}

/// The region `p` asks for, with its margin and the box it gives.
pub(crate) fn region(p: &ParticlesDesc) -> Option<Region> {
    let r = p.region?;
    let (lo, hi) = ([r[0], r[1], r[2]], [r[3], r[4], r[5]]);
    let side = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let support = |radius: f32| {
        let kernel = p
            .kernel
            .map_or(voxless_particles::Kernel::CubicSpline, |k| {
                super::particles::kernel_of(p, k)
            });
        radius as f64 * kernel.support_factor() as f64
    };
    let pad = match p.radius {
        Some(r) => support(r) * p.radius_scale.unwrap_or(1.0) as f64,
        None => REGION_MARGIN * side,
    };
    let period = p.periodic_box.as_ref().map(|b| {
        let (lo, hi) = b.corners();
        (lo, std::array::from_fn(|a| hi[a] - lo[a]))
    });
    Some(Region {
        lo,
        hi,
        pad,
        period,
    })
}

/// Checks `particles.region`: six finite numbers, each upper corner above
/// the lower one.
pub(crate) fn check_region(p: &ParticlesDesc) -> Result<(), SceneError> {
    let Some(r) = p.region else { return Ok(()) };
    if r.iter().any(|v| !v.is_finite()) || (0..3).any(|a| r[a + 3] <= r[a]) {
        return Err(SceneError::setting(
            "particles.region",
            format!(
                "{r:?} is not a box: give X0 Y0 Z0 X1 Y1 Z1 with each upper corner above the lower"
            ),
        ));
    }
    Ok(())
}

/// The columns holding the smoothing lengths and masses when `p` gives no
/// kernel: PySPH's `h`, `m`; SWIFT's `SmoothingLengths`; Gadget-4, GIZMO
/// and Gadget binary gas `SmoothingLength`; Tipsy gas `hsmooth`, `mass`.
/// Snapshot types without smoothing lengths (dark matter, stars) give
/// their masses alone (their radii come from neighbours), and so does a
/// snapshot when `p` gives a kernel. `None` without masses.
pub(crate) fn sph_columns(p: &ParticlesDesc, source: &Source) -> Option<(Option<String>, String)> {
    let hdf5 = source.format == ParticleFormat::Hdf5;
    let t = &source.table;
    if !(hdf5 || t.sph.is_some()) {
        return None;
    }
    // A kernel given: the smoothing lengths are the user's to choose, but
    // a snapshot's particles still weigh their masses.
    if p.kernel.is_some() {
        t.sph.as_ref()?;
        return ["Masses", "mass"]
            .into_iter()
            .find(|m| t.column(m).is_some())
            .map(|m| (None, m.to_string()));
    }
    let pair = [
        ("h", "m"),
        ("SmoothingLengths", "Masses"),
        ("SmoothingLength", "Masses"),
        ("hsmooth", "mass"),
    ]
    .into_iter()
    .find(|(h, m)| t.column(h).is_some() && t.column(m).is_some());
    if let Some((h, m)) = pair {
        return Some((Some(h.to_string()), m.to_string()));
    }
    // A snapshot's other types: masses, and the code's kernel.
    t.sph.as_ref()?;
    ["Masses", "mass"]
        .into_iter()
        .find(|m| t.column(m).is_some())
        .map(|m| (None, m.to_string()))
}

/// The defaults an SPH file or snapshot gives when `p` leaves them open:
/// the kernel, the smoothing lengths as radii (and the factor from the
/// code's convention to voxless's h), the masses as weights; sets `radii`
/// and `weights` to those columns and returns the kernel (`None` when `p`
/// gives one), the factor and a note saying what was used. `None` when the
/// file gives nothing.
pub(crate) fn defaults(
    p: &ParticlesDesc,
    source: &Source,
    radii: &mut Option<String>,
    weights: &mut Option<String>,
) -> Option<(
    Option<voxless_particles::Kernel>,
    Option<f32>,
    Option<String>,
)> {
    let (h, m) = sph_columns(p, source)?;
    let (kernel, factor, said) = super::sph::convention(&source.table);
    let mut used = Vec::new();
    let mut scale = None;
    if let Some(h) = h
        && radii.is_none()
        && p.radius.is_none()
        && p.neighbours.is_none()
    {
        used.push(if factor == 1.0 {
            format!("radii = {h}")
        } else {
            format!("radii = {factor:.6} × {h}")
        });
        *radii = Some(h);
        scale = Some(factor);
    }
    if weights.is_none() {
        used.push(format!("weights = {m}"));
        *weights = Some(m);
    }
    // A kernel the user gave stays theirs: only the weights are defaults.
    if p.kernel.is_some() {
        let note = (!used.is_empty())
            .then(|| format!("snapshot: {} (override with --weights)", used.join(", ")));
        return Some((None, scale, note));
    }
    let note = {
        // The code's smoothing-length convention only matters with
        // smoothing lengths.
        used.insert(
            0,
            if scale.is_some() {
                said
            } else {
                format!("{} kernel", kernel.name())
            },
        );
        format!(
            "{} and no kernel given: {} (override with --kernel, --radii, --weights)",
            if scale.is_some() {
                "SPH data"
            } else {
                "snapshot particles"
            },
            used.join(", ")
        )
    };
    Some((Some(kernel), scale, Some(note)))
}

/// AREPO's gas cells carry no smoothing length: each cell's kernel gets the
/// support that holds [`periodic::DEFAULT_NEIGHBOURS`] cells of its volume
/// `m/ρ`, so `(4π/3) H³ = N m/ρ`, and h = H / 2 (the cubic spline). `None`
/// for anything else, or when a radius was given.
pub(crate) fn cell_radii(p: &ParticlesDesc, t: &ParticleTable) -> Option<(Vec<f32>, String)> {
    let arepo = t.sph.as_ref().is_some_and(|s| s.code == SphCode::Arepo);
    if !arepo || p.radii.is_some() || p.radius.is_some() || p.neighbours.is_some() {
        return None;
    }
    let (m, rho) = (t.column("Masses")?, t.column("Density")?);
    let n = periodic::DEFAULT_NEIGHBOURS as f64;
    let radii = m
        .iter()
        .zip(rho)
        .map(|(&m, &rho)| {
            let v = m as f64 / rho as f64;
            (0.5 * (3.0 * n * v / (4.0 * std::f64::consts::PI)).cbrt()) as f32
        })
        .collect();
    Some((
        radii,
        format!(
            "AREPO gas cells: radii from the cell volumes Masses/Density (the cubic spline's \
             support holds {n} cells' volume; override with --radii, --radius or --neighbours)"
        ),
    ))
}

/// Notes on what a snapshot states: its epoch and its units (and that
/// positions stay comoving as stored).
pub(crate) fn describe(t: &ParticleTable, format: ParticleFormat) -> Vec<String> {
    if !format.is_snapshot() || t.sph.is_none() {
        return Vec::new();
    }
    let mut notes = Vec::new();
    let mut epoch = Vec::new();
    if let Some(time) = t.time {
        epoch.push(format!("time (scale factor in cosmological runs) {time}"));
    }
    if let Some(z) = t.redshift {
        epoch.push(format!("redshift {z:.4}"));
    }
    if !epoch.is_empty() {
        notes.push(format!("snapshot: {}", epoch.join(", ")));
    }
    notes.push(match &t.units {
        Some(u) => format!(
            "units: {}; column densities in {}",
            u.describe(),
            u.column_density()
        ),
        None => format!(
            "units: the {} states none; lengths and masses are the code's, as stored",
            format.name()
        ),
    });
    notes
}
