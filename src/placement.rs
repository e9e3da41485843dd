//! Where a front-end holds a scene's data: all of it in this process, or a
//! share on each rank of a communicator ([`Placement`]). What a front-end
//! does with a scene — open it, check it, render, project, sample, move
//! through a time series — is written once over [`Placed`] (a resolved
//! scene) and [`PlacedData`] (data without a view, for projections); the
//! two ways of holding data differ only inside these types. Rank 0 gets
//! the results a front-end writes (`None` on the others), and a step that
//! fails on one rank fails on all of them ([`Placement::agree`]).

use std::path::Path;

use voxless_core::{Control, Image};

use crate::device::Device;
use voxless_parallel::{Comm, CommExt};
use voxless_render::RayStats;
use voxless_render::colorbar::ColorbarSpec;
use voxless_scene::SceneDesc;

use crate::load::{self, Loaded, Purpose};
use crate::parallel::{self, FramePlan, Part, PartCounts, Timings};
use crate::slice::SliceDesc;
use crate::{
    DistributedScene, Fields, ParallelError, ProjectionDesc, ProjectionView, Resolved, Scene,
    SceneError, VolumeKind, WorldFrame,
};

/// Where a scene's data is held.
#[derive(Clone, Copy)]
pub enum Placement<'c> {
    /// All of it, in this process.
    Process,
    /// A share on each rank of the communicator (every rank calls the same
    /// methods in the same order).
    Ranks(&'c dyn Comm),
}

/// A resolved scene, held as its [`Placement`] says.
pub enum Placed<'c> {
    Process(Scene),
    Ranks(&'c dyn Comm, DistributedScene),
}

/// Loaded data without a view (what a projection needs), held as its
/// [`Placement`] says.
pub enum PlacedData<'c> {
    Process(Loaded),
    Ranks(&'c dyn Comm, Part),
}

/// A finished render: the image (premultiplied linear RGBA) and what its
/// rays saw, for the checks ([`Placed::check_rendered`]).
pub struct Rendered {
    pub image: Image,
    pub seen: RayStats,
}

impl<'c> Placement<'c> {
    /// This process's rank and the number of ranks (0 of 1 for one
    /// process).
    pub fn rank(&self) -> usize {
        match self {
            Placement::Process => 0,
            Placement::Ranks(c) => c.rank(),
        }
    }

    pub fn ranks(&self) -> usize {
        match self {
            Placement::Process => 1,
            Placement::Ranks(c) => c.size(),
        }
    }

    /// Whether this process writes results (rank 0).
    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// Every rank's outcome of a step that may fail on some ranks only
    /// (rank 0 writing a file): the local outcome when every rank
    /// succeeded, else an error everywhere — this rank's own, or the
    /// failing rank's message.
    pub fn agree<T, E: std::fmt::Display>(
        &self,
        local: Result<T, E>,
    ) -> Result<Result<T, E>, ParallelError> {
        match self {
            Placement::Process => Ok(local),
            Placement::Ranks(c) => Ok(c.agree(local)?),
        }
    }

    /// Whether projections may sum on `device` here: under mpirun they
    /// run on the ranks' CPUs.
    pub fn check_device(&self, device: &Device) -> Result<(), SceneError> {
        if device.is_gpu() && matches!(self, Placement::Ranks(_)) {
            return Err(SceneError::setting(
                "device",
                "a projection under mpirun runs on the ranks' CPUs: use --device cpu",
            ));
        }
        Ok(())
    }

