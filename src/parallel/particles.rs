//! Particles (and multi-material particles) over the ranks: each rank
//! reads its share of every set through the one-process reader, the ranks
//! agree on one world frame and on each set's statistics
//! (`crate::load::whole_set`), decompose the probes' positions (materials
//! share the boxes), and send every particle to each box its support
//! overlaps; each rank builds its part in row order.

use std::path::Path;

use voxless_core::{Aabb, Range1, Vec3};
use voxless_parallel::{Comm, CommExt, Decomposition, Reader};
use voxless_particles::{
    FieldStatistics, ParticleData, ParticleSettings, ParticleVolume, images, support_box,
};
use voxless_scene::ParticlesDesc;

use super::share::{exchange, outboxes, root_box};
use super::{ParallelError, Part, PartCounts};
use crate::load::Share;
use crate::load::materials::{build_materials, material_descs};
use crate::load::particles::{blame, frame_for, read_rows};
use crate::load::whole_set::{self, RowRadii, Set, agree, world_reach};
use crate::{AnyVolume, SceneError, VolumeKind, VolumeSummary, WorldFrame};

/// What a later frame of a time series keeps of the first: its world
/// frame, and (particles of one set) its settings, as
/// [`crate::Scene::load_frame`] keeps them.
#[derive(Clone, Copy)]
pub(crate) struct Earlier<'a> {
    pub world: &'a WorldFrame,
    pub settings: Option<&'a ParticleSettings>,
}

pub(crate) fn open(
    comm: &dyn Comm,
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    earlier: Option<Earlier>,
) -> Result<Part, ParallelError> {
    let mut notes = Vec::new();
    let descs = match &p.materials {
        Some(mats) => material_descs(p, mats)?,
        None => vec![p.clone()],
    };
    // Every set's rows first, so one frame fits them all (as one process
    // fits the frame over every material).
    let share = Share {
        rank: comm.rank(),
        ranks: comm.size(),
    };
    let mut read = Vec::with_capacity(descs.len());
    for d in &descs {
        let mut rows = agree(comm, read_rows(d, base, frame, share))?;
        whole_set::neighbour_radii(comm, d, &mut rows, &mut notes)?;
        notes.extend(rows.notes.iter().cloned());
        read.push(rows);
    }
    let world = match earlier {
        Some(e) => *e.world,
        None => {
            let mut reach: Option<([f64; 3], [f64; 3])> = None;
            for (d, rows) in descs.iter().zip(&read) {
                if let Some(r) = world_reach(comm, d, rows)? {
                    reach = Some(match reach {
                        None => r,
                        Some(a) => (
                            std::array::from_fn(|i| a.0[i].min(r.0[i])),
                            std::array::from_fn(|i| a.1[i].max(r.1[i])),
                        ),
                    });
                }
            }
            frame_for(reach)
        }
    };
    let keep = earlier.and_then(|e| e.settings);
    let mut sets = Vec::with_capacity(descs.len());
    for (d, rows) in descs.iter().zip(read) {
        sets.push(Set::settle(comm, d, rows, &world, keep, &mut notes)?);
    }
    // One decomposition for every set, from all probes (the same on every
    // rank: the probes were gathered).
    let bounds = sets.iter().fold(Aabb::EMPTY, |b, s| b.union(s.bounds));
    let points: Vec<(Vec3, f32)> = sets
        .iter()
        .flat_map(|s| s.probes.iter().map(|&(c, _)| (c, 1.0)))
        .collect();
    let decomposition = Decomposition::build(root_box(bounds), &points, comm.size());
    let read = sets
        .iter()
        .map(|s| s.rows.data.positions.len() as u64)
        .sum();
    let mut volumes = Vec::with_capacity(sets.len());
    for s in sets {
        volumes.push(into_part(s, comm, &decomposition, world.scale)?);
    }
    let held = volumes.iter().map(|v| v.0.len() as u64).sum();
    let radii = match volumes.as_slice() {
        [(_, r)] => Some(r.clone()),
        _ => None,
    };
    let mut volumes: Vec<ParticleVolume> = volumes.into_iter().map(|v| v.0).collect();
    let counts = PartCounts { read, held };
    let (volume, summary) = match &p.materials {
        Some(mats) => {
            let mut parts = volumes.into_iter();
            let v = build_materials(p, mats, &mut notes, &mut |_, _| {
                parts.next().ok_or_else(|| {
                    SceneError::setting("particles.materials", "a material has no particles")
                })
            })?;
            let summary = VolumeSummary {
                kind: VolumeKind::Materials,
                bounds,
                value_range: voxless_core::Volume::value_range(&v),
                attribute_range: None,
            };
            (AnyVolume::Materials(Box::new(v)), summary)
        }
        None => {
            let v = volumes.pop().ok_or_else(|| {
                ParallelError::Scene(SceneError::setting("particles", "no particles"))
            })?;
            let summary = VolumeSummary {
                kind: VolumeKind::Particles,
                bounds,
                value_range: v.statistics().value_range,
                attribute_range: voxless_core::Volume::attribute_range(&v),
            };
            (AnyVolume::Particles(Box::new(v)), summary)
        }
    };
    Ok(Part {
        fields: volume.fields(),
        volume: Some(volume),
        frame: world,
        summary,
        decomposition,
        counts,
        notes,
        radii,
    })
}

