//! Periodic boxes: a particle volume whose field repeats with the box.
//!
//! The periodic field is `Φ(x) = Σᵢ Σₙ φᵢ(x − n·L)` over every lattice
//! shift `n ∈ ℤ³`. Inside the box only the images whose support reaches the
//! box contribute, so the volume holds, beside each particle (wrapped into
//! the box), a *ghost* for each such image: the same radius, weight and
//! attribute, shifted by `n·L`. Every query then works unchanged —
//! points are wrapped into the box first — and the box is the volume's
//! bounds, so renders and per-pixel projections integrate the field over
//! the part of each ray inside the box: the line of sight crosses the box
//! once, and every particle's mass is counted once in `∫_box Φ dV`.
//!
//! Ghosts carry [`GHOST`] in their original index (so probes, radii in
//! file order and the total mass see each particle once). Projections by
//! splatting leave them out and make the images themselves
//! ([`crate::splat`]).
//!
//! Slabs deeper than the box (`--depth` through the tiled medium) walk each
//! ray through the lattice cells it crosses, integrating each piece in the
//! box with the ray shifted back by that cell's offset.

use rayon::prelude::*;
use voxless_core::{Aabb, Range1, Ray, Vec3};

use super::{ParticleData, ParticleSettings, ParticleVolume, part::map_factor};
use crate::error::ParticleError;

/// Marks a ghost's original index (particle indices are below 2³¹).
pub(crate) const GHOST: u32 = 1 << 31;

/// Image shifts beyond this many boxes are refused (supports that wide
/// cover the box many times over).
const MAX_SHIFT: i32 = 3;

/// A periodic volume reaches at most this many boxes deep in one slab.
pub const MAX_PERIODS: f64 = 1000.0;

/// `p` moved into `[lo, hi)` of `b` along every axis.
///
/// Built from three scalars, not written axis by axis into a copy of `p`:
/// a copy assembled from three 4-byte stores and read back as one 8-byte
/// load stalls store forwarding (~80 % of the streamed projection's loop
/// that builds its splat particles).
#[inline]
pub fn wrap(b: &Aabb, p: Vec3) -> Vec3 {
    #[inline(always)]
    fn axis(v: f32, lo: f32, hi: f32) -> f32 {
        if v >= lo && v < hi {
            return v;
        }
        let w = lo + (v - lo).rem_euclid(hi - lo);
        if w >= hi || w < lo { lo } else { w }
    }
    Vec3::new(
        axis(p.x, b.min.x, b.max.x),
        axis(p.y, b.min.y, b.max.y),
        axis(p.z, b.min.z, b.max.z),
    )
}

/// Particles wrapped into `b` with their ghosts appended: the extended
/// arrays, each row's original index (with [`GHOST`] for ghosts), and how
/// many particles had to be wrapped.
pub(super) struct Images {
    pub data: ParticleData,
    pub source: Vec<u32>,
    pub wrapped: usize,
}

/// A block's count of particles moved into the box, and its ghosts (the
/// particle's index and the ghost's centre), in particle order.
type Block = (usize, Vec<(u32, Vec3)>);

/// The ghosts of `data` in the periodic box `b` (every image whose support
/// box overlaps `b`); `range` normalises the attribute for the radius map.
pub(super) fn with_images(
    mut data: ParticleData,
    b: &Aabb,
    settings: &ParticleSettings,
    range: voxless_core::Range1,
) -> Result<Images, ParticleError> {
    let n = data.positions.len();
    // Every particle on its own: on every core, in blocks whose ghosts
    // are joined in particle order (the order a serial loop gives them);
    // each particle wrapped into the box as its block reaches it (one pass
    // over the positions, not one to wrap and one to find the images).
    let factor = settings.kernel.support_factor();
    let mut source: Vec<u32> = (0..n as u32).collect();
    const BLOCK: usize = 1 << 16;
    let (radii, attribute) = (data.radii.as_deref(), data.attribute.as_deref());
    let blocks: Vec<Result<Block, ParticleError>> = data
        .positions
        .par_chunks_mut(BLOCK)
        .enumerate()
        .map(|(blk, chunk)| {
            let (mut moved, mut extra, mut found) = (0, Vec::new(), Vec::new());
            for (k, p) in chunk.iter_mut().enumerate() {
                let i = blk * BLOCK + k;
                let q = wrap(b, *p);
                moved += (q != *p) as usize;
                *p = q;
                let base = radii.map_or(settings.radius, |r| r[i]);
                let attr = attribute.map(|a| a[i]);
                let r = base * map_factor(&settings.radius_map, attr, range);
                images(Some(b), q, factor * r, i, &mut found)?;
                for &(shift, ghost) in &found {
                    if shift != [0; 3] {
                        extra.push((i as u32, ghost));
                    }
                }
            }
            Ok((moved, extra))
        })
        .collect();
    // The first refusal in particle order, as a serial loop would give.
    let (mut extra, mut wrapped) = (Vec::new(), 0);
    for block in blocks {
        let (moved, mut ghosts) = block?;
        wrapped += moved;
        extra.append(&mut ghosts);
    }
    // Exactly the room the ghosts need (pushing one by one would double
    // the arrays' capacity: 12 bytes a particle of positions alone).
    data.positions.reserve_exact(extra.len());
    for v in [&mut data.radii, &mut data.weights, &mut data.attribute]
        .into_iter()
        .flatten()
    {
        v.reserve_exact(extra.len());
    }
    source.reserve_exact(extra.len());
    for (i, q) in extra {
        let i = i as usize;
        data.positions.push(q);
        for v in [&mut data.radii, &mut data.weights, &mut data.attribute]
            .into_iter()
            .flatten()
        {
            v.push(v[i]);
        }
        source.push(i as u32 | GHOST);
    }
    Ok(Images {
        data,
        source,
        wrapped,
    })
}

