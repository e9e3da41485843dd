//! Views of a volume held elsewhere: a front-end that keeps one volume and
//! renders it with many descriptions at once (Python threads) resolves each
//! description into a [`Resolved`] (see [`crate::resolve_in`]) and renders
//! and checks with it here (projections: [`crate::ProjectionView`]), without
//! a [`crate::Scene`] per view.

use voxless_core::{Cancelled, Control};
use voxless_render::Film;

use crate::{AnyVolume, Resolved, SceneError};

impl Resolved {
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
}
