//! Radii from neighbours for a set read in shares, in bounded memory: the
//! ranks search slabs of space, each with a halo, instead of every rank
//! gathering every position.
//!
//! 1. **Slabs.** The longest axis (of the periodic box, else of the data) is
//!    cut at quantiles of strided samples of every rank's rows, one slab per
//!    rank; each position goes, with its row number, to its slab's rank.
//! 2. **A first search within the slab** gives each point an upper bound of
//!    its answer: its N-th nearest among fewer points is no nearer.
//! 3. **Halo.** A point's true neighbours lie within that bound, so a slab
//!    needs the points within `W` of it along the axis (periodic distances
//!    in a box), `W` the largest part of a bound that reaches past the
//!    slab's faces. Each rank sends every other the points within its `W`.
//! 4. **The exact search** runs over the slab and its halo, asking only
//!    about the slab's points: every point within a bound is there, so the
//!    N-th nearest is the whole set's, the same bits as one process.
//! 5. The distances go back to the ranks that hold their rows.
//!
//! Each rank then holds its slab and halo — about `N / ranks` positions and
//! a margin of a few neighbour distances — not all `N`. A slab with fewer
//! than N points (tiny sets, many ranks) makes the ranks gather every
//! position instead (the caller's fallback).

use voxless_parallel::{Comm, CommExt, Reader, Writer};
use voxless_particles::ParticleError;
use voxless_particles::neighbours::{PeriodicBox, neighbour_distances, neighbour_distances_of};

use std::path::Path;

use super::whole_set::agree;
use crate::{ParallelError, SceneError};

/// Strided samples of the slab axis each rank gives to place the cuts.
const SAMPLES: usize = 4096;

/// The distance from each of this rank's rows (`mine`, rows `offset..`) to
/// its `n`-th nearest neighbour in the whole set, the same as one process
/// computes; `None` (on every rank) where a slab holds fewer than `n`
/// points. Errors name rows by their number in the whole set.
pub(crate) fn spread_distances(
    comm: &dyn Comm,
    mine: &[[f64; 3]],
    offset: usize,
    n: usize,
    periodic: Option<&PeriodicBox>,
    file: &Path,
) -> Result<Option<Vec<f64>>, ParallelError> {
    let blame = |e: ParticleError, rows: &[u64]| SceneError::Particles {
        path: file.to_path_buf(),
        source: renumber(e, rows),
    };
    let ranks = comm.size();
    let me = comm.rank();
    // The axis and its extent: the box's, or the data's (every rank has
    // the same box, so all take the same branch).
    let (axis, lo, hi) = match periodic {
        Some(b) => {
            let a = (0..3).fold(0, |m, a| if b.size[a] > b.size[m] { a } else { m });
            (a, b.lo[a], b.lo[a] + b.size[a])
        }
        None => {
            let fold = |start: f64, f: fn(f64, f64) -> f64| -> Vec<f64> {
                (0..3)
                    .map(|a| mine.iter().fold(start, |m, p| f(m, p[a])))
                    .collect()
            };
            let lo3 = comm.all_min(&fold(f64::INFINITY, f64::min))?;
            let hi3 = comm.all_max(&fold(f64::NEG_INFINITY, f64::max))?;
            let a = (0..3).fold(0, |m, a| {
                if hi3[a] - lo3[a] > hi3[m] - lo3[m] {
                    a
                } else {
                    m
                }
            });
            (a, lo3[a], hi3[a])
        }
    };
    // Cuts at quantiles of every rank's samples.
    let stride = mine.len().div_ceil(SAMPLES).max(1);
    let samples: Vec<f64> = mine.iter().step_by(stride).map(|p| p[axis]).collect();
    let mut all: Vec<f64> = comm.all_gather_f64(&samples)?.concat();
    all.sort_unstable_by(f64::total_cmp);
    if all.is_empty() {
        return Ok(None);
    }
    let cuts: Vec<f64> = (1..ranks).map(|k| all[k * all.len() / ranks]).collect();
    let slab = |k: usize| {
        let a = if k == 0 { lo } else { cuts[k - 1] };
        let b = if k + 1 == ranks { hi } else { cuts[k] };
        (a, b)
    };
    let owner = |c: f64| cuts.partition_point(|&x| x <= c);

    // 1. Every position to its slab, with its row number.
    let mut send: Vec<Writer> = (0..ranks).map(|_| Writer::new()).collect();
    for (i, p) in mine.iter().enumerate() {
        let w = &mut send[owner(p[axis])];
        w.u64((offset + i) as u64);
        p.iter().for_each(|&v| w.f64(v));
    }
    let got = comm.exchange(send.into_iter().map(Writer::into_bytes).collect())?;
    let (mut own, mut rows) = (Vec::new(), Vec::new());
    for msg in &got {
        let mut r = Reader::new(msg);
        while !r.is_done() {
            rows.push(r.u64()?);
            own.push([r.f64()?, r.f64()?, r.f64()?]);
        }
    }
    let fewest = comm.all_min(&[own.len() as f64])?[0];
    if fewest < n as f64 {
        return Ok(None);
    }

    // 2. Upper bounds within the slab, and how far they reach past it; a
    //    bound that stays inside is already the answer.
    let mut d = agree(
        comm,
        neighbour_distances(&own, n, periodic).map_err(|e| blame(e, &rows)),
    )?;
    let (a, b) = slab(me);
    let past = |p: &[f64; 3], d: f64| d - (p[axis] - a).min(b - p[axis]);
    let reach = own
        .iter()
        .zip(&d)
        .fold(0.0f64, |w, (p, &d)| w.max(past(p, d)));
    let reaches = comm.all_gather_f64(&[reach])?;

    // 3. The halo: this slab's points within each other slab's reach.
    let period = periodic.map(|b| b.size[axis]);
    let gap = |c: f64, (a, b): (f64, f64)| {
        let d = |c: f64| (a - c).max(c - b).max(0.0);
        match period {
            Some(l) => d(c).min(d(c - l)).min(d(c + l)),
            None => d(c),
        }
    };
    let mut send: Vec<Writer> = (0..ranks).map(|_| Writer::new()).collect();
    for (k, w) in send.iter_mut().enumerate() {
        if k == me {
            continue;
        }
        let (s, r) = (slab(k), reaches[k][0]);
        for p in own.iter().filter(|p| gap(p[axis], s) <= r) {
            p.iter().for_each(|&v| w.f64(v));
        }
    }
    let got = comm.exchange(send.into_iter().map(Writer::into_bytes).collect())?;

    // 4. The exact search for the points whose bound reaches past the slab:
    //    they come first (the queries), then the rest of the slab and the
    //    halo.
    let (near_face, inside): (Vec<usize>, Vec<usize>) =
        (0..own.len()).partition(|&i| past(&own[i], d[i]) > 0.0);
    let mut points: Vec<[f64; 3]> = near_face.iter().chain(&inside).map(|&i| own[i]).collect();
    drop(own);
    for msg in &got {
        let mut r = Reader::new(msg);
        while !r.is_done() {
            points.push([r.f64()?, r.f64()?, r.f64()?]);
        }
    }
    let exact = agree(
        comm,
        neighbour_distances_of(&points, near_face.len(), n, periodic).map_err(|e| {
            // Errors name the query's row (the halo's points were checked
            // on their own slabs).
            let order: Vec<u64> = near_face.iter().map(|&i| rows[i]).collect();
            blame(e, &order)
        }),
    )?;
    drop(points);
    for (&i, v) in near_face.iter().zip(exact) {
        d[i] = v;
    }

    // 5. Back to the rows' ranks.
    let mut w = Writer::new();
    w.u64(offset as u64);
    w.u64(mine.len() as u64);
    let mut ranges = Vec::with_capacity(ranks);
    for msg in comm.all_gather(&w.into_bytes())? {
        let mut r = Reader::new(&msg);
        ranges.push((r.u64()?, r.u64()?));
    }
    let mut send: Vec<Writer> = (0..ranks).map(|_| Writer::new()).collect();
    // Shares are consecutive in rank order: a row's rank is the last one
    // starting at or before it.
    for (&row, &v) in rows.iter().zip(&d) {
        let k = ranges.partition_point(|&(o, _)| o <= row).saturating_sub(1);
        send[k].u64(row);
        send[k].f64(v);
    }
    let mut out = vec![f64::NAN; mine.len()];
    for msg in comm.exchange(send.into_iter().map(Writer::into_bytes).collect())? {
        let mut r = Reader::new(&msg);
        while !r.is_done() {
            let row = r.u64()? as usize;
            let v = r.f64()?;
            if let Some(o) = row.checked_sub(offset).and_then(|i| out.get_mut(i)) {
                *o = v;
            }
        }
    }
    Ok(Some(out))
}

