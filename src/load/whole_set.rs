//! A particle set read in shares (one per rank of a communicator): the
//! whole set's world frame, settings and statistics, each exactly what the
//! one-process load computes over all rows, from pieces the ranks merge —
//! minima and maxima, the union of occupied cells, probes chosen by row
//! number and gathered.
//!
//! 1. The world frame from the whole data's reach ([`Reach`], merged over
//!    the ranks and over every material of the set).
//! 2. [`Set::settle`]: each rank places its rows in the frame, and the
//!    ranks agree on the settings — the default radius from the median
//!    nearest-neighbour spacing ([`whole_spacing`]: the occupied cells of
//!    the coarse grid are an OR of the ranks' grids; each probe's nearest
//!    neighbour is the minimum over the ranks' particles), the float32
//!    resolution check, the attribute range — and on the probes (every
//!    `stride`-th row) that give the median support and, once the data is
//!    exchanged, the density range.

use voxless_core::{Aabb, Range1, Vec3};
use voxless_parallel::{Comm, CommError, CommExt, Reader, Writer};
use voxless_particles::neighbours::radii_from_distances;
use voxless_particles::{
    ParticleError, ParticleSettings, check_data, median, probe_stride, support_box,
};
use voxless_scene::ParticlesDesc;

use super::particles::{
    FrameData, blame, in_world_units, particle_settings, prepare_arrays, radius_from_spacing,
};
use super::reach::{Reach, Unresolvable, WorldBox};
use super::spacing::{self, OccupancyGrid, PROBES};
use crate::{ParallelError, SceneError, WorldFrame};

/// Every rank's outcome of a local step: `Ok` everywhere or an error
/// everywhere (this rank's own, or the failing rank's).
pub(crate) fn agree<T, E>(comm: &dyn Comm, local: Result<T, E>) -> Result<T, ParallelError>
where
    E: std::fmt::Display + Into<ParallelError>,
{
    match comm.agree(local)? {
        Ok(v) => Ok(v),
        Err(e) => Err(e.into()),
    }
}

/// The union over all ranks of their boxes.
pub(crate) fn union_bounds(comm: &dyn Comm, b: Aabb) -> Result<Aabb, CommError> {
    let (lo, hi) = if b.is_empty() {
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3])
    } else {
        (
            [b.min.x as f64, b.min.y as f64, b.min.z as f64],
            [b.max.x as f64, b.max.y as f64, b.max.z as f64],
        )
    };
    let lo = comm.all_min(&lo)?;
    let hi = comm.all_max(&hi)?;
    Ok(Aabb::new(
        Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32),
        Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32),
    ))
}

/// The world box the whole set's supports reach (see
/// [`Reach::world_box`]): every rank's [`Reach`] merged.
pub(crate) fn world_reach(
    comm: &dyn Comm,
    p: &ParticlesDesc,
    rows: &FrameData,
) -> Result<Option<WorldBox>, CommError> {
    // A periodic box is the same on every rank: the frame fits it.
    if let Some(b) = &rows.periodic {
        return Ok(Some(super::periodic::corners(b)));
    }
    let own = Reach::of(&rows.positions, rows.data.radii.as_deref());
    let mut mine = Vec::with_capacity(7);
    mine.extend(own.lo);
    mine.extend(own.hi);
    // No radii is −∞, below any radius.
    mine.push(own.max_radius.map_or(f64::NEG_INFINITY, f64::from));
    let all = comm.all_gather_f64(&mine)?;
    let reach = all
        .iter()
        .map(|v| Reach {
            lo: [v[0], v[1], v[2]],
            hi: [v[3], v[4], v[5]],
            max_radius: (v[6] > f64::NEG_INFINITY).then_some(v[6] as f32),
        })
        .reduce(Reach::merge);
    Ok(reach.and_then(|r| r.world_box(p, rows.kernel(p), rows.total)))
}

/// A set's rows with the whole set's settings and statistics.
pub(crate) struct Set {
    pub rows: FrameData,
    pub settings: ParticleSettings,
    /// Effective radius per row (after the radius map).
    pub radius: Vec<f32>,
    /// Every probe of the set, in row order: centre and effective radius.
    pub probes: Vec<(Vec3, f32)>,
    pub median_support: f32,
    /// The union of the visible supports: the set's bounds.
    pub bounds: Aabb,
}

