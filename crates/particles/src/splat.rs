//! Column-density images by splatting, streamed: particles are added in
//! chunks to an image that is the only thing kept, so a projection of a
//! file never holds all its particles, their order or a BVH. The particle
//! volume's orthographic projections take the same path with its particles
//! (see [`crate::ParticleVolume`]'s `project_image`).
//!
//! **What is added.** Every particle adds `weight × F(b)` to the pixels
//! whose centre lies inside its support, `F(b)` its kernel's full column at
//! the pixel centre's distance `b` from it ([`crate::kernel::Column`]). The
//! SPH kernels' columns are evaluated eight pixels at a time as piecewise
//! polynomials of the table position `t ∝ b²` (no square root, no table
//! read: [`crate::kernel::column_poly`]; a gather per eight pixels cost more
//! than the rest of the pixel's work), within 1e-6 of the column's peak;
//! the table position is computed in f32 from the pixel offset. Every pixel
//! centre in the support's square is evaluated (no margin: a centre outside
//! the square has a column of exactly 0), those outside the support add 0,
//! which costs less than finding each row's chord.
//!
//! **Periodic boxes.** Each particle (wrapped into the box) is added once
//! per periodic image whose support meets the box. Along a box axis only
//! the images shifted *across* the view are added, each with its full
//! chord: over one period the chords of the images shifted along the view
//! are the parts of the particle's own chord that leave the box. Pixels
//! whose centre lies outside the box's shadow are 0 (their line misses the
//! box). Off axis, an image whose support crosses a face adds only the part
//! of its chord inside the box (each pixel's segment through the box, in
//! f64); the others add full chords. Either way the line of sight crosses
//! the box once and each particle's mass is counted once.
//!
//! **Determinism.** The image is cut into bands of [`BAND`] rows. A
//! chunk's particles are placed in pieces of 4,096 on every core, and each
//! piece's splats are binned, in order, to the bands their support
//! reaches; bands are summed in parallel, each over the pieces' lists in
//! order, into the f64 image (each lane's f32 column, already scaled by
//! the particle's weight, added in f64). The bits therefore depend on the order of
//! the particles and the CPU's lanes, not on the number of threads or how
//! the particles are chunked; another order moves only f64 rounding (a
//! streamed file and the volume's Hilbert order give the same f32 image in
//! practice, tested to 1e-6 of the peak). On a CPU with AVX-512 the SPH
//! columns take sixteen lanes and their own polynomials (`splat_wide.rs`):
//! within the polynomials' bound of the eight lanes' image, not its bits.
//!
//! **Placing.** Particles that share a radius are placed eight at a time
//! (`Placer::place_batch`: their image-plane centres, rows and columns in
//! lanes, f64 on eight lanes with AVX-512), the rest one at a time; both
//! give the same splats bit for bit (tested).

use rayon::prelude::*;
use std::sync::Arc;
use voxless_core::simd::{Simd, dispatch};

use voxless_core::{Aabb, Camera, Control, PixelIntegral, Projection, Vec3};

use crate::ParticleError;
use crate::kernel::area::AreaTable;
use crate::kernel::column_poly::{ColumnPoly, DEGREE, WIDE_DEGREE};
use crate::kernel::{Column, Kernel};

/// Rows per band. A particle ~20 pixels across meets 1.3 bands of 64 rows
/// on average (1.6 of 32: each visit costs the splat's set-up again); a
/// band (64 rows of a 1024-wide image: 540 KB of f64 sums) stays in the
/// core's L2 cache. Measured on the 2.1M-particle projection: 64 rows
/// ×0.97 of 32 (128: slower, eight bands balance badly on two cores). The
/// bits do not depend on it.
pub const BAND: u32 = 64;

/// Particles per chunk when a caller has no better size: each chunk's
/// splats take ~100 bytes a particle, so 2¹⁶ of them cost ~7 MB.
pub const CHUNK: usize = 1 << 16;

