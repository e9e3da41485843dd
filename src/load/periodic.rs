//! Periodic boxes and smoothing lengths from neighbours, for particle sets.
//!
//! **The box** comes from the description (`particles.box`, `--box`) or,
//! unless `particles.periodic = false`, from the file where its format
//! states one as periodic (SWIFT/Gadget `BoxSize`, LAMMPS `pp` bounds,
//! extended-XYZ `Lattice` with `pbc`). Positions outside it are wrapped in
//! float64 world coordinates, with a note saying how many; data that spans
//! more than a box the description gives along an axis is refused as the
//! wrong box unless `particles.wrap` asks for the wrap anyway (a file's own
//! box is trusted).
//!
//! **Neighbours**: each particle's radius such that its support reaches its
//! N-th nearest neighbour, the particle itself counted, with minimum-image
//! distances in a box ([`voxless_particles::neighbours`]). Asked for with
//! `particles.neighbours`; the default for particle types of cosmological
//! snapshots that carry no smoothing length (dark matter, AREPO cells).
//! The radii are world lengths, like radii read from a file.

use rayon::prelude::*;
use std::path::Path;

use voxless_particles::Kernel;
use voxless_particles::neighbours::{PeriodicBox, smoothing_lengths};
use voxless_scene::ParticlesDesc;

use crate::SceneError;

/// The neighbour count of the default for snapshots without smoothing
/// lengths (the cubic spline's usual 32; swiftsimio's and yt's default).
pub const DEFAULT_NEIGHBOURS: usize = 32;

/// The periodic box `p` gives (with `true`), else the file's (`false`),
/// else none. Errors name the setting.
pub(crate) fn resolve_box(
    p: &ParticlesDesc,
    file_box: Option<PeriodicBox>,
) -> Result<Option<(PeriodicBox, bool)>, SceneError> {
    if let Some(b) = &p.periodic_box {
        let (lo, hi) = b.corners();
        if !lo.iter().chain(&hi).all(|v| v.is_finite()) || (0..3).any(|a| !(hi[a] > lo[a])) {
            return Err(SceneError::setting(
                "particles.box",
                format!(
                    "--box {}: a periodic box needs a side L > 0, or corners x0 y0 z0 x1 y1 z1 with each \
                     upper corner above the lower one",
                    match b {
                        voxless_scene::BoxDesc::Side(l) => format!("{l}"),
                        voxless_scene::BoxDesc::Corners(c) => c.map(|v| v.to_string()).join(" "),
                    }
                ),
            ));
        }
        return Ok(Some((box_of(lo, hi), true)));
    }
    if p.periodic == Some(false) {
        return Ok(None);
    }
    Ok(file_box
        .filter(|b| (0..3).all(|a| b.size[a] > 0.0 && b.lo[a].is_finite() && b.size[a].is_finite()))
        .map(|b| (b, false)))
}

/// The box and the radii of a set's rows, one process or one share: the
/// periodic box `p` or the file (`file_box`) gives, with `positions`
/// (world) wrapped into it, and — for every row at once (`whole`) — radii
/// from neighbours when asked for or by default (`snapshot` without
/// `radii`). Notes say what was chosen.
#[allow(clippy::too_many_arguments)]
pub(crate) fn settle(
    p: &ParticlesDesc,
    file_box: Option<PeriodicBox>,
    positions: &mut [[f64; 3]],
    radii: &mut Option<Vec<f32>>,
    (snapshot, whole): (bool, bool),
    kernel: Kernel,
    file: &Path,
    notes: &mut Vec<String>,
) -> Result<Option<PeriodicBox>, SceneError> {
    let periodic = match resolve_box(p, file_box)? {
        // A region cut out of the box: its particles, unwrapped around it,
        // are no longer periodic.
        Some((b, _)) if cut_out(p, &b, positions, notes) => None,
        Some((b, given)) => {
            let (wrapped, span) = wrap_positions(positions, &b, p, given, file)?;
            notes.push(box_note(&b, given, wrapped, positions.len(), span));
            Some(b)
        }
        None => None,
    };
    // Radii from neighbours need every row: the ranks of a decomposed set
    // find them together (`whole_set::neighbour_radii`).
    if whole && let Some(n) = neighbour_count(p, snapshot, radii.is_some(), positions.len())? {
        *radii = Some(neighbour_radii(
            positions,
            n,
            periodic.as_ref(),
            kernel,
            file,
            notes,
        )?);
    }
    Ok(periodic)
}

