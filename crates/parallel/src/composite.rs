//! Sort-last compositing by direct send: image tiles, each owned by one
//! rank, receive the non-empty fragments of every rank and combine them;
//! [`gather`] then brings the finished tiles to rank 0.
//!
//! - [`over`]: premultiplied RGBA "over", front to back in the camera's
//!   visibility order, with early termination reproduced exactly (below).
//! - [`sum`]: column densities and other additive images, added in rank
//!   order (in `f64`), so the result never depends on timing.
//!
//! **Early termination.** A one-process render stops a ray once its opacity
//! reaches the threshold. A box renders its own part of the ray from
//! opacity 0, so on its own it stops where *its* opacity reaches the
//! threshold — too late when boxes in front already made the ray partly
//! opaque. The tile owner sees, per pixel, the opacity `A` in front of each
//! fragment: where `A + (1 − A)·a` passes the threshold inside a box
//! (and `A > 0`), it asks that box's rank to render the pixel again starting
//! from opacity `A` ([`Rerender`]), which stops exactly where the whole ray
//! would; the fragments behind are dropped. That is one extra exchange per
//! pass and usually a few pixels.

use rayon::prelude::*;

use crate::comm::{Comm, CommError};
use crate::wire::{Reader, Writer};

/// An image cut into square tiles, row by row; tile `t` belongs to rank
/// `t mod ranks`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileGrid {
    pub width: u32,
    pub height: u32,
    pub size: u32,
}

impl TileGrid {
    /// Tiles of `size` pixels (at least 1) over a `width`×`height` image.
    pub fn new(width: u32, height: u32, size: u32) -> TileGrid {
        TileGrid {
            width,
            height,
            size: size.max(1),
        }
    }

    fn per_row(&self) -> u32 {
        self.width.div_ceil(self.size)
    }

    /// How many tiles.
    pub fn count(&self) -> usize {
        self.per_row() as usize * self.height.div_ceil(self.size) as usize
    }

    /// Tile `t`'s pixels: `(x0, y0, w, h)`.
    pub fn rect(&self, t: usize) -> (u32, u32, u32, u32) {
        let (tx, ty) = (t as u32 % self.per_row(), t as u32 / self.per_row());
        let (x0, y0) = (tx * self.size, ty * self.size);
        (
            x0,
            y0,
            self.size.min(self.width - x0),
            self.size.min(self.height - y0),
        )
    }

    /// The rank that owns tile `t`.
    pub fn owner(&self, t: usize, ranks: usize) -> usize {
        t % ranks.max(1)
    }

    /// The tiles `rank` owns, in increasing order.
    pub fn owned(&self, rank: usize, ranks: usize) -> impl Iterator<Item = usize> + '_ {
        (rank..self.count()).step_by(ranks.max(1))
    }
}

/// The tiles one rank owns, composited: `ch` channels per pixel, tiles in
/// increasing order (every owned tile, empty or not).
#[derive(Clone, Debug, PartialEq)]
pub struct OwnedTiles {
    pub grid: TileGrid,
    pub channels: usize,
    pub tiles: Vec<(usize, Vec<f32>)>,
}

impl OwnedTiles {
    /// Every owned tile, zero.
    pub fn zeros(grid: TileGrid, channels: usize, rank: usize, ranks: usize) -> OwnedTiles {
        OwnedTiles {
            grid,
            channels,
            tiles: grid
                .owned(rank, ranks)
                .map(|t| {
                    let (_, _, w, h) = grid.rect(t);
                    (t, vec![0.0; (w * h) as usize * channels])
                })
                .collect(),
        }
    }

    /// Adds `other` (the same tiles) value by value: passes accumulate.
    pub fn add(&mut self, other: &OwnedTiles) {
        for ((_, a), (_, b)) in self.tiles.iter_mut().zip(&other.tiles) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += *y;
            }
        }
    }

    /// Multiplies every value by `s`.
    pub fn scale(&mut self, s: f32) {
        for (_, t) in &mut self.tiles {
            for x in t {
                *x *= s;
            }
        }
    }
}

/// Renders pixels `(x, y)` again from opacity `alpha` onwards (see the
/// module docs); one premultiplied RGBA per request, alpha the total.
pub type Rerender<'a> = dyn FnMut(&[(u32, u32, f32)]) -> Vec<[f32; 4]> + 'a;