    /// Opens frame `frame` of the data `desc` names (paths relative to
    /// `base`) with every default filled, for renders and samples.
    pub fn open(
        &self,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
    ) -> Result<Placed<'c>, ParallelError> {
        Ok(match *self {
            Placement::Process => Placed::Process(Scene::open(desc, base, frame)?),
            Placement::Ranks(c) => {
                let s = DistributedScene::open(c, desc, base, frame, Purpose::Render)?;
                Placed::Ranks(c, s)
            }
        })
    }

    /// Opens the first of `frames` with the defaults taken over the series
    /// (see [`crate::series`]), and the description to load the others
    /// with ([`Placed::load_frame`]).
    pub fn open_series(
        &self,
        desc: &SceneDesc,
        base: &Path,
        frames: &[usize],
    ) -> Result<(Placed<'c>, SceneDesc), ParallelError> {
        Ok(match *self {
            Placement::Process => {
                let (s, series) = Scene::open_series(desc, base, frames)?;
                (Placed::Process(s), series)
            }
            Placement::Ranks(c) => {
                let (s, series) = DistributedScene::open_series(c, desc, base, frames)?;
                (Placed::Ranks(c, s), series)
            }
        })
    }

    /// Loads frame `frame` of the data `desc` names, without resolving a
    /// view (a projection needs none).
    pub fn load(
        &self,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
        purpose: Purpose,
    ) -> Result<PlacedData<'c>, ParallelError> {
        Ok(match *self {
            Placement::Process => PlacedData::Process(load::load_for(desc, base, frame, purpose)?),
            Placement::Ranks(c) => {
                PlacedData::Ranks(c, parallel::open_part(c, desc, base, frame, purpose, None)?)
            }
        })
    }

    /// How the ranks share the frames of a series (`frames` frame numbers of
    /// the data `desc` names): whole frames per rank when a frame fits a
    /// rank comfortably, else each frame over all ranks (see
    /// [`parallel::frame_plan`]); one process renders frame after frame.
    pub fn frame_plan(
        &self,
        desc: &SceneDesc,
        base: &Path,
        frames: &[usize],
    ) -> Result<FramePlan, ParallelError> {
        let Placement::Ranks(c) = *self else {
            return Ok(FramePlan::BySpace);
        };
        let k = c.size();
        let per_rank = parallel::available_bytes().map_or(0, |a| {
            a / parallel::ranks_on_this_node().unwrap_or(k).max(1) as u64
        });
        // Every rank reads its own memory: agree on the smallest.
        let per_rank = c.all_min(&[per_rank as f64])?[0] as u64;
        let bytes = frames
            .first()
            .map_or(u64::MAX, |&f| frame_bytes(desc, base, f));
        Ok(parallel::frame_plan(frames.len(), k, bytes, per_rank))
    }

    /// Rank 0's `flags`, on every rank (one process: `flags` itself).
    pub fn broadcast_flags(&self, flags: Vec<bool>) -> Result<Vec<bool>, ParallelError> {
        match self {
            Placement::Process => Ok(flags),
            Placement::Ranks(c) => {
                let bytes: Vec<u8> = flags.iter().map(|&f| f as u8).collect();
                Ok(c.broadcast(0, &bytes)?
                    .into_iter()
                    .map(|b| b != 0)
                    .collect())
            }
        }
    }

    /// Every rank's image (of a round of whole frames, one per rank; `None`
    /// from a rank without a frame), on rank 0 in rank order; empty on the
    /// others.
    pub fn gather_images(&self, mine: Option<Image>) -> Result<Vec<Option<Image>>, ParallelError> {
        match self {
            Placement::Process => Ok(vec![mine]),
            Placement::Ranks(c) => Ok(parallel::gather_images(*c, mine)?),
        }
    }

    /// Where the ranks' time went in a render (`timings`, this rank's),
    /// said by rank 0: the span of their rendering times, and compositing —
    /// the least of the ranks' compositing times, as a rank's includes
    /// waiting for slower renderers (`None` elsewhere, and for one process).
    pub fn timings_report(&self, timings: Timings) -> Result<Option<String>, ParallelError> {
        let Placement::Ranks(c) = self else {
            return Ok(None);
        };
        let all = c.all_gather_f64(&[timings.render, timings.composite])?;
        let most = |k: usize| all.iter().map(|v| v[k]).fold(0.0, f64::max);
        let least = |k: usize| all.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min);
        Ok(c.is_root().then(|| {
            format!(
                "ranks rendering their boxes: {:.3}–{:.3}s; compositing: {:.3}s",
                least(0),
                most(0),
                least(1)
            )
        }))
    }

    /// Each rank's peak memory and what it read and held (`counts`), said
    /// by rank 0 (`None` elsewhere, and for one process).
    pub fn memory_report(
        &self,
        counts: Option<PartCounts>,
    ) -> Result<Option<String>, ParallelError> {
        let Placement::Ranks(c) = self else {
            return Ok(None);
        };
        let counts = counts.unwrap_or_default();
        let peak = parallel::peak_rss_bytes().unwrap_or(0);
        let all = c.all_gather_f64(&[peak as f64, counts.read as f64, counts.held as f64])?;
        let mib = |b: f64| b / (1u64 << 20) as f64;
        let list: Vec<String> = all
            .iter()
            .enumerate()
            .map(|(r, v)| {
                format!(
                    "rank {r}: {:.0} MiB (read {}, held {})",
                    mib(v[0]),
                    v[1],
                    v[2]
                )
            })
            .collect();
        Ok(c.is_root()
            .then(|| format!("peak memory per rank: {}", list.join("; "))))
    }
}

