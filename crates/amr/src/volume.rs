//! [`AmrVolume`]: construction, reconstruction and the `Volume` impl.

use std::time::{Duration, Instant};

use voxless_bvh::Bvh;
use voxless_core::{Aabb, Attribute, Interval, IntervalQuery, Range1, Ray, Sample, Vec3, Volume};

use crate::AmrError;
use crate::bricks::{self, Brick};
use crate::regions::{self, Region, Regions};

/// Cells and fields as read from a file.
#[derive(Clone, Debug, Default)]
pub struct AmrCells {
    /// `(x, y, z, level)`, finest units, level 0 finest.
    pub cells: Vec<[i32; 4]>,
    /// Name and one value per cell.
    pub fields: Vec<(String, Vec<f32>)>,
    /// World position of unit coordinate 0.
    pub origin: Vec3,
    /// World width of a finest cell.
    pub cell_size: f32,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reconstruction {
    /// Tent basis functions, continuous across levels (default).
    #[default]
    Basis,
    /// The value of the containing cell.
    Nearest,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct AmrSettings {
    /// Field driving opacity (index into the fields).
    pub field: usize,
    /// Field driving colour, when different (multi-field rendering).
    pub color_field: Option<usize>,
    pub reconstruction: Reconstruction,
}

/// Counts and timings of the build (the paper's Table 1 columns).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildStats {
    pub cells: usize,
    pub bricks: usize,
    pub regions: usize,
    /// Mean bricks per region, by count and weighted by region volume.
    pub bricks_per_region: f64,
    pub bricks_per_region_by_volume: f64,
    pub validate: Duration,
    pub brick_build: Duration,
    pub region_build: Duration,
    pub bvh_build: Duration,
}

pub struct AmrVolume {
    names: Vec<String>,
    origin: Vec3,
    h: f32,
    settings: AmrSettings,
    bricks: Vec<Brick>,
    /// Per field, values in brick order.
    values: Vec<Vec<f32>>,
    regions: Regions,
    /// World boxes of the regions.
    region_bounds: Vec<Aabb>,
    /// `region_ranges[r * fields + f]`.
    region_ranges: Vec<Range1>,
    /// Finest cell width per region, finest units.
    region_finest: Vec<i32>,
    field_ranges: Vec<Range1>,
    /// All regions, for point location and intervals (a prepared
    /// [`crate::AmrContext`] has its own tree over the visible ones).
    region_bvh: Bvh,
    /// Brick boxes, for nearest-cell lookups and exact projections.
    brick_bvh: Bvh,
    bounds: Aabb,
    stats: BuildStats,
}

/// `⌊x⌋` for |x| < 2³¹ without a libm call (`f32::floor` is one on
/// baseline x86-64, and the reconstruction takes three per brick).
#[inline]
pub(crate) fn floor_i32(x: f32) -> i32 {
    let i = x as i32;
    i - (x < i as f32) as i32
}

/// Reconstructed values at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Recon {
    value: f32,
    color: f32,
    gradient: Vec3,
}