/// Sends every particle to the boxes its support overlaps (in a periodic
/// box, every image of it that reaches into the box) and builds this
/// rank's part, with the whole set's density range; also returns this
/// rank's rows' radius parameters in world units.
fn into_part(
    set: Set,
    comm: &dyn Comm,
    d: &Decomposition,
    scale: f64,
) -> Result<(ParticleVolume, Box<RowRadii>), ParallelError> {
    let Set {
        rows,
        settings,
        radius,
        probes,
        median_support,
        ..
    } = set;
    let data = &rows.data;
    let kernel = settings.kernel;
    let mut out = outboxes(comm);
    let mut dst = Vec::new();
    let mut found = Vec::new();
    let factor = kernel.support_factor();
    for (i, q) in data.positions.iter().enumerate() {
        let (b, support) = (settings.periodic.as_ref(), factor * radius[i]);
        images(b, *q, support, rows.offset + i, &mut found)
            .map_err(|e| blame(rows.main_file.clone(), &rows.files, e))?;
        for &(shift, image) in &found {
            // Hidden particles (radius 0 after the map) touch nothing.
            d.overlapping(&support_box(image, radius[i], kernel), &mut dst);
            for &r in &dst {
                let w = &mut out[r];
                w.u64((rows.offset + i) as u64);
                shift.iter().for_each(|&k| w.u8(k as u8));
                w.vec3(image);
                for v in [&data.radii, &data.weights, &data.attribute]
                    .into_iter()
                    .flatten()
                {
                    w.f32(v[i]);
                }
            }
        }
    }
    let own_radii = Box::new(RowRadii {
        offset: rows.offset,
        values: radius.iter().map(|&r| (r as f64 * scale) as f32).collect(),
    });
    let has = [
        data.radii.is_some(),
        data.weights.is_some(),
        data.attribute.is_some(),
    ];
    // The rows are in the messages now: free them before the exchange.
    let (main_file, files) = (rows.main_file, rows.files);
    drop((rows.data, radius));
    // (row, image shift), centre, per-particle values.
    type Item = ((u64, [i8; 3]), Vec3, [f32; 3]);
    let mut items: Vec<Item> = Vec::new();
    for msg in exchange(comm, out)? {
        let mut r = Reader::new(&msg);
        while !r.is_done() {
            let row = r.u64()?;
            let shift = [r.u8()? as i8, r.u8()? as i8, r.u8()? as i8];
            let row = (row, shift);
            let q = r.vec3()?;
            let mut v = [0.0f32; 3];
            for (k, &h) in has.iter().enumerate() {
                if h {
                    v[k] = r.f32()?;
                }
            }
            items.push((row, q, v));
        }
    }
    // Row order: the part's own order does not depend on who sent what.
    items.sort_unstable_by_key(|it| it.0);
    let column = |k: usize| has[k].then(|| items.iter().map(|it| it.2[k]).collect());
    let part_data = ParticleData {
        positions: items.iter().map(|it| it.1).collect(),
        radii: column(0),
        weights: column(1),
        attribute: column(2),
    };
    let stats = FieldStatistics {
        median_support,
        value_range: Range1::new(0.0, 0.0),
    };
    drop(items);
    let built = ParticleVolume::new_part(part_data, settings, stats)
        .map_err(|e| blame(main_file.clone(), &files, e));
    let mut part = agree(comm, built)?;
    // The density range: each probe evaluated where its box is.
    let me = comm.rank();
    let local = probes
        .iter()
        .filter(|p| d.owner(p.0) == me)
        .map(|p| part.density_exact(p.0))
        .fold(0.0f32, f32::max);
    let max = comm.all_max(&[local as f64])?[0] as f32;
    part.set_value_range(Range1::new(0.0, max));
    Ok((part, own_radii))
}