impl Set {
    /// Places this rank's rows in the frame `world` and agrees with the
    /// other ranks on the set's settings and statistics (`keep`: a later
    /// frame of a series keeps the first frame's settings).
    pub fn settle(
        comm: &dyn Comm,
        p: &ParticlesDesc,
        mut rows: FrameData,
        world: &WorldFrame,
        keep: Option<&ParticleSettings>,
        notes: &mut Vec<String>,
    ) -> Result<Set, ParallelError> {
        rows.data.positions = rows.positions.iter().map(|&q| world.to_local(q)).collect();
        let periodic = super::particles::local_box(rows.periodic.as_ref(), world);
        rows.positions = Vec::new();
        let kernel = prepare_arrays(&mut rows.data, p, rows.sph_defaults, world.scale)?;
        let blame_it = |e: ParticleError| blame(rows.main_file.clone(), &rows.files, e);
        agree(comm, check_data(&rows.data, rows.offset).map_err(blame_it))?;
        // Every rank takes the same branches here (they depend on the
        // description and on which arrays are given), so a default radius
        // is found by all of them together.
        let mut settings = match keep {
            Some(k) => k.clone(),
            None => {
                let mut comm_error = None;
                let settings = particle_settings(
                    p,
                    kernel,
                    rows.data.radii.is_some(),
                    &mut |kernel| match whole_spacing(comm, &rows) {
                        Ok(d) => radius_from_spacing(d, rows.total, kernel),
                        Err(e) => {
                            comm_error = Some(e);
                            (1.0, String::new())
                        }
                    },
                    world.scale,
                    notes,
                )?;
                if let Some(e) = comm_error {
                    return Err(e.into());
                }
                let support = settings.radius * kernel.support_factor();
                check_resolvable(comm, &rows, support, world.scale)?;
                settings
            }
        };
        settings.periodic = periodic;
        let positions = union_bounds(comm, spacing::bounds(&rows.data.positions))?;
        if rows.data.attribute.is_none() {
            for (what, present) in [
                ("radius map", settings.radius_map.is_some()),
                ("weight map", settings.weight_map.is_some()),
            ] {
                if present {
                    return Err(blame_it(ParticleError::NeedsAttribute { what }).into());
                }
            }
        }
        if let (None, Some(a)) = (settings.attribute_range, &rows.data.attribute) {
            let (lo, hi) = a
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v as f64), hi.max(v as f64))
                });
            let lo = comm.all_min(&[lo])?[0];
            let hi = comm.all_max(&[hi])?[0];
            settings.attribute_range = Some(if lo <= hi {
                Range1::new(lo as f32, hi as f32)
            } else {
                Range1::EMPTY
            });
        }
        let range = settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
        let n = rows.data.positions.len();
        let radius: Vec<f32> = (0..n)
            .map(|i| {
                let base = rows.data.radii.as_ref().map_or(settings.radius, |r| r[i]);
                let attr = rows.data.attribute.as_ref().map(|a| a[i]);
                settings.effective_radius(base, attr, range)
            })
            .collect();
        // The probes, gathered in row order.
        let stride = probe_stride(rows.total);
        let mut w = Writer::new();
        for (i, (q, r)) in rows.data.positions.iter().zip(&radius).enumerate() {
            if (rows.offset + i).is_multiple_of(stride) {
                w.u8(1);
                w.vec3(*q);
                w.f32(*r);
            }
        }
        let mut probes = Vec::new();
        for msg in comm.all_gather(&w.into_bytes())? {
            let mut r = Reader::new(&msg);
            while !r.is_done() {
                r.u8()?;
                probes.push((r.vec3()?, r.f32()?));
            }
        }
        let kernel = settings.kernel;
        let factor = kernel.support_factor();
        // As the whole volume checks it: the probes' median support against
        // the positions' extent.
        if rows.total > 1000 {
            let mut supports: Vec<f32> = probes.iter().map(|p| p.1 * factor).collect();
            let support = median(&mut supports);
            let extent = positions.diagonal();
            if support > extent {
                let e = ParticleError::HugeRadius {
                    support,
                    extent,
                    count: rows.total,
                };
                return Err(blame_it(in_world_units(e, world.scale)).into());
            }
        }
        let mut visible: Vec<f32> = probes
            .iter()
            .filter(|p| p.1 > 0.0)
            .map(|p| {
                let s = factor * p.1;
                (s * s).sqrt()
            })
            .collect();
        let mut own = Aabb::EMPTY;
        for (q, &r) in rows.data.positions.iter().zip(&radius) {
            own = own.union(support_box(*q, r, kernel));
        }
        // A periodic volume's bounds are its box (every rank has the same).
        let bounds = match periodic {
            Some(b) => b,
            None => union_bounds(comm, own)?,
        };
        let median_support = if visible.is_empty() {
            bounds.diagonal().max(1e-6)
        } else {
            median(&mut visible)
        };
        Ok(Set {
            rows,
            settings,
            radius,
            probes,
            median_support,
            bounds,
        })
    }
}

