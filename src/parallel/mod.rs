//! Data-parallel rendering: one scene decomposed over the ranks of a
//! communicator (MPI with the `mpi` feature, or K threads of one process),
//! rendering, projecting and sampling exactly what one process would.
//!
//! **Model.** Each rank reads a share of the data (rows of a `.npy`, cells
//! of an ExaBricks file, Lagrangian slabs of a tessellation), and the ranks
//! agree on the whole data's statistics — bounds, value ranges, the default
//! radius, the sampling step — from mergeable pieces (minima, maxima, probe
//! samples chosen by row number). A k-d tree over a sample of the data
//! ([`Decomposition`]) gives each rank one box of about equal work; every
//! rank sends each item to the boxes it reaches into — particles whose
//! kernel support overlaps a box, AMR cells whose basis support does, tets
//! whose bounds do — so each rank ends up holding exactly what reconstructs
//! its box, and never the whole data set. The view (camera, transfer
//! function, settings) is resolved from the whole data's summary, so it is
//! the one-process view.
//!
//! - **Render**: each rank renders the samples whose positions lie in its
//!   box ([`voxless_render::Domain`]: the sample lattice is fixed per ray,
//!   so the boxes split the one-process samples between them), pass by
//!   pass; the passes composite "over" in the camera's visibility order by
//!   direct send, with early termination reproduced exactly
//!   ([`voxless_parallel::composite`]).
//! - **Project**: each rank integrates the part of every pixel's line inside
//!   its box (tessellations: the tets whose centroids lie in it, whole), and
//!   the images add up.
//! - **Sample**: each point goes to the rank whose box holds it, which
//!   evaluates it with canonical sums — the same bits as one process.
//!
//! What a box cannot reproduce alone is refused by name under more than one
//! rank: iso-surfaces (a crossing between two samples in different boxes),
//! single scattering (shadow rays cross boxes), the tessellation's level of
//! detail and k-buffer (both approximate per box, not per ray).

mod amr;
#[cfg(feature = "mpi")]
mod mpi_comm;
mod particles;
mod render;
mod share;
mod tets;
mod view;

pub(crate) use render::render_part;

use std::path::Path;

use voxless_core::{Aabb, Camera, Control, Image, Vec3};
use voxless_render::RenderSettings;
use voxless_scene::SceneDesc;
use voxless_transfer::TransferFunction;

#[cfg(feature = "mpi")]
pub use mpi_comm::MpiComm;
pub use voxless_parallel::memory::{available_bytes, peak_rss_bytes, ranks_on_this_node};
pub use voxless_parallel::{
    Comm, CommError, CommExt, Decomposition, LocalComm, SingleComm, run_local,
};

use crate::{AnyVolume, SceneError, VolumeSummary, WorldFrame};
use share::agree;

/// Why a decomposed scene failed: the scene (the same error one process
/// gives), or the ranks' communication.
#[derive(Debug, thiserror::Error)]
pub enum ParallelError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Comm(#[from] CommError),
    #[error("cancelled")]
    Cancelled,
}

impl From<voxless_parallel::WireError> for ParallelError {
    fn from(e: voxless_parallel::WireError) -> Self {
        ParallelError::Comm(e.into())
    }
}

impl From<voxless_core::Cancelled> for ParallelError {
    fn from(_: voxless_core::Cancelled) -> Self {
        ParallelError::Cancelled
    }
}

/// What a decomposed scene is opened for; it decides what each box keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Everything reaching into the box (renders and point samples).
    Render,
    /// Column densities: tessellations keep each tet in one box only (the
    /// box holding its centroid), so the boxes' projections add up; the
    /// other kinds keep what reaches into the box and integrate inside it.
    Project,
}

/// The names and the empty row of the sampled columns.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Columns {
    Particles { attribute: bool },
    Materials(Vec<String>),
    Tets { box_size: f32, n: usize },
    Amr(Vec<String>),
}

/// Where one rank's time went in a render, in seconds: rendering its box's
/// passes, and compositing (waiting for the others included).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    pub render: f64,
    pub composite: f64,
}