/// Appends `v` as little-endian bytes (a plain copy on little-endian
/// machines).
#[inline]
fn put_f32s(out: &mut Vec<u8>, v: &[f32]) {
    if cfg!(target_endian = "little") {
        out.extend_from_slice(bytemuck::cast_slice(v));
    } else {
        out.reserve(4 * v.len());
        for x in v {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// Little-endian `f32` bytes as values: borrowed when they are aligned on a
/// little-endian machine (the usual case), else copied.
fn f32s_of(b: &[u8]) -> std::borrow::Cow<'_, [f32]> {
    match bytemuck::try_cast_slice::<u8, f32>(b) {
        Ok(v) if cfg!(target_endian = "little") => std::borrow::Cow::Borrowed(v),
        _ => std::borrow::Cow::Owned(
            b.chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        ),
    }
}

/// Messages for each rank: the non-empty tiles of `image` (`ch` channels
/// per pixel, row-major) addressed to their owners, each as its index then
/// its values row by row (their count follows from the grid).
fn fragments(grid: &TileGrid, image: &[f32], ch: usize, ranks: usize) -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = vec![Vec::new(); ranks];
    for t in 0..grid.count() {
        let (x0, y0, w, h) = grid.rect(t);
        let row = |y: u32| {
            let at = (y * grid.width + x0) as usize * ch;
            &image[at..at + w as usize * ch]
        };
        if (y0..y0 + h).all(|y| row(y).iter().all(|&v| v == 0.0)) {
            continue;
        }
        let m = &mut out[grid.owner(t, ranks)];
        m.extend_from_slice(&(t as u32).to_le_bytes());
        for y in y0..y0 + h {
            put_f32s(m, row(y));
        }
    }
    out
}

/// The fragments received for each owned tile: `(source rank, its values
/// as little-endian bytes)`, in source order.
/// Per owned tile, its fragments: `(source rank, values as bytes)`.
type Fragments<'a> = Vec<Vec<(usize, &'a [u8])>>;

fn received<'a>(
    got: &'a [Vec<u8>],
    owned: &[usize],
    grid: &TileGrid,
    ch: usize,
) -> Result<Fragments<'a>, CommError> {
    let mut slot = vec![usize::MAX; grid.count()];
    for (i, &t) in owned.iter().enumerate() {
        slot[t] = i;
    }
    let mut out: Vec<Vec<(usize, &[u8])>> = vec![Vec::new(); owned.len()];
    for (src, msg) in got.iter().enumerate() {
        let mut at = 0;
        while at < msg.len() {
            let bad = || {
                CommError::Transport(format!(
                    "rank {src} sent a tile that is not this rank's or is cut short"
                ))
            };
            let head = msg.get(at..at + 4).ok_or_else(bad)?;
            let t = u32::from_le_bytes([head[0], head[1], head[2], head[3]]) as usize;
            let i = *slot.get(t).ok_or_else(bad)?;
            if i == usize::MAX {
                return Err(bad());
            }
            let (_, _, w, h) = grid.rect(t);
            let len = 4 * (w * h) as usize * ch;
            let values = msg.get(at + 4..at + 4 + len).ok_or_else(bad)?;
            out[i].push((src, values));
            at += 4 + len;
        }
    }
    Ok(out)
}

/// An owned tile composited: its pixels, and the pixels to ask again as
/// (source rank, pixel index in the tile, opacity in front).
type Composited = (Vec<f32>, Vec<(usize, usize, f32)>);

