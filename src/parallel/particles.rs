//! Particles (and multi-material particles) over the ranks, through the
//! one-process pipeline of `crate::load::particles` step by step.
//!
//! 1. Each rank reads rows `n·r/K .. n·(r+1)/K` in float64 — by offset from
//!    `.npy` files, by hyperslab from HDF5; any other format is read whole
//!    and cut (its rows are not at known offsets).
//! 2. The world frame from the whole data's reach (min/max of the
//!    positions, max of the radii), as one process fits it over every
//!    material; each rank places its rows in it.
//! 3. The whole set's defaults and statistics, from mergeable pieces: the
//!    default radius from the median nearest-neighbour spacing (the occupied
//!    cells of the coarse grid are an OR of the ranks' grids; each probe's
//!    nearest neighbour is the minimum over the ranks' particles), the
//!    attribute range (min/max), and the probes — every `stride`-th row,
//!    found by row number and gathered — for the median support (the step)
//!    and the density range (each probe evaluated by the rank whose box
//!    holds it, then the maximum).
//! 4. One decomposition for all sets (materials share the boxes), from the
//!    probes' positions; every particle goes to each box its support
//!    overlaps, and each rank builds its part in row order.

use std::path::{Path, PathBuf};

use voxless_core::{Aabb, Range1, Vec3};
use voxless_parallel::{Comm, CommExt, Decomposition, Reader, Writer};
use voxless_particles::{
    FieldStatistics, ParticleData, ParticleError, ParticleSettings, ParticleVolume, check_data,
    median, probe_stride, support_box,
};
use voxless_scene::ParticlesDesc;

use super::share::{agree, exchange, outboxes, root_box, share, union_bounds};
use super::{Columns, ParallelError, Part, PartCounts};
use crate::load::materials::{build_materials, material_descs};
use crate::load::particles::{
    FrameData, blame, frame_file, frame_for, in_world_units, locate, particle_settings,
    prepare_arrays, radius_from_spacing, read_frame_share,
};
use crate::{AnyVolume, SceneError, VolumeKind, VolumeSummary, WorldFrame};

mod whole;
use whole::{WorldBox, check_resolvable, whole_spacing, world_reach};

/// One rank's rows of a particle set.
struct Rows {
    /// World positions (float64), and the other arrays in world units (no
    /// positions until placed in the frame).
    world: Vec<[f64; 3]>,
    data: ParticleData,
    /// Row number of the first row, and the set's row count.
    offset: usize,
    total: usize,
    main_file: PathBuf,
    files: Vec<(&'static str, PathBuf)>,
    sph_defaults: Option<voxless_particles::Kernel>,
    notes: Vec<String>,
}

/// A set's rows with the whole set's settings and statistics.
struct Set {
    rows: Rows,
    settings: ParticleSettings,
    /// Effective radius per row (after the radius map).
    radius: Vec<f32>,
    /// Every probe of the set, in row order: centre and effective radius.
    probes: Vec<(Vec3, f32)>,
    median_support: f32,
    /// The union of the visible supports: the set's bounds.
    bounds: Aabb,
}

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
        Some(mats) => {
            if p.species.is_some() {
                return Err(SceneError::setting(
                    "particles.species",
                    "give the species per material ([[particles.materials]] species = ...), \
                     not both",
                )
                .into());
            }
            material_descs(p, mats)
        }
        None => vec![p.clone()],
    };
    // Every set's rows first, so one frame fits them all (as one process
    // fits the frame over every material).
    let mut read = Vec::with_capacity(descs.len());
    for d in &descs {
        let rows = agree(comm, read_rows(d, base, frame, comm.rank(), comm.size()))?;
        notes.extend(rows.notes.iter().cloned());
        read.push(rows);
    }
    let world = match earlier {
        Some(e) => *e.world,
        None => {
            let mut reach: Option<WorldBox> = None;
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
        volumes.push(s.into_part(comm, &decomposition)?);
    }
    let held = volumes.iter().map(|v| v.len() as u64).sum();
    let counts = PartCounts { read, held };
    let frame_ = world;
    match &p.materials {
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
            let names = v.materials().iter().map(|m| m.name.clone()).collect();
            Ok(Part {
                volume: Some(AnyVolume::Materials(Box::new(v))),
                frame: frame_,
                summary,
                decomposition,
                columns: Columns::Materials(names),
                colour_name: None,
                counts,
                notes,
            })
        }
        None => {
            let v = volumes.pop().ok_or_else(|| {
                ParallelError::Scene(SceneError::setting("particles", "no particles"))
            })?;
            let attribute = v.has_attribute();
            let summary = VolumeSummary {
                kind: VolumeKind::Particles,
                bounds,
                value_range: v.statistics().value_range,
                attribute_range: voxless_core::Volume::attribute_range(&v),
            };
            let colour_name = match &p.attribute {
                Some(spec) => crate::camera::name_of(spec),
                None if attribute => Some("temperature".into()),
                None => Some("density".into()),
            };
            Ok(Part {
                volume: Some(AnyVolume::Particles(Box::new(v))),
                frame: frame_,
                summary,
                decomposition,
                columns: Columns::Particles { attribute },
                colour_name,
                counts,
                notes,
            })
        }
    }
}

