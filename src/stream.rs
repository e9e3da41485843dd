//! Projections streamed from files: column densities of a particle file
//! summed chunk by chunk, never holding the particles, their order or a
//! BVH — peak memory is the image and one chunk, whatever the file's size.
//!
//! Which scenes stream: particles from files whose readers read a range of
//! rows — `.npy` positions (with radii and weights given as `.npy`),
//! Gadget binary, Tipsy and HDF5 (SWIFT, Gadget, AREPO, GIZMO, PySPH)
//! files with the per-particle arrays as their columns; one snapshot type
//! — with a global radius or per-particle radii (a snapshot's smoothing
//! lengths), no radius or weight map, and a projection over the whole line
//! (no `depth`). Everything else — radii from neighbours or the spacing,
//! which need every particle at once; text and VTK tables, species and
//! regions; several types; slabs — takes the in-memory path
//! ([`crate::PlacedData::project`]). A snapshot's kernel, units, masses
//! and periodic box are the loader's, read with every chunk.
//!
//! The result is the in-memory projection's: the same frame (chosen from
//! the whole set's reach in a first pass), the same local positions,
//! radii and weights (the loader's own conversions, chunk by chunk), the
//! same view, and the same splatter ([`voxless_particles::splat`]); only
//! the order in which particles are summed differs (file order here, the
//! volume's Hilbert order there), so the images agree to f32 rounding of
//! the sums (tested to 1e-6 of the peak).
//!
//! Under mpirun ([`project_ranks`]) each rank streams an even share of
//! the chunks (the same count on every rank) into an image of its own; the
//! passes' findings — the reach, the bounds, the periodic span and wrap
//! count, the mass — are combined over the ranks, an error in one rank's
//! share is an error on all, and the images are added on rank 0 in rank
//! order (f64 sums of f32 images: one process's image within 1e-6 of
//! its peak, tested).
//! Each rank holds the image and a chunk, however many particles.
//!
//! Passes over the file: with a periodic box one, the splatting pass (the
//! frame is the box's; the span and wrap count are taken on the way, and a
//! set wider than a given box is handed to the in-memory path, which
//! refuses it); without one, a pass for the reach (the frame), one for the
//! local bounds the view needs, and the splatting pass. Each pass reads
//! its chunks on every core; the splatting pass reads the next group of
//! chunks while it splats one.

use std::path::Path;
use std::sync::Mutex;

use rayon::prelude::*;

use voxless_core::{Aabb, Control, Vec3};
use voxless_parallel::{Comm, CommExt, TileGrid, composite};
use voxless_particles::check_data;
use voxless_particles::neighbours::PeriodicBox;
use voxless_particles::splat::{CHUNK, SplatParticle, Splatter};

use crate::device::Device;
use voxless_scene::{ParticlesDesc, SceneDesc};

use crate::load::particles::{self as load, FrameData};
use crate::load::{Share, periodic};
use crate::projection::{ProjectionDesc, ProjectionView};
use crate::{ParallelError, SceneError};

/// A projection streamed from its files.
pub struct Streamed {
    pub view: ProjectionView,
    /// Column densities in world units, row-major, row 0 at the top (on
    /// rank 0 of [`project_ranks`]; empty on the others).
    pub column: Vec<f32>,
    /// `∫ field dV` of all the particles, in world units.
    pub mass: f64,
    /// The particles in the file, and the chunks they were read in (over
    /// every rank).
    pub particles: usize,
    pub chunks: usize,
    /// The particles this process read (its share under
    /// [`project_ranks`]; all of them for one process).
    pub read: usize,
    /// What the loader would say (the periodic box, the wrap).
    pub notes: Vec<String>,
}

/// Projects frame `frame` of the data `desc` names through `projection` at
/// `w` × `h`, streaming the particles from their files, when the scene can
/// be streamed (module docs); `Ok(None)` when it cannot (nothing was
/// written; the in-memory path gives the same image and any error).
pub fn project(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    projection: &ProjectionDesc,
    (w, h): (u32, u32),
    control: &Control,
) -> Result<Option<Streamed>, SceneError> {
    project_on(
        desc,
        base,
        frame,
        projection,
        (w, h),
        &Device::cpu(),
        control,
    )
}

