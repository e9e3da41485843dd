//! Reconstruction (ExaBricks Table 3): the same points through cell
//! location (`CellLocator`) and through the regions (`AmrVolume::sample_in`
//! with the region as the interval hint, and `AmrVolume::sample`); see the
//! parent module for the setup.

use std::time::Instant;

use rayon::prelude::*;
use voxless_amr::{AmrVolume, CellLocator};
use voxless_core::{Camera, Interval, IntervalQuery, Range1, Vec3, Volume};

use super::Dataset;
use super::data::Rng;
use crate::common::{count, median, ms};

pub(super) fn bench_recon(
    s: &Dataset,
    vol: &AmrVolume,
    n: usize,
    repeats: usize,
    speedups: &mut Vec<(String, f64)>,
) -> Vec<String> {
    eprintln!("amr/{}: CellLocator::new", s.label);
    let t = Instant::now();
    let loc = CellLocator::new(&s.cells, s.field);
    let t_loc = t.elapsed().as_secs_f64();
    let mut rng = Rng::new(0x5eed_0000 ^ s.cells.cells.len() as u64);
    let b = vol.bounds();
    let uniform: Vec<Vec3> = (0..n)
        .map(|_| {
            let u = Vec3::new(rng.unit(), rng.unit(), rng.unit());
            b.min + b.extent().mul_elem(u)
        })
        .collect();
    let (o, h) = (s.cells.origin, s.cells.cell_size);
    let in_cells: Vec<Vec3> = (0..n)
        .map(|_| {
            let c = s.cells.cells[rng.below(s.cells.cells.len())];
            let w = (1i64 << c[3]) as f32;
            let u = Vec3::new(rng.unit(), rng.unit(), rng.unit());
            o + (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + u * w) * h
        })
        .collect();
    let on_rays = ray_samples(vol, n, &mut rng);
    let mut rows = Vec::new();
    for (what, pts) in [
        ("ray samples", &on_rays),
        ("uniform in bounds", &uniform),
        ("one in each of N random cells", &in_cells),
    ] {
        eprintln!("amr/{}: reconstruction, {what}", s.label);
        // The region of each point, as a ray's interval would hand it over.
        let hints: Vec<u32> = pts
            .par_iter()
            .map(|&p| vol.locate(p).map_or(Interval::NO_HINT, |r| r as u32))
            .collect();
        let interval = |hint| Interval {
            hint,
            ..Interval::sampled(Range1::EMPTY, Range1::EMPTY, 0.0)
        };
        // Repeats go round the three variants (see `bench_frames`).
        let (mut times, mut a, mut r, mut r2) =
            ([(); 3].map(|_| Vec::new()), vec![], vec![], vec![]);
        for _ in 0..repeats {
            let t = Instant::now();
            a = pts.par_iter().map(|&p| loc.sample(p)).collect::<Vec<_>>();
            times[0].push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            r = pts
                .par_iter()
                .zip(&hints)
                .map(|(&p, &hint)| match hint {
                    Interval::NO_HINT => None,
                    _ => vol.sample_in(p, &interval(hint)).map(|x| x.value),
                })
                .collect::<Vec<_>>();
            times[1].push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            r2 = pts
                .par_iter()
                .map(|&p| vol.sample(p).map(|x| x.value))
                .collect::<Vec<_>>();
            times[2].push(t.elapsed().as_secs_f64());
        }
        let [t_cell, t_in, t_sample] = times.map(median);
        let (mut max_diff, mut covered, mut one_only) = (0.0f32, 0usize, 0usize);
        for ((x, y), y2) in a.iter().zip(&r).zip(&r2) {
            match (x, y) {
                (Some(x), Some(y)) => {
                    max_diff = max_diff.max((x - y).abs());
                    covered += 1;
                }
                (None, None) => {}
                _ => one_only += 1,
            }
            if y != y2 {
                one_only += 1;
            }
        }
        speedups.push((s.label.clone(), t_cell / t_in));
        rows.push(format!(
            "| {} | {what}, {} | {:.1} % | {:.1} | {:.1} | {:.2} | {:.1} | {:.2} | {max_diff:.2e} | {one_only} | {:.0} |",
            s.label,
            count(n),
            100.0 * covered as f64 / n as f64,
            ms(t_cell),
            ms(t_in),
            t_cell / t_in,
            ms(t_sample),
            t_cell / t_sample,
            ms(t_loc)
        ));
    }
    rows
}

/// `n` sample positions of rays through random pixels of a 1024² framing
/// view: every interval of every region (no TF), stepped at half the region's
/// finest cell width from a random offset, segment midpoints — where the
/// renderer samples with adaptive sampling and no space skipping.
pub(super) fn ray_samples(vol: &AmrVolume, n: usize, rng: &mut Rng) -> Vec<Vec3> {
    let camera = Camera::framing(&vol.bounds(), 1.0);
    let mut out = Vec::with_capacity(n);
    let mut ivs = Vec::new();
    let mut misses = 0;
    while out.len() < n && misses < 1_000_000 {
        let ray = camera.ray(rng.unit() * 1024.0, rng.unit() * 1024.0, 1024, 1024);
        let t = vol.bounds().clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
        ivs.clear();
        if !t.is_empty() {
            vol.intervals(&ray, t, &IntervalQuery::all(), &mut ivs);
        }
        if ivs.is_empty() {
            misses += 1;
        }
        for iv in &ivs {
            let dt = iv.nominal_dt.max(iv.t.span() * 1e-6);
            let mut t0 = iv.t.lo;
            let mut t1 = iv.t.lo + rng.unit() * dt;
            while t0 < iv.t.hi && out.len() < n {
                let end = t1.min(iv.t.hi);
                out.push(ray.at(0.5 * (t0 + end)));
                t0 = end;
                t1 = end + dt;
            }
        }
    }
    out
}