impl Set {
    /// Places this rank's rows in the frame `world` and agrees with the
    /// other ranks on the set's settings and statistics.
    fn settle(
        comm: &dyn Comm,
        p: &ParticlesDesc,
        mut rows: Rows,
        world: &WorldFrame,
        keep: Option<&ParticleSettings>,
        notes: &mut Vec<String>,
    ) -> Result<Set, ParallelError> {
        rows.data.positions = rows.world.iter().map(|&q| world.to_local(q)).collect();
        rows.world = Vec::new();
        let kernel = prepare_arrays(&mut rows.data, p, rows.sph_defaults, world.scale)?;
        let blame_it = |e: ParticleError| blame(rows.main_file.clone(), &rows.files, e);
        agree(comm, check_data(&rows.data, rows.offset).map_err(blame_it))?;
        // Every rank takes the same branches here (they depend on the
        // description and on which arrays are given), so a default radius
        // is found by all of them together.
        let mut settings = match keep {
            // A later frame of a series keeps the first frame's settings.
            Some(k) => k.clone(),
            None => {
                let mut comm_error = None;
                let settings = particle_settings(
                    p,
                    kernel,
                    rows.data.radii.is_some(),
                    &mut |kernel| match whole_spacing(comm, &rows) {
                        Ok(d) => radius_from_spacing(d, rows.total, kernel),
                        Err(e) => {
                            comm_error = Some(e);
                            (1.0, String::new())
                        }
                    },
                    world.scale,
                    notes,
                )?;
                if let Some(e) = comm_error {
                    return Err(e);
                }
                let support = settings.radius * kernel.support_factor();
                check_resolvable(comm, &rows, support, world.scale)?;
                settings
            }
        };
        let mut own = Aabb::EMPTY;
        for q in &rows.data.positions {
            own.grow(*q);
        }
        let positions = union_bounds(comm, own)?;
        if rows.data.attribute.is_none() {
            for (what, present) in [
                ("radius map", settings.radius_map.is_some()),
                ("weight map", settings.weight_map.is_some()),
            ] {
                if present {
                    return Err(blame_it(ParticleError::NeedsAttribute { what }).into());
                }
            }
        }
        if let (None, Some(a)) = (settings.attribute_range, &rows.data.attribute) {
            let (lo, hi) = a
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v as f64), hi.max(v as f64))
                });
            let lo = comm.all_min(&[lo])?[0];
            let hi = comm.all_max(&[hi])?[0];
            settings.attribute_range = Some(if lo <= hi {
                Range1::new(lo as f32, hi as f32)
            } else {
                Range1::EMPTY
            });
        }
        let range = settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
        let n = rows.data.positions.len();
        let radius: Vec<f32> = (0..n)
            .map(|i| {
                let base = rows.data.radii.as_ref().map_or(settings.radius, |r| r[i]);
                let attr = rows.data.attribute.as_ref().map(|a| a[i]);
                settings.effective_radius(base, attr, range)
            })
            .collect();
        // The probes, gathered in row order.
        let stride = probe_stride(rows.total);
        let mut w = Writer::new();
        for (i, (q, r)) in rows.data.positions.iter().zip(&radius).enumerate() {
            if (rows.offset + i).is_multiple_of(stride) {
                w.u8(1);
                w.vec3(*q);
                w.f32(*r);
            }
        }
        let mut probes = Vec::new();
        for msg in comm.all_gather(&w.into_bytes())? {
            let mut r = Reader::new(&msg);
            while !r.is_done() {
                r.u8()?;
                probes.push((r.vec3()?, r.f32()?));
            }
        }
        let kernel = settings.kernel;
        let factor = kernel.support_factor();
        // As the whole volume checks it: the probes' median support against
        // the positions' extent.
        if rows.total > 1000 {
            let mut supports: Vec<f32> = probes.iter().map(|p| p.1 * factor).collect();
            let support = median(&mut supports);
            let extent = positions.diagonal();
            if support > extent {
                let e = ParticleError::HugeRadius {
                    support,
                    extent,
                    count: rows.total,
                };
                return Err(blame_it(in_world_units(e, world.scale)).into());
            }
        }
        let mut visible: Vec<f32> = probes
            .iter()
            .filter(|p| p.1 > 0.0)
            .map(|p| {
                let s = factor * p.1;
                (s * s).sqrt()
            })
            .collect();
        let mut own = Aabb::EMPTY;
        for (q, &r) in rows.data.positions.iter().zip(&radius) {
            own = own.union(support_box(*q, r, kernel));
        }
        let bounds = union_bounds(comm, own)?;
        let median_support = if visible.is_empty() {
            bounds.diagonal().max(1e-6)
        } else {
            median(&mut visible)
        };
        Ok(Set {
            rows,
            settings,
            radius,
            probes,
            median_support,
            bounds,
        })
    }

    /// Sends every particle to the boxes its support overlaps and builds
    /// this rank's part, with the whole set's density range.
    fn into_part(
        self,
        comm: &dyn Comm,
        d: &Decomposition,
    ) -> Result<ParticleVolume, ParallelError> {
        let Set {
            rows,
            settings,
            radius,
            probes,
            median_support,
            ..
        } = self;
        let data = &rows.data;
        let kernel = settings.kernel;
        let mut out = outboxes(comm);
        let mut dst = Vec::new();
        for (i, q) in data.positions.iter().enumerate() {
            // Hidden particles (radius 0 after the map) touch nothing.
            d.overlapping(&support_box(*q, radius[i], kernel), &mut dst);
            for &r in &dst {
                let w = &mut out[r];
                w.u64((rows.offset + i) as u64);
                w.vec3(*q);
                for v in [&data.radii, &data.weights, &data.attribute]
                    .into_iter()
                    .flatten()
                {
                    w.f32(v[i]);
                }
            }
        }
        let has = [
            data.radii.is_some(),
            data.weights.is_some(),
            data.attribute.is_some(),
        ];
        // The rows are in the messages now: free them before the exchange.
        let (main_file, files) = (rows.main_file, rows.files);
        drop((rows.data, radius));
        let mut items: Vec<(u64, Vec3, [f32; 3])> = Vec::new();
        for msg in exchange(comm, out)? {
            let mut r = Reader::new(&msg);
            while !r.is_done() {
                let row = r.u64()?;
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
        Ok(part)
    }
}

/// This rank's rows of the particle set `p` describes at `frame` (world
/// positions; no local positions yet).
fn read_rows(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    rank: usize,
    ranks: usize,
) -> Result<Rows, SceneError> {
    if let Some(rows) = npy_rows(p, base, frame, rank, ranks)? {
        return Ok(rows);
    }
    // Any other format: read the frame and keep this rank's rows — HDF5
    // files read only those (hyperslabs) when the per-particle arrays are
    // columns of the file.
    let columns_only = [&p.attribute, &p.radii, &p.weights]
        .into_iter()
        .flatten()
        .all(|spec| !is_npy(&base.join(spec)));
    let part = (p.species.is_none() && columns_only).then_some((rank, ranks));
    let FrameData {
        positions,
        data,
        main_file,
        files,
        sph_defaults,
        notes,
        rows,
    } = read_frame_share(p, base, frame, part)?;
    if let Some((offset, total)) = rows {
        return Ok(Rows {
            world: positions,
            data,
            offset,
            total,
            main_file,
            files,
            sph_defaults,
            notes,
        });
    }
    let total = positions.len();
    let r = share(total, rank, ranks);
    let cut = |v: Option<Vec<f32>>| v.map(|v| v[r.clone()].to_vec());
    Ok(Rows {
        world: positions[r.clone()].to_vec(),
        data: ParticleData {
            positions: Vec::new(),
            radii: cut(data.radii),
            attribute: cut(data.attribute),
            weights: cut(data.weights),
        },
        offset: r.start,
        total,
        main_file,
        files,
        sph_defaults,
        notes,
    })
}

fn is_npy(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// This rank's rows read by offset, when the positions and every
/// per-particle array are `.npy` files of the right shapes; `None` sends
/// the read down the general path (which also words any error).
fn npy_rows(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    rank: usize,
    ranks: usize,
) -> Result<Option<Rows>, SceneError> {
    let Some(f) = &p.file else {
        return Ok(None);
    };
    if p.species.is_some() {
        return Ok(None);
    }
    let (path, _) = locate(f, base, frame)?;
    if !is_npy(&path) {
        return Ok(None);
    }
    let (_, shape) = voxless_io::read_npy_rows(&path, 0..0)?;
    if shape.len() != 2 || shape[1] != 3 || shape[0] == 0 {
        return Ok(None);
    }
    let total = shape[0];
    let rows = share(total, rank, ranks);
    let mut files = Vec::new();
    let mut per = |spec: &Option<String>,
                   what: &'static str|
     -> Result<Option<Option<Vec<f32>>>, SceneError> {
        let Some(s) = spec else {
            return Ok(Some(None));
        };
        let spec = if crate::frames::is_sequence(s, base) {
            frame_file(s, base, frame)?
        } else {
            base.join(s)
        };
        if !is_npy(&spec) || !spec.is_file() {
            return Ok(None);
        }
        let (a, shape) = voxless_io::read_npy_rows(&spec, rows.clone())?;
        if !matches!(shape.as_slice(), [n] | [n, 1] if *n == total) {
            return Ok(None);
        }
        files.push((what, spec));
        Ok(Some(Some(a.data.iter().map(|&v| v as f32).collect())))
    };
    let (Some(attribute), Some(radii), Some(weights)) = (
        per(&p.attribute, "attribute")?,
        per(&p.radii, "radii")?,
        per(&p.weights, "weights")?,
    ) else {
        return Ok(None);
    };
    let (a, _) = voxless_io::read_npy_rows(&path, rows.clone())?;
    let world = a.data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Ok(Some(Rows {
        world,
        data: ParticleData {
            positions: Vec::new(),
            radii,
            attribute,
            weights,
        },
        offset: rows.start,
        total,
        main_file: path,
        files,
        sph_defaults: None,
        notes: Vec::new(),
    }))
}