impl AmrVolume {
    /// Validates the cells, builds bricks, regions and BVHs.
    pub fn new(input: AmrCells, settings: AmrSettings) -> Result<AmrVolume, AmrError> {
        let n = input.cells.len();
        if input.fields.is_empty() {
            return Err(AmrError::NoFields);
        }
        for (name, v) in &input.fields {
            if v.len() != n {
                return Err(AmrError::FieldLength {
                    name: name.clone(),
                    expected: n,
                    got: v.len(),
                });
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(AmrError::NonFinite {
                    name: name.clone(),
                    cell: i,
                    value: v[i],
                });
            }
        }
        if !input.origin.is_finite() {
            return Err(AmrError::BadGeometry {
                what: "origin component",
                value: [input.origin.x, input.origin.y, input.origin.z]
                    .into_iter()
                    .find(|v| !v.is_finite())
                    .unwrap_or(f32::NAN),
                extra: "",
            });
        }
        if !(input.cell_size.is_finite() && input.cell_size > 0.0) {
            return Err(AmrError::BadGeometry {
                what: "cell size",
                value: input.cell_size,
                extra: " and > 0",
            });
        }
        let nf = input.fields.len();
        for f in std::iter::once(settings.field).chain(settings.color_field) {
            if f >= nf {
                return Err(AmrError::UnknownField {
                    name: format!("#{f}"),
                    available: input
                        .fields
                        .iter()
                        .map(|f| f.0.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                });
            }
        }
        let mut stats = BuildStats {
            cells: n,
            ..Default::default()
        };
        let t = Instant::now();
        bricks::validate(&input.cells)?;
        stats.validate = t.elapsed();

        let t = Instant::now();
        let (names, fields): (Vec<String>, Vec<Vec<f32>>) = input.fields.into_iter().unzip();
        let (bricks, values) = bricks::build(&input.cells, &fields);
        drop(fields);
        stats.brick_build = t.elapsed();

        let t = Instant::now();
        let regions = regions::build(&bricks);
        let (region_ranges, region_finest) = regions::metadata(&regions, &bricks, &values);
        stats.region_build = t.elapsed();

        let (origin, h) = (input.origin, input.cell_size);
        let to_world = |lo: [f64; 3], hi: [f64; 3]| {
            Aabb::new(
                origin + Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32) * h,
                origin + Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32) * h,
            )
        };
        let region_bounds: Vec<Aabb> = regions
            .regions
            .iter()
            .map(|r| to_world(r.lo.map(|v| v as f64 * 0.5), r.hi.map(|v| v as f64 * 0.5)))
            .collect();
        let brick_bounds: Vec<Aabb> = bricks
            .iter()
            .map(|b| to_world(b.lower.map(|v| v as f64), b.upper().map(|v| v as f64)))
            .collect();
        let field_ranges = values
            .iter()
            .map(|v| {
                v.iter().fold(Range1::EMPTY, |mut r, &x| {
                    r.extend(x);
                    r
                })
            })
            .collect();
        stats.bricks = bricks.len();
        stats.regions = regions.regions.len();
        let total = regions.brick_ids.len();
        stats.bricks_per_region = total as f64 / stats.regions.max(1) as f64;
        let vol = |r: &Region| (0..3).map(|a| (r.hi[a] - r.lo[a]) as f64).product::<f64>();
        let vsum: f64 = regions.regions.iter().map(vol).sum();
        stats.bricks_per_region_by_volume = regions
            .regions
            .iter()
            .map(|r| vol(r) * r.bricks.len() as f64)
            .sum::<f64>()
            / vsum.max(1.0);