/// [`project`] with the splats summed on `device` (see
/// [`voxless_particles::splat::SplatDevice`]).
pub fn project_on(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    projection: &ProjectionDesc,
    size: (u32, u32),
    device: &Device,
    control: &Control,
) -> Result<Option<Streamed>, SceneError> {
    stream(
        Split(None),
        desc,
        base,
        frame,
        projection,
        size,
        device,
        control,
    )
    .map_err(|e| match e {
        ParallelError::Scene(e) => e,
        // (No communicator: no other error; worded as a setting if one came.)
        e => SceneError::setting("project", e.to_string()),
    })
}

/// [`project`] split over the ranks of `comm` (every rank calls it): each
/// rank streams an even, contiguous share of the file's chunks into an
/// image of its own, what the passes learn (the reach, the bounds, the
/// periodic span and wraps, the mass) is combined over the ranks, and the
/// images are added on rank 0 in rank order. Peak memory on every rank is
/// the image and a chunk, whatever the file's size; the image equals one
/// process's to f32 rounding of the sums' order. `column` is the whole
/// image on rank 0 and empty on the others; `Ok(None)` on every rank when
/// the scene cannot stream, and an error on one rank (its share's bad row)
/// is an error on all of them.
pub fn project_ranks(
    comm: &dyn Comm,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    projection: &ProjectionDesc,
    size: (u32, u32),
    control: &Control,
) -> Result<Option<Streamed>, ParallelError> {
    let cpu = Device::cpu();
    stream(
        Split(Some(comm)),
        desc,
        base,
        frame,
        projection,
        size,
        &cpu,
        control,
    )
}

/// How a streamed projection is split: one process reads every chunk;
/// under a communicator each rank reads its share (see [`project_ranks`]).
#[derive(Clone, Copy)]
struct Split<'c>(Option<&'c dyn Comm>);

impl Split<'_> {
    fn ranks(self) -> usize {
        self.0.map_or(1, |c| c.size())
    }

    /// The chunks this rank reads, in file order.
    fn share(self, chunks: usize) -> std::ops::Range<usize> {
        match self.0 {
            None => 0..chunks,
            Some(c) => chunks * c.rank() / c.size()..chunks * (c.rank() + 1) / c.size(),
        }
    }

    /// A step's outcome on every rank: this rank's error, else another
    /// rank's, else the local value.
    fn agree<T>(self, local: Result<T, SceneError>) -> Result<T, ParallelError> {
        match self.0 {
            None => Ok(local?),
            Some(c) => Ok(c.agree(local)??),
        }
    }

    /// What every rank's share taught (spans and reaches joined, wraps
    /// added).
    fn scan(self, s: Scan) -> Result<Scan, ParallelError> {
        let Some(c) = self.0 else { return Ok(s) };
        let reach = s.reach.unwrap_or(periodic::EMPTY_SPAN);
        let lo = c.all_min(&[s.span.0, reach.0].concat())?;
        let hi = c.all_max(&[s.span.1, reach.1].concat())?;
        let three = |v: &[f64]| [v[0], v[1], v[2]];
        let reach = (three(&lo[3..]), three(&hi[3..]));
        Ok(Scan {
            span: (three(&lo), three(&hi)),
            wrapped: c.all_sum(&[s.wrapped as f64])?[0] as usize,
            // An empty reach stays inverted (every rank's was).
            reach: (reach.0[0] <= reach.1[0]).then_some(reach),
        })
    }

    /// The union of every rank's bounds.
    fn bounds(self, b: Aabb) -> Result<Aabb, ParallelError> {
        let Some(c) = self.0 else { return Ok(b) };
        let lo = c.all_min(&b.min.to_array().map(f64::from))?;
        let hi = c.all_max(&b.max.to_array().map(f64::from))?;
        let v = |v: &[f64]| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        Ok(Aabb {
            min: v(&lo),
            max: v(&hi),
        })
    }

    fn sum(self, x: f64) -> Result<f64, ParallelError> {
        match self.0 {
            None => Ok(x),
            Some(c) => Ok(c.all_sum(&[x])?[0]),
        }
    }

    /// The ranks' images added (on rank 0; empty on the others).
    fn image(self, mine: Vec<f32>, (w, h): (u32, u32)) -> Result<Vec<f32>, ParallelError> {
        let Some(c) = self.0 else { return Ok(mine) };
        let grid = TileGrid::new(w, h, crate::parallel::COMPOSITE_TILE);
        let tiles = composite::sum(c, &grid, &mine, 1)?;
        Ok(composite::gather(c, &tiles)?.unwrap_or_default())
    }
}