/// One particle to splat, in the camera's (local) coordinates: the centre,
/// the kernel's radius parameter and the weight. A particle with radius
/// ≤ 0 or weight 0 adds nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatParticle {
    pub center: Vec3,
    pub radius: f32,
    pub weight: f32,
}

/// A column-density image being summed (see the module docs).
pub struct Splatter {
    camera: Camera,
    width: u32,
    height: u32,
    kernel: Kernel,
    mode: Periodic,
    /// Half the image's width and height in the image plane.
    half: (f64, f64),
    /// The running sums, row-major, row 0 at the top, rows
    /// [`row_stride`] apart.
    sum: Vec<f64>,
    /// Reused between chunks: the chunk's splats, placed and binned in
    /// pieces of [`PIECE`] particles on every core.
    pieces: Vec<Piece>,
    /// The SIMD lanes the bands run on (every backend gives the same
    /// image to f32 rounding of the table position; tests pick each).
    simd: Simd,
    /// SPH splats on sixteen lanes (`Simd::Auto` on a CPU with AVX-512;
    /// within the columns' bound of the eight lanes, see `splat_wide.rs`).
    wide: bool,
    /// Pixel areas ([`PixelIntegral::Area`]): the kernel's area table.
    area: Option<Arc<AreaTable>>,
    /// The device summing the plain splats, and its image.
    device: Option<Box<dyn DeviceImage>>,
    /// Reused between chunks: the plain splats for the device.
    plain: Vec<PlainSplat>,
}

/// A device that sums a splatter's plain splats (the GPU backend).
///
/// The splatter places every particle image on the CPU (periodic images,
/// the rows and columns each may touch) and keeps summing those that need
/// more than a column per pixel centre (pixel areas, images clipped to a
/// periodic box); the device sums the others — all of them in the usual
/// case — into an image of its own, added to the CPU's at the end.
pub trait SplatDevice: Send + Sync {
    /// An empty `width` × `height` image for particles with `kernel`.
    fn begin(
        &self,
        width: u32,
        height: u32,
        kernel: Kernel,
    ) -> Result<Box<dyn DeviceImage>, ParticleError>;
}

/// An image being summed on a device (see [`SplatDevice`]).
pub trait DeviceImage: Send {
    /// Adds `splats` (in order: the order a device sums them in may move
    /// f32 rounding only).
    fn add(&mut self, splats: &[PlainSplat]) -> Result<(), ParticleError>;
    /// The image, row-major, row 0 at the top.
    fn finish(self: Box<Self>) -> Result<Vec<f32>, ParticleError>;
}

/// One particle image a device sums: each pixel centre `(x + ½, y + ½)`
/// of rows `rows` and columns `cols` within the support gets
/// - SPH kernels: `scale × T(ax·dx² + ay·dy²)`, `T` the kernel's column
///   table ([`Kernel::sph_table`]) interpolated linearly, 0 from its last
///   entry on;
/// - the Gaussians: `scale × exp(−b²·g_exp) × erf(√(support2 − b²)·g_erf)`
///   with `b² = dx²·pw2 + dy²·ph2` below `support2` (the closed-form
///   column of the truncated Gaussian),
///
/// with `(dx, dy)` the offset of the pixel centre from `(cx, cy)` in
/// pixels. 64 bytes, laid out as a GPU buffer reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct PlainSplat {
    pub cx: f32,
    pub cy: f32,
    pub ax: f32,
    pub ay: f32,
    pub scale: f32,
    pub g_exp: f32,
    pub g_erf: f32,
    pub support2: f32,
    pub pw2: f32,
    pub ph2: f32,
    pub rows: [u32; 2],
    pub cols: [u32; 2],
    pub _pad: [u32; 2],
}