        let t = Instant::now();
        // Regions come out of the k-d subdivision depth first: already coherent.
        let region_bvh = Bvh::build_in_order(&region_bounds);
        let brick_bvh = Bvh::build(&brick_bounds);
        stats.bvh_build = t.elapsed();
        // The data's domain is the cells, not the tents' half-cell margin
        // around them: bounds, intervals and samples stop at the cells.
        let bounds = brick_bounds.iter().fold(Aabb::EMPTY, |b, &x| b.union(x));
        Ok(AmrVolume {
            names,
            origin,
            h,
            settings,
            bricks,
            values,
            regions,
            region_bounds,
            region_ranges,
            region_finest,
            field_ranges,
            region_bvh,
            brick_bvh,
            bounds,
            stats,
        })
    }

    pub fn stats(&self) -> &BuildStats {
        &self.stats
    }
    pub fn field_names(&self) -> &[String] {
        &self.names
    }
    pub fn bricks(&self) -> &[Brick] {
        &self.bricks
    }
    pub fn regions(&self) -> &[Region] {
        &self.regions.regions
    }
    /// The bricks active in region `r`.
    pub fn region_bricks(&self, r: usize) -> &[u32] {
        self.regions.bricks_of(r)
    }
    pub fn settings(&self) -> &AmrSettings {
        &self.settings
    }
    /// World box of region `r`.
    pub fn region_bounds(&self, r: usize) -> Aabb {
        self.region_bounds[r]
    }
    /// Value range of `field` in region `r`.
    pub fn region_range(&self, r: usize, field: usize) -> Range1 {
        self.region_ranges[r * self.values.len() + field]
    }
    /// Range of `field` over all cells.
    pub fn field_range(&self, field: usize) -> Range1 {
        self.field_ranges[field]
    }

    /// The intervals of the regions `bvh` holds (region `remap[i]` for leaf
    /// `i`, or `i` itself), in increasing `t`.
    pub(crate) fn region_intervals(
        &self,
        bvh: &Bvh,
        remap: Option<&[u32]>,
        ray: &Ray,
        t: Range1,
        query: &IntervalQuery,
        out: &mut Vec<Interval>,
    ) {
        let start = out.len();
        let nf = self.values.len();
        let t = self.bounds.clip_ray(ray, t);
        if t.is_empty() {
            return;
        }
        bvh.ray_query(ray, t, |i, hit| {
            let r = remap.map_or(i as usize, |m| m[i as usize] as usize);
            let range = self.region_ranges[r * nf + self.settings.field];
            if hit.hi > hit.lo && (query.is_visible)(range) {
                out.push(Interval {
                    hint: r as u32,
                    ..Interval::sampled(hit, range, 0.5 * self.region_finest[r] as f32 * self.h)
                });
            }
        });
        out[start..].sort_unstable_by(|a, b| a.t.lo.total_cmp(&b.t.lo));
    }

    /// The regions whose range of the opacity field `is_visible` accepts.
    pub(crate) fn visible_regions(&self, is_visible: &dyn Fn(Range1) -> bool) -> Vec<u32> {
        let nf = self.values.len();
        let f = self.settings.field;
        (0..self.regions.regions.len() as u32)
            .filter(|&r| is_visible(self.region_ranges[r as usize * nf + f]))
            .collect()
    }

    /// How many regions a transfer function accepting `is_visible` sees.
    pub fn visible_region_count(&self, is_visible: &dyn Fn(Range1) -> bool) -> usize {
        self.visible_regions(is_visible).len()
    }

    pub(crate) fn region_bvh(&self) -> &Bvh {
        &self.region_bvh
    }

    /// World position of unit coordinate 0.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }
    /// World width of a finest cell.
    pub fn cell_size(&self) -> f32 {
        self.h
    }

    /// Values of `field`, in brick order.
    pub(crate) fn field_values(&self, field: usize) -> &[f32] {
        &self.values[field]
    }

    fn to_units(&self, p: Vec3) -> Vec3 {
        (p - self.origin) * (1.0 / self.h)
    }

    /// The region containing `p` (world), if any.
    pub fn locate(&self, p: Vec3) -> Option<usize> {
        if !self.bounds.contains(p) {
            return None;
        }
        let mut found = None;
        self.region_bvh.point_query(p, |i| {
            if found.is_none() {
                found = Some(i as usize);
            }
        });
        found
    }

    /// Basis (or nearest) values of `field` and the colour field at `p`
    /// (world) using only region `region`'s bricks.
    fn reconstruct(&self, p: Vec3, region: usize, field: usize, gradient: bool) -> Option<Recon> {
        let pu = self.to_units(p);
        let color_field = self.settings.color_field.unwrap_or(field);
        if self.settings.reconstruction == Reconstruction::Nearest {
            return self.nearest(pu, region, field, color_field);
        }
        let (v0, v1) = (&self.values[field], &self.values[color_field]);
        // Without a separate colour field its sum is the value's: skip it.
        let two_fields = color_field != field;
        let (mut sw, mut sv, mut sc) = (0.0f64, 0.0f64, 0.0f64);
        let (mut sdw, mut sdv) = ([0.0f64; 3], [0.0f64; 3]);
        for &b in self.regions.bricks_of(region) {
            let b = &self.bricks[b as usize];
            let w = b.width() as f32;
            // Per axis: the two cells whose centres are within one width of
            // p, their tent weights, and the weights' derivatives along p.
            let mut idx = [[0i32; 2]; 3];
            let mut wt = [[0.0f32; 2]; 3];
            let mut dwt = [[0.0f32; 2]; 3];
            let mut empty = false;
            for a in 0..3 {
                let t = (pu[a] - b.lower[a] as f32) / w - 0.5;
                let i0 = floor_i32(t);
                let f = t - i0 as f32;
                for (k, (i, weight, dw)) in [(i0, 1.0 - f, -1.0 / w), (i0 + 1, f, 1.0 / w)]
                    .into_iter()
                    .enumerate()
                {
                    let inside = i >= 0 && i < b.size[a];
                    idx[a][k] = i;
                    wt[a][k] = if inside { weight } else { 0.0 };
                    dwt[a][k] = if inside { dw } else { 0.0 };
                }
                if wt[a][0] <= 0.0
                    && wt[a][1] <= 0.0
                    && (!gradient || (dwt[a][0] == 0.0 && dwt[a][1] == 0.0))
                {
                    empty = true;
                    break;
                }
            }
            if empty {
                continue;
            }
            for kz in 0..2 {
                for ky in 0..2 {
                    for kx in 0..2 {
                        let h = wt[0][kx] * wt[1][ky] * wt[2][kz];
                        let inside = (0..3).all(|a| {
                            let i = idx[a][[kx, ky, kz][a]];
                            i >= 0 && i < b.size[a]
                        });
                        if !inside || (h <= 0.0 && !gradient) {
                            continue;
                        }
                        let local = (idx[2][kz] * b.size[1] + idx[1][ky]) * b.size[0] + idx[0][kx];
                        let cell = b.offset as usize + local as usize;
                        let v = v0[cell] as f64;
                        sw += h as f64;
                        sv += h as f64 * v;
                        if two_fields {
                            sc += h as f64 * v1[cell] as f64;
                        }
                        if gradient {
                            let d = [
                                dwt[0][kx] * wt[1][ky] * wt[2][kz],
                                wt[0][kx] * dwt[1][ky] * wt[2][kz],
                                wt[0][kx] * wt[1][ky] * dwt[2][kz],
                            ];
                            for a in 0..3 {
                                sdw[a] += d[a] as f64;
                                sdv[a] += d[a] as f64 * v;
                            }
                        }
                    }
                }
            }
        }
        if sw <= 0.0 {
            return None;
        }
        let value = sv / sw;
        let mut g = Vec3::ZERO;
        if gradient {
            // Quotient rule; divide by h to go from unit to world coordinates.
            let q = |a: usize| ((sw * sdv[a] - sv * sdw[a]) / (sw * sw) / self.h as f64) as f32;
            g = Vec3::new(q(0), q(1), q(2));
        }
        Some(Recon {
            value: value as f32,
            color: if two_fields {
                (sc / sw) as f32
            } else {
                value as f32
            },
            gradient: g,
        })
    }

    fn nearest(&self, pu: Vec3, region: usize, field: usize, color_field: usize) -> Option<Recon> {
        for &b in self.regions.bricks_of(region) {
            if let Some(cell) = self.cell_in_brick(pu, b as usize) {
                return Some(Recon {
                    value: self.values[field][cell],
                    color: self.values[color_field][cell],
                    gradient: Vec3::ZERO,
                });
            }
        }
        None
    }

    /// Index (into the brick-ordered values) of the cell of brick `b`
    /// containing unit-space point `pu`.
    fn cell_in_brick(&self, pu: Vec3, b: usize) -> Option<usize> {
        let b = &self.bricks[b];
        let w = b.width() as f32;
        let mut i = [0i32; 3];
        for a in 0..3 {
            let x = ((pu[a] - b.lower[a] as f32) / w).floor();
            if !(x >= 0.0 && x < b.size[a] as f32) {
                return None;
            }
            i[a] = x as i32;
        }
        Some(b.offset as usize + ((i[2] * b.size[1] + i[1]) * b.size[0] + i[0]) as usize)
    }

    /// All fields at `p` (world): values, and gradients when asked, using the
    /// volume's reconstruction. `None` outside the data.
    pub fn fields_at(&self, p: Vec3, gradient: bool) -> Option<Vec<(f32, Vec3)>> {
        let r = self.locate(p)?;
        (0..self.values.len())
            .map(|f| {
                self.reconstruct(p, r, f, gradient)
                    .map(|x| (x.value, x.gradient))
            })
            .collect()
    }

    fn to_sample(&self, r: Recon) -> Sample {
        Sample {
            value: r.value,
            attribute: match self.settings.color_field {
                Some(_) => Attribute::Scalar(r.color),
                None => Attribute::None,
            },
        }
    }

    /// Exact `∫ value dt` with nearest reconstruction: every cell's value times
    /// the length of the ray inside it (3D DDA through each brick the ray hits).
    fn nearest_line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        let field = &self.values[self.settings.field];
        let mut sum = 0.0f64;
        self.brick_bvh.ray_query(ray, t, |bi, hit| {
            let b = &self.bricks[bi as usize];
            let w = b.width() as f64 * self.h as f64;
            let lower =
                [0, 1, 2].map(|a| self.origin[a] as f64 + b.lower[a] as f64 * self.h as f64);
            let o = [0, 1, 2].map(|a| ray.origin[a] as f64);
            let d = [0, 1, 2].map(|a| ray.dir[a] as f64);
            let (t0, t1) = (hit.lo as f64, hit.hi as f64);
            // Start cell at the midpoint-nudged entry, then step cell faces.
            let entry = t0 + (t1 - t0) * 1e-9;
            let mut i = [0i32; 3];
            let mut t_next = [f64::INFINITY; 3];
            let mut t_delta = [f64::INFINITY; 3];
            let mut step = [0i32; 3];
            for a in 0..3 {
                let x = (o[a] + d[a] * entry - lower[a]) / w;
                i[a] = (x.floor() as i32).clamp(0, b.size[a] - 1);
                if d[a] > 0.0 {
                    step[a] = 1;
                    t_next[a] = (lower[a] + (i[a] + 1) as f64 * w - o[a]) / d[a];
                    t_delta[a] = w / d[a];
                } else if d[a] < 0.0 {
                    step[a] = -1;
                    t_next[a] = (lower[a] + i[a] as f64 * w - o[a]) / d[a];
                    t_delta[a] = -w / d[a];
                }
            }
            let mut t_cur = t0;
            loop {
                let a = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                    0
                } else if t_next[1] <= t_next[2] {
                    1
                } else {
                    2
                };
                let t_exit = t_next[a].min(t1);
                let cell =
                    b.offset as usize + ((i[2] * b.size[1] + i[1]) * b.size[0] + i[0]) as usize;
                sum += field[cell] as f64 * (t_exit - t_cur).max(0.0);
                t_cur = t_exit;
                if t_exit >= t1 {
                    break;
                }
                i[a] += step[a];
                if i[a] < 0 || i[a] >= b.size[a] {
                    break;
                }
                t_next[a] += t_delta[a];
            }
        });
        sum
    }
}

