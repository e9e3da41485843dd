//! Whether a prepared context offers the hooks its volume offers: a context
//! that answers a capability hook differently from its volume (no packet
//! path, no tile view, …) has usually forgotten to forward it, and
//! integrators then take the slow path without a word.

use crate::camera::Camera;
use crate::control::Control;
use crate::math::{Range1, Ray, Vec3};
use crate::tiles::View;
use crate::volume::{IntervalQuery, SampleBatch, Volume};

/// What [`check_same_hooks`] compares between a volume and its context:
/// the plain answers about the whole volume, and whether each fast path
/// is there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hook {
    Bounds,
    ValueRange,
    AttributeRange,
    Classified,
    PacketSampling,
    /// Whether [`Volume::sample_batch_values`] takes a small batch.
    SampleBatchValues,
    SamplesInLanes,
    /// Whether [`Volume::intervals_chunk`] stops after one interval on
    /// some ray (a front-to-back walk) rather than giving every list whole.
    IntervalsChunk,
    /// Whether [`Volume::tile_view`] gives a view, for a perspective and an
    /// orthographic camera.
    TileView,
    /// Whether [`Volume::project_image`] gives an image, for a perspective
    /// and an orthographic camera.
    ProjectImage,
}

impl Hook {
    pub const ALL: [Hook; 10] = [
        Hook::Bounds,
        Hook::ValueRange,
        Hook::AttributeRange,
        Hook::Classified,
        Hook::PacketSampling,
        Hook::SampleBatchValues,
        Hook::SamplesInLanes,
        Hook::IntervalsChunk,
        Hook::TileView,
        Hook::ProjectImage,
    ];
}

/// Every hook of [`Volume`], with what [`check_same_hooks`] compares of it;
/// `None` for a query whose answers depend on the point or ray asked (a
/// context may answer those differently: pre-classified colours, hidden
/// regions), which [`super::check_contract`] checks on the context itself.
/// A test fails while a hook of the trait is missing here or from
/// [`crate::forward_volume!`].
pub const HOOKS: &[(&str, Option<Hook>)] = &[
    ("bounds", Some(Hook::Bounds)),
    ("value_range", Some(Hook::ValueRange)),
    ("attribute_range", Some(Hook::AttributeRange)),
    ("sample", None),
    ("gradient", None),
    ("sample_with_gradient", None),
    ("sample_in", None),
    ("sample_with_gradient_in", None),
    ("classified", Some(Hook::Classified)),
    ("packet_sampling", Some(Hook::PacketSampling)),
    ("sample_batch_values", Some(Hook::SampleBatchValues)),
    ("samples_in_lanes", Some(Hook::SamplesInLanes)),
    ("sample_values_lanes", None),
    ("sample_batch", None),
    ("intervals", None),
    ("intervals_chunk", Some(Hook::IntervalsChunk)),
    ("tile_view", Some(Hook::TileView)),
    ("project_image", Some(Hook::ProjectImage)),
    ("line_integral", None),
];

/// `volume`'s answer to `hook`, as text.
fn answer<V: Volume + ?Sized>(volume: &V, hook: Hook) -> String {
    let b = volume.bounds();
    let cameras = || {
        let ortho = Camera::axis_projection(&b, 2).ok();
        [Some(Camera::framing(&b, 1.0)), ortho]
            .into_iter()
            .flatten()
    };
    // Rays through the bounds, from outside, as the contract's.
    let rays = || {
        let mut rng = crate::SmallRng(7);
        (0..16).filter_map(move |_| {
            let target = b.center() + (rng.v() - Vec3::splat(0.5)) * (0.5 * b.diagonal());
            let dir = (rng.v() - Vec3::splat(0.5)).normalized();
            let ray = Ray::new(target - dir * (2.0 * b.diagonal()), dir);
            let t = b.clip_ray(&ray, Range1::new(0.0, f32::INFINITY));
            (dir.is_finite() && !t.is_empty()).then_some((ray, t))
        })
    };
    match hook {
        Hook::Bounds => format!("{b:?}"),
        Hook::ValueRange => format!("{:?}", volume.value_range()),
        Hook::AttributeRange => format!("{:?}", volume.attribute_range()),
        Hook::Classified => volume.classified().to_string(),
        Hook::PacketSampling => volume.packet_sampling().to_string(),
        Hook::SampleBatchValues => {
            // Eight samples along one ray.
            let (mut batch_rays, mut ts) = (Vec::new(), Vec::new());
            if let Some((ray, t)) = rays().next() {
                batch_rays.push(ray);
                ts.extend((0..8).map(|k| t.lo + (k as f32 + 0.5) / 8.0 * t.span()));
            }
            let offsets = [0, ts.len() as u32];
            let batch = SampleBatch {
                rays: &batch_rays,
                offsets: &offsets[..batch_rays.len() + 1],
                t: &ts,
                hints: None,
            };
            let mut out = vec![f32::NAN; ts.len()];
            volume.sample_batch_values(&batch, &mut out).to_string()
        }
        Hook::SamplesInLanes => volume.samples_in_lanes().to_string(),
        Hook::IntervalsChunk => {
            let mut out = Vec::new();
            rays()
                .any(|(ray, t)| {
                    out.clear();
                    volume
                        .intervals_chunk(&ray, t, &IntervalQuery::all(), &mut out, 1)
                        .is_some()
                })
                .to_string()
        }
        Hook::TileView => {
            let views = cameras().map(|camera| {
                let view = View {
                    camera,
                    width: 16,
                    height: 12,
                };
                volume.tile_view(&view).is_some()
            });
            format!("{:?}", views.collect::<Vec<_>>())
        }
        Hook::ProjectImage => {
            let control = Control::new();
            let images = cameras().map(|c| volume.project_image(&c, 8, 6, &control).is_some());
            format!("{:?}", images.collect::<Vec<_>>())
        }
    }
}

/// Checks that `context` (prepared from `volume`) answers every [`Hook`]
/// as `volume` does, but those in `differ`, which it must answer
/// differently (so a listed difference that goes away is reported too);
/// returns the mismatches (empty: none).
pub fn check_same_hooks<V: Volume + ?Sized, C: Volume + ?Sized>(
    volume: &V,
    context: &C,
    differ: &[Hook],
) -> Vec<String> {
    let mut bad = Vec::new();
    for hook in Hook::ALL {
        let (v, c) = (answer(volume, hook), answer(context, hook));
        match (differ.contains(&hook), v == c) {
            (false, false) => bad.push(format!(
                "{hook:?}: the context answers {c}, its volume {v} (a hook not forwarded?)"
            )),
            (true, true) => bad.push(format!(
                "{hook:?}: listed as differing, but context and volume both answer {v}"
            )),
            _ => {}
        }
    }
    bad
}

/// Panics listing the mismatches of [`check_same_hooks`], if any.
pub fn assert_same_hooks<V: Volume + ?Sized, C: Volume + ?Sized>(
    name: &str,
    volume: &V,
    context: &C,
    differ: &[Hook],
) {
    let bad = check_same_hooks(volume, context, differ);
    assert!(
        bad.is_empty(),
        "{name}: the prepared context does not offer its volume's hooks:\n{}",
        bad.join("\n")
    );
}

#[cfg(test)]
#[path = "hooks_tests.rs"]
mod tests;
