//! Phase-space tessellations: N³ positions in Lagrangian order from a
//! `.npy` (or any particle file), a JaxPM `.h5` run, or memory.
//!
//! The periodic box `[0, L)³` keeps its corner at the world origin; only its
//! scale is chosen by the placement policy ([`WorldFrame::fit`] on the box),
//! so boxes of 10⁻¹² or 10³⁰ units compute in a local unit about their size.
//! Without a particle mass the mean density is 1 (densities read as the
//! overdensity 1 + δ), whatever the box size; a given mass is divided by the
//! scale's cube so densities (mass over tet volume) stay in world units.

use rayon::prelude::*;
use std::ops::Range;
use std::path::{Path, PathBuf};

use voxless_scene::TetsDesc;
use voxless_tets::{BLOCK, LagrangianGrid, TetSettings, TetVolume};

use super::formats::ParticleFormat;
use super::{Share, WorldGrid};
use crate::checks::positive;
use crate::{SceneError, WorldFrame};

pub(crate) fn load_tets(
    t: &TetsDesc,
    base: &Path,
    notes: &mut Vec<String>,
) -> Result<(TetVolume, WorldFrame), SceneError> {
    let (grid, path) = read_grid(t, base, None, notes)?;
    build_world(grid, t, &path)
}

/// The block rows of share `share` of an `n`-plane Lagrangian grid (rows
/// of [`BLOCK`] planes), their first and last plane, and how many planes
/// the share reads: its own, plus the next plane (`last % n`), which the
/// cells of its last row reach into (0 for an empty share).
pub(crate) fn slab_planes(n: usize, share: Share) -> (Range<usize>, usize, usize, usize) {
    let rows = share.rows(n.div_ceil(BLOCK));
    let first = (rows.start * BLOCK).min(n);
    let last = (rows.end * BLOCK).min(n);
    let planes = if rows.is_empty() { 0 } else { last - first + 1 };
    (rows, first, last, planes)
}

/// The world positions the run `t` names: the whole grid (`slab` `None`,
/// one process), or the planes of share `slab` of a decomposed grid (see
/// [`slab_planes`]); with N, L and the file — every check one process
/// makes: the file, N³ particles (from the `.npy` header when a share reads
/// only its planes), all inside the box.
pub(crate) fn read_grid(
    t: &TetsDesc,
    base: &Path,
    slab: Option<Share>,
    notes: &mut Vec<String>,
) -> Result<(WorldGrid, PathBuf), SceneError> {
    let file = t.file.as_ref().ok_or_else(|| {
        SceneError::setting(
            "tets.file",
            "no positions file given (--particles FILE.npy with --lagrangian N --box L, or a \
             JaxPM FILE.h5)",
        )
    })?;
    let path = base.join(file);
    // The share's planes of a whole grid's positions.
    let cut = |mut g: WorldGrid| {
        let Some(share) = slab else {
            return g;
        };
        let (n, nn) = (g.n, g.n * g.n);
        let (_, first, last, planes) = slab_planes(n, share);
        let mut slab = Vec::with_capacity(planes * nn);
        if planes > 0 {
            slab.extend_from_slice(&g.positions[first * nn..last * nn]);
            let extra = last % n;
            slab.extend_from_slice(&g.positions[extra * nn..(extra + 1) * nn]);
        }
        g.positions = slab;
        g
    };
    if ParticleFormat::detect(&path)? == Some(ParticleFormat::Hdf5) {
        // A JaxPM run: N and L come from the file.
        let grid = super::jaxpm::grid(t, &path, notes)?;
        check_grid(&grid, &path)?;
        return Ok((cut(grid), path));
    }
    if t.snapshot.is_some() {
        return Err(SceneError::setting(
            "tets.snapshot",
            format!(
                "--snapshot picks a snapshot of a JaxPM .h5 run, but {} is not one",
                path.display()
            ),
        ));
    }
    if let Some(share) = slab
        && let Some(grid) = npy_planes(t, &path, share)?
    {
        return Ok((grid, path));
    }
    // A whole `.npy` decoded on every core into its rows; other tables
    // through their readers.
    let positions = if super::table::is_npy(&path) {
        voxless_io::npy::read_npy_positions(&path)?
    } else {
        super::table::read_positions(&path)?.0
    };
    Ok((cut(world_grid(positions, t, &path)?), path))
}