/// An error about the `i`-th point of a slab, about its row instead.
fn renumber(e: ParticleError, rows: &[u64]) -> ParticleError {
    let row = |i: usize| rows.get(i).map_or(i, |&r| r as usize);
    match e {
        ParticleError::NonFinitePosition { index, x, y, z } => ParticleError::NonFinitePosition {
            index: row(index),
            x,
            y,
            z,
        },
        e => e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxless_core::SmallRng;
    use voxless_parallel::run_local;

    /// Half the points in a small clump (radii vary a hundredfold), in a
    /// box `[1, 3) × [−1, 2) × [0, 0.5)`.
    fn clumped(count: usize) -> Vec<[f64; 3]> {
        let mut rng = SmallRng(17);
        (0..count)
            .map(|i| {
                let s = if i % 2 == 0 { 1.0 } else { 0.03 };
                let mut f = || (0.4 + s * rng.f() as f64).rem_euclid(1.0);
                [1.0 + 2.0 * f(), -1.0 + 3.0 * f(), 0.5 * f()]
            })
            .collect()
    }

    #[test]
    fn slabs_with_halos_give_the_one_process_distances() {
        let p = clumped(4000);
        let b = PeriodicBox {
            lo: [1.0, -1.0, 0.0],
            size: [2.0, 3.0, 0.5],
        };
        for (n, periodic) in [(32, Some(&b)), (7, Some(&b)), (32, None)] {
            let want = neighbour_distances(&p, n, periodic).unwrap();
            for ranks in [2, 3, 5] {
                // Shares of rows, as the readers give them (uneven).
                let cut = |k: usize| (p.len() * k * k) / (ranks * ranks);
                let got = run_local(ranks, |comm| {
                    let (a, b) = (cut(comm.rank()), cut(comm.rank() + 1));
                    spread_distances(comm, &p[a..b], a, n, periodic, Path::new("p.npy"))
                        .unwrap()
                        .expect("every slab holds n points")
                });
                let got: Vec<f64> = got.concat();
                assert_eq!(got.len(), want.len());
                for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(
                        g.to_bits(),
                        w.to_bits(),
                        "n {n}, {ranks} ranks, row {i}: {g} vs {w}"
                    );
                }
            }
        }
    }

    #[test]
    fn slabs_too_small_for_n_ask_for_the_gathered_search() {
        let p = clumped(60);
        let none = run_local(4, |comm| {
            let k = comm.rank();
            spread_distances(
                comm,
                &p[15 * k..15 * (k + 1)],
                15 * k,
                32,
                None,
                Path::new("p"),
            )
            .unwrap()
        });
        assert!(none.iter().all(Option::is_none));
    }
}