/// [`project_on`] and [`project_ranks`]: the passes over this rank's
/// chunks, combined over the ranks (module docs).
#[allow(clippy::too_many_arguments)]
fn stream(
    split: Split,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    projection: &ProjectionDesc,
    (w, h): (u32, u32),
    device: &Device,
    control: &Control,
) -> Result<Option<Streamed>, ParallelError> {
    let Some(p) = streamable(desc, projection) else {
        return Ok(None);
    };
    // No rows: the row count, the file's box, kernel and notes, and which
    // per-particle arrays there are (the other files checked). The same
    // files on every rank: the same outcome.
    let Some(first) = load::rows_of(
        p,
        base,
        frame,
        Share {
            rank: 0,
            ranks: usize::MAX,
        },
    )?
    else {
        return Ok(None);
    };
    // Radii from neighbours or the spacing need every particle.
    if p.radius.is_none() && first.data.radii.is_none() {
        return Ok(None);
    }
    let total = first.total;
    // As many chunks on every rank, each of at most CHUNK rows.
    let ranks = split.ranks();
    let chunks = ranks * total.div_ceil(ranks * CHUNK).max(1);
    let mine = split.share(chunks);
    let kernel = first.kernel(p);
    let boxed = periodic::resolve_box(p, first.periodic)?;
    // Each chunk with the box the loader settles on (the file's may be
    // ignored with --no-box, or replaced by a given one).
    let read = |k: usize| -> Result<FrameData, SceneError> {
        let mut fd = load::rows_of(
            p,
            base,
            frame,
            Share {
                rank: k,
                ranks: chunks,
            },
        )?
        .ok_or_else(|| {
            SceneError::setting("particles.file", "the files changed while being read")
        })?;
        fd.periodic = boxed.as_ref().map(|(b, _)| *b);
        Ok(fd)
    };
    let (has_radii, mut notes) = (first.data.radii.is_some(), first.notes);

    // Pass 1, without a periodic box: the world reach (the frame), the
    // chunks read on every core and combined in order. With a box the
    // frame is the box's; the span and wrap count are taken while
    // splatting (pass 3), and a set wider than the box is sent to the
    // in-memory path.
    let mut seen = Scan::EMPTY;
    if boxed.is_none() {
        let scans = mine
            .clone()
            .into_par_iter()
            .map(|k| read(k).map(|fd| Scan::of(&fd, p, boxed.as_ref())))
            .collect::<Vec<_>>();
        let local = scans.into_iter().try_fold(Scan::EMPTY, |mut seen, scan| {
            seen.merge(scan?);
            Ok(seen)
        });
        seen = split.scan(split.agree(local)?)?;
    }
    // Particles spanning more than a given box are refused (or wrapped with
    // --wrap) by the loader, which words it: such a set does not stream.
    let too_wide = |scan: &Scan| match &boxed {
        Some((b, true)) if p.wrap != Some(true) => {
            let span = scan.span;
            (0..3).any(|a| span.1[a] - span.0[a] > b.size[a] * (1.0 + 1e-6))
        }
        _ => false,
    };
    let reach = match &boxed {
        Some((b, _)) => Some(periodic::corners(b)),
        None => seen.reach,
    };
    let world = load::frame_for(reach);
    let local_box = load::local_box(boxed.as_ref().map(|b| &b.0), &world);
    // The global radius in the frame (validated as the loader does; the
    // default from the spacing never applies: a radius or radii are given).
    let radius = load::particle_settings(
        p,
        kernel,
        has_radii,
        &mut |_| (1.0, String::new()),
        world.scale,
        &mut Vec::new(),
    )?
    .radius;
    // The buffers of splatted chunks, reused by the chunks prepared after
    // them: freed and allocated afresh, megabytes a chunk went back to the
    // kernel and returned as zeroed pages (10–15 % of a 10⁷-particle run).
    let spare: Mutex<Vec<(Vec<Vec3>, Vec<SplatParticle>)>> = Mutex::new(Vec::new());
    let take_spare = || spare.lock().unwrap_or_else(|e| e.into_inner()).pop();
    let give_back = |c: Prepared| {
        let mut spare = spare.lock().unwrap_or_else(|e| e.into_inner());
        spare.push((c.local, c.particles));
    };
    // Each chunk as the loader prepares it: wrapped (world), placed in the
    // frame, scaled, local radii and weights. (The loader's notes were said
    // once above, for the whole set.)
    let prepare = |k: usize| -> Result<Prepared, SceneError> {
        let mut fd = read(k)?;
        let mut scan = boxed.is_some().then(|| Scan::of(&fd, p, boxed.as_ref()));
        if scan.as_ref().is_some_and(&too_wide) {
            // The in-memory path refuses it, naming the whole set's span.
            return Ok(Prepared {
                particles: Vec::new(),
                local: Vec::new(),
                offset: fd.offset,
                scan,
                mass: 0.0,
            });
        }
        // The loader's wrap (`periodic::settle` of a share: no region, no
        // neighbours; the span it checks against a given box is the
        // scan's, checked above), counted for the box's note.
        if let (Some((b, _)), Some(scan)) = (&boxed, scan.as_mut()) {
            scan.wrapped = periodic::wrap_into(&mut fd.positions, b);
        }
        let (offset, fd_kernel) = (fd.offset, fd.sph_defaults);
        let (local, mut particles) = take_spare().unwrap_or_default();
        let (mut data, main_file, files) = fd.place_into(&world, local);
        load::prepare_arrays(&mut data, p, fd_kernel, world.scale)?;
        check_data(&data, offset).map_err(|e| load::blame(main_file, &files, e))?;
        particles.clear();
        particles.extend((0..data.positions.len()).map(|i| {
            let c = data.positions[i];
            SplatParticle {
                // The volume wraps its local positions once more.
                center: local_box.map_or(c, |b| voxless_particles::wrap(&b, c)),
                radius: data.radii.as_ref().map_or(radius, |r| r[i]),
                weight: data.weights.as_ref().map_or(1.0, |w| w[i]),
            }
        }));
        let mass = particles
            .iter()
            .filter(|q| q.radius > 0.0)
            .map(|q| q.weight as f64 * kernel.integral(q.radius as f64))
            .sum::<f64>();
        Ok(Prepared {
            particles,
            local: data.positions,
            offset,
            scan,
            mass,
        })
    };

    // Pass 2 (no box): the volume's bounds, the union of the supports.
    let bounds = match local_box {
        Some(b) => b,
        None => {
            let factor = kernel.support_factor();
            let parts = mine
                .clone()
                .into_par_iter()
                .map(|k| -> Result<Aabb, SceneError> {
                    let mut b = Aabb::EMPTY;
                    let c = prepare(k)?;
                    for q in c.particles.iter().filter(|q| q.radius > 0.0) {
                        let s = factor * q.radius;
                        b = b.union(Aabb::around(q.center, (s * s).sqrt()));
                    }
                    give_back(c);
                    Ok(b)
                })
                .collect::<Vec<_>>();
            let local = parts
                .into_iter()
                .try_fold(Aabb::EMPTY, |b, part| part.map(|part| b.union(part)));
            split.bounds(split.agree(local)?)?
        }
    };
    let view = ProjectionView::new(projection, &bounds, &world)?;
    let Some(splatter) = Splatter::new(&view.camera, w, h, kernel, local_box) else {
        return Ok(None);
    };
    let mut splatter = splatter.with_pixels(crate::projection::pixel_integral(p.pixels));
    if let Some(d) = device.splat_device() {
        splatter = splatter
            .with_device(d)
            .map_err(|e| SceneError::setting("device", e.to_string()))?;
    }

    // Pass 3: splat chunk by chunk, in file order (the image's bits depend
    // on it). A group of chunks (one a core) is prepared on every core
    // while the group before it is splatted, so reading and converting
    // overlap the splatting; two groups are held at most.
    let group = rayon::current_num_threads().max(1);
    let prepare_group = |k0: usize| -> Vec<Result<Prepared, SceneError>> {
        (k0..(k0 + group).min(mine.end))
            .into_par_iter()
            .map(prepare)
            .collect()
    };
    let mut mass = 0.0;
    let mut splat_share = || -> Result<(), SceneError> {
        let mut next = (!mine.is_empty()).then(|| prepare_group(mine.start));
        let mut k0 = mine.start;
        while let Some(current) = next.take() {
            let k1 = k0 + current.len();
            let (ahead, added) = rayon::join(
                || (k1 < mine.end && !control.is_cancelled()).then(|| prepare_group(k1)),
                || -> Result<(), SceneError> {
                    for (k, c) in (k0..).zip(current) {
                        let mut c = c?;
                        if let Some(scan) = c.scan.take() {
                            seen.merge(scan);
                            if too_wide(&seen) {
                                return Ok(());
                            }
                        }
                        mass += c.mass;
                        splatter.add(&c.particles, c.offset, control).map_err(|e| {
                            let field = match e {
                                voxless_particles::ParticleError::Device(_) => "device",
                                _ => "particles.radius",
                            };
                            SceneError::setting(field, e.to_string())
                        })?;
                        give_back(c);
                        if control.is_cancelled() {
                            return Err(SceneError::setting("project", "cancelled"));
                        }
                        control.report((k - mine.start) as u64 + 1, mine.len() as u64);
                    }
                    Ok(())
                },
            );
            added?;
            if too_wide(&seen) {
                return Ok(());
            }
            if k1 < mine.end && ahead.is_none() {
                // Cancelled after the group's last check.
                return Err(SceneError::setting("project", "cancelled"));
            }
            next = ahead;
            k0 = k1;
        }
        Ok(())
    };
    split.agree(splat_share())?;
    // With a box the spans and wraps were taken while splatting: the whole
    // set's, over every rank's share.
    if boxed.is_some() {
        seen = split.scan(seen)?;
    }
    if too_wide(&seen) {
        return Ok(None);
    }
    if let Some((b, given)) = &boxed {
        notes.push(periodic::box_note(
            b,
            *given,
            seen.wrapped,
            total,
            seen.span,
        ));
    }
    let mine_image = splatter
        .finish()
        .map_err(|e| SceneError::setting("device", e.to_string()));
    let column = split.image(split.agree(mine_image)?, (w, h))?;
    Ok(Some(Streamed {
        view,
        column: world.columns_to_world(column),
        mass: split.sum(mass)? * world.scale.powi(3),
        particles: total,
        chunks,
        // (Chunk k holds rows total·k/chunks up to the next one's.)
        read: total * mine.end / chunks - total * mine.start / chunks,
        notes,
    }))
}