/// The share's planes of an N×3 `.npy`, read by offset after checking N
/// and L as the whole grid is checked; `None` for other files (read whole).
fn npy_planes(t: &TetsDesc, path: &Path, share: Share) -> Result<Option<WorldGrid>, SceneError> {
    let shape = if super::table::is_npy(path) {
        voxless_io::read_npy_rows(path, 0..0)?.1
    } else {
        return Ok(None);
    };
    let Some(n) = t.lagrangian.filter(|_| shape.len() == 2 && shape[1] == 3) else {
        return Ok(None);
    };
    let l = t.box_size.ok_or_else(|| {
        SceneError::setting("tets.box_size", "the periodic box size is needed (--box L)")
    })? as f64;
    check_count(n, shape[0], path)?;
    let (_, first, last, planes) = slab_planes(n, share);
    let nn = n * n;
    // The share's planes and the plane after them (the first, across the
    // periodic seam, for the last share), decoded on every core into
    // their places: no copy through another buffer (a second of the 256³
    // set-up on one core, with the pages it faulted in).
    let mut positions = vec![[0.0f64; 3]; planes * nn];
    if planes > 0 {
        let (slab, next) = positions.split_at_mut((last - first) * nn);
        voxless_io::npy::read_npy_positions_into(path, first * nn, slab)?;
        check_inside(slab, first * nn, l, path)?;
        voxless_io::npy::read_npy_positions_into(path, (last % n) * nn, next)?;
    }
    Ok(Some(WorldGrid {
        n,
        box_size: l,
        positions,
    }))
}

/// The Lagrangian grid of world `positions` with the description's N and
/// L, checked: N³ particles, all inside the periodic box.
pub(crate) fn world_grid(
    positions: Vec<[f64; 3]>,
    t: &TetsDesc,
    source: &Path,
) -> Result<WorldGrid, SceneError> {
    let n = t.lagrangian.ok_or_else(|| {
        SceneError::setting(
            "tets.lagrangian",
            "the Lagrangian grid size N is needed (--lagrangian N)",
        )
    })?;
    let box_size = t.box_size.ok_or_else(|| {
        SceneError::setting("tets.box_size", "the periodic box size is needed (--box L)")
    })?;
    let grid = WorldGrid {
        n,
        box_size: box_size as f64,
        positions,
    };
    check_grid(&grid, source)?;
    Ok(grid)
}

/// N³ particles inside `[0, L)³` (a hair of rounding past L allowed).
pub(crate) fn check_grid(g: &WorldGrid, source: &Path) -> Result<(), SceneError> {
    check_count(g.n, g.positions.len(), source)?;
    check_inside(&g.positions, 0, g.box_size, source)
}

/// `count` particles for a Lagrangian grid of N = `n`.
pub(crate) fn check_count(n: usize, count: usize, source: &Path) -> Result<(), SceneError> {
    if n.checked_pow(3) != Some(count) {
        let cube = (count as f64).cbrt().round() as usize;
        let hint = if cube >= 2 && cube.checked_pow(3) == Some(count) {
            format!(" ({count} = {cube}³: use --lagrangian {cube})")
        } else {
            " (which is not N³ for any whole N)".to_string()
        };
        return Err(SceneError::data(
            source,
            format!(
                "tets.lagrangian (--lagrangian) N = {} needs N³ = {} particles, but there are \
                 {count}{hint}",
                n,
                n.checked_pow(3)
                    .map_or("too many".to_string(), |c| c.to_string())
            ),
        ));
    }
    Ok(())
}

/// `positions` (particles `first ..` of the grid) inside a periodic box of
/// size `l`.
pub(crate) fn check_inside(
    positions: &[[f64; 3]],
    first: usize,
    l: f64,
    source: &Path,
) -> Result<(), SceneError> {
    if !(l.is_finite() && l > 0.0) {
        return Err(SceneError::setting(
            "tets.box_size (--box)",
            format!("the box size {l} must be finite and > 0"),
        ));
    }
    let slack = 1e-5 * l;
    let outside = |p: &[f64; 3]| p.iter().any(|&c| !(c >= -slack && c <= l + slack));
    if let Some(i) = positions.iter().position(outside) {
        let (lo, hi) = crate::frame::bounds_of(positions).unwrap_or(([0.0; 3], [0.0; 3]));
        let span_lo = lo.iter().fold(f64::INFINITY, |m, &v| m.min(v));
        let span_hi = hi.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
        return Err(SceneError::data(
            source,
            format!(
                "particle {i} at {:?} lies outside the periodic box [0, {l})³ (positions span \
                 [{span_lo}, {span_hi}]); is the box size (--box) right?",
                positions[i],
                i = first + i
            ),
        ));
    }
    Ok(())
}

