//! What a front-end draws over a rendered image, drawn here so every
//! front-end (CLI, viewer, Python, movies) draws the same: the colour bar
//! ([`voxless_render::colorbar`]), a scale bar in world units — labelled
//! with the file's length unit when it states one — and a label with the
//! frame's time or redshift ([`crate::frame_label`]), each on request
//! ([`Marks`]).

use std::path::Path;

use voxless_core::Image;
use voxless_render::annotate::{draw_label, draw_scale_bar};
use voxless_render::colorbar::{ColorbarSpec, draw_colorbar};
use voxless_scene::SceneDesc;

use crate::{Resolved, SceneError, WorldFrame};

/// Which annotations to draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Marks {
    pub colorbar: bool,
    pub scale_bar: bool,
    /// The frame's time or redshift, top left.
    pub label: bool,
}

/// The annotations of a scene's images, prepared once (the colour bar's
/// range, the length unit) and drawn on every frame.
#[derive(Clone, Debug, Default)]
pub struct Annotations {
    marks: Marks,
    colorbar: Option<ColorbarSpec>,
    /// The length unit's name and how many of it a world unit is.
    unit: Option<(String, f64)>,
}

impl Annotations {
    /// `marks` for frame `frame` of the data `desc` names, whose colour bar
    /// shows `colorbar` (see [`crate::Scene::colorbar`]).
    pub fn new(
        marks: Marks,
        colorbar: ColorbarSpec,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
    ) -> Result<Annotations, SceneError> {
        let unit = if marks.scale_bar {
            crate::map_fits::length_unit(&crate::map_fits::map_meta(desc, base, frame)?)
        } else {
            None
        };
        Ok(Annotations {
            marks,
            colorbar: marks.colorbar.then_some(colorbar),
            unit,
        })
    }

    /// Draws the annotations into `image`, rendered with `view` of data in
    /// `world` as `desc` describes it (the frame's own camera), showing
    /// data frame `data_frame`. Returns notes for what did not fit.
    pub fn draw(
        &self,
        image: &mut Image,
        view: &Resolved,
        world: &WorldFrame,
        desc: &SceneDesc,
        base: &Path,
        data_frame: usize,
    ) -> Result<Vec<String>, SceneError> {
        let mut notes = Vec::new();
        let (w, h) = (image.width, image.height);
        let small = |what: &str| format!("a {w}×{h} image is too small for {what}");
        if let Some(spec) = &self.colorbar
            && draw_colorbar(image, &view.tf, spec).is_none()
        {
            notes.push(small("a colour bar"));
        }
        if self.marks.scale_bar {
            let (unit, per) = match &self.unit {
                Some((u, per)) => (Some(u.as_str()), *per),
                None => (None, 1.0),
            };
            let wpp = view.world_per_pixel(desc, world) * per;
            if draw_scale_bar(image, wpp, unit).is_none() {
                notes.push(small("a scale bar"));
            }
        }
        if self.marks.label {
            let text = crate::frame_label(desc, base, data_frame)?;
            if draw_label(image, &text).is_none() {
                notes.push(small("a time label"));
            }
        }
        Ok(notes)
    }
}