/// Bytes of one frame's files (positions and per-particle arrays; other
/// data: unknown, the most).
fn frame_bytes(desc: &SceneDesc, base: &Path, frame: usize) -> u64 {
    let Some(p) = &desc.particles else {
        return u64::MAX;
    };
    let files = [&p.file, &p.attribute, &p.radii, &p.weights];
    files
        .into_iter()
        .flatten()
        .map(|spec| {
            let path = if crate::frames::is_sequence(spec, base) {
                crate::frames::file_numbered(spec, base, frame).ok()
            } else {
                Some(base.join(spec))
            };
            path.and_then(|p| std::fs::metadata(p).ok())
                .map_or(0, |m| m.len())
        })
        .sum()
}

impl<'c> Placed<'c> {
    /// See [`PlacedData::smoothing_lengths`].
    pub fn smoothing_lengths(&self) -> Result<Option<Vec<f32>>, ParallelError> {
        match self {
            Placed::Process(s) => Ok(Some(s.volume.smoothing_lengths(&s.frame)?)),
            Placed::Ranks(c, s) => radii_in_row_order(*c, s.radii.as_deref(), s.summary.kind),
        }
    }

    /// Where this scene's data is held.
    pub fn placement(&self) -> Placement<'c> {
        match self {
            Placed::Process(_) => Placement::Process,
            Placed::Ranks(c, _) => Placement::Ranks(*c),
        }
    }

    pub fn view(&self) -> &Resolved {
        match self {
            Placed::Process(s) => &s.view,
            Placed::Ranks(_, s) => &s.view,
        }
    }

    pub fn view_mut(&mut self) -> &mut Resolved {
        match self {
            Placed::Process(s) => &mut s.view,
            Placed::Ranks(_, s) => &mut s.view,
        }
    }

    /// Where the data's coordinates sit in the world.
    pub fn frame(&self) -> &WorldFrame {
        match self {
            Placed::Process(s) => &s.frame,
            Placed::Ranks(_, s) => &s.frame,
        }
    }

    /// The whole data's bounds in world coordinates.
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        match self {
            Placed::Process(s) => s.world_bounds(),
            Placed::Ranks(_, s) => s.world_bounds(),
        }
    }

    /// The data's kind.
    pub fn kind(&self) -> VolumeKind {
        match self {
            Placed::Process(s) => s.volume.volume_kind(),
            Placed::Ranks(_, s) => s.summary.kind,
        }
    }

    /// The whole data's fields.
    pub fn fields(&self) -> Fields {
        match self {
            Placed::Process(s) => s.fields(),
            Placed::Ranks(_, s) => s.fields.clone(),
        }
    }

    /// What this rank read and holds (decomposed scenes only).
    pub fn counts(&self) -> Option<PartCounts> {
        match self {
            Placed::Process(_) => None,
            Placed::Ranks(_, s) => Some(s.counts),
        }
    }

    /// An error when the render would take absurdly long or the field is 0
    /// everywhere; else a note when the step was raised.
    pub fn check_work(&self, desc: &SceneDesc) -> Result<Option<String>, ParallelError> {
        match self {
            Placed::Process(s) => Ok(s.check_work(desc)?),
            Placed::Ranks(c, s) => s.check_work(*c, desc),
        }
    }

    /// Renders all `spp` passes: the image on rank 0 (`None` on the
    /// others), adding where this rank's time went to `timings`.
    pub fn render(
        &self,
        control: &Control,
        timings: &mut Timings,
    ) -> Result<Option<Rendered>, ParallelError> {
        self.render_on(&Device::cpu(), control, timings, &mut Vec::new())
    }

    /// [`Placed::render`] on `device` (one process; ranks render on their
    /// CPUs and refuse a GPU), with what a front-end should say about the
    /// device added to `notes`.
    pub fn render_on(
        &self,
        device: &Device,
        control: &Control,
        timings: &mut Timings,
        notes: &mut Vec<String>,
    ) -> Result<Option<Rendered>, ParallelError> {
        if device.is_gpu() && matches!(self, Placed::Ranks(..)) {
            return Err(SceneError::setting(
                "device",
                "a render under mpirun runs on the ranks' CPUs: use --device cpu",
            )
            .into());
        }
        match self {
            Placed::Process(s) => {
                let t = std::time::Instant::now();
                let film = device.render_film(&s.volume, &s.view, control, notes)??;
                timings.render += t.elapsed().as_secs_f64();
                Ok(Some(Rendered {
                    image: film.resolve(),
                    seen: *film.stats(),
                }))
            }
            Placed::Ranks(c, s) => Ok(s
                .render_timed(*c, control, timings)?
                .map(|(image, seen)| Rendered { image, seen })),
        }
    }

    /// The checks of a finished render: iso-surfaces asked for but absent,
    /// an image that shows nothing at all.
    pub fn check_rendered(&self, r: &Rendered) -> Result<(), SceneError> {
        self.view()
            .check_image(self.world_bounds(), &r.seen, &r.image)
    }

    /// What a colour bar shows (see [`Resolved::colorbar`]).
    pub fn colorbar(&self, desc: &SceneDesc) -> ColorbarSpec {
        self.view().colorbar(self.fields().colour_name(desc))
    }

    /// Points the camera as `desc.camera` says.
    pub fn reaim(&mut self, desc: &SceneDesc) -> Result<(), SceneError> {
        let frame = *self.frame();
        self.view_mut().reaim(desc, &frame)
    }

    /// Moves the scene to frame `frame` of its series (`desc`: the series'
    /// description), keeping the view.
    pub fn load_frame(
        &mut self,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
    ) -> Result<(), ParallelError> {
        match self {
            Placed::Process(s) => Ok(s.load_frame(desc, base, frame)?),
            Placed::Ranks(c, s) => s.load_frame(*c, desc, base, frame),
        }
    }

    /// The fields at world `points` (rank 0's; the others may pass none):
    /// on rank 0 row-major `points × columns` ([`Fields::columns`]).
    pub fn sample(
        &self,
        points: &[[f64; 3]],
        gradient: bool,
    ) -> Result<Option<Vec<f32>>, ParallelError> {
        match self {
            Placed::Process(s) => Ok(Some(s.sample(points, gradient))),
            Placed::Ranks(c, s) => {
                let local: Vec<_> = points.iter().map(|&p| s.frame.to_local(p)).collect();
                s.sample(*c, &local, gradient)
            }
        }
    }
}

