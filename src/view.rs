//! Views of a volume held elsewhere: a front-end that keeps one volume and
//! renders it with many descriptions at once (Python threads) resolves each
//! description into a [`Resolved`] (see [`crate::resolve_in`]) and checks
//! and renders with it here, as [`crate::Scene`] does (projections:
//! [`crate::ProjectionView`]), without a [`crate::Scene`] per view.

use voxless_core::{Cancelled, Control, Image};
use voxless_render::Film;
use voxless_scene::SceneDesc;

use crate::{AnyVolume, Resolved, SceneError, WorldFrame};

impl Resolved {
    /// See [`crate::Scene::check_work`]: an error when the render's
    /// estimated work is absurd, else a note when the step was raised.
    pub fn check_work(
        &self,
        volume: &AnyVolume,
        frame: &WorldFrame,
        desc: &SceneDesc,
    ) -> Result<Option<String>, SceneError> {
        crate::resolve::check_work(volume, frame, desc, &self.camera, &self.tf, &self.settings)
    }

    /// Renders `volume` with this view into a film (all `spp` passes); the
    /// film also says what the rays saw (see [`Resolved::check_iso`]).
    pub fn render_film(&self, volume: &AnyVolume, control: &Control) -> Result<Film, Cancelled> {
        volume.render_passes(&self.camera, &self.tf, &self.settings, control, &mut |_| {
            true
        })
    }

    /// An error naming the iso-values when iso-surfaces were asked for but
    /// none appears in `film` (see [`crate::progressive::check_iso`]).
    pub fn check_iso(&self, film: &Film) -> Result<(), SceneError> {
        crate::progressive::check_iso(&self.settings, film)
    }

    /// See [`crate::Scene::check_visible`]: an error saying why when
    /// `image` shows nothing at all.
    pub fn check_visible(
        &self,
        volume: &AnyVolume,
        frame: &WorldFrame,
        film: &Film,
        image: &Image,
    ) -> Result<(), SceneError> {
        let b = volume.bounds();
        let bounds = (frame.to_world(b.min), frame.to_world(b.max));
        crate::scene::check_visible(&self.settings, bounds, film, image)
    }
}