impl Splatter {
    /// An empty image of `width` × `height` pixels through the orthographic
    /// `camera`, for particles with `kernel`, in the periodic box `periodic`
    /// (local coordinates) when there is one. `None` for other cameras or an
    /// empty image.
    pub fn new(
        camera: &Camera,
        width: u32,
        height: u32,
        kernel: Kernel,
        periodic: Option<Aabb>,
    ) -> Option<Splatter> {
        let Projection::Orthographic {
            half_width,
            half_height,
        } = camera.projection
        else {
            return None;
        };
        if width == 0 || height == 0 || !(half_width > 0.0 && half_height > 0.0) {
            return None;
        }
        let mode = match periodic {
            None => Periodic::No,
            Some(b) => match (0..3).find(|&a| camera.forward[a].abs() >= 1.0 - 1e-6) {
                Some(axis) => Periodic::OnAxis(b, axis),
                None => Periodic::OffAxis(b),
            },
        };
        Some(Splatter {
            camera: *camera,
            width,
            height,
            kernel,
            mode,
            half: (half_width as f64, half_height as f64),
            sum: written_zeros(row_stride(width) * height as usize),
            pieces: Vec::new(),
            simd: Simd::Auto,
            wide: splat_wide::available(),
            area: None,
            device: None,
            plain: Vec::new(),
        })
    }

    /// The same splatter summing its plain splats on `device` (see
    /// [`SplatDevice`]).
    pub fn with_device(mut self, device: &dyn SplatDevice) -> Result<Self, ParticleError> {
        self.device = Some(device.begin(self.width, self.height, self.kernel)?);
        Ok(self)
    }

    /// The same splatter integrating each pixel by `pixels`: with
    /// [`PixelIntegral::Area`] each pixel is its column averaged over its
    /// square (see [`crate::kernel::area`]) for supports narrower than
    /// [`table_pixels`], so Σ column × pixel area is the mass of every
    /// kernel inside the image at any kernel size; wider supports are
    /// sampled at pixel centres, which hold their mass to ~1e-7 and differ
    /// from the pixel means by ~1e-3 of a value at 16 pixels. Off-axis
    /// periodic images crossing a face average sub-pixel samples
    /// ([`clipped`]).
    pub fn with_pixels(mut self, pixels: PixelIntegral) -> Self {
        self.area = (pixels == PixelIntegral::Area).then(|| AreaTable::of(self.kernel));
        self
    }