/// The whole set's median nearest-neighbour spacing
/// ([`spacing::nearest_neighbour_spacing`] of every rank's local
/// positions together): the same bounds, occupancy grid and probes (every
/// `stride`-th row), each probe's nearest neighbour the minimum over the
/// ranks' particles.
fn whole_spacing(comm: &dyn Comm, rows: &FrameData) -> Result<Option<f32>, CommError> {
    let positions = &rows.data.positions;
    let b = union_bounds(comm, spacing::bounds(positions))?;
    // The mean spacing: the union of the ranks' occupied cells.
    let mean = match OccupancyGrid::new(b, rows.total) {
        None => None,
        Some(mut grid) => {
            for q in positions {
                grid.mark(*q);
            }
            let bits: Vec<u8> = grid
                .occupied
                .chunks(8)
                .map(|c| {
                    c.iter()
                        .enumerate()
                        .fold(0u8, |b, (i, &o)| b | (o as u8) << i)
                })
                .collect();
            let mut union = vec![0u8; bits.len()];
            for got in comm.all_gather(&bits)? {
                for (u, g) in union.iter_mut().zip(got) {
                    *u |= g;
                }
            }
            let count = union.iter().map(|b| b.count_ones() as usize).sum();
            Some(grid.spacing(count))
        }
    };
    // The probes, gathered in row order.
    let stride = (rows.total / PROBES).max(1);
    let mut w = Writer::new();
    for (i, q) in positions.iter().enumerate() {
        if (rows.offset + i).is_multiple_of(stride) {
            w.vec3(*q);
        }
    }
    let mut probes = Vec::new();
    for msg in comm.all_gather(&w.into_bytes())? {
        let mut r = Reader::new(&msg);
        while !r.is_done() {
            probes.push(r.vec3().map_err(CommError::from)?);
        }
    }
    let mut failed = None;
    let found = spacing::spacing_search(&b, mean, &mut |h| {
        let mine = spacing::nearest_within(positions, &probes, &b, h);
        match comm.all_min(&mine) {
            Ok(v) => v,
            Err(e) => {
                failed.get_or_insert(e);
                vec![f64::INFINITY; probes.len()]
            }
        }
    });
    match failed {
        Some(e) => Err(e),
        None => Ok(found),
    }
}

/// The float32 resolution check of the one-process load over the ranks
/// ([`Unresolvable`]): the medians (of the radii, and of the positions for
/// the centre) are the probes' — every [`probe_stride`]-th row — and the
/// particle named is the first of the farthest over every rank.
fn check_resolvable(
    comm: &dyn Comm,
    rows: &FrameData,
    support: f32,
    scale: f64,
) -> Result<(), ParallelError> {
    let positions = &rows.data.positions;
    let stride = probe_stride(rows.total);
    let mut w = Writer::new();
    for (i, q) in positions.iter().enumerate() {
        if (rows.offset + i).is_multiple_of(stride) {
            w.vec3(*q);
            w.f32(rows.data.radii.as_ref().map_or(0.0, |r| r[i]));
        }
    }
    let (mut centres, mut radii) = (Vec::new(), Vec::new());
    for msg in comm.all_gather(&w.into_bytes())? {
        let mut r = Reader::new(&msg);
        while !r.is_done() {
            centres.push(r.vec3()?);
            radii.push(r.f32()?);
        }
    }
    let radii = rows.data.radii.as_ref().map(|_| radii.as_mut_slice());
    let b = union_bounds(comm, spacing::bounds(positions))?;
    let Some(found) = Unresolvable::find(support, radii, &centres, b, rows.total) else {
        return Ok(());
    };
    let (far, d) = found.farthest(positions);
    let all = comm.all_gather_f64(&[d, (rows.offset + far) as f64])?;
    // The first of the farthest, as one process finds it.
    let far = all
        .iter()
        .fold(
            (0.0, -1.0),
            |m, v| if v[0] > m.1 { (v[1], v[0]) } else { m },
        )
        .0 as usize;
    Err(found.error(far, scale).into())
}

