//! [`Scene`]: a volume and how to look at it — what a front-end holds
//! between renders (the CLI for a time series or a turntable, the viewer
//! for a browser tab).

use std::path::Path;

use voxless_core::{Camera, Cancelled, Control, Image, Vec3};
use voxless_render::{Film, RenderSettings};
use voxless_scene::SceneDesc;
use voxless_transfer::TransferFunction;

use crate::load::{self, particles};
use crate::{AnyVolume, Resolved, SceneError, resolve};

/// Everything a render, sample or projection needs.
pub struct Scene {
    pub volume: AnyVolume,
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
        let loaded = load::load(desc, base, frame)?;
        let mut scene = Scene::with_volume(loaded.volume, desc, base)?;
        let mut notes = loaded.notes;
        notes.append(&mut scene.notes);
        scene.notes = notes;
        Ok(scene)
    }

    /// A volume built elsewhere (from memory) with the defaults `desc`
    /// leaves open, exactly as for a loaded one.
    pub fn with_volume(
        volume: AnyVolume,
        desc: &SceneDesc,
        base: &Path,
    ) -> Result<Scene, SceneError> {
        let Resolved {
            camera,
            tf,
            settings,
            background,
            notes,
        } = resolve(&volume, desc, base)?;
        Ok(Scene {
            volume,
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

    /// The fields at `points` (see [`AnyVolume::sample_points`]).
    pub fn sample(&self, points: &[Vec3], gradient: bool) -> Vec<f32> {
        self.volume.sample_points(points, gradient)
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