/// A projection of the data a description names, for a front-end that
/// holds no volume (Python's `voxless.project`): see [`project_file`].
pub struct FileProjection {
    pub view: ProjectionView,
    /// Column densities in world units, row-major, row 0 at the top.
    pub column: Vec<f32>,
    /// `∫ field dV` in world units, when known.
    pub mass: Option<f64>,
    /// What the loader and the projection said.
    pub notes: Vec<String>,
    /// The chunks the particles were streamed in; `None` when the data
    /// was loaded whole.
    pub chunks: Option<usize>,
}

/// Projects frame `frame` of the data `desc` names at `w` × `h` on
/// `device`, the way the CLI's one-process `project` does: streamed from
/// the files when the scene can be ([`project_on`]: peak memory the image
/// and a chunk), else loaded whole and projected in memory (the same
/// image to f32 rounding of the sums' order). The inner error is a
/// cancelled projection.
pub fn project_file(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    projection: &ProjectionDesc,
    (w, h): (u32, u32),
    device: &Device,
    control: &Control,
) -> Result<Result<FileProjection, voxless_core::Cancelled>, SceneError> {
    match project_on(desc, base, frame, projection, (w, h), device, control) {
        Ok(Some(s)) => {
            return Ok(Ok(FileProjection {
                view: s.view,
                column: s.column,
                mass: Some(s.mass),
                notes: s.notes,
                chunks: Some(s.chunks),
            }));
        }
        Ok(None) => {}
        // The stream words a cancelled projection as a setting.
        Err(_) if control.is_cancelled() => return Ok(Err(voxless_core::Cancelled)),
        Err(e) => return Err(e),
    }
    let loaded = crate::load::load_for(desc, base, frame, crate::load::Purpose::Project)?;
    let mut notes = loaded.notes.clone();
    let projected = loaded.project_on(projection, (w, h), None, device, control, &mut notes)?;
    Ok(projected.map(|(view, column)| FileProjection {
        view,
        column,
        mass: loaded.total_mass(),
        notes,
        chunks: None,
    }))
}

