//! Whole-image column densities of the basis reconstruction for views down
//! an axis ([`voxless_core::Volume::project_image`]).
//!
//! **Why.** The rays of an orthographic view down axis `m` are parallel and
//! share their start and direction along `m`, so a region's pieces along
//! them — which bricks' cells it holds along `m`, where the kinks of its
//! tents cut the rays — are the same for every ray through it
//! ([`AxisPieces`]). Per ray, the walk of the region tree, the clipping and
//! the kinks cost more than the basis sums themselves; here they are done
//! once per region and band of rows, and every pixel of the band whose ray
//! crosses the region only evaluates its sums.
//!
//! **Exactness.** Each pixel's ray is the camera's, its range the bounds
//! clipped to it, its regions those the walk would give (the region box
//! clipped to the ray, as the walk computes it), visited in the walk's
//! order, and each region's term comes from the same functions as
//! [`AmrVolume::line_integral`]: the image is bit for bit the per-pixel
//! one (tested). Views that are not down an axis, or whose pixels do not
//! share the axis position and range, get `None` (the per-pixel path).

use rayon::prelude::*;
use voxless_core::{Aabb, Camera, Cancelled, Control, Range1, Ray, Volume};

use crate::integral::{AxisPieces, Line};
use crate::volume::AmrVolume;

/// Rows per task: a region's pieces are found once per band.
const BAND: u32 = 8;

/// Indices `i` with `lo <= v[i] < hi` of a strictly monotone `v`.
pub(crate) fn span(v: &[f32], lo: f32, hi: f32) -> std::ops::Range<usize> {
    if v.len() < 2 || v[0] < v[1] {
        v.partition_point(|&x| x < lo)..v.partition_point(|&x| x < hi)
    } else {
        v.partition_point(|&x| x >= hi)..v.partition_point(|&x| x >= lo)
    }
}

fn monotone(v: &[f32]) -> bool {
    v.windows(2).all(|w| w[0] < w[1]) || v.windows(2).all(|w| w[0] > w[1])
}

/// An image of `height` rows made in bands of `band` rows on the thread
/// pool: `f` gives a band's pixels (row-major), progress is reported as
/// bands finish, and a cancelled control stops the bands not yet started.
pub(crate) fn in_bands(
    height: usize,
    band: usize,
    control: &Control,
    f: impl Fn(std::ops::Range<usize>) -> Vec<f32> + Sync,
) -> Result<Vec<f32>, Cancelled> {
    let done = std::sync::atomic::AtomicU64::new(0);
    let bands: Vec<Option<Vec<f32>>> = (0..height.div_ceil(band))
        .into_par_iter()
        .map(|k| {
            if control.is_cancelled() {
                return None;
            }
            let rows = k * band..((k + 1) * band).min(height);
            let n = rows.len() as u64;
            let pixels = f(rows);
            let d = done.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
            control.report(d + n, height as u64);
            Some(pixels)
        })
        .collect();
    if control.is_cancelled() {
        return Err(Cancelled);
    }
    Ok(bands.into_iter().flatten().flatten().collect())
}

/// The pixels of an orthographic view down axis `m`: the range `t` all rays
/// that meet the bounds share; the axes `ax` and `ay` across the view and
/// the pixel centres' positions along them, `xs` by column and `ys` by row.
pub(crate) struct AxisPixels {
    pub m: usize,
    pub t: Range1,
    pub ax: usize,
    pub ay: usize,
    pub xs: Vec<f32>,
    pub ys: Vec<f32>,
}