    /// Adds `particles` (positions inside the periodic box, when there is
    /// one: callers wrap). `offset` is the first particle's index in the
    /// whole set, for errors. Bands are skipped once `control` is cancelled;
    /// the caller checks it after the call. Errors: a support wider than the
    /// periodic box allows ([`ParticleError::SupportBeyondBox`]).
    pub fn add(
        &mut self,
        particles: &[SplatParticle],
        offset: usize,
        control: &Control,
    ) -> Result<(), ParticleError> {
        // Place and bin in pieces on every core; a piece's splats keep its
        // particles' order and the pieces are summed in order, so the bits
        // do not depend on the number of threads.
        let on_device = self.device.is_some();
        let mut pieces = std::mem::take(&mut self.pieces);
        let placer = self.placer();
        let simd = self.simd;
        // (Pieces left from a larger chunk would be summed again.)
        pieces.resize_with(particles.len().div_ceil(PIECE), Piece::default);
        // Collected in order, so the first bad particle in order is named
        // whichever piece fails first.
        let placed: Vec<Result<(), ParticleError>> = pieces
            .par_iter_mut()
            .zip(particles.par_chunks(PIECE))
            .enumerate()
            .map(|(k, (piece, part))| {
                piece.splats.clear();
                piece.lean.clear();
                // Compiled for the lanes `simd` picks (AVX2: `floor` and
                // `ceil` one instruction each, not SSE2's sequences; the
                // same bits, no operation fused or reordered).
                let first = offset + k * PIECE;
                dispatch(
                    simd,
                    PlaceAll {
                        placer: &placer,
                        part,
                        first,
                        piece,
                    },
                )?;
                // On a device the CPU sums only what it keeps (pixel
                // areas, clipped images), so only those are binned.
                let height = placer.size.1;
                let keep = |p: &Splat| (!on_device || p.clip || p.area).then_some(p.lean.rows);
                piece.bands.bin(piece.splats.iter().map(keep), height);
                piece
                    .lean_bands
                    .bin(piece.lean.iter().map(|p| Some(p.rows)), height);
                Ok(())
            })
            .collect();
        self.pieces = pieces;
        placed.into_iter().collect::<Result<(), _>>()?;
        if let Some(device) = &mut self.device {
            self.plain.clear();
            self.plain.extend(
                self.pieces
                    .iter()
                    .flat_map(|piece| &piece.splats)
                    .filter(|p| !p.clip && !p.area)
                    .map(plain),
            );
            device.add(&self.plain)?;
        }
        let w = row_stride(self.width);
        let (camera, mode, kernel) = (&self.camera, self.mode, self.kernel);
        let height = self.height;
        let pieces = &self.pieces;
        // The Gaussians read none (their columns are closed forms).
        let poly = kernel.column_poly().unwrap_or(&NO_POLY);
        let (simd, wide) = (self.simd, self.wide);
        let area = self.area.as_deref();
        self.sum
            .par_chunks_mut(w * BAND as usize)
            .enumerate()
            .for_each(|(band, out)| {
                let splats = BandSplats { pieces, band };
                if splats.is_empty() || control.is_cancelled() {
                    return;
                }
                let y0 = band as u32 * BAND;
                let rows = (out.len() / w) as u32;
                if let Some(table) = area {
                    area_band(splats, table, (y0, y0 + rows), w, &mut *out);
                }
                if !on_device {
                    dispatch(
                        simd,
                        SplatBand {
                            splats,
                            wide,
                            y: (y0, y0 + rows),
                            stride: w,
                            poly,
                            out: &mut *out,
                        },
                    );
                }
                if let Periodic::OffAxis(b) = mode {
                    clipped(splats, camera, &b, height, y0, (w, out));
                }
            });
        Ok(())
    }

    /// What placing a particle needs of this splatter.
    fn placer(&self) -> Placer {
        let (w, h) = (self.width as f64, self.height as f64);
        Placer {
            basis: self.camera.basis_f64(),
            size: (self.width, self.height),
            pixel: (2.0 * self.half.0 / w, 2.0 * self.half.1 / h),
            to_pixels: (0.5 * w / self.half.0, 0.5 * h / self.half.1),
            kernel: self.kernel,
            factor: self.kernel.support_factor(),
            mode: self.mode,
            periodic: match self.mode {
                Periodic::No => None,
                Periodic::OnAxis(b, _) | Periodic::OffAxis(b) => Some(b),
            },
            half: self.half,
            area: self.area.is_some(),
            lean: self.device.is_none() && self.kernel.column_poly().is_some(),
            wide: self.wide,
        }
    }

    /// The image: column densities through every pixel centre, or
    /// averaged over every pixel (f32, row-major, row 0 at the top).
    /// Errors: the device's (see [`Splatter::with_device`]).
    pub fn finish(mut self) -> Result<Vec<f32>, ParticleError> {
        let sum = std::mem::take(&mut self.sum);
        let (w, stride) = (self.width as usize, row_stride(self.width));
        let device = self.device.take().map(|d| d.finish()).transpose()?;
        // Row by row on every core (a megapixel took ~5 ms on one).
        let mut image = vec![0.0f32; w * self.height as usize];
        let shadow = Shadow {
            camera: &self.camera,
            half: self.half,
            size: (self.width, self.height),
        };
        let mode = self.mode;
        image
            .par_chunks_mut(w)
            .zip(sum.par_chunks(stride))
            .enumerate()
            .for_each(|(y, (out, row))| {
                let row = &row[..w];
                match &device {
                    // The device's f32 sums added in f64, as the lanes' are.
                    Some(d) => {
                        for ((o, &s), &d) in out.iter_mut().zip(row).zip(&d[y * w..][..w]) {
                            *o = (s + d as f64) as f32;
                        }
                    }
                    None => {
                        for (o, &s) in out.iter_mut().zip(row) {
                            *o = s as f32;
                        }
                    }
                }
                if let Periodic::OnAxis(b, axis) = mode {
                    shadow.outside_to_zero(&b, axis, y, out);
                }
            });
        Ok(image)
    }

