//! Placing particles: each particle's periodic images as splats (their
//! centres, rows and columns in pixels), one at a time or, where
//! particles share a radius, eight at a time in lanes (see the module
//! docs of `splat.rs`).

use voxless_core::simd::{Lanes, WithLanes};
use voxless_core::{Aabb, Vec3};

use super::pixels::SubCells;
use super::{Lean, Periodic, Piece, Splat, SplatParticle};
use crate::ParticleError;
use crate::kernel::Kernel;
use crate::kernel::area::table_pixels;
use crate::volume::{images, only_image};

/// What placing a particle needs of its splatter.
#[derive(Clone, Copy)]
pub(super) struct Placer {
    pub(super) size: (u32, u32),
    /// A pixel's width and height in the image plane.
    pub(super) pixel: (f64, f64),
    pub(super) kernel: Kernel,
    /// The kernel's support over its radius.
    pub(super) factor: f32,
    pub(super) mode: Periodic,
    /// The mode's periodic box.
    pub(super) periodic: Option<Aabb>,
    pub(super) half: (f64, f64),
    /// Pixels per unit of the image plane along right and up (`W/2hw`,
    /// `H/2hh`: the reciprocals of `pixel`), so that a particle takes
    /// products, not divisions (four were 5 % of a 16.7M-particle
    /// projection).
    pub(super) to_pixels: (f64, f64),
    /// Pixel areas asked for.
    pub(super) area: bool,
    /// SPH splats summed on the CPU's lanes are kept as [`Lean`] splats.
    pub(super) lean: bool,
    /// The CPU has AVX-512F (batches placed on its lanes).
    pub(super) wide: bool,
    /// The camera's eye, right, up and forward in f64.
    pub(super) basis: [[f64; 3]; 4],
}

/// [`Placer::place`] for each particle of `part`, the first being particle
/// `first` of the whole set (run through `dispatch` for its compilation).
pub(super) struct PlaceAll<'a> {
    pub(super) placer: &'a Placer,
    pub(super) part: &'a [SplatParticle],
    pub(super) first: usize,
    pub(super) piece: &'a mut Piece,
}

impl WithLanes for PlaceAll<'_> {
    type Output = Result<(), ParticleError>;
    #[inline(always)]
    fn run<L: Lanes>(self) -> Self::Output {
        // Batches of lean splats in lanes where nothing needs the general
        // path (pixel areas, images clipped off axis, a device).
        let batched = self.placer.lean
            && !self.placer.area
            && !matches!(self.placer.mode, Periodic::OffAxis(_));
        let mut done = 0;
        if batched {
            for batch in self.part.chunks_exact(BATCH) {
                self.placer.place_batch(
                    batch.try_into().expect("a batch"),
                    self.first + done,
                    self.piece,
                )?;
                done += BATCH;
            }
        }
        for (i, p) in self.part[done..].iter().enumerate() {
            self.placer.place(p, self.first + done + i, self.piece)?;
        }
        Ok(())
    }
}

/// Particles placed together by [`Placer::place_batch`].
pub(super) const BATCH: usize = 8;

/// What [`Placer::place_batch`]'s lanes give for each particle `k` (bit
/// `k` of the masks): whether it is its own only image, whether its splat
/// is kept (seen, with pixels), its centre and its rows and columns.
#[derive(Default)]
pub(super) struct BatchLanes {
    pub(super) only: u8,
    pub(super) keep: u8,
    pub(super) cx: [f64; BATCH],
    pub(super) cy: [f64; BATCH],
    pub(super) row0: [u32; BATCH],
    pub(super) row1: [u32; BATCH],
    pub(super) col0: [u32; BATCH],
    pub(super) col1: [u32; BATCH],
}