/// How many items a rank read and holds, for memory reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PartCounts {
    /// Items (particles, cells, Lagrangian particles) read from files.
    pub read: u64,
    /// Items (particles, cells, tets) held for the rank's box, ghosts
    /// included.
    pub held: u64,
}

/// One rank's part of the data, before the view is resolved.
pub(crate) struct Part {
    pub volume: Option<AnyVolume>,
    pub frame: WorldFrame,
    pub summary: VolumeSummary,
    pub decomposition: Decomposition,
    pub columns: Columns,
    pub colour_name: Option<String>,
    pub counts: PartCounts,
    pub notes: Vec<String>,
}

/// A scene decomposed over the ranks of a communicator: this rank's part
/// of the volume and the view every rank shares.
pub struct DistributedScene {
    /// What this rank holds (`None`: no data reaches its box).
    pub part: Option<AnyVolume>,
    /// Where the volume's coordinates sit in the world.
    pub frame: WorldFrame,
    pub camera: Camera,
    pub tf: TransferFunction,
    /// The view's settings, restricted to this rank's box.
    pub settings: RenderSettings,
    pub background: [f32; 3],
    pub notes: Vec<String>,
    /// The box (local) a default camera frames (see
    /// [`crate::Resolved::framed`]).
    pub framed: Aabb,
    /// The boxes of all ranks.
    pub decomposition: Decomposition,
    /// The whole data's kind, bounds and ranges.
    pub summary: VolumeSummary,
    pub counts: PartCounts,
    pub(crate) columns: Columns,
    pub(crate) colour_name: Option<String>,
}

impl DistributedScene {
    /// Opens frame `frame` of the data `desc` names (paths relative to
    /// `base`) on every rank of `comm`: each reads its share, the ranks
    /// decompose the data and exchange it, and each resolves the view from
    /// the whole data's summary and a probe of its field the ranks sample
    /// together. Every rank must call this with the same arguments; an
    /// error on any rank is an error on all.
    pub fn open(
        comm: &dyn Comm,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
        purpose: Purpose,
    ) -> Result<DistributedScene, ParallelError> {
        let part = open_part(comm, desc, base, frame, purpose, None)?;
        view::resolve(comm, part, desc, base, None, None)
    }

    /// This rank's box, half-open.
    pub fn owned_box(&self, comm: &dyn Comm) -> Aabb {
        self.decomposition.box_of(comm.rank())
    }

    /// Renders all `spp` passes: on rank 0 the image (the one-process
    /// image), `None` on the others. Progress is this rank's own share.
    pub fn render(
        &self,
        comm: &dyn Comm,
        control: &Control,
    ) -> Result<Option<Image>, ParallelError> {
        self.render_timed(comm, control).map(|r| r.0)
    }

    /// [`DistributedScene::render`], and where this rank's time went.
    pub fn render_timed(
        &self,
        comm: &dyn Comm,
        control: &Control,
    ) -> Result<(Option<Image>, Timings), ParallelError> {
        let mut timings = Timings::default();
        let image = render::render(self, comm, control, &mut timings)?;
        Ok((image, timings))
    }