/// Composites one pass: this rank's premultiplied RGBA `image` (the whole
/// image, transparent outside its box) with every other rank's, "over"
/// front to back in `order` (ranks, nearest first), stopping where a
/// one-process ray would stop at `early_termination`. `rerender` answers
/// the requests of tile owners for pixels of this rank that need to be
/// rendered again from a known opacity. Returns this rank's tiles.
pub fn over(
    comm: &dyn Comm,
    grid: &TileGrid,
    image: &[[f32; 4]],
    order: &[usize],
    early_termination: f32,
    rerender: &mut Rerender,
) -> Result<OwnedTiles, CommError> {
    let ranks = comm.size();
    let flat: &[f32] = image.as_flattened();
    let got = comm.exchange(fragments(grid, flat, 4, ranks))?;
    let owned: Vec<usize> = grid.owned(comm.rank(), ranks).collect();
    let frags = received(&got, &owned, grid, 4)?;
    let mut pos = vec![usize::MAX; ranks];
    for (i, &r) in order.iter().enumerate() {
        if r < ranks {
            pos[r] = i;
        }
    }
    // Per owned tile: its composited pixels and the pixels to ask again,
    // (source rank, pixel index in the tile, opacity in front).
    let et = early_termination;
    let done: Vec<Composited> = owned
        .par_iter()
        .zip(frags.into_par_iter())
        .map(|(&t, mut fr)| {
            fr.sort_by_key(|f| pos[f.0]);
            let fr: Vec<(usize, std::borrow::Cow<[f32]>)> =
                fr.into_iter().map(|(src, b)| (src, f32s_of(b))).collect();
            let (_, _, w, h) = grid.rect(t);
            let n = (w * h) as usize;
            let mut px = vec![0.0f32; 4 * n];
            let mut ask = Vec::new();
            for p in 0..n {
                let (mut c, mut a) = ([0.0f32; 3], 0.0f32);
                for (src, v) in &fr {
                    let f = &v[4 * p..4 * p + 4];
                    if f[3] == 0.0 && f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0 {
                        continue;
                    }
                    if a >= et {
                        break;
                    }
                    if a == 0.0 {
                        // Nothing in front: the box's own render is the ray's.
                        c = [f[0], f[1], f[2]];
                        a = f[3];
                        continue;
                    }
                    let t = 1.0 - a;
                    if a + t * f[3] < et {
                        for k in 0..3 {
                            c[k] += t * f[k];
                        }
                        a += t * f[3];
                        continue;
                    }
                    // The ray stops inside this box: render it again from `a`.
                    ask.push((*src, p, a));
                    break;
                }
                px[4 * p..4 * p + 3].copy_from_slice(&c);
                px[4 * p + 3] = a;
            }
            (px, ask)
        })
        .collect();
    // Requests to the ranks whose boxes stop rays, and their answers.
    let mut requests: Vec<Writer> = (0..ranks).map(|_| Writer::new()).collect();
    let mut pending: Vec<Vec<(usize, usize)>> = vec![Vec::new(); ranks];
    for (i, (&t, (_, ask))) in owned.iter().zip(&done).enumerate() {
        let (x0, y0, w, _) = grid.rect(t);
        for &(src, p, a) in ask {
            let w_ = &mut requests[src];
            w_.u32(x0 + p as u32 % w);
            w_.u32(y0 + p as u32 / w);
            w_.f32(a);
            pending[src].push((i, p));
        }
    }
    let asked = comm.exchange(requests.into_iter().map(Writer::into_bytes).collect())?;
    let mut all = Vec::new();
    let mut counts = Vec::with_capacity(ranks);
    for msg in &asked {
        let mut r = Reader::new(msg);
        let before = all.len();
        while !r.is_done() {
            all.push((r.u32()?, r.u32()?, r.f32()?));
        }
        counts.push(all.len() - before);
    }
    let answers = if all.is_empty() {
        Vec::new()
    } else {
        rerender(&all)
    };
    if answers.len() != all.len() {
        return Err(CommError::Transport(format!(
            "{} pixels rendered again for {} requests",
            answers.len(),
            all.len()
        )));
    }
    let mut replies: Vec<Vec<u8>> = Vec::with_capacity(ranks);
    let mut at = 0;
    for n in counts {
        let mut w = Writer::new();
        for a in &answers[at..at + n] {
            for v in a {
                w.f32(*v);
            }
        }
        at += n;
        replies.push(w.into_bytes());
    }
    let back = comm.exchange(replies)?;
    let mut tiles: Vec<(usize, Vec<f32>)> = owned
        .iter()
        .zip(done)
        .map(|(&t, (px, _))| (t, px))
        .collect();
    for (src, msg) in back.iter().enumerate() {
        let mut r = Reader::new(msg);
        for &(i, p) in &pending[src] {
            let px = &mut tiles[i].1[4 * p..4 * p + 4];
            for c in &mut px[..3] {
                *c += r.f32()?;
            }
            px[3] = r.f32()?;
        }
    }
    Ok(OwnedTiles {
        grid: *grid,
        channels: 4,
        tiles,
    })
}

/// Adds every rank's `values` (`channels` per pixel, row-major) tile by
/// tile at the tiles' owners, in rank order; returns this rank's tiles.
pub fn sum(
    comm: &dyn Comm,
    grid: &TileGrid,
    values: &[f32],
    channels: usize,
) -> Result<OwnedTiles, CommError> {
    let ranks = comm.size();
    let got = comm.exchange(fragments(grid, values, channels, ranks))?;
    let owned: Vec<usize> = grid.owned(comm.rank(), ranks).collect();
    let frags = received(&got, &owned, grid, channels)?;
    let tiles = owned
        .iter()
        .zip(frags)
        .map(|(&t, fr)| {
            let (_, _, w, h) = grid.rect(t);
            let mut acc = vec![0.0f64; (w * h) as usize * channels];
            // `received` keeps source order: the sum's order is fixed.
            for (_, v) in &fr {
                for (a, x) in acc.iter_mut().zip(f32s_of(v).iter()) {
                    *a += *x as f64;
                }
            }
            (t, acc.into_iter().map(|a| a as f32).collect())
        })
        .collect();
    Ok(OwnedTiles {
        grid: *grid,
        channels,
        tiles,
    })
}