impl AmrVolume {
    /// The view's [`AxisPixels`]; `None` unless every ray runs down one
    /// axis with the same direction and range along it, and each pixel's
    /// position across it depends on its column or its row only — checked
    /// on every pixel's own ray, to the bit, in one pass on every core
    /// (a 512² view has 262,144 rays; none is kept).
    pub(crate) fn axis_pixels(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Option<AxisPixels> {
        use rayon::prelude::*;
        let (w, h) = (width as usize, height as usize);
        // An orthographic camera's rays from their column and row parts:
        // the bits of `Camera::ray`, without its divisions per pixel.
        let parts = camera.ortho_parts(width, height);
        let ray = |x: usize, y: usize| match &parts {
            Some((across, down)) => Ray::new(across[x] + down[y], camera.forward),
            None => camera.ray(x as f32 + 0.5, y as f32 + 0.5, width, height),
        };
        let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
        let clip = |r: &Ray| self.bounds().clip_ray(r, all);
        let row0: Vec<Ray> = (0..w).map(|x| ray(x, 0)).collect();
        let col0: Vec<Ray> = (0..h).map(|y| ray(0, y)).collect();
        let first = *row0.first()?;
        let m = Line::new(self, &first).axis?;
        let t = (0..h)
            .into_par_iter()
            .find_map_first(|y| (0..w).map(|x| clip(&ray(x, y))).find(|t| !t.is_empty()))?;
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits();
        let (p, q) = ((m + 1) % 3, (m + 2) % 3);
        // Every ray shares direction, start along m and (when it meets the
        // bounds) range; its position along `ax` is its column's, along
        // `ay` its row's.
        let fits = |ax: usize, ay: usize| {
            (0..h).into_par_iter().all(|y| {
                (0..w).all(|x| {
                    let r = ray(x, y);
                    let rt = clip(&r);
                    (0..3).all(|a| same(r.dir[a], first.dir[a]))
                        && same(r.origin[m], first.origin[m])
                        && (rt.is_empty() || (same(rt.lo, t.lo) && same(rt.hi, t.hi)))
                        && same(r.origin[ax], row0[x].origin[ax])
                        && same(r.origin[ay], col0[y].origin[ay])
                })
            })
        };
        let (ax, ay) = if fits(p, q) {
            (p, q)
        } else if fits(q, p) {
            (q, p)
        } else {
            return None;
        };
        let xs: Vec<f32> = row0.iter().map(|r| r.origin[ax]).collect();
        let ys: Vec<f32> = col0.iter().map(|r| r.origin[ay]).collect();
        if !monotone(&xs) || !monotone(&ys) {
            return None;
        }
        Some(AxisPixels {
            m,
            t,
            ax,
            ay,
            xs,
            ys,
        })
    }

    /// The view's [`AxisPixels`] with every pixel's ray (row-major) and its
    /// range inside the bounds.
    pub(crate) fn axis_grid(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Option<(AxisPixels, Vec<Ray>, Vec<Range1>)> {
        use rayon::prelude::*;
        let pixels = self.axis_pixels(camera, width, height)?;
        let w = width as usize;
        let all = Range1::new(f32::NEG_INFINITY, f32::INFINITY);
        let rays: Vec<Ray> = (0..w * height as usize)
            .into_par_iter()
            .map(|i| camera.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5, width, height))
            .collect();
        let ts = rays
            .par_iter()
            .map(|r| self.bounds().clip_ray(r, all))
            .collect();
        Some((pixels, rays, ts))
    }

    /// The basis column densities through every pixel centre of a view
    /// down an axis (see the module docs); `None` for other views.
    pub(crate) fn project_axis_view(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        let (
            AxisPixels {
                m,
                t,
                ax,
                ay,
                xs,
                ys,
            },
            rays,
            ts,
        ) = self.axis_grid(camera, width, height)?;
        let w = width as usize;
        Some(in_bands(height as usize, BAND as usize, control, |rows| {
            self.project_band(
                &rays[rows.start * w..rows.end * w],
                &ts,
                rows.start * w,
                m,
                t,
                (ax, &xs),
                (ay, &ys[rows]),
            )
        }))
    }

    /// The columns of a band of rows: `rays` row-major, `ts[base + i]` the
    /// range of `rays[i]`; pixel positions `xs` along `ax` by column, `ys`
    /// along `ay` by row of the band.
    #[allow(clippy::too_many_arguments)]
    fn project_band(
        &self,
        rays: &[Ray],
        ts: &[Range1],
        base: usize,
        m: usize,
        t: Range1,
        (ax, xs): (usize, &[f32]),
        (ay, ys): (usize, &[f32]),
    ) -> Vec<f32> {
        let w = xs.len();
        let mut sums = vec![0.0f64; rays.len()];
        let lines: Vec<Line> = rays.iter().map(|r| Line::new(self, r)).collect();
        let (ylo, yhi) = ys
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &y| {
                (a.min(y), b.max(y))
            });
        let mut pieces = AxisPieces::default();
        let mut columns = Vec::new();
        // Subtrees holding none of the band's rows are skipped (closed
        // bounds: the half-open decision is the clip's below).
        let keep = |b: &Aabb| b.min[ay] <= yhi && b.max[ay] >= ylo;
        self.region_tree()
            .visit_along(m, rays[0].dir[m] > 0.0, keep, |r| {
                let r = r as usize;
                let rb = self.region_bounds(r);
                let (cols, rows) = (
                    span(xs, rb.min[ax], rb.max[ax]),
                    span(ys, rb.min[ay], rb.max[ay]),
                );
                let mut found = false;
                for y in rows {
                    for x in cols.clone() {
                        let i = y * w + x;
                        let (ray, rt) = (&rays[i], ts[base + i]);
                        // The walk's test: the region's box clipped to the ray.
                        if rt.is_empty() || rb.clip_ray(ray, rt).is_empty() {
                            continue;
                        }
                        if !found {
                            self.axis_pieces(&lines[i], m, t, r, &mut pieces);
                            found = true;
                        }
                        sums[i] +=
                            self.axis_region_integral(ray, &lines[i], r, &pieces, &mut columns);
                    }
                }
            });
        sums.into_iter().map(|s| s as f32).collect()
    }
}