    /// Column densities `∫ value dt` per pixel centre of `camera` (an axis
    /// projection, typically over [`DistributedScene::summary`]'s bounds),
    /// in world units: on rank 0 the image, `None` on the others.
    pub fn project(
        &self,
        comm: &dyn Comm,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Result<Option<Vec<f32>>, ParallelError> {
        self.project_over(comm, camera, None, width, height, control)
    }

    /// The column densities of a projection view (an axis or a normal, a
    /// slab; see [`crate::ProjectionView`]) in world units, as
    /// [`crate::ProjectionView::project`] gives them for one process: on
    /// rank 0 the image, `None` on the others.
    pub fn project_view(
        &self,
        comm: &dyn Comm,
        view: &crate::ProjectionView,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Result<Option<Vec<f32>>, ParallelError> {
        self.project_over(comm, &view.camera, view.t_range, width, height, control)
    }

    fn project_over(
        &self,
        comm: &dyn Comm,
        camera: &Camera,
        t: Option<voxless_core::Range1>,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Result<Option<Vec<f32>>, ParallelError> {
        let local = render::project(self, comm, camera, width, height, t, control)?;
        // In world units, as [`crate::Scene::project`] gives them.
        let s = self.frame.scale;
        Ok(local.map(|c| {
            if s == 1.0 {
                c
            } else {
                c.iter().map(|&v| (v as f64 * s) as f32).collect()
            }
        }))
    }

    /// The fields at `points` (the volume's coordinates; rank 0's are used,
    /// the others may pass none): on rank 0, row-major `points × columns`
    /// as [`AnyVolume::sample_points`] gives them, `None` on the others.
    pub fn sample(
        &self,
        comm: &dyn Comm,
        points: &[Vec3],
        gradient: bool,
    ) -> Result<Option<Vec<f32>>, ParallelError> {
        render::sample(self, comm, points, gradient)
    }

    /// Names of the columns [`DistributedScene::sample`] writes.
    pub fn sample_columns(&self, gradient: bool) -> Vec<String> {
        let grad = |name: &str| ["x", "y", "z"].map(|a| format!("d{name}/d{a}"));
        match &self.columns {
            Columns::Particles { attribute } => {
                let mut c = vec!["density".to_string()];
                if *attribute {
                    c.push("attribute".into());
                }
                if gradient {
                    c.extend(grad("density"));
                }
                c
            }
            Columns::Tets { .. } => vec!["density".into(), "streams".into()],
            Columns::Materials(names) => names.iter().map(|n| format!("density ({n})")).collect(),
            Columns::Amr(names) => {
                let mut c = names.clone();
                if gradient {
                    for n in names {
                        c.extend(grad(n));
                    }
                }
                c
            }
        }
    }

    /// The volume's bounds in world coordinates (lower, upper corner).
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        let b = self.summary.bounds;
        (self.frame.to_world(b.min), self.frame.to_world(b.max))
    }

    /// What a colour bar for this scene shows (as [`crate::Scene::colorbar`]).
    pub fn colorbar(&self) -> voxless_render::colorbar::ColorbarSpec {
        let st = &self.settings;
        let (range, log10) = match st.attribute_range {
            Some(r) => (r, false),
            None => (st.value_range, st.log_scale),
        };
        voxless_render::colorbar::ColorbarSpec {
            lo: range.lo,
            hi: range.hi,
            log10,
            label: self.colour_name.clone(),
        }
    }
}

impl DistributedScene {
    /// Points the camera as `desc.camera` says (a turntable frame), keeping
    /// the data and settings, as [`crate::Scene::reaim`] does; a default
    /// light follows the camera.
    pub fn reaim(&mut self, desc: &SceneDesc) -> Result<(), SceneError> {
        let aspect = self.settings.width as f32 / self.settings.height as f32;
        self.camera = crate::resolve::camera(&desc.camera, &self.framed, aspect, &self.frame)?;
        let follows = desc.light.as_ref().is_some_and(|l| l.direction.is_none());
        if let Some(light) = &mut self.settings.light
            && follows
        {
            light.direction = crate::camera::default_light_direction(&self.camera);
            if let Some(sc) = &mut self.settings.scatter
                && let voxless_render::LightSource::Directional(d) = &mut sc.light
            {
                *d = light.direction;
            }
        }
        Ok(())
    }
}

/// This rank's part of frame `frame` of the data `desc` names (`earlier`:
/// what a later frame of a series keeps of the first).
pub(crate) fn open_part(
    comm: &dyn Comm,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    purpose: Purpose,
    earlier: Option<particles::Earlier>,
) -> Result<Part, ParallelError> {
    if comm.size() > 1 {
        refuse_what_boxes_cannot_do(desc)?;
    }
    let sources = [
        desc.particles.is_some(),
        desc.amr.is_some(),
        desc.tets.is_some(),
    ];
    if sources.iter().filter(|&&s| s).count() > 1 {
        return Err(SceneError::setting(
            "scene",
            "more than one data source ([particles], [amr], [tets]) is given; pick one",
        )
        .into());
    }
    // `--particles run.h5` of a JaxPM run: its tessellation.
    let jaxpm = match &desc.particles {
        Some(p) => agree(comm, crate::load::jaxpm::as_tessellation(p, base))?,
        None => None,
    };
    let particles = if jaxpm.is_some() {
        None
    } else {
        desc.particles.as_ref()
    };
    let tets = desc.tets.as_ref().or(jaxpm.as_ref());
    match (particles, &desc.amr, tets) {
        (Some(p), _, _) => particles::open(comm, p, base, frame, earlier),
        (_, Some(a), _) => amr::open(comm, a, base),
        (_, _, Some(t)) => {
            if comm.size() > 1 {
                refuse_what_boxes_cannot_do_for_tets(t)?;
            }
            tets::open(comm, t, base, purpose)
        }
        (None, None, None) => Err(SceneError::setting(
            "scene",
            "no data source: add a [particles], [amr] or [tets] table to the scene, or pass \
             --particles FILE (with --lagrangian N --box L for a phase-space tessellation), \
             --cells FILE --scalars FILE, or --amrclaw FILE",
        )
        .into()),
    }
}

/// How the ranks share the frames of a time series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FramePlan {
    /// Each rank renders whole frames, one process each (frame `A + r`,
    /// `A + r + K`, … on rank `r`).
    ByFrame,
    /// The ranks render every frame together, decomposed.
    BySpace,
}

/// Whole frames per rank when there are at least as many frames as ranks
/// and one frame fits a rank comfortably (`frame_bytes`, the data of one
/// frame, at most a quarter of `memory_per_rank`): every rank then works
/// all the time, nothing is exchanged or composited, and each frame costs
/// what one process takes — the fastest way through a movie. Otherwise
/// (fewer frames than ranks, or frames too big for one rank) each frame is
/// decomposed over all ranks in turn.
pub fn frame_plan(
    frames: usize,
    ranks: usize,
    frame_bytes: u64,
    memory_per_rank: u64,
) -> FramePlan {
    if ranks > 1 && frames >= ranks && frame_bytes.saturating_mul(4) <= memory_per_rank {
        FramePlan::ByFrame
    } else {
        FramePlan::BySpace
    }
}

/// Settings whose result one box cannot compute alone.
fn refuse_what_boxes_cannot_do(desc: &SceneDesc) -> Result<(), SceneError> {
    let why = "under MPI each rank renders only its own box";
    if desc.render.iso.as_ref().is_some_and(|v| !v.is_empty()) {
        return Err(SceneError::setting(
            "render.iso (--iso)",
            format!(
                "iso-surfaces are not rendered on more than one rank yet: {why}, and a crossing \
                 between two samples in different boxes is seen by neither; render them with one \
                 rank"
            ),
        ));
    }
    if desc.light.as_ref().is_some_and(|l| l.shadows == Some(true)) {
        return Err(SceneError::setting(
            "light.shadows (--shadows)",
            format!(
                "single scattering is not rendered on more than one rank: {why}, and shadow rays \
                 cross boxes"
            ),
        ));
    }
    if !desc.meshes.is_empty() || !desc.instances.is_empty() || desc.render.ao.is_some() {
        return Err(SceneError::setting(
            if !desc.meshes.is_empty() {
                "meshes (--mesh)"
            } else if !desc.instances.is_empty() {
                "instances (--mirror)"
            } else {
                "render.ao (--ao)"
            },
            format!(
                "surfaces and mirror instances are not rendered on more than one rank yet:                  {why}; render them with one rank"
            ),
        ));
    }
    if let Some(t) = &desc.tets {
        refuse_what_boxes_cannot_do_for_tets(t)?;
    }
    Ok(())
}

/// Tessellation settings whose result one box cannot compute alone.
fn refuse_what_boxes_cannot_do_for_tets(t: &voxless_scene::TetsDesc) -> Result<(), SceneError> {
    let why = "under MPI each rank renders only its own box";
    if t.lod_pixels.is_some() {
        return Err(SceneError::setting(
            "tets.lod_pixels (--lod)",
            format!("the level of detail is not used on more than one rank: {why}"),
        ));
    }
    if t.mode == Some(voxless_scene::TetModeName::Kbuffer) {
        return Err(SceneError::setting(
            "tets.mode (--tet-mode kbuffer)",
            format!(
                "the k-buffer keeps the first k events of each box's part of a ray, not of \
                 the ray ({why}); use the exact mode"
            ),
        ));
    }
    Ok(())
}
