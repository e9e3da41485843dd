//! [`Scene`]: a volume and how to look at it — what a front-end holds
//! between renders (the CLI for a time series or a turntable, the viewer
//! for a browser tab).

use std::path::Path;

use voxless_core::{Camera, Cancelled, Control, Image, Vec3};
use voxless_render::{Film, RenderSettings};
use voxless_scene::SceneDesc;
use voxless_transfer::TransferFunction;

use crate::autorange::Probe;
use crate::load::{self, Loaded, particles};
use crate::{AnyVolume, Resolved, SceneError, WorldFrame, resolve_with};

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
    /// The box (local) a default camera frames (see [`Resolved::framed`]).
    pub framed: voxless_core::Aabb,
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
        Scene::in_frame_with(volume, frame, desc, base, None, None)
    }

    /// [`Scene::in_frame`] with defaults over more than this volume (see
    /// [`resolve_with`]).
    pub(crate) fn in_frame_with(
        volume: AnyVolume,
        frame: WorldFrame,
        desc: &SceneDesc,
        base: &Path,
        probe: Option<&Probe>,
        framed: Option<([f64; 3], [f64; 3])>,
    ) -> Result<Scene, SceneError> {
        let Resolved {
            camera,
            tf,
            settings,
            background,
            notes,
            framed,
        } = resolve_with(&volume, &frame, desc, base, probe, framed)?;
        Ok(Scene {
            volume,
            frame,
            camera,
            tf,
            settings,
            background,
            notes,
            framed,
        })
    }

    /// Checks, before a render starts, that its estimated work is sane (see
    /// [`AnyVolume::estimate_work`]): an error names the flag to change
    /// when it would take absurdly long; a note says when the step was
    /// raised to what f32 resolves along the rays.
    pub fn check_work(&self, desc: &SceneDesc) -> Result<Option<String>, SceneError> {
        crate::resolve::check_work(
            &self.volume,
            &self.frame,
            desc,
            &self.camera,
            &self.tf,
            &self.settings,
        )
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

    /// An error saying why, when `image` (resolved from `film`) shows
    /// nothing at all: never a silent black image. The reason is what the
    /// rays saw: no data at all (the camera looks past it, or it is far
    /// smaller than a pixel), or only values the transfer function makes
    /// transparent.
    pub fn check_visible(&self, film: &Film, image: &Image) -> Result<(), SceneError> {
        check_visible(&self.settings, self.world_bounds(), film, image)
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
        let s = self.frame.scale;
        Ok(if s == 1.0 {
            local
        } else {
            local.iter().map(|&c| (c as f64 * s) as f32).collect()
        })
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
            let (v, _) = load::materials::load_materials(
                p,
                mats,
                base,
                &mut Vec::new(),
                frame,
                Some(&self.frame),
            )?;
            self.volume = AnyVolume::Materials(Box::new(v));
            return Ok(());
        }
        let (AnyVolume::Particles(v), Some(p)) = (&mut self.volume, &desc.particles) else {
            return Err(SceneError::setting(
                "frames",
                "time series are supported for particle data",
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

/// See [`Scene::check_visible`]: `bounds` are the data's world bounds.
pub(crate) fn check_visible(
    st: &RenderSettings,
    (lo, hi): ([f64; 3], [f64; 3]),
    film: &Film,
    image: &Image,
) -> Result<(), SceneError> {
    let alpha = image.pixels.iter().fold(0f32, |m, p| m.max(p[3]));
    if alpha >= 0.5 / 255.0 {
        return Ok(());
    }
    let seen = film.stats().values;
    let point = |p: [f64; 3]| format!("[{:.4e}, {:.4e}, {:.4e}]", p[0], p[1], p[2]);
    let (lo, hi) = (point(lo), point(hi));
    let zero = !(seen.hi > 0.0 || seen.lo < 0.0 || st.log_scale);
    let why = if seen.is_empty() || zero {
        format!(
            "no ray meets any of the field: the camera does not see the data's bounds \
             {lo}..{hi}, or the field there is zero or far thinner than a pixel \
             (check --eye/--look-at, --clip, the radius, or outliers far from the rest)"
        )
    } else {
        let unit = if st.log_scale { "log10 of " } else { "" };
        let shown = |v: f32| {
            if st.log_scale {
                v.max(f32::MIN_POSITIVE).log10()
            } else {
                v
            }
        };
        format!(
            "{unit}the field along the rays lies in [{:.4e}, {:.4e}], which the transfer \
             function (value range [{:.4e}, {:.4e}]) leaves transparent; give a \
             --value-range covering it, another --opacity, or a larger --opacity-scale",
            shown(seen.lo),
            shown(seen.hi),
            st.value_range.lo,
            st.value_range.hi
        )
    };
    Err(SceneError::setting(
        "image",
        format!("the image would be empty: {why}"),
    ))
}