/// The images of particle `index` at `c` (in the periodic box `b`; none:
/// just the particle) with support radius `support` whose support box
/// meets `b`, the particle itself (shift 0) included, into `out`
/// (cleared): each image's shift in boxes and centre. A hidden particle
/// (support ≤ 0) in a box has none. Refused when the images would reach
/// beyond [`MAX_SHIFT`] boxes.
#[inline(always)]
pub fn images(
    b: Option<&Aabb>,
    c: Vec3,
    support: f32,
    index: usize,
    out: &mut Vec<([i8; 3], Vec3)>,
) -> Result<(), ParticleError> {
    out.clear();
    let Some(b) = b else {
        out.push(([0; 3], c));
        return Ok(());
    };
    if !(support > 0.0) {
        return Ok(());
    }
    if only_image(b, c, support) {
        // (+ 0 as the loop below adds it: a −0 coordinate becomes +0.)
        out.push(([0; 3], c + Vec3::splat(0.0)));
        return Ok(());
    }
    images_near_faces(b, c, support, index, out)
}

/// How far inside (−1, 1) [`only_image`]'s quotients must lie.
pub const INSIDE: f32 = 1.0 - 1.0 / (1 << 20) as f32;

/// Whether the particle at `c` with support radius `s > 0` is its own only
/// image in the box `b` (its support reaches no face; [`images`] then
/// gives `c + 0`). No branch, so that a batch of particles takes it in
/// lanes.
#[inline(always)]
pub fn only_image(b: &Aabb, c: Vec3, s: f32) -> bool {
    // Shifts k along each axis with [c + kL − s, c + kL + s] ∩ [lo, hi] ≠ ∅:
    // from ⌈(lo − c − s)/L⌉ to ⌊(hi − c + s)/L⌋. Most particles reach no
    // face: both quotients lie in (−1, 1) on every axis, so the particle
    // is its only image. Tested without the divisions (six were 8 % of a
    // 16.7M-particle projection) and a hair inside (−1, 1), so that a
    // quotient this passes is in (−1, 1) however it rounds; the few it
    // leaves take the divisions of `images_near_faces`.
    let size = b.extent();
    let axis = |a: usize| {
        (b.min[a] - c[a] - s > -INSIDE * size[a]) & (b.max[a] - c[a] + s < INSIDE * size[a])
    };
    axis(0) & axis(1) & axis(2)
}

/// [`images`] of a particle whose support may reach a face of `b` (kept
/// out of line: the common case above is inlined into the splatter's
/// loop).
#[inline(never)]
fn images_near_faces(
    b: &Aabb,
    c: Vec3,
    s: f32,
    index: usize,
    out: &mut Vec<([i8; 3], Vec3)>,
) -> Result<(), ParticleError> {
    let size = b.extent();
    let mut span = [(0i32, 0i32); 3];
    for a in 0..3 {
        let lo = ((b.min[a] - c[a] - s) / size[a]).ceil() as i32;
        let hi = ((b.max[a] - c[a] + s) / size[a]).floor() as i32;
        if lo < -MAX_SHIFT || hi > MAX_SHIFT {
            return Err(ParticleError::SupportBeyondBox {
                index,
                support: s,
                size: size[a],
            });
        }
        span[a] = (lo.min(0), hi.max(0));
    }
    for kx in span[0].0..=span[0].1 {
        for ky in span[1].0..=span[1].1 {
            for kz in span[2].0..=span[2].1 {
                let q = Vec3::new(
                    c.x + kx as f32 * size.x,
                    c.y + ky as f32 * size.y,
                    c.z + kz as f32 * size.z,
                );
                // Only images whose support box meets the box.
                if (kx, ky, kz) == (0, 0, 0)
                    || (0..3).all(|a| q[a] - s <= b.max[a] && q[a] + s >= b.min[a])
                {
                    out.push(([kx as i8, ky as i8, kz as i8], q));
                }
            }
        }
    }
    Ok(())
}