/// With `particles.region` narrower than the box `b` (with its margin),
/// moves every particle to its image nearest the region's centre and says
/// so; returns whether it did (the cutout is then not periodic).
fn cut_out(
    p: &ParticlesDesc,
    b: &PeriodicBox,
    positions: &mut [[f64; 3]],
    notes: &mut Vec<String>,
) -> bool {
    let Some(r) = super::snapshot::region(p) else {
        return false;
    };
    let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * (r.lo[a] + r.hi[a]));
    // The margin the reader kept must fit too.
    let fits = (0..3).all(|a| r.hi[a] - r.lo[a] + 2.0 * r.pad < b.size[a]);
    if !fits {
        notes.push(
            "--region spans (nearly) the whole periodic box: the box stays periodic".to_string(),
        );
        return false;
    }
    for q in positions.iter_mut() {
        for a in 0..3 {
            let l = b.size[a];
            q[a] = centre[a] + (q[a] - centre[a] + 0.5 * l).rem_euclid(l) - 0.5 * l;
        }
    }
    notes.push(format!(
        "--region cut out of the periodic box (side {:?}): particles moved to their image \
         nearest the region; the cutout is not periodic",
        b.size
    ));
    true
}

fn box_of(lo: [f64; 3], hi: [f64; 3]) -> PeriodicBox {
    PeriodicBox {
        lo,
        size: std::array::from_fn(|a| hi[a] - lo[a]),
    }
}

/// The box's corners.
pub(crate) fn corners(b: &PeriodicBox) -> ([f64; 3], [f64; 3]) {
    (b.lo, std::array::from_fn(|a| b.lo[a] + b.size[a]))
}

/// Wraps `positions` into `b` (float64, world); refuses data spanning more
/// than a box the user gave (`given`) along an axis unless `p.wrap` — a
/// file's own box is trusted (dumps hold atoms that drifted out between
/// re-wraps). Returns how many were wrapped and the span of the wrapped
/// positions. Non-finite positions are left for the volume's check.
fn wrap_positions(
    positions: &mut [[f64; 3]],
    b: &PeriodicBox,
    p: &ParticlesDesc,
    given: bool,
    file: &Path,
) -> Result<(usize, Span), SceneError> {
    // One pass wraps and takes both spans (each pass over a 16.7M-particle
    // set's 400 MB of f64 positions was 3 % of its load); on a refusal the
    // wrapped copy is dropped with the error.
    let (wrapped, (lo, hi), after) = wrap_and_span(positions, b);
    if given && p.wrap != Some(true) {
        for a in 0..3 {
            let span = hi[a] - lo[a];
            // A box edge's own rounding is allowed.
            if span > b.size[a] * (1.0 + 1e-6) {
                return Err(SceneError::data(
                    file,
                    format!(
                        "the particles span {span} along {}, more than the periodic box's side {} \
                         (particles.box, --box): give the right box, or ask for the wrap with \
                         --wrap (particles.wrap = true)",
                        ["x", "y", "z"][a],
                        b.size[a]
                    ),
                ));
            }
        }
    }
    Ok((wrapped, after))
}

/// Wraps the finite `positions` outside `b` into it; returns how many.
pub(crate) fn wrap_into(positions: &mut [[f64; 3]], b: &PeriodicBox) -> usize {
    wrap_and_span(positions, b).0
}

/// [`wrap_into`], in one pass with the span of the rows whose coordinates
/// are all finite before the wrap, and the span of the finite coordinates
/// after it. Blocks of rows whose span lies in the box (nearly all of a
/// wrapped snapshot's) take only their span: its corners in the box put
/// every row in it, and the span after equals the span before.
fn wrap_and_span(positions: &mut [[f64; 3]], b: &PeriodicBox) -> (usize, Span, Span) {
    const ROWS: usize = 4096;
    positions
        .par_chunks_mut(ROWS)
        .map(|rows| {
            let mut before = EMPTY_SPAN;
            let mut finite = true;
            for q in rows.iter() {
                if q.iter().all(|v| v.is_finite()) {
                    extend_span(&mut before, q);
                } else {
                    finite = false;
                }
            }
            if finite && b.contains(before.0) && b.contains(before.1) {
                return (0, before, before);
            }
            let (mut wrapped, mut after) = (0, EMPTY_SPAN);
            for q in rows.iter_mut() {
                let outside = q.iter().all(|v| v.is_finite()) && !b.contains(*q);
                if outside {
                    *q = b.wrap(*q);
                }
                extend_span(&mut after, q);
                wrapped += outside as usize;
            }
            (wrapped, before, after)
        })
        .reduce(
            || (0, EMPTY_SPAN, EMPTY_SPAN),
            |a, b| (a.0 + b.0, join_spans(a.1, b.1), join_spans(a.2, b.2)),
        )
}

