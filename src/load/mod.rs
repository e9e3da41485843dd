//! Loading: files named by a scene description become a volume — the front
//! half every front-end shares, one process or many.
//!
//! - **Which data** (`source`): the description's one data source, a
//!   JaxPM `.h5` given as particles recognised as its tessellation.
//! - **Which part of it** ([`Share`]): one process reads everything; the
//!   ranks of a decomposed scene read one share each (rows of a `.npy`,
//!   cells of an ExaBricks file, Lagrangian slabs), through the same
//!   readers, with the same checks and error texts.
//! - **The data's own defaults** (a particle radius from the spacing, SPH
//!   kernels for SPH files, the world frame), filled here and said in the
//!   notes; over ranks from statistics the ranks merge, so they equal the
//!   one-process defaults.
//!
//! Every reader's failure is a [`SceneError`] naming the file. Defaults of
//! the view (camera, transfer function, settings) are not filled here:
//! resolving does that, for loaded and in-memory volumes alike.

pub(crate) mod amr;
pub mod formats;
pub mod frames;
pub(crate) mod jaxpm;
pub(crate) mod materials;
pub(crate) mod particles;
pub(crate) mod periodic;
pub(crate) mod reach;
pub(crate) mod scale;
pub(crate) mod snapshot;
pub(crate) mod spacing;
mod sph;
pub(crate) mod spread_radii;
pub(crate) mod table;
pub(crate) mod tets;
pub(crate) mod whole_set;

use std::borrow::Cow;
use std::ops::Range;
use std::path::Path;

use voxless_io::IoError;
use voxless_scene::{AmrDesc, ParticlesDesc, SceneDesc, TetsDesc};

pub use amr::AmrArrays;
pub(crate) use amr::{amr_settings, build_amr, cells_reach};
pub use particles::{SUPPORT_PER_SPACING, default_radius, frame_count, frame_numbers};

use crate::{AnyVolume, SceneError, WorldFrame};

/// A loaded volume, the world frame its coordinates are relative to, and
/// what was worth saying about loading it.
pub struct Loaded {
    pub volume: AnyVolume,
    pub frame: WorldFrame,
    pub notes: Vec<String>,
}

/// The part of a data set one process reads: share `rank` of `ranks`, rows
/// `n·rank/ranks .. n·(rank+1)/ranks` of `n` (every row in exactly one
/// share, shares in rank order). One process reads [`Share::WHOLE`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Share {
    pub rank: usize,
    pub ranks: usize,
}

impl Share {
    /// Everything, for one process.
    pub const WHOLE: Share = Share { rank: 0, ranks: 1 };

    /// Whether this share is all of the data.
    pub fn is_whole(self) -> bool {
        self.ranks <= 1
    }

    /// This share's rows of `n`.
    pub fn rows(self, n: usize) -> Range<usize> {
        let ranks = self.ranks.max(1) as u128;
        let at = |r: usize| (n as u128 * r as u128 / ranks) as usize;
        at(self.rank)..at(self.rank + 1)
    }
}

/// Lagrangian positions in world units (a tessellation's N³ grid, or a
/// share's planes of it), before they are placed in a frame.
pub(crate) struct WorldGrid {
    pub n: usize,
    /// The periodic box's side.
    pub box_size: f64,
    pub positions: Vec<[f64; 3]>,
}

/// What a scene is loaded for; it decides what each box of a decomposed
/// scene keeps (one process keeps everything either way).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Everything reaching into the box (renders and point samples).
    Render,
    /// Column densities: tessellations keep each tet in one box only (the
    /// box holding its centroid), so the boxes' projections add up; the
    /// other kinds keep what reaches into the box and integrate inside it.
    Project,
}

