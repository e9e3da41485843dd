//! Views of a volume held elsewhere: a front-end that keeps one volume and
//! renders it with many descriptions at once (Python threads, viewer tabs)
//! resolves each description into a [`Resolved`] (see [`crate::resolve_in`])
//! and renders and checks with it here (projections: [`crate::ProjectionView`]), without a [`crate::Scene`]
//! per view. [`crate::Scene`] uses the same checks.

use voxless_core::{Cancelled, Control};
use voxless_render::{Film, RenderSettings};

use crate::{AnyVolume, Resolved, SceneError};

impl Resolved {
    /// Renders `volume` with this view into a film (all `spp` passes); the
    /// film also says what the rays saw (see [`Resolved::check_iso`]).
    pub fn render_film(&self, volume: &AnyVolume, control: &Control) -> Result<Film, Cancelled> {
        volume.render_passes(&self.camera, &self.tf, &self.settings, control, &mut |_| {
            true
        })
    }

    /// See [`check_iso`].
    pub fn check_iso(&self, film: &Film) -> Result<(), SceneError> {
        check_iso(&self.settings, film)
    }
}

/// An error naming the iso-values when iso-surfaces were asked for but none
/// appears anywhere in `film` — with the range of values the rays did see,
/// in the transfer function's units — so an empty surface is never a silent
/// image.
pub fn check_iso(st: &RenderSettings, film: &Film) -> Result<(), SceneError> {
    if st.iso.is_empty() || film.stats().iso_hits > 0 {
        return Ok(());
    }
    let unit = |v: f32| {
        if st.log_scale {
            v.max(f32::MIN_POSITIVE).log10()
        } else {
            v
        }
    };
    let asked: Vec<String> = st.iso.iter().map(|&v| format!("{}", unit(v))).collect();
    let scale = if st.log_scale {
        "log10 of the field"
    } else {
        "the field"
    };
    let seen = film.stats().values;
    let what = if seen.is_empty() {
        "the rays meet no data".to_string()
    } else {
        format!(
            "{scale} along the rays lies in [{:.4}, {:.4}]",
            unit(seen.lo),
            unit(seen.hi)
        )
    };
    Err(SceneError::setting(
        "render.iso (--iso)",
        format!(
            "no iso-surface at {} appears in the image: {what}; the transfer function's \
             value range is [{:.4}, {:.4}] in the same units",
            asked.join(", "),
            st.value_range.lo,
            st.value_range.hi
        ),
    ))
}
