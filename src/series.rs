//! Time series: defaults over the whole series, not its first frame.
//!
//! A series' first frame is often unlike the rest (a dam break at rest has
//! speed 0 everywhere; the water then leaves the box the first frame
//! fills). So opening a series ([`crate::Scene::open_series`], and
//! [`crate::DistributedScene::open_series`] over ranks) makes a cheap first
//! pass over up to [`SERIES_SAMPLES`] frames spread evenly over the range
//! (first and last included): the camera frames the union of their bounds,
//! the value range and opacity scale come from one probe merged over them,
//! and the attribute range is the union of theirs. All of it stays fixed
//! for every frame, so the sequence does not flicker. One pass
//! (`over_series`) serves one process and the ranks alike; only how a
//! frame is loaded and probed differs (`SeriesFrames`).

use voxless_core::Aabb;
use voxless_scene::SceneDesc;

use crate::autorange::Probe;
use crate::{Range1, SceneError, WorldFrame};

/// Frames the first pass over a series loads at most.
pub const SERIES_SAMPLES: usize = 8;

/// Up to `k` of `frames`, spread evenly, first and last included.
pub(crate) fn spread(frames: &[usize], k: usize) -> Vec<usize> {
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

/// How the frames of a series are loaded and probed: whole by one process,
/// or in shares by the ranks of a communicator.
pub(crate) trait SeriesFrames {
    /// A loaded frame, before its view is resolved.
    type Part;
    type Error: From<SceneError>;

    /// Frame `frame` of the data `desc` names, in the world frame `world`
    /// (`None`: the one the placement policy picks).
    fn load(
        &mut self,
        desc: &SceneDesc,
        frame: usize,
        world: Option<&WorldFrame>,
    ) -> Result<Self::Part, Self::Error>;

    /// The probe of a loaded frame's field inside `clip` (local).
    fn probe(&mut self, part: &Self::Part, clip: Option<&Aabb>) -> Result<Probe, Self::Error>;

    /// A loaded frame's world frame, local bounds and attribute range.
    fn extent(part: &Self::Part) -> (WorldFrame, Aabb, Option<Range1>);

    /// Where a loaded frame's notes go (the series' note joins them).
    fn notes(part: &mut Self::Part) -> &mut Vec<String>;
}

/// The first frame of a series with the defaults taken over it (see the
/// module docs).
pub(crate) struct OverSeries<P> {
    /// The first frame, loaded with `desc`, its notes ending with what the
    /// series decided.
    pub first: P,
    /// The description to load every frame with: the series' attribute
    /// range filled in.
    pub desc: SceneDesc,
    /// The probe merged over the sampled frames.
    pub probe: Probe,
    /// The union of the sampled frames' world bounds.
    pub framed: ([f64; 3], [f64; 3]),
}

/// The first pass over `frames` (frame numbers, at least two; see the
/// module docs).
pub(crate) fn over_series<F: SeriesFrames>(
    f: &mut F,
    desc: &SceneDesc,
    frames: &[usize],
) -> Result<OverSeries<F::Part>, F::Error> {
    let Some(&first) = frames.first() else {
        return Err(SceneError::setting("frames", "no frames to render").into());
    };
    let part = f.load(desc, first, None)?;
    let (world, b, mut attribute) = F::extent(&part);
    let clip = desc.render.clip.map(|c| world.box_to_local(c));
    let sampled = spread(frames, SERIES_SAMPLES);
    let mut probe = Probe::default();
    let mut framed = world.box_to_world(b);
    for &k in &sampled {
        let other = if k == first {
            None
        } else {
            Some(f.load(desc, k, Some(&world))?)
        };
        let v = other.as_ref().unwrap_or(&part);
        probe.merge(f.probe(v, clip.as_ref())?);
        let (_, b, a) = F::extent(v);
        let (lo, hi) = world.box_to_world(b);
        framed = (
            std::array::from_fn(|a| framed.0[a].min(lo[a])),
            std::array::from_fn(|a| framed.1[a].max(hi[a])),
        );
        attribute = union(attribute, a);
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
    // pre-classification and the later frames take from the volume); the
    // notes of loading it are those of the first load.
    let mut first_part = if series.particles.as_ref().and_then(|p| p.attribute_range)
        != desc.particles.as_ref().and_then(|p| p.attribute_range)
    {
        let mut again = f.load(&series, first, Some(&world))?;
        let mut part = part;
        std::mem::swap(F::notes(&mut again), F::notes(&mut part));
        again
    } else {
        part
    };
    F::notes(&mut first_part).push(format!(
        "time series of {} frames: {} over frames {which}",
        frames.len(),
        what.join(", ")
    ));
    Ok(OverSeries {
        first: first_part,
        desc: series,
        probe,
        framed,
    })
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