impl Volume for AmrVolume {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn value_range(&self) -> Range1 {
        self.field_ranges[self.settings.field]
    }

    fn attribute_range(&self) -> Option<Range1> {
        self.settings.color_field.map(|f| self.field_ranges[f])
    }

    fn sample(&self, p: Vec3) -> Option<Sample> {
        let r = self.locate(p)?;
        self.reconstruct(p, r, self.settings.field, false)
            .map(|x| self.to_sample(x))
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        self.sample_with_gradient(p).map_or(Vec3::ZERO, |s| s.1)
    }

    fn sample_with_gradient(&self, p: Vec3) -> Option<(Sample, Vec3)> {
        let r = self.locate(p)?;
        self.reconstruct(p, r, self.settings.field, true)
            .map(|x| (self.to_sample(x), x.gradient))
    }

    fn sample_in(&self, p: Vec3, iv: &Interval) -> Option<Sample> {
        self.reconstruct(p, iv.hint as usize, self.settings.field, false)
            .map(|x| self.to_sample(x))
    }

    fn sample_with_gradient_in(&self, p: Vec3, iv: &Interval) -> Option<(Sample, Vec3)> {
        self.reconstruct(p, iv.hint as usize, self.settings.field, true)
            .map(|x| (self.to_sample(x), x.gradient))
    }

