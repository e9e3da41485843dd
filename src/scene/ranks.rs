//! [`DistributedScene`]: a scene decomposed over the ranks of a
//! communicator — this rank's part of the volume, and the view every rank
//! shares, resolved as one process resolves it: from the whole data's
//! summary and a probe of its field whose points the ranks sample together
//! (see [`crate::parallel`] for how the data is shared and composited).

use std::path::Path;

use voxless_core::{Aabb, Camera, Control, Image, Range1, Vec3};
use voxless_parallel::{Comm, Decomposition};
use voxless_render::colorbar::ColorbarSpec;
use voxless_render::{Domain, RayStats};
use voxless_scene::SceneDesc;

use crate::autorange::Probe;
use crate::load::Purpose;
use crate::parallel::{self, Earlier, Part, PartCounts, Timings, open_part};
use crate::series::{SeriesFrames, over_series};
use crate::{
    AnyVolume, Fields, ParallelError, ProjectionView, Resolved, SceneError, VolumeKind,
    VolumeSummary, WorldFrame, resolve_summary,
};

/// A scene decomposed over the ranks of a communicator: this rank's part
/// of the volume and the view every rank shares.
pub struct DistributedScene {
    /// What this rank holds (`None`: no data reaches its box).
    pub part: Option<AnyVolume>,
    /// Where the volume's coordinates sit in the world.
    pub frame: WorldFrame,
    /// The one-process view, its settings restricted to this rank's box.
    pub view: Resolved,
    /// The boxes of all ranks.
    pub decomposition: Decomposition,
    /// The whole data's kind, bounds and ranges.
    pub summary: VolumeSummary,
    /// The whole data's fields.
    pub fields: Fields,
    pub counts: PartCounts,
    /// This rank's rows' radius parameters (particles of one set).
    pub radii: Option<Box<crate::load::whole_set::RowRadii>>,
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
        DistributedScene::resolved(comm, part, desc, base, None, None)
    }

    /// Resolves the view of `part` (with a series' `probe` and `framed`
    /// box, as [`crate::resolve_with`] takes them) and restricts the
    /// settings to this rank's box.
    pub(crate) fn resolved(
        comm: &dyn Comm,
        part: Part,
        desc: &SceneDesc,
        base: &Path,
        series_probe: Option<&Probe>,
        framed: Option<([f64; 3], [f64; 3])>,
    ) -> Result<DistributedScene, ParallelError> {
        let mut failed = None;
        let mut own = |clip: Option<&Aabb>| match parallel::probe(comm, &part, clip) {
            Ok(p) => p,
            Err(e) => {
                failed.get_or_insert(e);
                Probe::default()
            }
        };
        // Every rank resolves the same description from the same summary,
        // so all take the same branches (and probe together, or not at all).
        let view = resolve_summary(
            &part.summary,
            &part.frame,
            desc,
            base,
            series_probe,
            &mut own,
            framed,
        );
        if let Some(e) = failed {
            return Err(e);
        }
        let mut view = view?;
        view.settings.domain = Some(Domain {
            owned: part.decomposition.box_of(comm.rank()),
            bounds: part.summary.bounds,
        });
        let mut notes = part.notes;
        notes.append(&mut view.notes);
        view.notes = notes;
        Ok(DistributedScene {
            part: part.volume,
            frame: part.frame,
            view,
            decomposition: part.decomposition,
            summary: part.summary,
            fields: part.fields,
            counts: part.counts,
            radii: part.radii,
        })
    }

    /// Opens the first of `frames` (frame numbers) with the defaults taken
    /// over the series, as [`crate::Scene::open_series`] does. Returns the
    /// scene and the description to load the other frames with
    /// ([`DistributedScene::load_frame`]).
    pub fn open_series(
        comm: &dyn Comm,
        desc: &SceneDesc,
        base: &Path,
        frames: &[usize],
    ) -> Result<(DistributedScene, SceneDesc), ParallelError> {
        if let [only] = frames {
            let s = DistributedScene::open(comm, desc, base, *only, Purpose::Render)?;
            return Ok((s, desc.clone()));
        }
        let s = over_series(&mut Ranks { comm, base }, desc, frames)?;
        let scene = DistributedScene::resolved(
            comm,
            s.first,
            &s.desc,
            base,
            Some(&s.probe),
            Some(s.framed),
        )?;
        Ok((scene, s.desc))
    }

    /// Moves the scene to frame `frame` of its series (`desc`: the series'
    /// description from [`DistributedScene::open_series`]), as
    /// [`crate::Scene::load_frame`] does: the data in the first frame's
    /// world frame (particles keep their settings), the view unchanged.
    pub fn load_frame(
        &mut self,
        comm: &dyn Comm,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
    ) -> Result<(), ParallelError> {
        if !matches!(
            self.summary.kind,
            VolumeKind::Particles | VolumeKind::Materials | VolumeKind::Tets | VolumeKind::Amr
        ) {
            return Err(SceneError::setting(
                "frames",
                "time series are supported for particles, tessellations and AMR",
            )
            .into());
        }
        let settings = match &self.part {
            Some(AnyVolume::Particles(v)) => Some(v.settings().clone()),
            _ => None,
        };
        let earlier = Earlier {
            world: &self.frame,
            settings: settings.as_ref(),
        };
        let part = open_part(comm, desc, base, frame, Purpose::Render, Some(earlier))?;
        self.view.settings.domain = Some(Domain {
            owned: part.decomposition.box_of(comm.rank()),
            bounds: part.summary.bounds,
        });
        self.part = part.volume;
        self.decomposition = part.decomposition;
        self.summary = part.summary;
        self.counts = part.counts;
        self.radii = part.radii;
        Ok(())
    }

    /// This rank's box, half-open.
    pub fn owned_box(&self, comm: &dyn Comm) -> Aabb {
        self.decomposition.box_of(comm.rank())
    }

    /// The volume's bounds in world coordinates (lower, upper corner).
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.frame.box_to_world(self.summary.bounds)
    }

    /// An error when the render with this view would take absurdly long
    /// over all ranks, or the field is 0 everywhere; else a note when the
    /// step was raised (see [`crate::Scene::check_work`]).
    pub fn check_work(
        &self,
        comm: &dyn Comm,
        desc: &SceneDesc,
    ) -> Result<Option<String>, ParallelError> {
        let work = parallel::work(comm, self.part.as_ref(), &self.view)?;
        Ok(crate::checks::check_work(
            &self.summary,
            &self.frame,
            desc,
            &work,
        )?)
    }

    /// Renders all `spp` passes: on rank 0 the image (the one-process
    /// image), `None` on the others. Progress is this rank's own share.
    pub fn render(
        &self,
        comm: &dyn Comm,
        control: &Control,
    ) -> Result<Option<Image>, ParallelError> {
        let mut timings = Timings::default();
        Ok(self.render_timed(comm, control, &mut timings)?.map(|r| r.0))
    }

    /// [`DistributedScene::render`] with what every rank's rays saw (on
    /// rank 0), adding where this rank's time went to `timings`.
    pub fn render_timed(
        &self,
        comm: &dyn Comm,
        control: &Control,
        timings: &mut Timings,
    ) -> Result<Option<(Image, RayStats)>, ParallelError> {
        let (part, view) = (self.part.as_ref(), &self.view);
        parallel::render(comm, part, view, &self.decomposition, control, timings)
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
    /// slab; see [`ProjectionView`]) in world units, as
    /// [`ProjectionView::project`] gives them for one process: on rank 0
    /// the image, `None` on the others.
    pub fn project_view(
        &self,
        comm: &dyn Comm,
        view: &ProjectionView,
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
        t: Option<Range1>,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Result<Option<Vec<f32>>, ParallelError> {
        let (part, d) = (self.part.as_ref(), &self.decomposition);
        let local = parallel::project(comm, part, d, camera, width, height, t, control)?;
        Ok(local.map(|c| self.frame.columns_to_world(c)))
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
        let (part, d) = (self.part.as_ref(), &self.decomposition);
        parallel::sample(comm, part, d, &self.fields, points, gradient)
    }

    /// Names of the columns [`DistributedScene::sample`] writes.
    pub fn sample_columns(&self, gradient: bool) -> Vec<String> {
        self.fields.columns(gradient)
    }

    /// Points the camera as `desc.camera` says (see [`Resolved::reaim`]).
    pub fn reaim(&mut self, desc: &SceneDesc) -> Result<(), SceneError> {
        self.view.reaim(desc, &self.frame)
    }

    /// What a colour bar for this scene shows (see [`Resolved::colorbar`]).
    pub fn colorbar(&self, desc: &SceneDesc) -> ColorbarSpec {
        self.view.colorbar(self.fields.colour_name(desc))
    }
}

/// The frames of a series, each decomposed over the ranks of `comm`.
struct Ranks<'a> {
    comm: &'a dyn Comm,
    base: &'a Path,
}

impl SeriesFrames for Ranks<'_> {
    type Part = Part;
    type Error = ParallelError;

    fn load(
        &mut self,
        desc: &SceneDesc,
        frame: usize,
        world: Option<&WorldFrame>,
    ) -> Result<Part, ParallelError> {
        let earlier = world.map(|world| Earlier {
            world,
            settings: None,
        });
        open_part(self.comm, desc, self.base, frame, Purpose::Render, earlier)
    }

    fn probe(&mut self, part: &Part, clip: Option<&Aabb>) -> Result<Probe, ParallelError> {
        parallel::probe(self.comm, part, clip)
    }

    fn extent(part: &Part) -> (WorldFrame, Aabb, Option<Range1>) {
        let s = &part.summary;
        (part.frame, s.bounds, s.attribute_range)
    }

    fn notes(part: &mut Part) -> &mut Vec<String> {
        &mut part.notes
    }
}