impl Placer {
    /// [`Placer::place`] of `batch` (the first being particle `first`),
    /// the same lean splats in the same order with the same bits, computed
    /// lane by lane without branches where the particles share a radius
    /// and each is its own only image (the usual case): one pass of
    /// arithmetic in lanes (`splat_wide::place_lanes` on AVX-512, else
    /// [`Placer::lanes`], which the compiler vectorises), then the pushes.
    /// Anything else takes `place`. Only where `place` would keep every splat lean (no
    /// pixel areas, no device, not clipped off axis).
    #[inline(always)]
    pub(super) fn place_batch(
        &self,
        batch: &[SplatParticle; BATCH],
        first: usize,
        piece: &mut Piece,
    ) -> Result<(), ParticleError> {
        let r = batch[0].radius;
        if !(r > 0.0) || batch.iter().any(|p| p.radius != r) {
            for (k, p) in batch.iter().enumerate() {
                self.place(p, first + k, piece)?;
            }
            return Ok(());
        }
        if piece.column.as_ref().is_some_and(|(c, _)| *c != r) {
            piece.column = None;
        }
        let (_, column) = piece
            .column
            .get_or_insert_with(|| (r, self.kernel.column(r as f64)));
        let (to_index, scale) = (column.to_index(), column.scale());
        // As `place` computes them, operation for operation.
        let (pw, ph) = self.pixel;
        let (kx, ky) = self.to_pixels;
        let support = self.factor * r;
        let s = support as f64;
        let (rx, ry) = (s * kx, s * ky);
        let (ay, ax) = (to_index * ph * ph, (to_index * pw * pw) as f32);
        let mut l = BatchLanes::default();
        #[cfg(target_arch = "x86_64")]
        if self.wide {
            // SAFETY: `wide` is set only where the CPU has AVX-512F.
            unsafe { super::splat_wide::place_lanes(self, batch, support, (rx, ry), &mut l) };
        } else {
            self.lanes(batch, support, (rx, ry), &mut l);
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.lanes(batch, support, (rx, ry), &mut l);
        for (k, p) in batch.iter().enumerate() {
            if p.weight == 0.0 {
                continue;
            }
            if l.only & (1 << k) == 0 {
                self.place(p, first + k, piece)?;
            } else if l.keep & (1 << k) != 0 {
                piece.lean.push(Lean {
                    cx: l.cx[k],
                    cy: l.cy[k],
                    ay,
                    ax,
                    scale: (scale * p.weight as f64) as f32,
                    rows: (l.row0[k], l.row1[k]),
                    cols: (l.col0[k], l.col1[k]),
                });
            }
        }
        Ok(())
    }

    /// The lanes of [`Placer::place_batch`] for a batch of particles with
    /// support radius `support` (`r`: in pixels along x and y), as `place`
    /// computes them, operation for operation.
    #[inline(always)]
    pub(super) fn lanes(
        &self,
        batch: &[SplatParticle; BATCH],
        support: f32,
        (rx, ry): (f64, f64),
        l: &mut BatchLanes,
    ) {
        let [eye, right, up, _] = &self.basis;
        let dot = |d: [f64; 3], e: &[f64; 3]| d[0] * e[0] + d[1] * e[1] + d[2] * e[2];
        // One array a quantity, each written and read a lane at a time.
        let mut only = [true; BATCH];
        let (mut cx, mut cy) = ([0.0f64; BATCH], [0.0f64; BATCH]);
        let (mut row0, mut row1) = ([0u32; BATCH], [0u32; BATCH]);
        let (mut col0, mut col1) = ([0u32; BATCH], [0u32; BATCH]);
        let mut keep = [false; BATCH];
        for k in 0..BATCH {
            let mut q = batch[k].center;
            if let Some(b) = &self.periodic {
                only[k] = only_image(b, q, support);
                q += Vec3::splat(0.0);
            }
            let d = [
                q.x as f64 - eye[0],
                q.y as f64 - eye[1],
                q.z as f64 - eye[2],
            ];
            let c = self.pixel_of(dot(d, right), dot(d, up));
            let ((r0, r1), (c0, c1)) = self.centre_rect(c, (rx, ry));
            (row0[k], row1[k], col0[k], col1[k]) = (r0, r1, c0, c1);
            keep[k] = self.seen(c, (rx, ry)) & (r0 < r1) & (c0 < c1);
            (cx[k], cy[k]) = c;
        }
        let mask = |b: [bool; BATCH]| (0..BATCH).fold(0u8, |m, k| m | ((b[k] as u8) << k));
        *l = BatchLanes {
            only: mask(only),
            keep: mask(keep),
            cx,
            cy,
            row0,
            row1,
            col0,
            col1,
        };
    }

    /// Pixel coordinates of the image-plane point at offsets `(a, b)` from
    /// the eye along right and up: x = (a / hw + 1)·W/2, y = (1 − b / hh)·H/2.
    #[inline(always)]
    fn pixel_of(&self, a: f64, b: f64) -> (f64, f64) {
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let (kx, ky) = self.to_pixels;
        (a * kx + 0.5 * w, 0.5 * h - b * ky)
    }

    /// Whether a support `r` pixels wide around `c` comes within a pixel
    /// of the image (nothing of one further out is drawn). No branch, so
    /// that batches take it in lanes.
    #[inline(always)]
    fn seen(&self, (cx, cy): (f64, f64), (rx, ry): (f64, f64)) -> bool {
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        !((cx + rx + 1.0 < 0.0) | (cx - rx - 1.0 > w) | (cy + ry + 1.0 < 0.0) | (cy - ry - 1.0 > h))
    }

    /// The rows and columns of the pixel centres a support `r` pixels wide
    /// around `c` may touch: those strictly inside the support's square,
    /// |k + 0.5 − c| < r, and `CENTRE_SLACK` more. A centre outside has
    /// |dx| ≥ r: table position ≥ L, where every column is exactly 0
    /// (`column_poly`, tested; the Gaussians' `Column::at` alike), and it
    /// is below 1e-7 of its peak from L − 64 on, so no rounding of the
    /// lanes' offsets can lose a contribution. (The pixel of margin the
    /// pixel areas take made a support 8 pixels wide span 10–11 columns:
    /// two lane groups where one does.)
    #[inline(always)]
    fn centre_rect(&self, (cx, cy): (f64, f64), (rx, ry): (f64, f64)) -> ((u32, u32), (u32, u32)) {
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        (
            (
                ceil_in(cy - ry - 0.5 - CENTRE_SLACK, h),
                floor_in(cy + ry + 0.5 + CENTRE_SLACK, h),
            ),
            (
                ceil_in(cx - rx - 0.5 - CENTRE_SLACK, w),
                floor_in(cx + rx + 0.5 + CENTRE_SLACK, w),
            ),
        )
    }

    /// Particle `p`'s periodic images as splats, in order, onto the
    /// piece's splats (`index`: the particle's index in the whole set, for
    /// errors).
    #[inline(always)]
    pub(super) fn place(
        &self,
        p: &SplatParticle,
        index: usize,
        piece: &mut Piece,
    ) -> Result<(), ParticleError> {
        if !(p.radius > 0.0) || p.weight == 0.0 {
            return Ok(());
        }
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let (pw, ph) = self.pixel;
        let (kx, ky) = self.to_pixels;
        // Read from `self` where used, not copied into locals: the copies
        // were spilled and reloaded across the loop with a wider load than
        // their store (a store-forwarding stall: ~20 % of placing).
        let [eye, right, up, fwd] = &self.basis;
        let dot = |d: [f64; 3], e: &[f64; 3]| d[0] * e[0] + d[1] * e[1] + d[2] * e[2];
        let support = self.factor * p.radius;
        // The piece's fields borrowed apart, so that the column is read in
        // place while splats are pushed (a copy of it a particle, 72 bytes,
        // was ~20 % of placing).
        let Piece {
            found,
            column: cache,
            lean: leans,
            splats,
            ..
        } = piece;
        images(self.periodic.as_ref(), p.center, support, index, found)?;
        // Neighbours often share a radius (a global one always).
        if cache.as_ref().is_some_and(|(r, _)| *r != p.radius) {
            *cache = None;
        }
        let (_, column) =
            &*cache.get_or_insert_with(|| (p.radius, self.kernel.column(p.radius as f64)));
        let s = support as f64;
        for &(shift, q) in found.iter() {
            let clip = match self.mode {
                Periodic::No => false,
                // Images shifted along the view repeat the particle's own chord.
                Periodic::OnAxis(_, axis) if shift[axis] != 0 => continue,
                Periodic::OnAxis(..) => false,
                Periodic::OffAxis(b) => {
                    !(0..3).all(|k| q[k] - support >= b.min[k] && q[k] + support <= b.max[k])
                }
            };
            let d = [
                q.x as f64 - eye[0],
                q.y as f64 - eye[1],
                q.z as f64 - eye[2],
            ];
            let (a, b) = (dot(d, right), dot(d, up));
            let (cx, cy) = self.pixel_of(a, b);
            let (rx, ry) = (s * kx, s * ky);
            if !self.seen((cx, cy), (rx, ry)) {
                continue;
            }
            // Supports narrower than table_pixels take the area table;
            // wider ones are sampled at pixel centres.
            let area = self.area && rx.min(ry) < table_pixels(self.kernel);
            let (rows, cols) = if area || (clip && self.area) {
                // Averages over pixel areas: every pixel the support
                // overlaps, and one more against rounding.
                (
                    (floor_in(cy - ry - 1.5, h), ceil_in(cy + ry + 0.5, h)),
                    (floor_in(cx - rx - 1.5, w), ceil_in(cx + rx + 0.5, w)),
                )
            } else {
                self.centre_rect((cx, cy), (rx, ry))
            };
            if rows.0 >= rows.1 || cols.0 >= cols.1 {
                continue;
            }
            let lean = Lean {
                cx,
                cy,
                // Table position per pixel² along y and x.
                ay: column.to_index() * ph * ph,
                ax: (column.to_index() * pw * pw) as f32,
                scale: (column.scale() * p.weight as f64) as f32,
                rows,
                cols,
            };
            if self.lean && !clip && !area {
                leans.push(lean);
                continue;
            }
            let mut splat = Splat {
                lean,
                pixel: (pw, ph),
                weight: p.weight as f64,
                column: *column,
                a,
                b,
                depth: dot(d, fwd),
                clip,
                area,
                cells: SubCells::centres(self.size, self.half),
                clip_scale: p.weight as f64,
            };
            if clip && self.area {
                splat.cells = SubCells::new(&splat, self.size, self.half);
                splat.clip_scale = splat.cells.scale(&splat);
            }
            splats.push(splat);
        }
        Ok(())
    }
}

/// Pixels of slack around a support's square of pixel centres (see
/// `Placer::place`).
pub(super) const CENTRE_SLACK: f64 = 1e-4;

/// `⌊x⌋` clamped to `0..=hi` (`hi` a whole number below 2³²; NaN gives
/// 0): the clamp first, then a truncation, which is the floor of a value
/// ≥ 0 and needs no call into libm (the default x86-64 target has no
/// SSE4.1 rounding instruction). `max`/`min` and an unchecked truncation,
/// not `clamp` and `as`: `clamp` keeps NaN and asserts its bounds, `as`
/// saturates (four of these a splat were 7 % of a 16.7M-particle
/// projection's samples).
#[inline(always)]
fn floor_in(x: f64, hi: f64) -> u32 {
    truncate(x.max(0.0).min(hi))
}

/// `⌈x⌉` clamped to `0..=hi`, as [`floor_in`].
#[inline(always)]
fn ceil_in(x: f64, hi: f64) -> u32 {
    let x = x.max(0.0).min(hi);
    let t = truncate(x);
    t + ((t as f64) < x) as u32
}

/// `x` (in `[0, hi]` for a `hi` below 2³², as [`floor_in`] clamps it)
/// truncated.
#[inline(always)]
fn truncate(x: f64) -> u32 {
    debug_assert!((0.0..4294967296.0).contains(&x));
    // SAFETY: the callers clamp `x` to `[0, hi]` (`max` drops NaN), so its
    // truncation is a u32.
    unsafe { x.to_int_unchecked::<u32>() }
}
