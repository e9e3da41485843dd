//! The splatter's per-pixel paths beside the lanes: pixel areas from the
//! kernel's area table, and the clipped images of off-axis periodic
//! projections sampled at pixel centres or sub-pixel cells.

use voxless_core::{Aabb, Camera};

use super::{BAND, BandSplats, Splat};
use crate::kernel::area::AreaTable;

/// One band's f64 sums over its splats in order that average each pixel
/// over its square ([`PixelIntegral::Area`], supports narrower than
/// [`table_pixels`]): each pixel's share of the mass from the kernel's area
/// table at its corners, so the shares add up to the whole. Wider supports
/// take the pixel-centre lanes ([`SplatBand`]), clipped splats [`clipped`].
/// `out`: the band's rows, `stride` apart.
pub(super) fn area_band(
    splats: BandSplats,
    table: &AreaTable,
    y: (u32, u32),
    stride: usize,
    out: &mut [f64],
) {
    let mut upper: Vec<f64> = Vec::new();
    let mut lower: Vec<f64> = Vec::new();
    for p in splats.iter() {
        if p.clip || !p.area {
            continue;
        }
        let (first, end) = (p.lean.cols.0 as usize, p.lean.cols.1 as usize);
        let rows = p.lean.rows.0.max(y.0)..p.lean.rows.1.min(y.1);
        if first >= end || rows.is_empty() {
            continue;
        }
        let (pw, ph) = p.pixel;
        let support = p.column.support2().sqrt();
        // The support in pixels along x and y; pixel edges in units of the
        // support: (x − cx) / sx.
        let (sx, sy) = (support / pw, support / ph);
        let mass = p.weight * p.column.mass() / (pw * ph);
        let corners = |row: f64, into: &mut Vec<f64>| {
            let v = (row - p.lean.cy) / sy;
            into.clear();
            into.extend((first..=end).map(|x| table.at((x as f64 - p.lean.cx) / sx, v)));
        };
        corners(rows.start as f64, &mut upper);
        for r in rows {
            corners(r as f64 + 1.0, &mut lower);
            let line = &mut out[(r - y.0) as usize * stride..][..stride];
            for (k, o) in line[first..end].iter_mut().enumerate() {
                *o += mass * (lower[k + 1] - lower[k] - upper[k + 1] + upper[k]);
            }
            std::mem::swap(&mut upper, &mut lower);
        }
    }
}

/// The sub-pixel cells a clipped splat is sampled at ([`clipped`]): with
/// pixel areas, `n × n` cells a pixel, no wider than an eighth of the
/// support (only those near the support are visited); else one, the pixel
/// centre.
#[derive(Clone, Copy)]
pub(super) struct SubCells {
    n: u32,
    /// Image width and height, and half the image plane's width and height.
    size: (u32, u32),
    half: (f64, f64),
}

impl SubCells {
    /// One cell a pixel: its centre.
    pub(super) fn centres(size: (u32, u32), half: (f64, f64)) -> SubCells {
        SubCells { n: 1, size, half }
    }

    pub(super) fn new(p: &Splat, size: (u32, u32), half: (f64, f64)) -> SubCells {
        let (pw, ph) = p.pixel;
        let n = (8.0 * pw.max(ph) / p.column.support2().sqrt())
            .ceil()
            .clamp(1.0, 4096.0) as u32;
        SubCells { n, size, half }
    }

    /// The image plane's (u, v) of the centre of sub-cell `(kx, ky)` of
    /// pixel `(x, y)`.
    fn at(&self, (x, kx): (u32, u32), (y, ky): (u32, u32)) -> (f64, f64) {
        let n = self.n as f64;
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let u = (2.0 * (x as f64 + (kx as f64 + 0.5) / n) / w - 1.0) * self.half.0;
        let v = (1.0 - 2.0 * (y as f64 + (ky as f64 + 0.5) / n) / h) * self.half.1;
        (u, v)
    }