    /// The same splatter on the SIMD lanes `simd` (for tests of each
    /// backend).
    #[cfg(test)]
    pub(crate) fn on(mut self, simd: Simd) -> Self {
        self.simd = simd;
        self.wide = simd == Simd::Auto && splat_wide::available();
        self
    }
}

/// What a splatter's image needs to know of its pixels' lines of sight.
struct Shadow<'a> {
    camera: &'a Camera,
    half: (f64, f64),
    size: (u32, u32),
}

impl Shadow<'_> {
    /// Zeroes the pixels of row `y` whose centre lies outside the shadow of
    /// the box `b` along `axis` (their line misses the box).
    fn outside_to_zero(&self, b: &Aabb, axis: usize, y: usize, row: &mut [f32]) {
        let (w, h) = (self.size.0 as usize, self.size.1 as usize);
        let (hw, hh) = self.half;
        let cam = self.camera;
        let vv = (1.0 - (2 * y + 1) as f64 / h as f64) * hh;
        // The two axes across the view, their terms read once a row and
        // the tests combined without branches, so that the loop runs on
        // lanes (the same expressions, in the same order, as a pixel's
        // line takes: the same pixels; the closure over the axes was ~1.5
        // ms of every 1024² projection).
        let [a0, a1] = match axis {
            0 => [1, 2],
            1 => [0, 2],
            _ => [0, 1],
        };
        let term = |a: usize| {
            (
                cam.eye[a] as f64,
                cam.right[a] as f64,
                cam.up[a] as f64 * vv,
                b.min[a] as f64,
                b.max[a] as f64,
            )
        };
        let (t0, t1) = (term(a0), term(a1));
        let within = |(eye, right, up, lo, hi): (f64, f64, f64, f64, f64), uu: f64| {
            let o = eye + right * uu + up;
            (o >= lo) & (o <= hi)
        };
        for (x, s) in row.iter_mut().enumerate() {
            let uu = ((2 * x + 1) as f64 / w as f64 - 1.0) * hw;
            if !(within(t0, uu) & within(t1, uu)) {
                *s = 0.0;
            }
        }
    }
}

/// The distance between the sums' rows for an image `width` wide: whole
/// 64-byte lines, and never within 256 bytes of a multiple of 4 KiB. Rows
/// of a power-of-two width (4 or 8 KiB of f64) put every row of a splat in
/// the same few L1 sets, and a row's load right after the store to the row
/// above waited on it (4K aliasing: the addresses' low 12 bits match).
/// Measured at 1024²: the 2.1M-particle projection's loop ×0.92, the
/// 16.7M one's ×0.92 (the same bits). The lanes of a group past the
/// image's right edge add their zeros to the padding, which the image
/// leaves out.
fn row_stride(width: u32) -> usize {
    // (Rows under 2 KiB are left as they are: no two rows of a lane group
    // alias, and a narrow image is not made many times wider.)
    if width < 256 {
        return width as usize;
    }
    let mut s = (width as usize).next_multiple_of(8);
    while !(256..=4096 - 256).contains(&(s * 8 % 4096)) {
        s += 8;
    }
    s
}