impl ParticleVolume {
    /// The periodic box, when the volume has one.
    pub fn periodic(&self) -> Option<Aabb> {
        self.settings.periodic
    }

    /// `p` wrapped into the periodic box (unchanged without one).
    #[inline]
    pub(super) fn wrap_point(&self, p: Vec3) -> Vec3 {
        match &self.settings.periodic {
            Some(b) => wrap(b, p),
            None => p,
        }
    }

    /// Whether entry `i` (volume order) is a ghost.
    #[inline]
    pub(super) fn is_ghost(&self, i: usize) -> bool {
        self.original_index[i] & GHOST != 0
    }

    /// How many particles lay outside the periodic box and were wrapped
    /// into it when the volume was built.
    pub fn wrapped(&self) -> usize {
        self.wrapped
    }

    /// Number of particles (ghosts of a periodic box not counted).
    pub fn particle_count(&self) -> usize {
        self.len() - self.ghosts
    }

    /// The particles without their ghosts, in input order, with the input
    /// radii (if any) and weights before the maps: what to rebuild from.
    pub(super) fn originals(&self) -> ParticleData {
        let mut idx: Vec<usize> = (0..self.len()).filter(|&i| !self.is_ghost(i)).collect();
        idx.sort_unstable_by_key(|&i| self.original_index[i]);
        let take =
            |v: &[f32]| (!v.is_empty()).then(|| idx.iter().map(|&i| v[i]).collect::<Vec<f32>>());
        ParticleData {
            positions: idx.iter().map(|&i| self.packed[i].center).collect(),
            radii: take(&self.base_radius),
            weights: take(&self.base_weight),
            attribute: self.attribute.as_deref().and_then(take),
        }
    }

    /// Effective radii in input order (ghosts left out): the smoothing
    /// lengths the volume renders with.
    pub fn radii_in_input_order(&self) -> Vec<f32> {
        let mut out = vec![0.0f32; self.particle_count()];
        for (i, &o) in self.original_index.iter().enumerate() {
            if o & GHOST == 0 {
                out[o as usize] = self.radius[i];
            }
        }
        out
    }

    /// `∫ Φ dt` along `ray` over `t` through the tiled periodic medium: the
    /// ray is cut where it crosses a cell of the lattice, and each piece is
    /// integrated in the box by the ray shifted back by its cell's offset.
    /// Without a box, the plain line integral.
    pub fn periodic_line_integral(&self, ray: &Ray, t: Range1) -> f64 {
        use voxless_core::Volume;
        let Some(b) = self.settings.periodic else {
            return self.line_integral(ray, self.bounds().clip_ray(ray, t));
        };
        if t.is_empty() || !t.lo.is_finite() || !t.hi.is_finite() {
            return 0.0;
        }
        let size = b.extent();
        // Every parameter where the ray crosses a lattice plane inside t.
        let mut cuts = vec![t.lo as f64, t.hi as f64];
        for a in 0..3 {
            let d = ray.dir[a] as f64;
            if d == 0.0 {
                continue;
            }
            let (o, lo, l) = (ray.origin[a] as f64, b.min[a] as f64, size[a] as f64);
            let x0 = o + d * t.lo as f64;
            let x1 = o + d * t.hi as f64;
            let (k0, k1) = (
                ((x0.min(x1) - lo) / l).ceil() as i64,
                ((x0.max(x1) - lo) / l).floor() as i64,
            );
            for k in k0..=k1 {
                cuts.push((lo + k as f64 * l - o) / d);
            }
        }
        cuts.sort_unstable_by(f64::total_cmp);
        let mut sum = 0.0;
        for w in cuts.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            if t1 <= t0 {
                continue;
            }
            let mid = 0.5 * (t0 + t1);
            // The lattice cell of the piece, and the ray moved back into the box.
            let shift: Vec3 = Vec3::new(
                (((ray.origin.x as f64 + ray.dir.x as f64 * mid) - b.min.x as f64) / size.x as f64)
                    .floor() as f32
                    * size.x,
                (((ray.origin.y as f64 + ray.dir.y as f64 * mid) - b.min.y as f64) / size.y as f64)
                    .floor() as f32
                    * size.y,
                (((ray.origin.z as f64 + ray.dir.z as f64 * mid) - b.min.z as f64) / size.z as f64)
                    .floor() as f32
                    * size.z,
            );
            let moved = Ray::new(ray.origin - shift, ray.dir);
            sum += self.line_integral(&moved, Range1::new(t0 as f32, t1 as f32));
        }
        sum
    }
}