/// Every particle's radius parameter in world units, in row order, on
/// rank 0 (`None` on the others): one process's volume, or the rows'
/// radii the ranks of a decomposed set hold.
fn radii_in_row_order(
    comm: &dyn Comm,
    mine: Option<&crate::load::whole_set::RowRadii>,
    kind: VolumeKind,
) -> Result<Option<Vec<f32>>, ParallelError> {
    let local = mine.ok_or_else(|| {
        SceneError::setting(
            "particles",
            format!(
                "radii (--save-radii, smoothing_lengths) belong to one set of particles, not to {}",
                kind.name()
            ),
        )
    });
    let mine = crate::load::whole_set::agree(comm, local)?;
    let mut w = voxless_parallel::Writer::with_capacity(16 + 4 * mine.values.len());
    w.u64(mine.offset as u64);
    w.f32s(&mine.values);
    let all = comm.all_gather(&w.into_bytes())?;
    if comm.rank() != 0 {
        return Ok(None);
    }
    let mut rows: Vec<(usize, Vec<f32>)> = Vec::new();
    for msg in all {
        let mut r = voxless_parallel::Reader::new(&msg);
        rows.push((r.u64()? as usize, r.f32s()?));
    }
    rows.sort_by_key(|r| r.0);
    Ok(Some(rows.into_iter().flat_map(|r| r.1).collect()))
}

