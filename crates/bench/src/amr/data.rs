//! The AMR data sets: ExaBricks frames of the AMRClaw run, and a
//! deterministic synthetic multi-level set of any size.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use voxless_amr::AmrCells;
use voxless_core::Vec3;

/// ExaBricks frame `frame` in `dir/exabricks`: the cells and every
/// `frameN.*.scalars`, sorted by name; the opacity field is `density` if there
/// is one, else the first.
pub(super) fn read_frame(dir: &Path, frame: u32) -> Result<(AmrCells, usize)> {
    let ex = dir.join("exabricks");
    let cells = ex.join(format!("frame{frame}.cells"));
    let prefix = format!("frame{frame}.");
    let mut scalars: Vec<PathBuf> = std::fs::read_dir(&ex)
        .with_context(|| format!("listing {}", ex.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".scalars"))
        })
        .collect();
    scalars.sort();
    if scalars.is_empty() {
        bail!("no {prefix}*.scalars in {}", ex.display());
    }
    let d = voxless_io::read_exabricks(&cells, &scalars)?;
    let field = d.fields.iter().position(|f| f.0 == "density").unwrap_or(0);
    let o = d.origin.map(|v| v as f32);
    Ok((
        AmrCells {
            cells: d.cells,
            fields: d.fields,
            origin: Vec3::new(o[0], o[1], o[2]),
            cell_size: d.finest_cell_size as f32,
        },
        field,
    ))
}

/// About `target` leaf cells on four levels (level 3, 8 units wide, the
/// coarsest) in the unit cube: a G³ grid of level-3 cells, refined by aligned
/// patches of 4³ cells of one level (each cell into 8) when the patch comes
/// within 1.5 cell widths of a wavy spherical shell, or with probability 1/32
/// anywhere (hash of patch and level).
/// Level-3 cells outside the shell are left out in about 15 % of the 32-unit
/// blocks (holes). One field, "density": a smooth background in about
/// [0.08, 0.32] plus a peak of 0.65 on the shell. G is found by a few
/// counting passes.
pub(super) fn synthetic(target: usize) -> AmrCells {
    let mut g = 64;
    let mut best = (usize::MAX, g);
    for _ in 0..8 {
        let n = Synth { g }.count();
        let err = n.abs_diff(target);
        if err < best.0 {
            best = (err, g);
        }
        if err * 100 < target {
            break;
        }
        let next = ((g as f64) * (target as f64 / n.max(1) as f64).powf(0.4)).round() as i32;
        let next = next.clamp(1, 1 << 17);
        if next == g {
            break;
        }
        g = next;
    }
    let s = Synth { g: best.1 };
    let cells: Vec<[i32; 4]> = (0..s.g)
        .into_par_iter()
        .flat_map_iter(|z| {
            let mut v = Vec::new();
            s.slice(z, &mut |c| v.push(c));
            v
        })
        .collect();
    let l = 8.0 * s.g as f64;
    let values = cells
        .par_iter()
        .map(|c| {
            let w = (1i64 << c[3]) as f64;
            s.value([0, 1, 2].map(|a| c[a] as f64 + 0.5 * w))
        })
        .collect();
    AmrCells {
        cells,
        fields: vec![("density".into(), values)],
        origin: Vec3::ZERO,
        cell_size: (1.0 / l) as f32,
    }
}

struct Synth {
    /// Level-3 cells per axis; the domain is 8g finest units wide.
    g: i32,
}

impl Synth {
    fn count(&self) -> usize {
        (0..self.g)
            .into_par_iter()
            .map(|z| {
                let mut n = 0usize;
                self.slice(z, &mut |_| n += 1);
                n
            })
            .sum()
    }

    /// Every leaf cell of the level-3 slice `z`, in order.
    fn slice(&self, z: i32, out: &mut dyn FnMut([i32; 4])) {
        for y in 0..self.g {
            for x in 0..self.g {
                let p = [8 * x, 8 * y, 8 * z];
                let c = p.map(|v| v as f64 + 4.0);
                let hole = hash([p[0] >> 5, p[1] >> 5, p[2] >> 5, 99]) % 100 < 15;
                if hole && self.shell(c) > 0.0 {
                    continue;
                }
                self.visit(p, 3, out);
            }
        }
    }

    fn visit(&self, p: [i32; 3], level: i32, out: &mut dyn FnMut([i32; 4])) {
        let w = 1 << level;
        // Refinement is decided per aligned block of 4³ cells of this level
        // (block-structured AMR refines patches, not single cells).
        let block = p.map(|v| v >> (level + 2));
        let bw = 4.0 * w as f64;
        let c = block.map(|b| (b as f64 + 0.5) * bw);
        let refine = level > 0
            && (self.shell(c).abs() < 0.87 * bw + 1.5 * w as f64
                || hash([block[0], block[1], block[2], level]).is_multiple_of(32));
        if !refine {
            out([p[0], p[1], p[2], level]);
            return;
        }
        let h = w / 2;
        for k in 0..8 {
            let q = [
                p[0] + (k & 1) * h,
                p[1] + (k >> 1 & 1) * h,
                p[2] + (k >> 2) * h,
            ];
            self.visit(q, level - 1, out);
        }
    }

    /// Signed distance-like function to the wavy shell, finest units
    /// (negative inside).
    fn shell(&self, c: [f64; 3]) -> f64 {
        let l = 8.0 * self.g as f64;
        let u = c.map(|v| v / l);
        let d = u.iter().map(|v| (v - 0.5) * (v - 0.5)).sum::<f64>().sqrt();
        let tau = std::f64::consts::TAU;
        let r = 0.3 + 0.03 * (3.0 * tau * u[0]).sin() * (3.0 * tau * u[1]).sin();
        (d - r) * l
    }

    fn value(&self, c: [f64; 3]) -> f32 {
        let l = 8.0 * self.g as f64;
        let u = c.map(|v| v / l);
        let tau = std::f64::consts::TAU;
        let background = 0.2 + 0.12 * (tau * (u[0] + u[1])).sin() * (tau * u[2]).cos();
        let s = self.shell(c) / (0.01 * l);
        (background + 0.65 * (-s * s).exp()) as f32
    }
}

/// splitmix64 of four coordinates.
fn hash(v: [i32; 4]) -> u64 {
    let mut x = v.iter().fold(0x243f_6a88_85a3_08d3u64, |h, &c| {
        (h ^ c as u32 as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
    });
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// xorshift64: deterministic, no dependency.
pub(super) struct Rng(u64);

impl Rng {
    pub(super) fn new(seed: u64) -> Rng {
        Rng(seed | 1)
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// Uniform in (0, 1).
    pub(super) fn unit(&mut self) -> f32 {
        ((self.next() >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    }
    /// Uniform in 0..n.
    pub(super) fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}