#[cfg(test)]
mod tests {
    //! The whole-image path against one line integral per pixel.
    use crate::tests::{cells_with, smooth, synthetic};
    use crate::{AmrSettings, AmrVolume};
    use voxless_core::{Aabb, Camera, Control, Projection, Vec3, Volume};
    use voxless_render::project_per_pixel;

    #[test]
    fn axis_views_equal_the_per_pixel_projection_to_the_bit() {
        let vols = [(41, true), (42, false)].map(|(seed, holes)| {
            AmrVolume::new(
                cells_with(synthetic(seed, holes), smooth),
                AmrSettings::default(),
            )
            .unwrap()
        });
        let mut checked = 0;
        for vol in &vols {
            let b = vol.bounds();
            // The data are 64 finest cells wide: 32 pixels put the pixel
            // centres in finest cell faces (half-open decisions), 64 on
            // cell centres (kink planes); 50 × 37 anywhere. A sub-box and a
            // box larger than the data frame other positions.
            let inner = Aabb::new(b.min + b.extent() * 0.3, b.max - b.extent() * 0.2);
            let outer = Aabb::new(b.min - b.extent() * 0.1, b.max + b.extent() * 0.05);
            for (frame, w, h) in [
                (b, 32, 32),
                (b, 64, 64),
                (b, 50, 37),
                (inner, 41, 29),
                (outer, 33, 35),
            ] {
                for axis in 0..3 {
                    let down = Camera::axis_projection(&frame, axis).unwrap();
                    // Looking down +axis as well (rays towards −axis above).
                    let mut up = down;
                    up.forward = -up.forward;
                    up.right = -up.right;
                    for cam in [down, up] {
                        let fast = vol
                            .project_image(&cam, w, h, &Control::new())
                            .unwrap()
                            .unwrap();
                        let slow = project_per_pixel(vol, &cam, w, h, &Control::new()).unwrap();
                        assert_eq!(fast.len(), slow.len());
                        for (i, (a, s)) in fast.iter().zip(&slow).enumerate() {
                            assert!(
                                a.to_bits() == s.to_bits(),
                                "axis {axis} pixel {i}: {a} vs {s}"
                            );
                        }
                        assert!(slow.iter().any(|&v| v != 0.0));
                        checked += 1;
                    }
                }
            }
        }
        assert_eq!(checked, 60);
    }

    /// Nearest columns of an on-axis view, from the cells (before any
    /// brick: `fresh`) and from the bricks (`bricked`), against the
    /// per-pixel DDA.
    fn check_nearest(fresh: &AmrVolume, bricked: &AmrVolume, cam: &Camera, w: u32, h: u32) {
        let axis = (0..3).find(|&a| cam.forward[a] != 0.0).unwrap();
        let cells = fresh
            .project_image(cam, w, h, &Control::new())
            .unwrap()
            .unwrap();
        assert!(
            fresh.with_cells(|_| ()).is_some(),
            "the cell path built bricks"
        );
        let bricks = bricked
            .project_image(cam, w, h, &Control::new())
            .unwrap()
            .unwrap();
        let slow = project_per_pixel(bricked, cam, w, h, &Control::new()).unwrap();
        // Centres on a cell face (within rounding) may take either side in
        // the per-pixel DDA: left out.
        let on_face = |i: usize| {
            let r = cam.ray(
                (i % w as usize) as f32 + 0.5,
                (i / w as usize) as f32 + 0.5,
                w,
                h,
            );
            (0..3).filter(|&a| a != axis).any(|a| {
                let u = (r.origin[a] - bricked.origin()[a]) / bricked.cell_size();
                (u - u.round()).abs() < 1e-3
            })
        };
        for fast in [&cells, &bricks] {
            let (mut sf, mut ss, mut n) = (0.0f64, 0.0f64, 0);
            for (i, (a, s)) in fast.iter().zip(&slow).enumerate() {
                if on_face(i) {
                    continue;
                }
                n += 1;
                (sf, ss) = (sf + *a as f64, ss + *s as f64);
                assert!(
                    (a - s).abs() <= 1e-5 * s.abs().max(1.0),
                    "axis {axis} {w}×{h} pixel {i}: {a} vs {s}"
                );
            }
            assert!(n * 2 > fast.len(), "{n} pixels off faces");
            assert!(
                ((sf - ss) / ss).abs() < 1e-6,
                "axis {axis} {w}×{h}: Σ {sf} vs {ss}"
            );
        }
        // Off faces the two fast paths differ in their sums' order only.
        for (i, (a, b)) in cells.iter().zip(&bricks).enumerate() {
            assert!(
                on_face(i) || (a - b).abs() <= 1e-6 * b.abs().max(1e-3),
                "{a} vs {b}"
            );
        }
    }