/// A per-axis span `(lo, hi)` of coordinates.
pub(crate) type Span = ([f64; 3], [f64; 3]);

/// A span holding nothing (see [`extend_span`]).
pub(crate) const EMPTY_SPAN: Span = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);

/// The union of two spans (min and max are exact: any grouping of rows
/// gives a serial loop's span).
pub(crate) fn join_spans(a: Span, b: Span) -> Span {
    (
        std::array::from_fn(|k| a.0[k].min(b.0[k])),
        std::array::from_fn(|k| a.1[k].max(b.1[k])),
    )
}

/// Grows the per-axis span `(lo, hi)` by the finite coordinates of `q`.
pub(crate) fn extend_span(span: &mut Span, q: &[f64; 3]) {
    for (a, &v) in q.iter().enumerate() {
        // Selects, not a branch (the loop then needs no jump a coordinate):
        // a non-finite coordinate leaves the span as it is.
        let finite = v.is_finite();
        span.0[a] = span.0[a].min(if finite { v } else { f64::INFINITY });
        span.1[a] = span.1[a].max(if finite { v } else { f64::NEG_INFINITY });
    }
}

/// What a periodic box note says: the box, how many of `total` particles
/// were wrapped into it, and a question when the particles' `span` fills
/// under a hundredth of its side.
pub(crate) fn box_note(
    b: &PeriodicBox,
    given: bool,
    wrapped: usize,
    total: usize,
    (l, h): ([f64; 3], [f64; 3]),
) -> String {
    let (lo, hi) = corners(b);
    let mut s = format!(
        "periodic box ({}): [{lo:?}, {hi:?}]; the field sums every periodic image",
        if given { "given" } else { "the file's" }
    );
    if wrapped > 0 {
        s.push_str(&format!(
            "; {wrapped} of {total} particles lay outside it and were wrapped in"
        ));
    }
    let fill = (0..3)
        .map(|a| (h[a] - l[a]) / b.size[a])
        .fold(0.0f64, f64::max);
    if total > 1 && fill < 0.01 {
        s.push_str(&format!(
            "; the particles fill only {fill:.1e} of its side: is the box right (--box)?"
        ));
    }
    s
}

/// The neighbour count for these particles: the description's, or the
/// default for a snapshot without smoothing lengths (`snapshot`) when no
/// radius or radii are given. Refuses a count together with a radius.
pub(crate) fn neighbour_count(
    p: &ParticlesDesc,
    snapshot: bool,
    has_radii: bool,
    total: usize,
) -> Result<Option<usize>, SceneError> {
    match p.neighbours {
        Some(n) => {
            for (given, what) in [
                (p.radius.is_some(), "particles.radius (--radius)"),
                (p.radii.is_some(), "particles.radii (--radii)"),
            ] {
                if given {
                    return Err(SceneError::setting(
                        "particles.neighbours",
                        format!(
                            "give either neighbours (--neighbours) or {what}: both size the kernels"
                        ),
                    ));
                }
            }
            if n < 2 {
                return Err(SceneError::setting(
                    "particles.neighbours",
                    format!("--neighbours {n}: needs N ≥ 2 (the particle itself is counted)"),
                ));
            }
            Ok(Some(n))
        }
        // The default fits types with fewer particles (a few stars); one
        // particle alone has no neighbour and keeps the default radius.
        None if snapshot && !has_radii && p.radius.is_none() && p.radii.is_none() => {
            Ok((total >= 2).then_some(DEFAULT_NEIGHBOURS.min(total)))
        }
        None => Ok(None),
    }
}

