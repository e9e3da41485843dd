//! Work counters of a tessellation frame: tet visits (a tet of a block
//! binned to a tile, once per such tile), pixel tests (a ray clipped against
//! a tet's planes, for every pixel of the tet's screen rectangle) and
//! crossings (tests that hit), counted over the same `raster::Frame` tiles,
//! bins and rectangles the tile view renders from (rays through pixel
//! centres: the first pass).

use rayon::prelude::*;
use voxless_core::Camera;
use voxless_tets::TetMesh;
use voxless_tets::raster::{Frame, box_spans, for_each_crossing};

pub(super) struct Work {
    pub visits: u64,
    pub tests: u64,
    /// `None` when the pixel tests exceed the limit given to [`work`].
    pub crossings: Option<u64>,
    covered: u64,
    max: u32,
}

impl Work {
    pub fn row(&self, label: &str, view: &str) -> String {
        let (crossings, per_pixel, ratio) = match self.crossings {
            Some(c) => (
                sci(c as f64),
                format!("{:.1}, {}", c as f64 / self.covered.max(1) as f64, self.max),
                format!("{:.3}", c as f64 / self.tests.max(1) as f64),
            ),
            None => ("—".into(), "—".into(), "—".into()),
        };
        format!(
            "| {label} | {view} | {} | {} | {crossings} | {per_pixel} | {ratio} |",
            sci(self.visits as f64),
            sci(self.tests as f64),
        )
    }
}

pub(super) fn sci(v: f64) -> String {
    format!("{v:.2e}")
}

/// Pixel tests beyond which [`work`] does not count crossings (and a view is
/// not timed): a frame that size would take hours.
const TEST_LIMIT: u64 = 20_000_000_000;

/// Counts the renderer's work for one frame (same tiles, bins and pixel
/// rects as the tile view) and, unless the pixel tests exceed [`TEST_LIMIT`], the
/// crossings per pixel (row-major).
pub(super) fn work(
    mesh: &TetMesh,
    camera: &Camera,
    size: u32,
    lod: Option<f32>,
) -> (Work, Vec<u32>) {
    let frame = Frame::new(mesh, camera, size, size, lod);
    let coarse = if lod.is_some() { mesh.lod() } else { &[] };
    let levels: Vec<&TetMesh> = std::iter::once(mesh).chain(coarse.iter()).collect();
    let (visits, tests) = (0..frame.tiles_x * frame.tiles_y)
        .into_par_iter()
        .map(|i| {
            let (x0, y0, w, h) = frame.tile(i);
            let (mut visits, mut tests) = (0u64, 0u64);
            let mut buf = Vec::new();
            for &e in &frame.bins[i as usize] {
                let m = levels[(e >> 28) as usize];
                let b = (e & ((1 << 28) - 1)) as usize;
                // The block's tets, derived (a lean mesh holds none), and
                // their pixel rectangles.
                let tets = m.block_tets(b, &mut buf);
                visits += tets.len() as u64;
                for r in tets.iter().filter_map(|t| frame.screen.pixel_rect(&t.v)) {
                    let (ax, bx) = (r.0.max(x0), r.1.min(x0 + w - 1));
                    let (ay, by) = (r.2.max(y0), r.3.min(y0 + h - 1));
                    if ax <= bx && ay <= by {
                        tests += ((bx - ax + 1) * (by - ay + 1)) as u64;
                    }
                }
            }
            (visits, tests)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let mut counts = vec![0u32; (size * size) as usize];
    let mut crossings = None;
    if tests <= TEST_LIMIT {
        let per_tile: Vec<(u32, Vec<u32>)> = (0..frame.tiles_x * frame.tiles_y)
            .into_par_iter()
            .map(|i| {
                let rays = frame.rays(i);
                let spans = box_spans(mesh, &rays);
                let mut hits = vec![0u32; rays.len()];
                for_each_crossing(mesh, &frame, i, &rays, &spans, |p, _, _, _| hits[p] += 1);
                (i, hits)
            })
            .collect();
        for (i, hits) in per_tile {
            let (x0, y0, w, _) = frame.tile(i);
            for (k, c) in hits.into_iter().enumerate() {
                counts[((y0 + k as u32 / w) * size + x0 + k as u32 % w) as usize] = c;
            }
        }
        crossings = Some(counts.iter().map(|&c| c as u64).sum());
    }
    let covered = counts.iter().filter(|&&c| c > 0).count() as u64;
    let max = counts.iter().copied().max().unwrap_or(0);
    (
        Work {
            visits,
            tests,
            crossings,
            covered,
            max,
        },
        counts,
    )
}
