//! [`Scene`]: a volume and how to look at it — what a front-end holds
//! between renders (the CLI for a time series or a turntable, the viewer
//! for a browser tab).

use std::path::Path;

use voxless_core::{Camera, Cancelled, Control, Image, Vec3};
use voxless_render::{Film, RenderSettings};
use voxless_scene::SceneDesc;
use voxless_transfer::TransferFunction;

use crate::load::{self, Loaded, particles};
use crate::{AnyVolume, Resolved, SceneError, WorldFrame, resolve_in};

/// Everything a render, sample or projection needs.
pub struct Scene {
    pub volume: AnyVolume,
    /// Where the volume's coordinates sit in the world; the camera and
    /// settings below are in the volume's coordinates.
    pub frame: WorldFrame,
    pub camera: Camera,
    pub tf: TransferFunction,
    pub settings: RenderSettings,
    /// Linear RGB behind the volume.
    pub background: [f32; 3],
    /// Defaults chosen from the data, worth telling the user.
    pub notes: Vec<String>,
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
        let Loaded {
            volume,
            frame,
            notes: mut loading,
        } = loaded;
        let mut scene = Scene::in_frame(volume, frame, desc, base)?;
        loading.append(&mut scene.notes);
        scene.notes = loading;
        Ok(scene)
    }

    /// A volume in world coordinates with the defaults `desc` leaves open.
    pub fn with_volume(
        volume: AnyVolume,
        desc: &SceneDesc,
        base: &Path,
    ) -> Result<Scene, SceneError> {
        Scene::in_frame(volume, WorldFrame::default(), desc, base)
    }

    fn in_frame(
        volume: AnyVolume,
        frame: WorldFrame,
        desc: &SceneDesc,
        base: &Path,
    ) -> Result<Scene, SceneError> {
        let Resolved {
            camera,
            tf,
            settings,
            background,
            notes,
        } = resolve_in(&volume, &frame, desc, base)?;
        Ok(Scene {
            volume,
            frame,
            camera,
            tf,
            settings,
            background,
            notes,
        })
    }

    /// Renders the scene (all `spp` passes).
    pub fn render(&self, control: &Control) -> Result<Image, Cancelled> {
        self.volume
            .render(&self.camera, &self.tf, &self.settings, control)
    }

    /// Renders the scene into a film, which also says what the rays saw
    /// (see [`Scene::check_iso`]).
    pub fn render_film(&self, control: &Control) -> Result<Film, Cancelled> {
        self.volume
            .render_passes(&self.camera, &self.tf, &self.settings, control, &mut |_| {
                true
            })
    }

    /// An error naming the iso-values when iso-surfaces were asked for but
    /// none appears anywhere in `film` — with the range of values the rays
    /// did see, in the transfer function's units — so an empty surface is
    /// never a silent image.
    pub fn check_iso(&self, film: &Film) -> Result<(), SceneError> {
        crate::progressive::check_iso(&self.settings, film)
    }

    /// The fields at world `points` (see [`AnyVolume::sample_points`]).
    pub fn sample(&self, points: &[[f64; 3]], gradient: bool) -> Vec<f32> {
        let local: Vec<Vec3> = points.iter().map(|&p| self.frame.to_local(p)).collect();
        self.volume.sample_points(&local, gradient)
    }

    /// The volume's bounds in world coordinates (lower, upper corner).
    pub fn world_bounds(&self) -> ([f64; 3], [f64; 3]) {
        let b = self.volume.bounds();
        (self.frame.to_world(b.min), self.frame.to_world(b.max))
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
            let mats = p.materials.as_deref().unwrap_or_default();
            let v = load::materials::load_materials(p, mats, base, &mut Vec::new(), frame)?;
            self.volume = AnyVolume::Materials(Box::new(v));
            return Ok(());
        }
        let (AnyVolume::Particles(v), Some(p)) = (&mut self.volume, &desc.particles) else {
            return Err(SceneError::setting(
                "frames",
                "time series are supported for particle data",
            ));
        };
        let particles::FrameData {
            mut data,
            main_file,
            files,
            ..
        } = particles::read_frame(p, base, frame)?;
        load::scale::scale_arrays(&mut data, p)?;
        v.load_frame(data)
            .map_err(|source| particles::blame(main_file, &files, source))?;
        Ok(())
    }
}