/// The note of radii from neighbours: `(lo, median, hi)` of the radii and
/// the search's seconds.
pub(crate) fn radii_note(
    n: usize,
    periodic: bool,
    kernel: Kernel,
    (lo, mid, hi): (f64, f64, f64),
    seconds: f64,
) -> String {
    format!(
        "radii from the {n} nearest neighbours ({}the particle itself counted; {} kernel, support \
         {}·h): h from {lo:.4e} to {hi:.4e}, median {mid:.4e}; {seconds:.2} s (change with \
         --neighbours or --radius)",
        if periodic { "periodic distances, " } else { "" },
        kernel.name(),
        kernel.support_factor(),
    )
}

/// Each particle's radius parameter (world units) so that its support
/// reaches its `n`-th nearest neighbour, with a note saying so.
pub(crate) fn neighbour_radii(
    positions: &[[f64; 3]],
    n: usize,
    b: Option<&PeriodicBox>,
    kernel: Kernel,
    file: &Path,
    notes: &mut Vec<String>,
) -> Result<Vec<f32>, SceneError> {
    let start = std::time::Instant::now();
    let h = smoothing_lengths(positions, n, b, kernel).map_err(|e| SceneError::Particles {
        path: file.to_path_buf(),
        source: e,
    })?;
    let mut sorted = h.to_vec();
    sorted.sort_unstable_by(f64::total_cmp);
    let range = (
        sorted[0],
        sorted[sorted.len() / 2],
        sorted[sorted.len() - 1],
    );
    notes.push(radii_note(
        n,
        b.is_some(),
        kernel,
        range,
        start.elapsed().as_secs_f64(),
    ));
    Ok(h.into_iter().map(|v| v as f32).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The row-by-row wrap and spans the blocks' shortcut replaces.
    fn wrap_rows(positions: &mut [[f64; 3]], b: &PeriodicBox) -> (usize, Span, Span) {
        let (mut n, mut before, mut after) = (0, EMPTY_SPAN, EMPTY_SPAN);
        for q in positions.iter_mut() {
            let finite = q.iter().all(|v| v.is_finite());
            if finite {
                extend_span(&mut before, q);
            }
            if finite && !b.contains(*q) {
                *q = b.wrap(*q);
                n += 1;
            }
            extend_span(&mut after, q);
        }
        (n, before, after)
    }

    /// Blocks wholly inside the box, blocks with rows outside it, on its
    /// far faces and with non-finite coordinates: the same rows, count and
    /// spans (bit for bit) as wrapping row by row.
    #[test]
    fn blocks_wrap_as_rows_do() {
        let b = PeriodicBox {
            lo: [-1.0, 2.0, 0.0],
            size: [10.0, 5.0, 3.0],
        };
        let mut rng = voxless_core::SmallRng(12345);
        let mut next = || f64::from(rng.f());
        let n = 5 * 4096 + 123;
        let mut rows: Vec<[f64; 3]> = (0..n)
            .map(|_| std::array::from_fn(|a| b.lo[a] + next() * b.size[a]))
            .collect();
        // Block 1: one row outside; block 2: on the far face (outside) and
        // at the near one (inside); block 3: non-finite coordinates; the
        // last, short block: outside by several boxes.
        rows[4096 + 7] = [12.0, 3.0, 1.0];
        rows[2 * 4096 + 1] = [9.0, 7.0, 1.0];
        rows[2 * 4096 + 2] = [-1.0, 2.0, 0.0];
        rows[3 * 4096 + 5] = [f64::NAN, 3.0, 1.0];
        rows[3 * 4096 + 6] = [0.0, f64::INFINITY, 40.0];
        rows[n - 1] = [-35.5, 2.5, -7.25];
        let mut want = rows.clone();
        let expect = wrap_rows(&mut want, &b);
        let got = wrap_and_span(&mut rows, &b);
        assert_eq!(expect.0, 3, "wrapped rows");
        assert_eq!(got, expect);
        for (g, w) in rows.iter().zip(&want) {
            assert_eq!(g.map(f64::to_bits), w.map(f64::to_bits));
        }
        // A block wholly inside takes the shortcut and changes nothing.
        let mut inside = want[..4096].to_vec();
        let (count, before, after) = wrap_and_span(&mut inside, &b);
        assert_eq!((count, before), (0, after));
        assert_eq!(inside, want[..4096]);
    }
}
