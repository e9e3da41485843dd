//! The view of a decomposed scene — camera, transfer function, settings —
//! resolved as one process resolves it: from the whole data's summary and
//! a probe of its field ([`crate::autorange`]) whose points the ranks
//! sample together, each point by the rank whose box holds it. A time
//! series takes its defaults over the series ([`crate::series`]) the same
//! way.

use std::path::Path;

use rayon::prelude::*;
use voxless_core::{Aabb, Range1};
use voxless_parallel::{Comm, Decomposition};
use voxless_render::Domain;
use voxless_scene::SceneDesc;

use super::particles::Earlier;
use super::{DistributedScene, ParallelError, Part, Purpose, open_part};
use crate::autorange::{Probe, value_at};
use crate::series::{SERIES_SAMPLES, spread, union};
use crate::{AnyVolume, Resolved, SceneError, VolumeKind, WorldFrame, resolve_summary};

/// The probe of the decomposed volume within its whole bounds (and `clip`,
/// local): every point evaluated by the rank whose box holds it, the
/// values gathered on every rank — the probe one process takes.
fn probe(
    comm: &dyn Comm,
    part: Option<&AnyVolume>,
    summary_kind: VolumeKind,
    bounds: Aabb,
    decomposition: &Decomposition,
    clip: Option<&Aabb>,
) -> Result<Probe, ParallelError> {
    if summary_kind == VolumeKind::Materials {
        return Ok(Probe::default());
    }
    let mut b = bounds;
    if let Some(c) = clip {
        b = Aabb::new(b.min.max(c.min), b.max.min(c.max));
    }
    let points = Probe::points(&b);
    let owners: Vec<usize> = points.par_iter().map(|&q| decomposition.owner(q)).collect();
    let me = comm.rank();
    let mine: Vec<u8> = points
        .par_iter()
        .zip(&owners)
        .map(|(&q, &o)| match (o == me, part) {
            (true, Some(v)) => value_at(v, q).filter(|v| v.is_finite()).unwrap_or(f32::NAN),
            _ => f32::NAN,
        })
        .flat_map_iter(|v| v.to_le_bytes())
        .collect();
    let all = comm.all_gather(&mine)?;
    let values: Vec<f32> = owners
        .iter()
        .enumerate()
        .map(|(i, &o)| {
            all.get(o)
                .and_then(|m| m.get(4 * i..4 * i + 4))
                .map_or(f32::NAN, |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        })
        .collect();
    Ok(Probe::from_values(&b, &values))
}

/// The probe of `part` (see [`probe`]).
fn probe_of(comm: &dyn Comm, part: &Part, clip: Option<&Aabb>) -> Result<Probe, ParallelError> {
    probe(
        comm,
        part.volume.as_ref(),
        part.summary.kind,
        part.summary.bounds,
        &part.decomposition,
        clip,
    )
}

/// The world box of local bounds `b` in `frame`.
fn world_box(b: Aabb, frame: &WorldFrame) -> ([f64; 3], [f64; 3]) {
    (frame.to_world(b.min), frame.to_world(b.max))
}

/// Resolves the view of `part` (with a series' `probe` and `framed` box,
/// as [`crate::resolve_with`] takes them) and restricts the settings to
/// this rank's box.
pub(crate) fn resolve(
    comm: &dyn Comm,
    part: Part,
    desc: &SceneDesc,
    base: &Path,
    series_probe: Option<&Probe>,
    framed: Option<([f64; 3], [f64; 3])>,
) -> Result<DistributedScene, ParallelError> {
    let mut failed = None;
    let mut own = |clip: Option<&Aabb>| match probe_of(comm, &part, clip) {
        Ok(p) => p,
        Err(e) => {
            failed.get_or_insert(e);
            Probe::default()
        }
    };
    // Every rank resolves the same description from the same summary, so
    // all take the same branches (and probe together, or not at all).
    let resolved = resolve_summary(
        &part.summary,
        &part.frame,
        desc,
        base,
        series_probe,
        &mut own,
        framed,
    );
    if let Some(e) = failed {
        return Err(e);
    }
    let Resolved {
        camera,
        tf,
        mut settings,
        background,
        notes: resolved_notes,
        framed,
    } = resolved?;
    settings.domain = Some(Domain {
        owned: part.decomposition.box_of(comm.rank()),
        bounds: part.summary.bounds,
    });
    let mut notes = part.notes;
    notes.extend(resolved_notes);
    Ok(DistributedScene {
        part: part.volume,
        frame: part.frame,
        camera,
        tf,
        settings,
        background,
        notes,
        framed,
        decomposition: part.decomposition,
        summary: part.summary,
        counts: part.counts,
        columns: part.columns,
        colour_name: part.colour_name,
    })
}

impl DistributedScene {
    /// Opens the first of `frames` (frame numbers) with the defaults taken
    /// over the series, as [`crate::Scene::open_series`] does: the camera
    /// frames the union of the sampled frames' bounds, the value range and
    /// opacity scale come from one probe merged over them, the attribute
    /// range is the union of theirs. Returns the scene and the description
    /// to load the other frames with ([`DistributedScene::load_frame`]).
    pub fn open_series(
        comm: &dyn Comm,
        desc: &SceneDesc,
        base: &Path,
        frames: &[usize],
    ) -> Result<(DistributedScene, SceneDesc), ParallelError> {
        let Some(&first) = frames.first() else {
            return Err(SceneError::setting("frames", "no frames to render").into());
        };
        if frames.len() == 1 {
            let s = DistributedScene::open(comm, desc, base, first, Purpose::Render)?;
            return Ok((s, desc.clone()));
        }
        let part = open_part(comm, desc, base, first, Purpose::Render, None)?;
        let world = part.frame;
        let clip = desc.render.clip.map(|c| world.box_to_local(c));
        let sampled = spread(frames, SERIES_SAMPLES);
        let mut merged = Probe::default();
        let mut bounds = world_box(part.summary.bounds, &world);
        let mut attribute = part.summary.attribute_range;
        let earlier = Earlier {
            world: &world,
            settings: None,
        };
        for &f in &sampled {
            let other = if f == first {
                None
            } else {
                Some(open_part(
                    comm,
                    desc,
                    base,
                    f,
                    Purpose::Render,
                    Some(earlier),
                )?)
            };
            let v = other.as_ref().unwrap_or(&part);
            merged.merge(probe_of(comm, v, clip.as_ref())?);
            let (lo, hi) = world_box(v.summary.bounds, &world);
            bounds = (
                std::array::from_fn(|a| bounds.0[a].min(lo[a])),
                std::array::from_fn(|a| bounds.1[a].max(hi[a])),
            );
            attribute = union(attribute, v.summary.attribute_range);
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
        // The first frame again, now with the series' attribute range.
        let part = if series.particles.as_ref().and_then(|p| p.attribute_range)
            != desc.particles.as_ref().and_then(|p| p.attribute_range)
        {
            open_part(comm, &series, base, first, Purpose::Render, Some(earlier))?
        } else {
            part
        };
        let loading = part.notes.len();
        let mut scene = resolve(comm, part, &series, base, Some(&merged), Some(bounds))?;
        // As one process says them: loading notes, the series, the view's.
        let view_notes = scene.notes.split_off(loading);
        scene.notes.push(format!(
            "time series of {} frames: {} over frames {which}",
            frames.len(),
            what.join(", ")
        ));
        scene.notes.extend(view_notes);
        Ok((scene, series))
    }

    /// Moves the scene to frame `frame` of its series (`desc`: the series'
    /// description from [`DistributedScene::open_series`]), as
    /// [`crate::Scene::load_frame`] does: the data in the first frame's
    /// world frame (particles keep their settings), the view unchanged.
    pub fn load_frame(
        &mut self,
        comm: &dyn Comm,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
    ) -> Result<(), ParallelError> {
        if !matches!(
            self.summary.kind,
            VolumeKind::Particles | VolumeKind::Materials
        ) {
            return Err(SceneError::setting(
                "frames",
                "time series are supported for particle data",
            )
            .into());
        }
        let settings = match &self.part {
            Some(AnyVolume::Particles(v)) => Some(v.settings().clone()),
            _ => None,
        };
        let earlier = Earlier {
            world: &self.frame,
            settings: settings.as_ref(),
        };
        let part = open_part(comm, desc, base, frame, Purpose::Render, Some(earlier))?;
        self.settings.domain = Some(Domain {
            owned: part.decomposition.box_of(comm.rank()),
            bounds: part.summary.bounds,
        });
        self.part = part.volume;
        self.decomposition = part.decomposition;
        self.summary = part.summary;
        self.counts = part.counts;
        Ok(())
    }

    /// An error when the field is 0 everywhere (as the one-process work
    /// check refuses it): there would be nothing to render.
    pub fn check_field(&self) -> Result<(), SceneError> {
        let data: Range1 = self.summary.value_range;
        if self.summary.kind == VolumeKind::Materials || data.hi > 0.0 || data.lo < 0.0 {
            return Ok(());
        }
        let (field, why) = match self.summary.kind {
            VolumeKind::Particles => (
                "particles.weights (--weights)",
                "every particle's weight is 0 (or a weight or radius map hides it)",
            ),
            VolumeKind::Amr => ("amr.field (--field)", "every cell's value is 0"),
            _ => ("data", "it holds no mass"),
        };
        Err(SceneError::setting(
            field,
            format!("the field is 0 everywhere, so there is nothing to render: {why}"),
        ))
    }
}
