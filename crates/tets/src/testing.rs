//! Tessellations with known structure, for tests here and in other crates
//! (feature `testing`): uniform and jittered grids and a shell-crossed sheet.

use voxless_core::SmallRng as Lcg;
use voxless_core::Vec3;

use crate::LagrangianGrid;

/// A grid of N³ particles with positions `q + displacement(q)`, wrapped into the box.
pub fn grid(n: usize, l: f32, disp: impl Fn([f32; 3]) -> [f32; 3]) -> LagrangianGrid {
    let dq = l / n as f32;
    let mut positions = Vec::with_capacity(n * n * n);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let q = [i as f32 * dq, j as f32 * dq, k as f32 * dq];
                let d = disp(q);
                let w = |x: f32| x.rem_euclid(l);
                positions.push(Vec3::new(w(q[0] + d[0]), w(q[1] + d[1]), w(q[2] + d[2])));
            }
        }
    }
    LagrangianGrid {
        n,
        box_size: l,
        positions,
    }
}

pub fn jitter(seed: u64, amp: f32) -> impl Fn([f32; 3]) -> [f32; 3] {
    move |q| {
        // Deterministic per point: hash the position.
        let mut r = Lcg(seed
            ^ ((q[0] * 1e4) as u64)
            ^ (((q[1] * 1e4) as u64) << 20)
            ^ (((q[2] * 1e4) as u64) << 40));
        [0, 1, 2].map(|_| (r.f() - 0.5) * 2.0 * amp)
    }
}

/// The Zel'dovich sheet below, jittered in all three axes: shell-crossed,
/// overlapping and tilted tets.
pub fn folded_sheet(n: usize, seed: u64) -> LagrangianGrid {
    let k = std::f32::consts::TAU;
    let a = 1.5 / k;
    let j = jitter(seed, 0.03);
    grid(n, 1.0, move |q| {
        let d = j(q);
        [a * (k * q[0]).sin() + d[0], d[1], d[2]]
    })
}
