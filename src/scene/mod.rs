//! A volume and how to look at it — what a front-end holds between renders
//! (the CLI for a time series or a turntable, the viewer for a browser
//! tab): [`Scene`] held by one process, [`DistributedScene`] decomposed
//! over the ranks of a communicator. Both hold the same view ([`Resolved`])
//! resolved the same way, and differ only in how the data is held.

mod ranks;

pub use ranks::DistributedScene;

use std::path::Path;

use voxless_core::{Aabb, Camera, Cancelled, Control, Image, Range1, Vec3};
use voxless_render::Film;
use voxless_render::colorbar::ColorbarSpec;
use voxless_scene::SceneDesc;

use crate::autorange::Probe;
use crate::load::{self, Loaded, particles};
use crate::series::{SeriesFrames, over_series};
use crate::{AnyVolume, Fields, Resolved, SceneError, WorldFrame, resolve_with};

/// Everything a render, sample or projection needs, held by one process:
/// the volume, where it sits in the world, and the view of it.
pub struct Scene {
    pub volume: AnyVolume,
    /// Where the volume's coordinates sit in the world; the view's camera
    /// and settings are in the volume's coordinates.
    pub frame: WorldFrame,
    /// Camera, transfer function, settings, background, the notes of
    /// loading and resolving, and the framed box.
    pub view: Resolved,
}

impl Scene {
    /// Loads the data `desc` names (paths relative to `base`) at frame
    /// `frame` and fills every default.
    pub fn open(desc: &SceneDesc, base: &Path, frame: usize) -> Result<Scene, SceneError> {
        Scene::with_loaded(load::load(desc, base, frame)?, desc, base)
    }

    /// A volume loaded (from files or memory) with the defaults `desc`
    /// leaves open; the loading notes come first.
    pub fn with_loaded(loaded: Loaded, desc: &SceneDesc, base: &Path) -> Result<Scene, SceneError> {
        Scene::resolved(loaded, desc, base, None, None)
    }

    /// A volume in world coordinates with the defaults `desc` leaves open.
    pub fn with_volume(
        volume: AnyVolume,
        desc: &SceneDesc,
        base: &Path,
    ) -> Result<Scene, SceneError> {
        let loaded = Loaded {
            volume,
            frame: WorldFrame::default(),
            notes: Vec::new(),
        };
        Scene::with_loaded(loaded, desc, base)
    }

    /// [`Scene::with_loaded`] with defaults over more than this volume (see
    /// [`resolve_with`]).
    pub(crate) fn resolved(
        loaded: Loaded,
        desc: &SceneDesc,
        base: &Path,
        probe: Option<&Probe>,
        framed: Option<([f64; 3], [f64; 3])>,
    ) -> Result<Scene, SceneError> {
        let Loaded {
            volume,
            frame,
            mut notes,
        } = loaded;
        let mut view = resolve_with(&volume, &frame, desc, base, probe, framed)?;
        notes.append(&mut view.notes);
        view.notes = notes;
        Ok(Scene {
            volume,
            frame,
            view,
        })
    }

    /// What the volume's field is made of: its sampled columns, the name
    /// its colours stand for.
    pub fn fields(&self) -> Fields {
        self.volume.fields()
    }

    /// Checks, before a render starts, that its estimated work is sane (see
    /// [`Resolved::check_work`]): an error names the flag to change when it
    /// would take absurdly long; a note says when the step was raised to
    /// what f32 resolves along the rays.
    pub fn check_work(&self, desc: &SceneDesc) -> Result<Option<String>, SceneError> {
        self.view.check_work(&self.volume, &self.frame, desc)
    }

    /// Renders the scene (all `spp` passes).
    pub fn render(&self, control: &Control) -> Result<Image, Cancelled> {
        let v = &self.view;
        self.volume.render(&v.camera, &v.tf, &v.settings, control)
    }

    /// Renders the scene into a film, which also says what the rays saw
    /// (see [`Scene::check_visible`]).
    pub fn render_film(&self, control: &Control) -> Result<Film, Cancelled> {
        self.view.render_film(&self.volume, control)
    }

    /// The checks of a finished render: iso-surfaces asked for but absent,
    /// and an image that shows nothing at all (see [`Resolved::check_iso`],
    /// [`Resolved::check_visible`]).
    pub fn check_visible(&self, film: &Film, image: &Image) -> Result<(), SceneError> {
        self.view
            .check_image(self.world_bounds(), film.stats(), image)
    }

    /// Points the camera as `desc.camera` says (see [`Resolved::reaim`]).
    pub fn reaim(&mut self, desc: &SceneDesc) -> Result<(), SceneError> {
        self.view.reaim(desc, &self.frame)
    }

    /// What a colour bar for this scene shows (see [`Resolved::colorbar`]).
    pub fn colorbar(&self, desc: &SceneDesc) -> ColorbarSpec {
        self.view.colorbar(self.fields().colour_name(desc))
    }