    /// The cells of pixel `k` (along an axis where the splat's centre is at
    /// `centre` pixels and the support spans `support` pixels) whose centres
    /// may lie in the support.
    fn near(&self, k: u32, centre: f64, support: f64) -> std::ops::Range<u32> {
        if self.n == 1 {
            return 0..1;
        }
        let n = self.n as f64;
        let c = (centre - k as f64) * n - 0.5;
        let lo = (c - support * n).floor().clamp(0.0, n) as u32;
        let hi = ((c + support * n).ceil() + 1.0).clamp(0.0, n) as u32;
        lo..hi
    }

    /// The factor of a pixel's sum of samples: the weight, or with cells
    /// the mean over a pixel's cells scaled so that the splat's unclipped
    /// samples add up to its exact mass.
    pub(super) fn scale(&self, p: &Splat) -> f64 {
        if self.n == 1 {
            return p.weight;
        }
        let mut full = 0.0;
        self.each(p, p.lean.rows.0..p.lean.rows.1, |_, _, b2, _, _| {
            full += p.column.at(b2);
        });
        let cells = (self.n as f64).powi(2);
        let cell_area = p.pixel.0 * p.pixel.1 / cells;
        if full > 0.0 {
            p.weight * p.column.mass() / (full * cell_area) / cells
        } else {
            0.0
        }
    }

    /// Calls `f(x, y, b², u, v)` for every cell centre of rows `rows` inside
    /// the splat's support (`b²` its squared distance from the centre).
    fn each(
        &self,
        p: &Splat,
        rows: std::ops::Range<u32>,
        mut f: impl FnMut(u32, u32, f64, f64, f64),
    ) {
        let support2 = p.column.support2();
        let (sx, sy) = (support2.sqrt() / p.pixel.0, support2.sqrt() / p.pixel.1);
        for y in rows {
            for ky in self.near(y, p.lean.cy, sy) {
                for x in p.lean.cols.0..p.lean.cols.1 {
                    for kx in self.near(x, p.lean.cx, sx) {
                        let (u, v) = self.at((x, kx), (y, ky));
                        let (du, dv) = (u - p.a, v - p.b);
                        let b2 = du * du + dv * dv;
                        if b2 < support2 {
                            f(x, y, b2, u, v);
                        }
                    }
                }
            }
        }
    }
}

/// The clipped splats of a band (off-axis periodic projections): the part
/// of each sample's chord inside the box `b`, in f64, at pixel centres or,
/// with pixel areas, at sub-pixel cells no wider than an eighth of the
/// support, scaled so that the kernel's unclipped samples would hold its
/// exact mass (then the images of a particle crossing faces add up to its
/// mass to the quadrature's error along the faces; [`SubCells`]).
pub(super) fn clipped(
    splats: BandSplats,
    camera: &Camera,
    b: &Aabb,
    height: u32,
    y0: u32,
    (stride, out): (usize, &mut [f64]),
) {
    let [eye, right, up, fwd] = camera.basis_f64();
    // The line's parameter at a face is (face − o)/fwd: a product with the
    // reciprocal per pixel instead of a division.
    let per_fwd = fwd.map(|f| 1.0 / f);
    let y1 = (y0 + BAND).min(height);
    for p in splats.iter() {
        if !p.clip {
            continue;
        }
        p.cells.each(
            p,
            p.lean.rows.0.max(y0)..p.lean.rows.1.min(y1),
            |x, y, b2, u, v| {
                // The line's segment [t0, t1] through the box.
                let mut t = (f64::NEG_INFINITY, f64::INFINITY);
                for k in 0..3 {
                    let o = eye[k] + right[k] * u + up[k] * v;
                    let (lo, hi) = (b.min[k] as f64, b.max[k] as f64);
                    if fwd[k] == 0.0 {
                        if o < lo || o > hi {
                            t = (1.0, 0.0);
                        }
                        continue;
                    }
                    let (t0, t1) = ((lo - o) * per_fwd[k], (hi - o) * per_fwd[k]);
                    t = (t.0.max(t0.min(t1)), t.1.min(t0.max(t1)));
                }
                if t.0 < t.1 {
                    let c = p.column.chord(b2, t.0 - p.depth, t.1 - p.depth);
                    out[(y - y0) as usize * stride + x as usize] += p.clip_scale * c;
                }
            },
        );
    }
}