    /// One interval per visible region the ray crosses, in order; the step is
    /// half the region's finest cell width (two samples per finest cell at
    /// sampling rate 1: adaptive sampling, ExaBricks §4.2). Every region is
    /// traversed here; a prepared [`crate::AmrContext`] traverses only the
    /// visible ones.
    fn intervals(&self, ray: &Ray, t: Range1, query: &IntervalQuery, out: &mut Vec<Interval>) {
        self.region_intervals(&self.region_bvh, None, ray, t, query, out);
    }

    fn line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        match self.settings.reconstruction {
            Reconstruction::Nearest => self.nearest_line_integral(ray, t),
            Reconstruction::Basis => self.basis_line_integral(ray, t),
        }
    }
}

/// The reconstruction that the regions replace: cell location through a BVH
/// over every cell's support, then the same basis sum (Wald et al.'s method).
/// The baseline for benchmarks and a cross-check in tests.
pub struct CellLocator {
    cells: Vec<[i32; 4]>,
    values: Vec<f32>,
    bvh: Bvh,
    origin: Vec3,
    h: f32,
}

impl CellLocator {
    pub fn new(cells: &AmrCells, field: usize) -> CellLocator {
        let (o, h) = (cells.origin, cells.cell_size);
        let boxes: Vec<Aabb> = cells
            .cells
            .iter()
            .map(|c| {
                let w = (1i64 << c[3]) as f32;
                let lo = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) - Vec3::splat(0.5 * w);
                Aabb::new(o + lo * h, o + (lo + Vec3::splat(2.0 * w)) * h)
            })
            .collect();
        CellLocator {
            cells: cells.cells.clone(),
            values: cells.fields[field].1.clone(),
            bvh: Bvh::build(&boxes),
            origin: o,
            h,
        }
    }

    /// Basis-reconstructed value at `p` (world), `None` where no tent reaches.
    pub fn sample(&self, p: Vec3) -> Option<f32> {
        let pu = (p - self.origin) * (1.0 / self.h);
        let (mut sw, mut sv) = (0.0f64, 0.0f64);
        self.bvh.point_query(p, |i| {
            let c = self.cells[i as usize];
            let w = (1i64 << c[3]) as f32;
            let mut h = 1.0f32;
            for a in 0..3 {
                let centre = c[a] as f32 + 0.5 * w;
                h *= (1.0 - (centre - pu[a]).abs() / w).max(0.0);
            }
            sw += h as f64;
            sv += h as f64 * self.values[i as usize] as f64;
        });
        (sw > 0.0).then(|| (sv / sw) as f32)
    }
}

impl AmrVolume {
    /// `∫ value dV` of the opacity field when it is known exactly: with
    /// nearest reconstruction, Σ value × cell volume (what a projection over
    /// the full bounds must conserve). `None` for basis reconstruction.
    pub fn exact_integral(&self) -> Option<f64> {
        if self.settings.reconstruction != Reconstruction::Nearest {
            return None;
        }
        let field = &self.values[self.settings.field];
        let h3 = (self.h as f64).powi(3);
        Some(
            self.bricks
                .iter()
                .map(|b| {
                    let w3 = (b.width() as f64).powi(3) * h3;
                    let start = b.offset as usize;
                    field[start..start + b.cell_count()]
                        .iter()
                        .map(|&v| v as f64)
                        .sum::<f64>()
                        * w3
                })
                .sum(),
        )
    }
}