/// What pass 1 learns from one chunk.
struct Scan {
    span: periodic::Span,
    wrapped: usize,
    reach: Option<periodic::Span>,
}

impl Scan {
    const EMPTY: Scan = Scan {
        span: periodic::EMPTY_SPAN,
        wrapped: 0,
        reach: None,
    };

    /// A chunk's span, and without a periodic box (`boxed`) its world
    /// reach (with one, the wrap count is taken while wrapping).
    fn of(fd: &FrameData, p: &ParticlesDesc, boxed: Option<&(PeriodicBox, bool)>) -> Scan {
        let mut scan = Scan::EMPTY;
        for q in &fd.positions {
            periodic::extend_span(&mut scan.span, q);
        }
        // With a box, the wrap count is taken while wrapping.
        if boxed.is_none() {
            scan.reach = fd.world_reach(p);
        }
        scan
    }

    /// Adds a later chunk's scan.
    fn merge(&mut self, other: Scan) {
        self.span = periodic::join_spans(self.span, other.span);
        self.wrapped += other.wrapped;
        if let Some(r) = other.reach {
            self.reach = Some(self.reach.map_or(r, |s| periodic::join_spans(s, r)));
        }
    }
}

/// One chunk's particles, local and ready to splat.
struct Prepared {
    particles: Vec<SplatParticle>,
    /// The chunk's local positions (a buffer to reuse once splatted).
    local: Vec<Vec3>,
    offset: usize,
    /// With a periodic box: what pass 1 would have learned of the chunk.
    scan: Option<Scan>,
    /// The chunk's `∫ field dV`, summed in its order (while the chunk is
    /// prepared: on the core that prepares it, not on the splatting
    /// path).
    mass: f64,
}

/// The particle description of a scene that may stream (module docs;
/// whether its file is read by rows and has radii is learnt by reading
/// none of its rows).
fn streamable<'a>(desc: &'a SceneDesc, projection: &ProjectionDesc) -> Option<&'a ParticlesDesc> {
    let p = desc.particles.as_ref()?;
    let plain = desc.amr.is_none()
        && desc.tets.is_none()
        && projection.depth.is_none()
        && p.demo != Some(true)
        && p.materials.is_none()
        // Several snapshot types are materials.
        && p.part_type.as_ref().is_none_or(|t| !t.0.contains(','))
        && p.species.is_none()
        && p.region.is_none()
        && p.neighbours.is_none()
        && p.radius_map.is_none()
        && p.weight_map.is_none();
    (plain && p.file.is_some()).then_some(p)
}