/// A tessellation of world positions, placed in the frame its box picks.
pub(crate) fn build_world(
    g: WorldGrid,
    t: &TetsDesc,
    source: &Path,
) -> Result<(TetVolume, WorldFrame), SceneError> {
    let frame = box_frame(g.box_size);
    let grid = LagrangianGrid {
        n: g.n,
        box_size: (g.box_size / frame.scale) as f32,
        // On every core (200 MB at 256³).
        positions: g.positions.par_iter().map(|&p| frame.to_local(p)).collect(),
    };
    // The float64 world positions are not needed past this point.
    drop(g.positions);
    let mass = particle_mass(t, g.n, grid.box_size, g.box_size, frame.scale)?;
    let local = TetsDesc {
        particle_mass: Some(mass),
        ..t.clone()
    };
    let v = build_tets(grid, &local, source)?;
    Ok((v, frame))
}

/// The frame of a periodic box of size `l` (world): its corner stays at
/// the origin, its scale is the policy's for the box.
pub(crate) fn box_frame(l: f64) -> WorldFrame {
    WorldFrame {
        origin: [0.0; 3],
        scale: WorldFrame::fit([0.0; 3], [l; 3]).scale,
    }
}

/// The particle mass in a frame of scale `s` for a grid of N = `n` in a box
/// of `box_local` (local) and `box_world` units.
pub(crate) fn particle_mass(
    t: &TetsDesc,
    n: usize,
    box_local: f32,
    box_world: f64,
    s: f64,
) -> Result<f64, SceneError> {
    // Without a mass, the mean density is 1 (densities read as 1 + δ, the
    // overdensity), whatever the box size. A given mass is in world units:
    // mass over local volume is density in world units when the mass is
    // divided by scale³.
    let n3 = (n as f64).powi(3);
    let mass = match t.particle_mass {
        None => (box_local as f64).powi(3) / n3,
        Some(m) => {
            if !(m.is_finite() && m > 0.0) {
                return Err(SceneError::setting(
                    "tets.particle_mass (--particle-mass)",
                    format!("{m} must be finite and > 0"),
                ));
            }
            let local = m / s.powi(3);
            let mean = local * n3 / (box_local as f64).powi(3);
            if !(1e-30..=1e30).contains(&mean) {
                return Err(SceneError::setting(
                    "tets.particle_mass (--particle-mass)",
                    format!(
                        "a mass of {m} per particle in a box of {} gives a mean density of \
                         {:.3e}, beyond what float32 computes with; give the mass in other \
                         units, or leave it out for a mean density of 1",
                        box_world,
                        m * n3 / box_world.powi(3)
                    ),
                ));
            }
            local
        }
    };
    Ok(mass)
}

/// Levels of detail past this many would subsample the 8³-cell blocks below
/// one cell.
const MAX_LOD_LEVELS: usize = 3;

/// A tessellation of `grid` (local units; its positions become the
/// mesh's) with the description's mass, level of detail and projection
/// pixels; errors name `source`.
pub(crate) fn build_tets(
    grid: LagrangianGrid,
    t: &TetsDesc,
    source: &Path,
) -> Result<TetVolume, SceneError> {
    let settings = TetSettings {
        particle_mass: t.particle_mass,
        ..Default::default()
    };
    if let Some(p) = t.lod_pixels {
        positive("tets.lod_pixels (--lod)", p)?;
    }
    if let Some(l) = t.lod_levels.filter(|&l| l > MAX_LOD_LEVELS) {
        return Err(SceneError::setting(
            "tets.lod_levels",
            format!("{l} is more than {MAX_LOD_LEVELS} (each level halves N)"),
        ));
    }
    let levels = t
        .lod_levels
        .unwrap_or(if t.lod_pixels.is_some() { 3 } else { 0 });
    let v = TetVolume::from_grid(grid, &settings, levels).map_err(|e| SceneError::Tets {
        path: source.to_path_buf(),
        source: e,
    })?;
    Ok(v.with_lod_pixels(t.lod_pixels)
        .with_pixel_integral(crate::projection::pixel_integral(t.pixels)))
}