/// `n` zeros written on every core, not `calloc`'s untouched pages: the
/// bands read each pixel before they write it, and a read of an untouched
/// page maps the shared zero page, whose copy on the following write
/// flushes the other cores' TLBs (measured: 2.5 % of a 2.1M-particle
/// projection's samples at 1024², in the kernel's TLB flushes).
fn written_zeros(n: usize) -> Vec<f64> {
    rayon::iter::repeat_n(0.0, n).collect()
}

/// What a device sums of splat `p` (see [`PlainSplat`]).
fn plain(p: &Splat) -> PlainSplat {
    let (pw, ph) = p.pixel;
    let q = &p.lean;
    let (scale, g_exp, g_erf) = match p.column.gaussian() {
        // The SPH kernels read the table.
        None => (q.scale as f64, 0.0, 0.0),
        // amp·exp(−b²/2s²)·s·√(π/2)·(erf(l/√2s) − erf(−l/√2s)).
        Some((s, amp)) => (
            p.weight * amp * s * (2.0 * std::f64::consts::PI).sqrt(),
            1.0 / (2.0 * s * s),
            1.0 / (std::f64::consts::SQRT_2 * s),
        ),
    };
    PlainSplat {
        cx: q.cx as f32,
        cy: q.cy as f32,
        ax: q.ax,
        ay: q.ay as f32,
        scale: scale as f32,
        g_exp: g_exp as f32,
        g_erf: g_erf as f32,
        support2: p.column.support2() as f32,
        pw2: (pw * pw) as f32,
        ph2: (ph * ph) as f32,
        rows: [q.rows.0, q.rows.1],
        cols: [q.cols.0, q.cols.1],
        _pad: [0; 2],
    }
}

/// A projection's treatment of a periodic box (see the module docs).
#[derive(Clone, Copy)]
enum Periodic {
    No,
    OnAxis(Aabb, usize),
    OffAxis(Aabb),
}

/// One particle image as the image sees it.
struct Splat {
    /// What the lanes read: the centre, table positions, scale, rows and
    /// columns.
    lean: Lean,
    /// World (local) width and height of a pixel.
    pixel: (f64, f64),
    weight: f64,
    column: Column,
    /// Offsets of the centre from the eye along right, up and the view.
    a: f64,
    b: f64,
    depth: f64,
    /// Add only the part of the chord inside the periodic box.
    clip: bool,
    /// Average each pixel from the area table ([`area_band`]).
    area: bool,
    /// A clipped splat's sub-cells per pixel side, and the factor of its
    /// samples' sum in a pixel ([`clipped`]).
    cells: SubCells,
    clip_scale: f64,
}

/// What the lanes read of a particle image. SPH splats summed at pixel
/// centres on the CPU (neither clipped nor averaged over pixel areas:
/// nearly every splat) are kept as this alone — 48 bytes against a
/// [`Splat`]'s ~200, so a chunk's splats stay in the cores' caches between
/// placing, binning and summing.
#[derive(Clone, Copy)]
struct Lean {
    /// The centre in pixel coordinates (x right, y down; pixel `k`'s
    /// centre at `k + 0.5`).
    cx: f64,
    cy: f64,
    /// The table position of a row offset: `ay·dy²` (f64, as the lanes
    /// take it), and of a column offset: `ax·dx²` (f32).
    ay: f64,
    ax: f32,
    /// `weight ×` the column table's scale, in f32 as the lanes take it.
    scale: f32,
    /// Rows `rows.0..rows.1` and columns `cols.0..cols.1` it may touch.
    rows: (u32, u32),
    cols: (u32, u32),
}

impl Lean {
    /// Row `y`'s table position `ay·dy²` in f32, as the lanes add it to
    /// the columns'; `None` from row `end` on (past the band or the
    /// support) or where it is not below `last` (the row adds nothing).
    #[inline(always)]
    fn row_position(&self, y: u32, end: u32, last: f64) -> Option<f32> {
        let dy = y as f64 + 0.5 - self.cy;
        let ty = self.ay * dy * dy;
        (y < end && ty < last).then_some(ty as f32)
    }
}