    /// Column density `∫ value dt` per pixel centre in world units (the
    /// volume's local integrals times the frame's scale), row-major; see
    /// [`AnyVolume::project`].
    pub fn project(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Result<Vec<f32>, Cancelled> {
        let local = self.volume.project(camera, width, height, control)?;
        Ok(self.frame.columns_to_world(local))
    }

    /// The integral of the field over all space in world units, when the
    /// data kind knows it exactly (see [`AnyVolume::total_mass`]).
    pub fn total_mass(&self) -> Option<f64> {
        self.volume
            .total_mass()
            .map(|m| m * self.frame.scale.powi(3))
    }

    /// The fields at world `points` (see [`AnyVolume::sample_points`]).
    pub fn sample(&self, points: &[[f64; 3]], gradient: bool) -> Vec<f32> {
        let local: Vec<Vec3> = points.iter().map(|&p| self.frame.to_local(p)).collect();
        self.volume.sample_points(&local, gradient)
    }

    /// The volume's bounds in world coordinates (lower, upper corner).
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.frame.box_to_world(self.volume.bounds())
    }

    /// Opens the first of `frames` (frame numbers, see
    /// [`crate::frame_numbers`]) with the defaults taken over the series
    /// (see [`crate::series`]). Returns the scene and the description to
    /// load the other frames with ([`Scene::load_frame`]): `desc` with the
    /// series' attribute range filled in.
    pub fn open_series(
        desc: &SceneDesc,
        base: &Path,
        frames: &[usize],
    ) -> Result<(Scene, SceneDesc), SceneError> {
        if let [only] = frames {
            return Ok((Scene::open(desc, base, *only)?, desc.clone()));
        }
        let s = over_series(&mut Whole { base }, desc, frames)?;
        let scene = Scene::resolved(s.first, &s.desc, base, Some(&s.probe), Some(s.framed))?;
        Ok((scene, s.desc))
    }

    /// Moves a particle scene to frame `frame` of its sequence: the BVH is
    /// rebuilt in its buffers, and camera, value range and attribute range stay
    /// as resolved for the first frame, so a sequence does not flicker.
    pub fn load_frame(
        &mut self,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
    ) -> Result<(), SceneError> {
        if let (AnyVolume::Materials(_), Some(p)) = (&self.volume, &desc.particles) {
            // Each material is rebuilt from the new frame (no buffer reuse).
            let p = load::materials::with_types(p)?;
            let mats = p.materials.as_deref().unwrap_or_default();
            let (v, _) = load::materials::load_materials(
                &p,
                mats,
                base,
                &mut Vec::new(),
                frame,
                Some(&self.frame),
            )?;
            self.volume = AnyVolume::Materials(Box::new(v));
            return Ok(());
        }
        if let AnyVolume::Tets(_) | AnyVolume::Amr(_) = &self.volume {
            // Numbered tessellation grids or AMR outputs: the next one, in
            // the frame of the first (a box's, a domain's).
            let next = load::load_in(desc, base, frame, Some(&self.frame))?;
            if next.frame != self.frame {
                return Err(SceneError::setting(
                    "frames",
                    format!(
                        "frame {frame} lies in another domain than the series' first frame: \
                         a series keeps one box"
                    ),
                ));
            }
            self.volume = next.volume;
            return Ok(());
        }
        let (AnyVolume::Particles(v), Some(p)) = (&mut self.volume, &desc.particles) else {
            return Err(SceneError::setting(
                "frames",
                "time series are supported for particles, tessellations and AMR",
            ));
        };
        let fd = particles::read_frame(p, base, frame)?;
        let kernel = fd.kernel(p);
        let (mut data, main_file, files) = fd.place(&self.frame);
        load::scale::scale_arrays(&mut data, p)?;
        particles::localise(&mut data, kernel, self.frame.scale);
        v.load_frame(data)
            .map_err(|source| particles::blame(main_file, &files, source))?;
        Ok(())
    }
}

/// The frames of a series, each loaded whole by this process.
struct Whole<'a> {
    base: &'a Path,
}

impl SeriesFrames for Whole<'_> {
    type Part = Loaded;
    type Error = SceneError;

    fn load(
        &mut self,
        desc: &SceneDesc,
        frame: usize,
        world: Option<&WorldFrame>,
    ) -> Result<Loaded, SceneError> {
        load::load_in(desc, self.base, frame, world)
    }

    fn probe(&mut self, part: &Loaded, clip: Option<&Aabb>) -> Result<Probe, SceneError> {
        Ok(Probe::of(&part.volume, clip))
    }

    fn extent(part: &Loaded) -> (WorldFrame, Aabb, Option<Range1>) {
        let v = &part.volume;
        (part.frame, v.bounds(), v.attribute_range())
    }

    fn notes(part: &mut Loaded) -> &mut Vec<String> {
        &mut part.notes
    }
}
