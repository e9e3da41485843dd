//! The view of a scene — [`Resolved`]: camera, transfer function, render
//! settings, background, notes and the framed box — and what every
//! front-end does with it. A scene held by one process ([`crate::Scene`]),
//! one decomposed over ranks ([`crate::DistributedScene`]), and a volume
//! held elsewhere with many views at once (Python threads, viewer tabs) all
//! re-aim, label colour bars and check their images through these methods,
//! so they say the same things.

use voxless_core::{Cancelled, Control, Image};
use voxless_render::colorbar::ColorbarSpec;
use voxless_render::{Film, LightSource, RayStats};
use voxless_scene::SceneDesc;

use crate::camera::{camera, default_light_direction};
use crate::checks;
use crate::{AnyVolume, Resolved, SceneError, WorldFrame};

impl Resolved {
    /// Points the camera as `desc.camera` says (e.g. a turntable frame's
    /// orbit) for a volume placed in `frame`, keeping the image size and
    /// settings; a default light follows the camera.
    pub fn reaim(&mut self, desc: &SceneDesc, frame: &WorldFrame) -> Result<(), SceneError> {
        let aspect = self.settings.width as f32 / self.settings.height as f32;
        self.camera = camera(&desc.camera, &self.framed, aspect, frame)?;
        let follows = desc.light.as_ref().is_some_and(|l| l.direction.is_none());
        if let Some(light) = &mut self.settings.light
            && follows
        {
            light.direction = default_light_direction(&self.camera);
            if let Some(sc) = &mut self.settings.scatter
                && let LightSource::Directional(d) = &mut sc.light
            {
                *d = light.direction;
            }
        }
        Ok(())
    }

    /// What a colour bar shows: the attribute range when colour comes from
    /// an attribute (or an AMR colour field), else the value range, in
    /// log10 units when the transfer function is in log scale; `label` is
    /// the field's name (see [`crate::Fields::colour_name`]).
    pub fn colorbar(&self, label: Option<String>) -> ColorbarSpec {
        let st = &self.settings;
        let (range, log10) = match st.attribute_range {
            Some(r) => (r, false),
            None => (st.value_range, st.log_scale),
        };
        ColorbarSpec {
            lo: range.lo,
            hi: range.hi,
            log10,
            label,
        }
    }

    /// The world width of one pixel (in `frame`'s world units) where a
    /// scale bar applies: the image plane of an orthographic camera, or
    /// for a perspective one the plane through the look-at point (the
    /// description's, else the framed box's centre).
    pub fn world_per_pixel(&self, desc: &SceneDesc, frame: &WorldFrame) -> f64 {
        let h = self.settings.height.max(1) as f64;
        let local = match self.camera.projection {
            voxless_core::Projection::Orthographic { half_height, .. } => {
                2.0 * half_height as f64 / h
            }
            voxless_core::Projection::Perspective { fov_y_deg } => {
                let target = match desc.camera.look_at {
                    Some(p) => frame.to_local(p),
                    None => self.framed.center(),
                };
                let depth = (target - self.camera.eye).dot(self.camera.forward) as f64;
                2.0 * depth.abs() * (0.5 * fov_y_deg as f64).to_radians().tan() / h
            }
        };
        local * frame.scale
    }

    /// An error when the render of `volume` (in `frame`) with this view
    /// would take absurdly long, naming the flag to change; else a note
    /// when the step was raised to what f32 resolves along the rays.
    pub fn check_work(
        &self,
        volume: &AnyVolume,
        frame: &WorldFrame,
        desc: &SceneDesc,
    ) -> Result<Option<String>, SceneError> {
        let work = volume.estimate_work(&self.camera, &self.tf, &self.settings);
        checks::check_work(&volume.summary(), frame, desc, &work)
    }

    /// Renders `volume` with this view into a film (all `spp` passes); the
    /// film also says what the rays saw ([`Film::stats`]).
    pub fn render_film(&self, volume: &AnyVolume, control: &Control) -> Result<Film, Cancelled> {
        volume.render_passes(&self.camera, &self.tf, &self.settings, control, &mut |_| {
            true
        })
    }

    /// The checks of a finished image whose rays saw `seen`: iso-surfaces
    /// asked for but absent ([`Resolved::check_iso`]), then an image that
    /// shows nothing at all ([`Resolved::check_visible`]; `bounds` are the
    /// data's world bounds).
    pub fn check_image(
        &self,
        bounds: ([f64; 3], [f64; 3]),
        seen: &RayStats,
        image: &Image,
    ) -> Result<(), SceneError> {
        self.check_iso(seen)?;
        self.check_visible(bounds, seen, image)
    }

    /// An error naming the iso-values when iso-surfaces were asked for but
    /// none appears in the image whose rays saw `seen`.
    pub fn check_iso(&self, seen: &RayStats) -> Result<(), SceneError> {
        checks::check_iso(&self.settings, seen)
    }

    /// An error saying why, when `image` (whose rays saw `seen`) shows
    /// nothing at all: never a silent black image. `bounds` are the data's
    /// world bounds.
    pub fn check_visible(
        &self,
        bounds: ([f64; 3], [f64; 3]),
        seen: &RayStats,
        image: &Image,
    ) -> Result<(), SceneError> {
        checks::check_visible(&self.settings, bounds, seen, image)
    }
}
