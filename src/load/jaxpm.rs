//! JaxPM runs (`.h5`) as phase-space tessellations: the grid size N and the
//! box size L come from the file unless the scene gives them, in which case
//! they must agree with it.

use std::path::Path;

use voxless_scene::{ParticlesDesc, TetsDesc};

use super::WorldGrid;
use crate::SceneError;

/// The Lagrangian grid of snapshot `t.snapshot` (default: the last) of the
/// JaxPM run at `path` (unchecked: the caller checks it as it checks every
/// grid); a note says which snapshot was read.
#[cfg(feature = "hdf5")]
pub(crate) fn grid(
    t: &TetsDesc,
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<WorldGrid, SceneError> {
    use voxless_io::{Hdf5Kind, hdf5_kind, jaxpm_snapshots, read_jaxpm};

    let kind = hdf5_kind(path)?;
    if kind != Hdf5Kind::Jaxpm {
        let what = match kind {
            Hdf5Kind::PySph => "PySPH output",
            Hdf5Kind::Gadget => "a SWIFT/Gadget snapshot",
            Hdf5Kind::Flash | Hdf5Kind::Athena => "AMR output (read it with --amr)",
            _ => "an HDF5 file of unknown layout",
        };
        return Err(SceneError::data(
            path,
            format!(
                "a tessellation needs a JaxPM run (q_index and snap_<K> groups), but this is \
                 {what}; render its particles without --lagrangian/--box/--snapshot"
            ),
        ));
    }
    let snapshots = jaxpm_snapshots(path)?;
    let k = match (t.snapshot, snapshots.last()) {
        (Some(k), _) => k,
        (None, Some(&last)) => last,
        (None, None) => {
            return Err(SceneError::data(
                path,
                "a JaxPM file without snap_<K> groups",
            ));
        }
    };
    let snap = read_jaxpm(path, k)?;
    if let Some(n) = t.lagrangian
        && n != snap.n
    {
        return Err(SceneError::setting(
            "tets.lagrangian",
            format!(
                "N = {n} was given, but {} holds a {}³ Lagrangian grid (leave N out to use \
                 the file's)",
                path.display(),
                snap.n
            ),
        ));
    }
    if let Some(l) = t.box_size
        && !((l as f64 - snap.box_size).abs() <= 1e-5 * snap.box_size.abs())
    {
        return Err(SceneError::setting(
            "tets.box_size",
            format!(
                "L = {l} was given, but {} has a box of size {} (leave L out to use the file's)",
                path.display(),
                snap.box_size
            ),
        ));
    }
    let scale = snap
        .scale_factor
        .map(|a| format!(" (a = {a})"))
        .unwrap_or_default();
    let others = if t.snapshot.is_none() && snapshots.len() > 1 {
        format!(
            " (snapshots {}; pick one with --snapshot K)",
            snapshots
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )
    } else {
        String::new()
    };
    notes.push(format!(
        "JaxPM snapshot snap_{k}{scale}: N = {}, box L = {}{others}",
        snap.n, snap.box_size
    ));
    let grid = WorldGrid {
        n: snap.n,
        box_size: snap.box_size,
        positions: snap
            .positions
            .into_iter()
            .map(|p| p.map(f64::from))
            .collect(),
    };
    Ok(grid)
}

/// Without the `hdf5` feature a JaxPM file is an error saying how to build
/// with it.
#[cfg(not(feature = "hdf5"))]
pub(crate) fn grid(
    _: &TetsDesc,
    path: &Path,
    _: &mut Vec<String>,
) -> Result<WorldGrid, SceneError> {
    Err(crate::formats::hdf5::unsupported(path))
}

/// A particle file that is a JaxPM run (`--particles run.h5` alone) is a
/// tessellation of its last snapshot: the description to load it with.
/// Particle settings that cannot apply to it are errors naming them.
#[cfg(feature = "hdf5")]
pub(crate) fn as_tessellation(
    p: &ParticlesDesc,
    base: &Path,
) -> Result<Option<TetsDesc>, SceneError> {
    use super::formats::ParticleFormat;
    let Some(file) = &p.file else {
        return Ok(None);
    };
    let path = base.join(file);
    if p.materials.is_some()
        || super::frames::is_sequence(file, base)
        || ParticleFormat::detect(&path)? != Some(ParticleFormat::Hdf5)
        || voxless_io::hdf5_kind(&path)? != voxless_io::Hdf5Kind::Jaxpm
    {
        return Ok(None);
    }
    let given = [
        ("particles.attribute (--attribute)", p.attribute.is_some()),
        ("particles.radius (--radius)", p.radius.is_some()),
        ("particles.radii (--radii)", p.radii.is_some()),
        ("particles.weights (--weights)", p.weights.is_some()),
        ("particles.kernel (--kernel)", p.kernel.is_some()),
        ("particles.species (--species)", p.species.is_some()),
        ("particles.group (--group)", p.group.is_some()),
        ("particles.part_type (--part-type)", p.part_type.is_some()),
    ];
    if let Some((field, _)) = given.iter().find(|g| g.1) {
        return Err(SceneError::setting(
            field,
            format!(
                "{} is a JaxPM run, rendered as a phase-space tessellation whose density comes \
                 from the tets; this particle setting does not apply to it",
                path.display()
            ),
        ));
    }
    Ok(Some(TetsDesc {
        file: Some(file.clone()),
        ..Default::default()
    }))
}

/// Without the `hdf5` feature no file is read as a JaxPM run here (loading
/// it as particles says how to build with HDF5).
#[cfg(not(feature = "hdf5"))]
pub(crate) fn as_tessellation(_: &ParticlesDesc, _: &Path) -> Result<Option<TetsDesc>, SceneError> {
    Ok(None)
}