/// The one data source a description names.
pub(crate) enum Source<'a> {
    /// Particles (with `materials`, several species of one file; several
    /// snapshot types become materials, see
    /// [`materials::with_types`]).
    Particles(Box<Cow<'a, ParticlesDesc>>),
    Amr(Cow<'a, AmrDesc>),
    /// A phase-space tessellation: a `[tets]` table, or a JaxPM run given
    /// as particles.
    Tets(Cow<'a, TetsDesc>),
}

/// The data source `desc` names (paths relative to `base`): an error when
/// it names none or more than one.
pub(crate) fn source<'a>(desc: &'a SceneDesc, base: &Path) -> Result<Source<'a>, SceneError> {
    let sources = [
        desc.particles.is_some(),
        desc.amr.is_some(),
        desc.tets.is_some(),
    ];
    if sources.iter().filter(|&&s| s).count() > 1 {
        return Err(SceneError::setting(
            "scene",
            "more than one data source ([particles], [amr], [tets]) is given; pick one",
        ));
    }
    if let Some(p) = &desc.particles {
        // `--particles run.h5` of a JaxPM run: its tessellation.
        return Ok(match jaxpm::as_tessellation(p, base)? {
            Some(t) => Source::Tets(Cow::Owned(t)),
            None => Source::Particles(Box::new(materials::with_types(p)?)),
        });
    }
    match (&desc.amr, &desc.tets) {
        (Some(a), _) => Ok(Source::Amr(Cow::Borrowed(a))),
        (_, Some(t)) => Ok(Source::Tets(Cow::Borrowed(t))),
        (None, None) => Err(SceneError::setting(
            "scene",
            "no data source: add a [particles], [amr] or [tets] table to the scene, or pass \
             --particles FILE (with --lagrangian N --box L for a phase-space tessellation), \
             --amr PATH (AMReX, FLASH, Enzo, Athena++, AMRClaw), --cells FILE --scalars FILE, or \
             --amrclaw FILE (or use `voxless demo`)",
        )),
    }
}

/// The AMR output `a` names when it is a sequence of numbered outputs
/// (`file` or `amrclaw`, e.g. `fort.q%04d` or `plt*`): the spec and
/// whether it is `file`.
pub(crate) fn amr_sequence(a: &AmrDesc, base: &Path) -> Option<(String, bool)> {
    let (spec, is_file) = match (&a.file, &a.amrclaw) {
        (Some(f), _) => (f, true),
        (None, Some(q)) => (q, false),
        _ => return None,
    };
    frames::is_sequence(spec, base).then(|| (spec.clone(), is_file))
}

/// [`source`], refusing a frame other than 0 of data that has one frame
/// (AMR cells, a tessellation: their files are not read as time series, so
/// the frame would be ignored without a word).
pub(crate) fn source_at<'a>(
    desc: &'a SceneDesc,
    base: &Path,
    frame: usize,
) -> Result<Source<'a>, SceneError> {
    let s = source(desc, base)?;
    let what = match s {
        // A sequence of AMR outputs (fort.q%04d, plt*): the file of this frame.
        Source::Amr(a) if amr_sequence(&a, base).is_some() => {
            let Some((spec, _)) = amr_sequence(&a, base) else {
                unreachable!()
            };
            let file = frames::file_numbered(&spec, base, frame)?;
            let file = file.strip_prefix(base).unwrap_or(&file);
            let file = Some(file.to_string_lossy().into_owned());
            let mut a = a.into_owned();
            match a.file {
                Some(_) => a.file = file,
                None => a.amrclaw = file,
            }
            return Ok(Source::Amr(Cow::Owned(a)));
        }
        Source::Amr(_) => "AMR cells have",
        // A sequence of numbered position files: the file of this frame.
        Source::Tets(t)
            if t.file
                .as_deref()
                .is_some_and(|f| frames::is_sequence(f, base)) =>
        {
            let spec = t.file.as_deref().unwrap_or_default();
            let file = frames::file_numbered(spec, base, frame)?;
            // Relative to `base` again, as the description's paths are.
            let file = file.strip_prefix(base).unwrap_or(&file);
            let mut t = t.into_owned();
            t.file = Some(file.to_string_lossy().into_owned());
            return Ok(Source::Tets(Cow::Owned(t)));
        }
        Source::Tets(_) => "a phase-space tessellation has",
        Source::Particles(_) => return Ok(s),
    };
    if frame > 0 {
        return Err(SceneError::setting(
            "frame (--frame, --frames)",
            format!(
                "frame {frame} was asked for, but {what} one frame, 0 (a single file is not a \
                 time series; give numbered files, e.g. fort.q%04d or step_%03d.npy)"
            ),
        ));
    }
    Ok(s)
}

