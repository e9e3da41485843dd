//! Spatiotemporal blue noise for the random numbers of stochastic rendering.
//!
//! A 64×64 tileable blue-noise *rank mask* is generated in code by
//! void-and-cluster (Ulichney 1993): with a toroidal Gaussian energy
//! (σ = 1.5 pixels), an initial random binary pattern is relaxed by moving its
//! tightest cluster into its largest void until stable; its points are then
//! ranked by repeatedly removing the tightest cluster, and the remaining
//! pixels by repeatedly filling the largest void. `rank / N` is a threshold
//! map whose values are uniform on [0, 1) and whose neighbouring pixels are
//! as different as possible: its error spectrum lacks low frequencies.
//!
//! Over time (sample index and frame), each pixel's value advances by the
//! golden ratio modulo 1 — a rank-1 lattice, so successive samples of one
//! pixel are evenly spread (low discrepancy) while every single frame keeps
//! the mask's blue spectrum. The mask is built once per process (a few ms)
//! and is a pure function of its fixed seed, so renders stay deterministic.

use std::sync::OnceLock;

/// Side of the mask in pixels.
pub const SIZE: usize = 64;
const N: usize = SIZE * SIZE;
const SIGMA: f32 = 1.5;
/// Kernel half-width: the Gaussian is below 1e-6 of its peak beyond it.
const RADIUS: i32 = 8;

/// The mask: a threshold in [0, 1) per pixel, row-major.
pub fn mask() -> &'static [f32] {
    static MASK: OnceLock<Vec<f32>> = OnceLock::new();
    MASK.get_or_init(|| {
        let ranks = void_and_cluster(0x0b1e_5eed);
        ranks.iter().map(|&r| (r as f32 + 0.5) / N as f32).collect()
    })
}

/// The blue-noise value of pixel `(x, y)` for sample index `index`
/// (`frame · spp + sample`), and decorrelated streams via `dim` (each
/// dimension reads the mask at its own fixed toroidal offset).
#[inline]
pub fn value(x: u32, y: u32, index: u64, dim: u32) -> f32 {
    const GOLDEN: f64 = 0.618_033_988_749_894_9;
    // Fixed, well-separated offsets per dimension.
    let ox = (dim as usize).wrapping_mul(23) % SIZE;
    let oy = (dim as usize).wrapping_mul(41) % SIZE;
    let m = mask()[((y as usize + oy) % SIZE) * SIZE + (x as usize + ox) % SIZE] as f64;
    let v = (m + index as f64 * GOLDEN).fract() as f32;
    v.min(1.0 - f32::EPSILON)
}

/// Ranks `0..N` over the `SIZE`×`SIZE` torus (see the module docs).
fn void_and_cluster(seed: u64) -> Vec<u32> {
    let kernel = gaussian_kernel();
    let mut rng = voxless_core::SmallRng(seed);
    // Initial pattern: ~10 % of the pixels, at random.
    let mut on = vec![false; N];
    let mut energy = vec![0.0f32; N];
    let initial = N / 10;
    let mut placed = 0;
    while placed < initial {
        let i = (rng.f() * N as f32) as usize % N;
        if !on[i] {
            on[i] = true;
            splat(&mut energy, &kernel, i, 1.0);
            placed += 1;
        }
    }
    // Relax: move the tightest cluster into the largest void until the
    // void it would fill is the spot it came from.
    for _ in 0..N {
        let cluster = extreme(&energy, &on, true);
        on[cluster] = false;
        splat(&mut energy, &kernel, cluster, -1.0);
        let void = extreme(&energy, &on, false);
        on[void] = true;
        splat(&mut energy, &kernel, void, 1.0);
        if void == cluster {
            break;
        }
    }
    let mut rank = vec![0u32; N];
    // Phase 1: rank the initial points, tightest cluster last-in first-out.
    {
        let mut on1 = on.clone();
        let mut e1 = energy.clone();
        for r in (0..initial).rev() {
            let c = extreme(&e1, &on1, true);
            on1[c] = false;
            splat(&mut e1, &kernel, c, -1.0);
            rank[c] = r as u32;
        }
    }
    // Phase 2: fill the largest void, in rank order.
    for r in initial..N {
        let v = extreme(&energy, &on, false);
        on[v] = true;
        splat(&mut energy, &kernel, v, 1.0);
        rank[v] = r as u32;
    }
    rank
}

fn gaussian_kernel() -> Vec<f32> {
    let w = (2 * RADIUS + 1) as usize;
    let mut k = vec![0.0; w * w];
    for dy in -RADIUS..=RADIUS {
        for dx in -RADIUS..=RADIUS {
            let r2 = (dx * dx + dy * dy) as f32;
            k[((dy + RADIUS) as usize) * w + (dx + RADIUS) as usize] =
                (-r2 / (2.0 * SIGMA * SIGMA)).exp();
        }
    }
    k
}

/// Adds `sign` × the kernel centred on pixel `i` (toroidally) to `energy`.
fn splat(energy: &mut [f32], kernel: &[f32], i: usize, sign: f32) {
    let (cx, cy) = ((i % SIZE) as i32, (i / SIZE) as i32);
    let w = (2 * RADIUS + 1) as usize;
    for dy in -RADIUS..=RADIUS {
        let y = (cy + dy).rem_euclid(SIZE as i32) as usize;
        for dx in -RADIUS..=RADIUS {
            let x = (cx + dx).rem_euclid(SIZE as i32) as usize;
            energy[y * SIZE + x] +=
                sign * kernel[((dy + RADIUS) as usize) * w + (dx + RADIUS) as usize];
        }
    }
}

/// The set pixel of highest energy (`cluster`) or the unset pixel of lowest
/// energy (void); ties go to the lowest index, for determinism.
fn extreme(energy: &[f32], on: &[bool], cluster: bool) -> usize {
    let mut best = usize::MAX;
    let mut best_e = if cluster {
        f32::NEG_INFINITY
    } else {
        f32::INFINITY
    };
    for (i, (&e, &o)) in energy.iter().zip(on).enumerate() {
        if o == cluster && ((cluster && e > best_e) || (!cluster && e < best_e)) {
            best = i;
            best_e = e;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_is_a_permutation_of_ranks() {
        let m = mask();
        let mut ranks: Vec<usize> = m.iter().map(|&v| (v * N as f32) as usize).collect();
        ranks.sort_unstable();
        assert_eq!(ranks, (0..N).collect::<Vec<_>>());
    }

    #[test]
    fn neighbours_differ_more_than_white_noise() {
        // Mean absolute difference of horizontal neighbours: 1/3 for
        // independent uniforms; blue noise pushes neighbours apart.
        let m = mask();
        let mut sum = 0.0;
        for y in 0..SIZE {
            for x in 0..SIZE {
                sum += (m[y * SIZE + x] - m[y * SIZE + (x + 1) % SIZE]).abs() as f64;
            }
        }
        let mean = sum / N as f64;
        assert!(mean > 0.38, "neighbour difference {mean} is not blue");
    }

    #[test]
    fn values_stay_in_unit_interval_and_cycle_evenly() {
        let mut hist = [0u32; 10];
        for s in 0..1000u64 {
            let v = value(5, 9, s, 0);
            assert!((0.0..1.0).contains(&v));
            hist[(v * 10.0) as usize] += 1;
        }
        // A rank-1 lattice: each tenth gets 100 ± a few.
        assert!(hist.iter().all(|&h| (95..=105).contains(&h)), "{hist:?}");
    }
}
