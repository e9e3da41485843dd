//! The whole set's statistics that fix the world frame and the default
//! radius, and the float32 resolution check, over the ranks — each exactly
//! what the one-process load (`crate::load::particles`) computes over all
//! rows.

use voxless_core::Vec3;
use voxless_parallel::{Comm, CommExt, Reader, Writer};
use voxless_particles::{median, probe_stride};
use voxless_scene::{KernelName, ParticlesDesc};

use super::Rows;
use crate::SceneError;
use crate::load::particles::kernel_of;
use crate::load::spacing::{self, OccupancyGrid, PROBES};
use crate::parallel::ParallelError;
use crate::parallel::share::union_bounds;

/// A world box: lower and upper corner (float64).
pub(super) type WorldBox = ([f64; 3], [f64; 3]);

/// The world box the whole set's supports reach, as
/// [`FrameData::world_reach`] finds it for one process: the positions'
/// bounds over every rank, grown by the largest support (unless refused as
/// too large for the data's extent).
pub(super) fn world_reach(
    comm: &dyn Comm,
    p: &ParticlesDesc,
    rows: &Rows,
) -> Result<Option<WorldBox>, ParallelError> {
    // As `bounds_of` folds them (NaN passed over), over every rank's rows.
    let mut mine = vec![f64::INFINITY; 3];
    mine.extend([f64::NEG_INFINITY; 3]);
    for q in &rows.world {
        for a in 0..3 {
            mine[a] = mine[a].min(q[a]);
            mine[3 + a] = mine[3 + a].max(q[a]);
        }
    }
    let own_radius = rows
        .data
        .radii
        .as_ref()
        .map_or(0.0f32, |r| r.iter().fold(0.0f32, |m, &v| m.max(v)));
    mine.push(own_radius as f64);
    let all = comm.all_gather_f64(&mine)?;
    let least = |k: usize| all.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min);
    let most = |k: usize| all.iter().map(|v| v[k]).fold(f64::NEG_INFINITY, f64::max);
    let lo: [f64; 3] = std::array::from_fn(least);
    let hi: [f64; 3] = std::array::from_fn(|a| most(3 + a));
    if !lo.iter().chain(&hi).all(|v| v.is_finite()) {
        return Ok(None);
    }
    // The largest radius as f32 folds it (NaN passed over), then widened.
    let max_radius = most(6) as f32 as f64;
    let kernel = rows
        .sph_defaults
        .unwrap_or_else(|| kernel_of(p, p.kernel.unwrap_or(KernelName::Gaussian3)));
    let factor = kernel.support_factor() as f64;
    let radius = match (p.radius, &rows.data.radii) {
        (Some(r), _) => r as f64,
        (None, Some(_)) => max_radius,
        (None, None) => 0.0,
    };
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let refused = rows.total > 1000 && factor * radius > extent;
    let grow = if radius.is_finite() && !refused {
        factor * radius
    } else {
        0.0
    };
    Ok(Some((lo.map(|v| v - grow), hi.map(|v| v + grow))))
}

/// The whole set's median nearest-neighbour spacing
/// ([`spacing::nearest_neighbour_spacing`] of every rank's local
/// positions together): the same bounds, occupancy grid and probes (every
/// `stride`-th row), each probe's nearest neighbour the minimum over the
/// ranks' particles.
pub(super) fn whole_spacing(comm: &dyn Comm, rows: &Rows) -> Result<Option<f32>, ParallelError> {
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
            probes.push(r.vec3()?);
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
        Some(e) => Err(e.into()),
        None => Ok(found),
    }
}

/// `crate::load::particles::check_resolvable` over the ranks: supports
/// below what float32 resolves across the whole set's extent are an error
/// naming the particle farthest from the rest. The medians (of the radii,
/// and of the positions for the centre) are the probes' — every
/// [`probe_stride`]-th row, so exact up to that many particles.
pub(super) fn check_resolvable(
    comm: &dyn Comm,
    rows: &Rows,
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
    let support = match &rows.data.radii {
        Some(_) if !radii.is_empty() => support * median(&mut radii),
        _ => support,
    } as f64;
    let b = union_bounds(comm, spacing::bounds(positions))?;
    let extent = (0..3)
        .map(|a| (b.max[a] - b.min[a]) as f64)
        .fold(0.0, f64::max);
    if rows.total < 2 || !extent.is_finite() || !(support < extent * 1e-6) {
        return Ok(());
    }
    let centre: [f32; 3] = std::array::from_fn(|a| {
        let mut v: Vec<f32> = centres.iter().map(|p| p[a]).collect();
        median(&mut v)
    });
    let dist = |p: &Vec3| {
        (0..3)
            .map(|a| (p[a] - centre[a]).abs() as f64)
            .fold(0.0, f64::max)
    };
    let (far, d) = positions.iter().enumerate().fold((0, -1.0), |m, (i, p)| {
        if dist(p) > m.1 {
            (rows.offset + i, dist(p))
        } else {
            m
        }
    });
    let all = comm.all_gather_f64(&[d, far as f64])?;
    // The first of the farthest, as one process finds it.
    let far = all
        .iter()
        .fold(
            (0.0, -1.0),
            |m, v| if v[0] > m.1 { (v[1], v[0]) } else { m },
        )
        .0 as usize;
    Err(SceneError::setting(
        "particles (positions)",
        format!(
            "the particles' supports ({:.3e}) are too small for float32 to resolve across the \
             data's extent ({:.3e}): particle {far} lies farthest from the rest; leave out \
             outliers like it (or give a larger --radius)",
            support * scale,
            extent * scale
        ),
    )
    .into())
}