/// The polynomials of the kernels that have none (the Gaussians).
static NO_POLY: ColumnPoly = ColumnPoly {
    lanes8: [[0.0; 8]; DEGREE + 1],
    wide: [[0.0; 32]; WIDE_DEGREE + 1],
};

/// Particles a piece holds: the chunk is placed and binned in pieces of
/// this many particles on every core.
const PIECE: usize = 4096;

/// A piece of a chunk: its particles' splats, in order, binned to bands.
#[derive(Default)]
struct Piece {
    splats: Vec<Splat>,
    /// The SPH splats summed on the lanes, in order, and their bands.
    lean: Vec<Lean>,
    lean_bands: Bands,
    /// Reused: a particle's periodic images.
    found: Vec<([i8; 3], Vec3)>,
    /// The last radius placed and its column.
    column: Option<(f32, Column)>,
    bands: Bands,
}

/// A piece's splats binned to bands of rows (counting sort, in order).
#[derive(Default)]
struct Bands {
    /// Band `t`'s splats are `members[start[t]..start[t + 1]]`.
    start: Vec<u32>,
    members: Vec<u32>,
}

impl Bands {
    /// Bins splats by their rows (`None`: not binned), splat `i` the
    /// `i`-th item (reusing the buffers).
    fn bin(&mut self, rows: impl Iterator<Item = Option<(u32, u32)>> + Clone, height: u32) {
        let bands = height.div_ceil(BAND) as usize;
        let range = |r: (u32, u32)| (r.0 / BAND) as usize..=((r.1 - 1) / BAND) as usize;
        self.start.clear();
        self.start.resize(bands + 1, 0);
        let start = &mut self.start;
        for r in rows.clone().flatten() {
            for t in range(r) {
                start[t + 1] += 1;
            }
        }
        for t in 0..bands {
            start[t + 1] += start[t];
        }
        let mut fill = start.clone();
        self.members.clear();
        self.members.resize(start[bands] as usize, 0);
        for (i, r) in rows.enumerate() {
            let Some(r) = r else { continue };
            for t in range(r) {
                self.members[fill[t] as usize] = i as u32;
                fill[t] += 1;
            }
        }
    }

    fn members(&self, band: usize) -> &[u32] {
        &self.members[self.start[band] as usize..self.start[band + 1] as usize]
    }
}

/// The splats of one band over a chunk's pieces, in order.
#[derive(Clone, Copy)]
struct BandSplats<'a> {
    pieces: &'a [Piece],
    band: usize,
}

impl<'a> BandSplats<'a> {
    fn is_empty(self) -> bool {
        self.pieces.iter().all(|p| {
            p.bands.members(self.band).is_empty() && p.lean_bands.members(self.band).is_empty()
        })
    }

    /// The band's lean splats, in order.
    fn lean(self) -> impl Iterator<Item = &'a Lean> {
        self.pieces.iter().flat_map(move |piece| {
            piece
                .lean_bands
                .members(self.band)
                .iter()
                .map(move |&i| &piece.lean[i as usize])
        })
    }

    fn iter(self) -> impl Iterator<Item = &'a Splat> {
        self.pieces.iter().flat_map(move |piece| {
            piece
                .bands
                .members(self.band)
                .iter()
                .map(move |&i| &piece.splats[i as usize])
        })
    }
}

#[path = "splat_band.rs"]
mod band;
#[path = "splat_pixels.rs"]
mod pixels;
#[path = "splat_place.rs"]
mod place;
#[path = "splat_wide.rs"]
mod splat_wide;
use band::SplatBand;
use pixels::{SubCells, area_band, clipped};
use place::{BATCH, BatchLanes, CENTRE_SLACK, PlaceAll, Placer};

#[cfg(test)]
#[path = "splat_tests.rs"]
mod tests;
