//! Time series: defaults over the whole series, not its first frame.
//!
//! A series' first frame is often unlike the rest (a dam break at rest has
//! speed 0 everywhere; the water then leaves the box the first frame
//! fills). So [`Scene::open_series`] makes a cheap first pass over up to
//! [`SERIES_SAMPLES`] frames spread evenly over the range (first and last
//! included): the camera frames the union of their bounds, the value range
//! and opacity scale come from one probe merged over them, and the
//! attribute range is the union of theirs. All of it stays fixed for every
//! frame, so the sequence does not flicker.

use std::path::Path;

use voxless_scene::SceneDesc;

use crate::autorange::Probe;
use crate::load::{self, Loaded};
use crate::{AnyVolume, Range1, Scene, SceneError, WorldFrame};

/// Frames the first pass over a series loads at most.
pub const SERIES_SAMPLES: usize = 8;

/// Up to `k` of `frames`, spread evenly, first and last included.
fn spread(frames: &[usize], k: usize) -> Vec<usize> {
    if frames.len() <= k {
        return frames.to_vec();
    }
    let mut picked: Vec<usize> = (0..k)
        .map(|i| frames[(i * (frames.len() - 1) + (k - 1) / 2) / (k - 1)])
        .collect();
    picked.dedup();
    picked
}

fn union(a: Option<Range1>, b: Option<Range1>) -> Option<Range1> {
    match (a, b) {
        (Some(a), Some(b)) => Some(Range1::new(a.lo.min(b.lo), a.hi.max(b.hi))),
        (a, b) => a.or(b),
    }
}

impl Scene {
    /// Opens the first of `frames` (frame numbers, see
    /// [`crate::frame_numbers`]) with the defaults taken over the series
    /// (module docs). Returns the scene and the description to load the
    /// other frames with ([`Scene::load_frame`]): `desc` with the series'
    /// attribute range filled in.
    pub fn open_series(
        desc: &SceneDesc,
        base: &Path,
        frames: &[usize],
    ) -> Result<(Scene, SceneDesc), SceneError> {
        let Some(&first) = frames.first() else {
            return Err(SceneError::setting("frames", "no frames to render"));
        };
        if frames.len() == 1 {
            return Ok((Scene::open(desc, base, first)?, desc.clone()));
        }
        let Loaded {
            volume,
            frame: world,
            notes: mut loading,
        } = load::load(desc, base, first)?;
        let clip = desc.render.clip.map(|c| world.box_to_local(c));
        let sampled = spread(frames, SERIES_SAMPLES);
        let mut probe = Probe::default();
        let mut bounds = world_bounds(&volume, &world);
        let mut attribute = volume.attribute_range();
        for &f in &sampled {
            let v = if f == first {
                None
            } else {
                Some(load::load_in(desc, base, f, Some(&world))?.volume)
            };
            let v = v.as_ref().unwrap_or(&volume);
            probe.merge(Probe::of(v, clip.as_ref()));
            let (lo, hi) = world_bounds(v, &world);
            bounds = (
                std::array::from_fn(|a| bounds.0[a].min(lo[a])),
                std::array::from_fn(|a| bounds.1[a].max(hi[a])),
            );
            attribute = union(attribute, v.attribute_range());
        }
        let mut series = desc.clone();
        let which = crate::frames::list_numbers(&sampled);
        let mut what = vec!["value range", "opacity scale", "framing"];
        if let (Some(p), Some(r)) = (series.particles.as_mut(), attribute)
            && p.attribute_range.is_none()
            && p.materials.is_none()
        {
            p.attribute_range = Some([r.lo, r.hi]);
            what.push("attribute range");
        }
        // The first frame again, now with the series' attribute range (which
        // pre-classification and the later frames take from the volume).
        let volume = if series.particles.as_ref().and_then(|p| p.attribute_range)
            != desc.particles.as_ref().and_then(|p| p.attribute_range)
        {
            load::load_in(&series, base, first, Some(&world))?.volume
        } else {
            volume
        };
        let mut scene =
            Scene::in_frame_with(volume, world, &series, base, Some(&probe), Some(bounds))?;
        loading.push(format!(
            "time series of {} frames: {} over frames {which}",
            frames.len(),
            what.join(", ")
        ));
        loading.append(&mut scene.notes);
        scene.notes = loading;
        Ok((scene, series))
    }
}

/// The world box of a volume in `frame`.
fn world_bounds(v: &AnyVolume, frame: &WorldFrame) -> ([f64; 3], [f64; 3]) {
    let b = v.bounds();
    (frame.to_world(b.min), frame.to_world(b.max))
}

#[cfg(test)]
mod tests {
    #[test]
    fn spread_keeps_first_and_last() {
        let f: Vec<usize> = (0..10).map(|i| i * 250).collect();
        let s = super::spread(&f, 8);
        assert_eq!(s.first(), Some(&0));
        assert_eq!(s.last(), Some(&2250));
        assert_eq!(s.len(), 8);
        assert_eq!(super::spread(&f[..3], 8), vec![0, 250, 500]);
    }
}