/// Radii from neighbours for a set read in shares: the ranks search slabs
/// of space with halos ([`super::spread_radii`]), each keeping its rows';
/// where a slab would hold fewer than N points, every rank gathers all
/// positions (24 bytes per particle) and searches.
pub(crate) fn neighbour_radii(
    comm: &dyn Comm,
    p: &ParticlesDesc,
    rows: &mut FrameData,
    notes: &mut Vec<String>,
) -> Result<(), ParallelError> {
    let n =
        super::periodic::neighbour_count(p, rows.snapshot, rows.data.radii.is_some(), rows.total);
    let Some(n) = agree(comm, n)? else {
        return Ok(());
    };
    let kernel = rows.kernel(p);
    let start = std::time::Instant::now();
    let periodic = rows.periodic.as_ref();
    if comm.size() > 1
        && let Some(d) = super::spread_radii::spread_distances(
            comm,
            &rows.positions,
            rows.offset,
            n,
            periodic,
            &rows.main_file,
        )?
    {
        // A radius of 0 (n − 1 others at a particle's position) names the
        // particle's row in the whole set.
        let h = radii_from_distances(d, n, kernel).map_err(|e| {
            let e = match e {
                ParticleError::CoincidentNeighbours { index, others } => {
                    ParticleError::CoincidentNeighbours {
                        index: rows.offset + index,
                        others,
                    }
                }
                e => e,
            };
            SceneError::Particles {
                path: rows.main_file.clone(),
                source: e,
            }
        });
        let h = agree(comm, h)?;
        let lo = comm.all_min(&[h.iter().copied().fold(f64::INFINITY, f64::min)])?[0];
        let hi = comm.all_max(&[h.iter().copied().fold(f64::NEG_INFINITY, f64::max)])?[0];
        let mid = whole_median(comm, &h)?.unwrap_or(lo);
        let seconds = start.elapsed().as_secs_f64();
        notes.push(super::periodic::radii_note(
            n,
            periodic.is_some(),
            kernel,
            (lo, mid, hi),
            seconds,
        ));
        rows.data.radii = Some(h.iter().map(|&v| v as f32).collect());
        return Ok(());
    }
    let mut w = Writer::with_capacity(16 + 24 * rows.positions.len());
    w.u64(rows.offset as u64);
    w.u64(rows.positions.len() as u64);
    for q in &rows.positions {
        q.iter().for_each(|&v| w.f64(v));
    }
    let mut all = vec![[0.0f64; 3]; rows.total];
    for msg in comm.all_gather(&w.into_bytes())? {
        let mut r = Reader::new(&msg);
        let (offset, len) = (r.u64()? as usize, r.u64()? as usize);
        for q in all.iter_mut().skip(offset).take(len) {
            *q = [r.f64()?, r.f64()?, r.f64()?];
        }
    }
    let mut said = Vec::new();
    let found = super::periodic::neighbour_radii(
        &all,
        n,
        rows.periodic.as_ref(),
        kernel,
        &rows.main_file,
        &mut said,
    );
    let h = agree(comm, found)?;
    let mine = rows.offset..rows.offset + rows.positions.len();
    rows.data.radii = Some(h[mine].to_vec());
    notes.extend(said);
    Ok(())
}

/// The median of every rank's `values`, from each rank's 4096 quantiles
/// weighted by its count (within 1/4096 of the ranks' rows); `None` when
/// there are none.
fn whole_median(comm: &dyn Comm, values: &[f64]) -> Result<Option<f64>, CommError> {
    let mut sorted = values.to_vec();
    sorted.sort_unstable_by(f64::total_cmp);
    let m = sorted.len().min(4096);
    let mut sketch = Vec::with_capacity(2 * m);
    for k in 0..m {
        sketch.push(sorted[(2 * k + 1) * sorted.len() / (2 * m)]);
        sketch.push(sorted.len() as f64 / m as f64);
    }
    let mut all: Vec<(f64, f64)> = comm
        .all_gather_f64(&sketch)?
        .iter()
        .flat_map(|s| s.chunks_exact(2).map(|c| (c[0], c[1])).collect::<Vec<_>>())
        .collect();
    all.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let half = all.iter().map(|c| c.1).sum::<f64>() / 2.0;
    let mut below = 0.0;
    Ok(all
        .iter()
        .find(|c| {
            below += c.1;
            below >= half
        })
        .map(|c| c.0))
}

/// Radius parameters of rows `offset..offset + values.len()` of a particle
/// set, in world units.
#[derive(Clone, Debug, Default)]
pub struct RowRadii {
    pub offset: usize,
    pub values: Vec<f32>,
}