impl PlacedData<'_> {
    /// Every particle's radius parameter in world units, in the file's
    /// row order (rank 0; `None` on the others): what `--save-radii`
    /// writes (see [`AnyVolume::smoothing_lengths`]).
    pub fn smoothing_lengths(&self) -> Result<Option<Vec<f32>>, ParallelError> {
        match self {
            PlacedData::Process(l) => Ok(Some(l.volume.smoothing_lengths(&l.frame)?)),
            PlacedData::Ranks(c, p) => radii_in_row_order(*c, p.radii.as_deref(), p.summary.kind),
        }
    }

    /// What loading said.
    pub fn notes(&self) -> &[String] {
        match self {
            PlacedData::Process(l) => &l.notes,
            PlacedData::Ranks(_, p) => &p.notes,
        }
    }

    /// The data's kind.
    pub fn kind(&self) -> VolumeKind {
        match self {
            PlacedData::Process(l) => l.volume.volume_kind(),
            PlacedData::Ranks(_, p) => p.summary.kind,
        }
    }

    /// The whole data's bounds in world coordinates.
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        match self {
            PlacedData::Process(l) => l.frame.box_to_world(l.volume.bounds()),
            PlacedData::Ranks(_, p) => p.frame.box_to_world(p.summary.bounds),
        }
    }

    /// What this rank read and holds (decomposed data only).
    pub fn counts(&self) -> Option<PartCounts> {
        match self {
            PlacedData::Process(_) => None,
            PlacedData::Ranks(_, p) => Some(p.counts),
        }
    }

    /// The integral of the field over all space in world units, when one
    /// process holds a kind that knows it exactly.
    pub fn total_mass(&self) -> Option<f64> {
        match self {
            PlacedData::Process(l) => l.total_mass(),
            PlacedData::Ranks(..) => None,
        }
    }

    /// The fields at world `points`, exactly as [`Placed::sample`] gives
    /// them (rank 0; `None` on the others).
    pub fn sample(
        &self,
        points: &[[f64; 3]],
        gradient: bool,
    ) -> Result<Option<Vec<f32>>, ParallelError> {
        match self {
            PlacedData::Process(l) => {
                let local: Vec<_> = points.iter().map(|&p| l.frame.to_local(p)).collect();
                Ok(Some(l.volume.sample_points(&local, gradient)))
            }
            PlacedData::Ranks(c, p) => {
                let local: Vec<_> = points.iter().map(|&x| p.frame.to_local(x)).collect();
                let (part, d) = (p.volume.as_ref(), &p.decomposition);
                parallel::sample(*c, part, d, &p.fields, &local, gradient)
            }
        }
    }

    /// The data's fields.
    pub fn fields(&self) -> Fields {
        match self {
            PlacedData::Process(l) => l.volume.fields(),
            PlacedData::Ranks(_, p) => p.fields.clone(),
        }
    }

    /// The slice `slice` describes (see [`crate::slice`]) at `width` ×
    /// `height`: its plane, the name of the quantity shown and (rank 0;
    /// `None` on the others) its values, row-major. `progress` hears the
    /// rows done of all.
    pub fn slice(
        &self,
        desc: &SceneDesc,
        slice: &SliceDesc,
        size: (u32, u32),
        progress: &dyn Fn(u64, u64),
    ) -> Result<(ProjectionView, String, Option<Vec<f32>>), ParallelError> {
        let (bounds, frame) = match self {
            PlacedData::Process(l) => (l.volume.bounds(), &l.frame),
            PlacedData::Ranks(_, p) => (p.summary.bounds, &p.frame),
        };
        let mut sample = |pts: &[[f64; 3]]| self.sample(pts, false);
        let space = crate::slice::Space {
            fields: &self.fields(),
            bounds: &bounds,
            frame,
        };
        crate::slice::slice_with(&space, desc, slice, size, &mut sample, progress)
    }

    /// The projection `projection` describes over the data's bounds, and
    /// its column densities in world units at `width` × `height` (on rank
    /// 0; `None` on the others).
    pub fn project(
        &self,
        projection: &ProjectionDesc,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Result<(ProjectionView, Option<Vec<f32>>), ParallelError> {
        self.project_on(
            &Device::cpu(),
            projection,
            width,
            height,
            control,
            &mut Vec::new(),
        )
    }

    /// [`PlacedData::project`] with particle splats summed on `device`
    /// (one process), with what a front-end should say added to `notes`.
    pub fn project_on(
        &self,
        device: &Device,
        projection: &ProjectionDesc,
        width: u32,
        height: u32,
        control: &Control,
        notes: &mut Vec<String>,
    ) -> Result<(ProjectionView, Option<Vec<f32>>), ParallelError> {
        if let PlacedData::Ranks(c, _) = self {
            Placement::Ranks(*c).check_device(device)?;
        }
        match self {
            PlacedData::Process(l) => {
                let (view, column) =
                    l.project_on(projection, (width, height), None, device, control, notes)??;
                Ok((view, Some(column)))
            }
            PlacedData::Ranks(c, p) => {
                let view = ProjectionView::new(projection, &p.summary.bounds, &p.frame)?;
                let periodic = matches!(
                    p.fields,
                    Fields::Particles {
                        periodic: Some(_),
                        ..
                    }
                );
                if periodic && view.t_range.is_some() {
                    return Err(SceneError::setting(
                        "depth",
                        "a slab through the tiled periodic box is integrated by one process: \
                         run it without mpirun",
                    )
                    .into());
                }
                let (part, d) = (p.volume.as_ref(), &p.decomposition);
                let (cam, t) = (&view.camera, view.t_range);
                let local = parallel::project(*c, part, d, cam, width, height, t, control)?;
                let column = local.map(|c| p.frame.columns_to_world(c));
                Ok((view, column))
            }
        }
    }
}