    fn nearest(cells: &crate::AmrCells) -> AmrVolume {
        let settings = AmrSettings {
            reconstruction: crate::Reconstruction::Nearest,
            ..Default::default()
        };
        AmrVolume::new(cells.clone(), settings).unwrap()
    }

    #[test]
    fn nearest_axis_views_equal_the_per_pixel_chord_sums() {
        let mut checked = 0;
        for (seed, holes) in [(44, true), (45, false)] {
            let cells = cells_with(synthetic(seed, holes), smooth);
            let bricked = nearest(&cells);
            let _ = bricked.bricks();
            let b = bricked.bounds();
            let inner = Aabb::new(b.min + b.extent() * 0.3, b.max - b.extent() * 0.2);
            let outer = Aabb::new(b.min - b.extent() * 0.1, b.max + b.extent() * 0.05);
            for (frame, w, h) in [(b, 47, 52), (b, 50, 37), (inner, 41, 29), (outer, 33, 35)] {
                for axis in 0..3 {
                    let down = Camera::axis_projection(&frame, axis).unwrap();
                    let mut up = down;
                    up.forward = -up.forward;
                    up.right = -up.right;
                    for cam in [down, up] {
                        check_nearest(&nearest(&cells), &bricked, &cam, w, h);
                        checked += 1;
                    }
                }
            }
        }
        assert_eq!(checked, 48);
    }

    /// Finest cells only in two far corners of a coarse domain: their
    /// level's lattice would be far larger than its cells and the image,
    /// so each cell adds its column to its pixels instead.
    #[test]
    fn nearest_columns_of_sparse_levels_add_cell_by_cell() {
        fn split(c: [i32; 4], targets: &[[i32; 3]], out: &mut Vec<[i32; 4]>) {
            let w = 1 << c[3];
            let inside = |t: &[i32; 3]| (0..3).all(|a| t[a] >= c[a] && t[a] < c[a] + w);
            if c[3] == 0 || !targets.iter().any(inside) {
                out.push(c);
                return;
            }
            let h = w / 2;
            for k in 0..8 {
                let d = [k & 1, (k >> 1) & 1, k >> 2].map(|b| b * h);
                split(
                    [c[0] + d[0], c[1] + d[1], c[2] + d[2], c[3] - 1],
                    targets,
                    out,
                );
            }
        }
        let mut cells = Vec::new();
        for k in 0..64 {
            let c = [k % 4, (k / 4) % 4, k / 16].map(|v| v * 32);
            split(
                [c[0], c[1], c[2], 5],
                &[[1, 2, 3], [126, 125, 127]],
                &mut cells,
            );
        }
        let cells = cells_with(cells, smooth);
        let bricked = nearest(&cells);
        let _ = bricked.bricks();
        let b = bricked.bounds();
        for axis in 0..3 {
            let cam = Camera::axis_projection(&b, axis).unwrap();
            check_nearest(&nearest(&cells), &bricked, &cam, 37, 45);
        }
    }

    #[test]
    fn other_views_take_the_per_pixel_path() {
        let vol = AmrVolume::new(
            cells_with(synthetic(43, true), smooth),
            AmrSettings::default(),
        )
        .unwrap();
        let oblique = Camera::framing(&vol.bounds(), 1.0);
        assert!(
            vol.project_image(&oblique, 16, 16, &Control::new())
                .is_none()
        );
        let mut tilted = Camera::axis_projection(&vol.bounds(), 2).unwrap();
        tilted.forward = Vec3::new(0.1, 0.0, -1.0).normalized();
        assert!(matches!(tilted.projection, Projection::Orthographic { .. }));
        assert!(
            vol.project_image(&tilted, 16, 16, &Control::new())
                .is_none()
        );
    }
}
