//! The per-render context every integrator hands down to its samples: the
//! transfer function, the settings and how the volume's samples come
//! ([`Ctx`]).

use voxless_core::{Attribute, Range1, Sample, Vec3};
use voxless_transfer::TransferFunction;

use crate::RenderSettings;

/// What every sample of a frame needs besides the sample itself.
pub(crate) struct Ctx<'a> {
    pub tf: &'a TransferFunction,
    pub settings: &'a RenderSettings,
    /// Whether samples come classified
    /// ([`Volume::classified`](voxless_core::Volume::classified)).
    pub classified: bool,
    attr_range: Range1,
}

impl<'a> Ctx<'a> {
    pub fn new(tf: &'a TransferFunction, settings: &'a RenderSettings, classified: bool) -> Self {
        Ctx {
            tf,
            settings,
            classified,
            attr_range: settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0)),
        }
    }

    /// Whether samples need the gradient (shading the volume).
    pub fn needs_gradient(&self) -> bool {
        self.settings.light.is_some() && self.settings.volume
    }

    /// Whether a packet pass may classify its plain samples in lanes
    /// ([`crate::classify`]): emission–absorption of the volume, values
    /// classified here, no iso-surfaces (which need every sample in order).
    pub fn classifies_in_lanes(&self) -> bool {
        !self.classified && self.settings.volume && self.settings.iso.is_empty()
    }

    /// The colour of a sample whose normalised value is `x`.
    #[inline(always)]
    pub fn colour_of(&self, s: &Sample, x: f32) -> Vec3 {
        match s.attribute {
            Attribute::Scalar(v) => self.tf.color(self.attr_range.normalize(v)),
            Attribute::Rgb(c) => c,
            Attribute::None => self.tf.color(x),
        }
    }

    /// The opacity (before `opacity_scale`) of a sample whose normalised
    /// value is `x`.
    #[inline]
    pub fn opacity_of(&self, s: &Sample, x: f32) -> f32 {
        if self.classified {
            s.value
        } else {
            self.tf.opacity(x)
        }
    }
}
