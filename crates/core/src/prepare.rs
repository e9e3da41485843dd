//! Preparing an immutable volume for one render.
//!
//! Volumes are immutable after they are built and `Sync`, so one volume can
//! serve many renders at once (browser tabs with their own transfer
//! functions, Python threads). Whatever depends on the transfer function or
//! the render's settings — the AMR regions the transfer function can see and
//! a BVH over them, particle colours pre-classified through the colormap —
//! lives in a context that [`Prepare::prepare`] builds per render (Open VKL's
//! interval-iterator context is the model). The context is the
//! [`Volume`] integrators sample; it borrows the volume.
//!
//! A volume is always a correct context for itself (every region visible,
//! attributes unclassified); preparing only adds what depends on the query.

use crate::math::{Range1, Vec3};
use crate::simd::Simd;
use crate::volume::Volume;

/// Tessellations: keep only the first `k` crossing events of each pixel
/// exactly and fold the rest into `layers` log-spaced depth layers (the
/// k-buffer of the phase-space paper; bounded memory per pixel).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EventBudget {
    pub k: usize,
    pub layers: usize,
}

/// What a render asks of a volume.
pub struct PrepareQuery<'a> {
    /// Whether a value range can show up in the image (the transfer
    /// function gives it opacity, or an iso-value lies in it).
    pub is_visible: &'a (dyn Fn(Range1) -> bool + Sync),
    /// The colour (linear RGB) of an attribute value: for volumes that
    /// pre-classify attributes (colour-map each element, then average).
    pub attribute_color: &'a (dyn Fn(f32) -> Vec3 + Sync),
    /// Tessellations: the k-buffer instead of exact event sorting.
    pub event_budget: Option<EventBudget>,
    /// Tessellations: draw Lagrangian blocks smaller than this many pixels
    /// on screen from coarser levels of detail, when the mesh has them
    /// (overrides the volume's own threshold; coarse previews use it).
    pub lod_pixels: Option<f32>,
    /// The SIMD backend of packet paths ([`Simd::Auto`]: the best the CPU
    /// has).
    pub simd: Simd,
}

impl PrepareQuery<'static> {
    /// Everything visible, attributes unclassified (grey), no budget.
    pub fn all() -> Self {
        PrepareQuery {
            is_visible: &|_| true,
            attribute_color: &|_| Vec3::ZERO,
            event_budget: None,
            lod_pixels: None,
            simd: Simd::Auto,
        }
    }
}

/// A volume that can be prepared for a render.
pub trait Prepare: Send + Sync {
    /// The prepared context integrators sample.
    type Prepared<'a>: Volume
    where
        Self: 'a;

    fn prepare<'a>(&'a self, query: &PrepareQuery) -> Self::Prepared<'a>;
}

/// Implements [`Prepare`] for volumes that need nothing per render: the
/// context is the volume itself.
#[macro_export]
macro_rules! prepare_as_self {
    ($($t:ty),* $(,)?) => {
        $(impl $crate::Prepare for $t {
            type Prepared<'a> = &'a $t where Self: 'a;
            fn prepare<'a>(&'a self, _: &$crate::PrepareQuery) -> &'a $t {
                self
            }
        })*
    };
}