/// Loads the data `desc` names (paths relative to `base`) at frame `frame`
/// of a time series (0 for single frames), in the frame the placement
/// policy picks for it (see [`WorldFrame::fit`]).
pub fn load(desc: &SceneDesc, base: &Path, frame: usize) -> Result<Loaded, SceneError> {
    load_in(desc, base, frame, None)
}

/// [`load`] for `purpose`: a projection integrates one field, so AMR text
/// output has only that field parsed (and the colour field a description
/// names, so its settings resolve); renders and samples read every field.
pub fn load_for(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    purpose: Purpose,
) -> Result<Loaded, SceneError> {
    load_with(desc, base, frame, None, purpose)
}

/// [`load`] in a given world frame (`None`: the one the policy picks) —
/// how every frame of a time series lands in the frame of the first.
pub fn load_in(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    world: Option<&WorldFrame>,
) -> Result<Loaded, SceneError> {
    load_with(desc, base, frame, world, Purpose::Render)
}

fn load_with(
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    world: Option<&WorldFrame>,
    purpose: Purpose,
) -> Result<Loaded, SceneError> {
    let mut notes = Vec::new();
    let (volume, world) = match source_at(desc, base, frame)? {
        Source::Particles(p) => match &p.materials {
            Some(mats) => {
                let (v, f) = materials::load_materials(&p, mats, base, &mut notes, frame, world)?;
                (AnyVolume::Materials(Box::new(v)), f)
            }
            None => {
                let (v, f) = particles::load_particles(&p, base, &mut notes, frame, world)?;
                (AnyVolume::Particles(Box::new(v)), f)
            }
        },
        Source::Amr(a) => {
            let (v, f) = amr::load_amr(&a, base, amr::field_pick(&a, purpose))?;
            (AnyVolume::Amr(Box::new(v)), f)
        }
        Source::Tets(t) => {
            let (v, f) = tets::load_tets(&t, base, &mut notes)?;
            (AnyVolume::Tets(Box::new(v)), f)
        }
    };
    Ok(Loaded {
        volume,
        frame: world,
        notes,
    })
}

/// Query points for `sample`, in world coordinates (float64): an N×3
/// `.npy` (float32/float64) or a CSV with x, y, z columns; non-finite
/// coordinates are an error naming the point.
/// The data flag a file given on its own is read with, for front-ends
/// that take a bare path: `cells` for ExaBricks `.cells`, `amrclaw` for
/// `fort.qNNNN`, `amr` for the other AMR outputs ([`voxless_io::amr_format`]:
/// an AMReX plotfile directory, an Enzo parameter file, Athena++ `.athdf`,
/// FLASH HDF5 when HDF5 support is built in), else `particles`.
pub fn data_flag_for(path: &Path) -> &'static str {
    use voxless_io::AmrFormat;
    match voxless_io::amr_format(path) {
        Ok(AmrFormat::ExaBricks) => "cells",
        Ok(AmrFormat::AmrClaw) => "amrclaw",
        // Without HDF5 support any HDF5 file looks like FLASH: it is read
        // as particles, whose reader says what is missing.
        Ok(AmrFormat::Flash) if !cfg!(feature = "hdf5") => "particles",
        Ok(_) => "amr",
        Err(_) => "particles",
    }
}

pub fn read_points(path: &Path) -> Result<Vec<[f64; 3]>, SceneError> {
    let (points, _) = table::read_positions(path)?;
    if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(SceneError::data(
            path,
            format!("point {i} has a non-finite coordinate"),
        ));
    }
    Ok(points)
}

/// Reads a TOML scene file (unknown keys are errors, so typos surface).
pub fn read_scene(path: &Path) -> Result<SceneDesc, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Io {
        path: path.into(),
        source,
    })?;
    parse_scene(&text).map_err(|message| SceneError::Toml {
        path: path.into(),
        message,
    })
}

/// Parses a scene from TOML text (unknown keys are errors).
pub fn parse_scene(text: &str) -> Result<SceneDesc, String> {
    toml::from_str(text).map_err(|e| e.to_string())
}