/// The whole image on rank 0 (row-major, `channels` per pixel), `None` on
/// the others; tiles that are zero are not sent.
pub fn gather(comm: &dyn Comm, owned: &OwnedTiles) -> Result<Option<Vec<f32>>, CommError> {
    let ranks = comm.size();
    let mut mine = Vec::new();
    for (t, v) in &owned.tiles {
        if v.iter().any(|&x| x != 0.0) {
            mine.extend_from_slice(&(*t as u32).to_le_bytes());
            put_f32s(&mut mine, v);
        }
    }
    let mut send = vec![Vec::new(); ranks];
    send[0] = mine;
    let got = comm.exchange(send)?;
    if comm.rank() != 0 {
        return Ok(None);
    }
    let g = &owned.grid;
    let ch = owned.channels;
    let mut image = vec![0.0f32; (g.width * g.height) as usize * ch];
    for msg in &got {
        let mut at = 0;
        while at < msg.len() {
            let bad =
                || CommError::Transport("a gathered tile is cut short or out of the image".into());
            let head = msg.get(at..at + 4).ok_or_else(bad)?;
            let t = u32::from_le_bytes([head[0], head[1], head[2], head[3]]) as usize;
            if t >= g.count() {
                return Err(bad());
            }
            let (x0, y0, w, h) = g.rect(t);
            let n = w as usize * ch;
            let values = f32s_of(
                msg.get(at + 4..at + 4 + 4 * n * h as usize)
                    .ok_or_else(bad)?,
            );
            for r in 0..h as usize {
                let row = ((y0 as usize + r) * g.width as usize + x0 as usize) * ch;
                image[row..row + n].copy_from_slice(&values[r * n..(r + 1) * n]);
            }
            at += 4 + 4 * n * h as usize;
        }
    }
    Ok(Some(image))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run_local;

    /// A ray through `k` slabs of opacity `a` and colour `c` each, composited
    /// one sample at a time with early termination.
    fn reference(slabs: &[(f32, f32)], et: f32) -> [f32; 4] {
        let (mut c, mut a) = (0.0f32, 0.0f32);
        for &(sc, sa) in slabs {
            if a >= et {
                break;
            }
            c += (1.0 - a) * sa * sc;
            a += (1.0 - a) * sa;
        }
        [c, c, c, a]
    }

    #[test]
    fn over_with_early_termination_matches_one_ray() {
        // Pixel (x, 0) of rank r holds slab r of pixel x; ten slabs per
        // pixel, five per rank... each rank renders a run of samples.
        let samples: Vec<(f32, f32)> = (0..12).map(|i| (0.1 * i as f32, 0.25)).collect();
        let et = 0.9;
        let width = 5u32;
        for ranks in 1..=4 {
            let out = run_local(ranks, |comm| {
                // Rank r owns samples [r*12/K, (r+1)*12/K); pixel x starts at sample x.
                let mine = |x: u32, from_alpha: f32| {
                    let lo = comm.rank() * 12 / ranks;
                    let hi = (comm.rank() + 1) * 12 / ranks;
                    let (mut c, mut a) = (0.0f32, from_alpha);
                    for &(sc, sa) in &samples[(lo.max(x as usize))..hi.max(x as usize)] {
                        if a >= et {
                            break;
                        }
                        c += (1.0 - a) * sa * sc;
                        a += (1.0 - a) * sa;
                    }
                    [c, c, c, a]
                };
                let image: Vec<[f32; 4]> = (0..width).map(|x| mine(x, 0.0)).collect();
                let grid = TileGrid::new(width, 1, 2);
                let order: Vec<usize> = (0..ranks).collect();
                let tiles = over(comm, &grid, &image, &order, et, &mut |req| {
                    req.iter().map(|&(x, _, a)| mine(x, a)).collect()
                })
                .unwrap();
                gather(comm, &tiles).unwrap()
            });
            let image = out[0].as_ref().unwrap();
            for x in 0..width as usize {
                let want = reference(&samples[x..], et);
                for k in 0..4 {
                    assert!(
                        (image[4 * x + k] - want[k]).abs() < 1e-6,
                        "{ranks} ranks, pixel {x}: {:?} vs {want:?}",
                        &image[4 * x..4 * x + 4]
                    );
                }
            }
        }
    }

    #[test]
    fn sum_adds_every_rank_and_skips_nothing() {
        let out = run_local(3, |comm| {
            let grid = TileGrid::new(7, 5, 3);
            let v: Vec<f32> = (0..35)
                .map(|i| if i % 3 == comm.rank() { i as f32 } else { 0.0 })
                .collect();
            let tiles = sum(comm, &grid, &v, 1).unwrap();
            gather(comm, &tiles).unwrap()
        });
        let image = out[0].as_ref().unwrap();
        assert_eq!(image, &(0..35).map(|i| i as f32).collect::<Vec<_>>());
        assert!(out[1].is_none());
    }
}
