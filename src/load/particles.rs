//! Particles: one frame of any particle file (or a sequence of files), or
//! arrays in memory, through one constructor that fills the data's own
//! defaults (the radius from the particle spacing, SPH kernels for SPH
//! files) — every failure a [`SceneError`] naming the file at fault.

use std::path::{Path, PathBuf};

use voxless_core::{Aabb, Range1, Vec3};
use voxless_particles::{
    Classification, Kernel, ParticleData, ParticleError, ParticleSettings, ParticleVolume,
};
use voxless_scene::{ClassificationName, KernelName, ParticlesDesc};
use voxless_transfer::ControlPoints;

use super::formats::{self, ParticleFormat, TableOptions};
use super::{frames, table as load};
use crate::{SceneError, demo};

pub(crate) fn positive(field: &str, v: f32) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::setting(
            field,
            format!("{v} must be finite and > 0"),
        ))
    }
}

pub(crate) fn range(field: &str, lo: f32, hi: f32) -> Result<Range1, SceneError> {
    if lo.is_finite() && hi.is_finite() && lo <= hi {
        Ok(Range1::new(lo, hi))
    } else {
        Err(SceneError::setting(
            field,
            format!("[{lo}, {hi}] is not a finite, increasing range"),
        ))
    }
}

fn kernel_of(p: &ParticlesDesc, name: KernelName) -> Kernel {
    match name {
        KernelName::Gaussian3 => Kernel::Gaussian3,
        KernelName::Gaussian => Kernel::Gaussian {
            kappa: p.kappa.unwrap_or(1.0),
            sigma: p.sigma.unwrap_or(2.0),
        },
        KernelName::CubicSpline => Kernel::CubicSpline,
    }
}

fn control_points(
    field: &str,
    pts: &Option<Vec<[f32; 2]>>,
) -> Result<Option<ControlPoints>, SceneError> {
    pts.as_ref()
        .map(|p| {
            let v: Vec<(f32, f32)> = p.iter().map(|q| (q[0], q[1])).collect();
            ControlPoints::new(field, &v).map_err(SceneError::from)
        })
        .transpose()
}

/// Particle arrays of frame `frame`, the file to blame for bad positions, the
/// files that supplied each per-particle array, whether the SPH defaults
/// (cubic spline, radii = h, weights = m) apply, and notes on what was read.
pub(crate) struct FrameData {
    pub data: ParticleData,
    pub main_file: PathBuf,
    pub files: Vec<(&'static str, PathBuf)>,
    pub sph_defaults: bool,
    pub notes: Vec<String>,
}

/// The file of `spec` for frame `frame`: the `frame`-th of a sequence, or the
/// file itself (the same for every frame).
fn frame_file(spec: &str, base: &Path, frame: usize) -> Result<PathBuf, SceneError> {
    let files = frames::expand(spec, base)?;
    if files.len() == 1 && !frames::is_sequence(spec, base) {
        return Ok(files[0].clone());
    }
    files.get(frame).cloned().ok_or_else(|| {
        SceneError::data(
            base.join(spec),
            format!(
                "frame {frame} requested, but the pattern matches {} files (frames 0..{})",
                files.len(),
                files.len() - 1
            ),
        )
    })
}

/// The particle file of frame `frame` and the frame to read in it: the
/// `frame`-th file (its first frame) of a sequence, else frame `frame` of
/// the file itself (single-frame formats have the same data every frame).
fn locate(spec: &str, base: &Path, frame: usize) -> Result<(PathBuf, usize), SceneError> {
    if frames::is_sequence(spec, base) {
        Ok((frame_file(spec, base, frame)?, 0))
    } else {
        Ok((base.join(spec), frame))
    }
}

/// The columns SPH output carries for smoothing lengths and masses, when
/// `p` gives no kernel: PySPH's `h`, `m` or SWIFT/Gadget's
/// `SmoothingLengths`, `Masses`. `None` unless both are present.
fn sph_columns(p: &ParticlesDesc, source: &load::Source) -> Option<(String, String)> {
    if p.kernel.is_some() || source.format != ParticleFormat::Hdf5 {
        return None;
    }
    let t = &source.table;
    [("h", "m"), ("SmoothingLengths", "Masses")]
        .into_iter()
        .find(|(h, m)| t.column(h).is_some() && t.column(m).is_some())
        .map(|(h, m)| (h.to_string(), m.to_string()))
}

pub(crate) fn read_frame(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
) -> Result<FrameData, SceneError> {
    let mut files: Vec<(&'static str, PathBuf)> = Vec::new();
    let mut notes = Vec::new();
    let mut sph_defaults = false;
    let (data, main_file) = match (&p.file, p.demo.unwrap_or(false)) {
        (Some(f), _) => {
            let (path, in_file) = locate(f, base, frame)?;
            let select = load::Selection {
                options: TableOptions {
                    group: p.group.clone(),
                    part_type: p.part_type,
                },
                species: p.species.as_ref().map(|s| s.0.as_str()),
            };
            let (positions, source, note) = load::open(&path, in_file, &select)?;
            notes.extend(note);
            let n = positions.len();
            let mut data = ParticleData {
                positions,
                ..Default::default()
            };
            let (mut radii, mut weights) = (p.radii.clone(), p.weights.clone());
            if let Some((h, m)) = sph_columns(p, &source) {
                sph_defaults = true;
                let mut used = Vec::new();
                if radii.is_none() && p.radius.is_none() {
                    used.push(format!("radii = {h}"));
                    radii = Some(h);
                }
                if weights.is_none() {
                    used.push(format!("weights = {m}"));
                    weights = Some(m);
                }
                used.insert(0, "cubic-spline kernel".into());
                notes.push(format!(
                    "SPH data and no kernel given: {} (override with --kernel, --radii, --weights)",
                    used.join(", ")
                ));
            }
            let mut per = |spec: &Option<String>,
                           what: &'static str|
             -> Result<Option<Vec<f32>>, SceneError> {
                spec.as_ref()
                    .map(|s| {
                        // A sequence of per-particle files follows the frames.
                        let spec = if frames::is_sequence(s, base) {
                            frame_file(s, base, frame)?.to_string_lossy().into_owned()
                        } else {
                            s.clone()
                        };
                        let (v, path) = load::read_per_particle(&spec, base, &source, n, what)?;
                        files.push((what, path));
                        Ok(v)
                    })
                    .transpose()
            };
            data.attribute = per(&p.attribute, "attribute")?;
            data.radii = per(&radii, "radii")?;
            data.weights = per(&weights, "weights")?;
            (data, path)
        }
        (None, true) => (demo::galaxy(120_000), PathBuf::from("<demo>")),
        (None, false) => {
            return Err(SceneError::setting(
                "particles.file",
                "no particle file given (or set demo = true)",
            ));
        }
    };
    Ok(FrameData {
        data,
        main_file,
        files,
        sph_defaults,
        notes,
    })
}

/// Attributes a particle error to the file that holds the bad values.
pub(crate) fn blame(
    main_file: PathBuf,
    files: &[(&str, PathBuf)],
    source: ParticleError,
) -> SceneError {
    let blamed = |what: &str| files.iter().find(|f| f.0 == what).map(|f| f.1.clone());
    let path = match &source {
        ParticleError::BadRadius { .. } => blamed("radii"),
        ParticleError::BadWeight { .. } => blamed("weights"),
        ParticleError::NonFiniteValue { what, .. } | ParticleError::LengthMismatch { what, .. } => {
            blamed(what)
        }
        _ => None,
    }
    .unwrap_or(main_file);
    SceneError::Particles { path, source }
}

pub(crate) fn load_particles(
    p: &ParticlesDesc,
    base: &Path,
    notes: &mut Vec<String>,
    frame: usize,
) -> Result<ParticleVolume, SceneError> {
    let mut fd = read_frame(p, base, frame)?;
    notes.append(&mut fd.notes);
    let FrameData {
        data,
        main_file,
        files,
        sph_defaults,
        ..
    } = fd;
    build_particles(data, p, sph_defaults, notes).map_err(|e| e.blame(main_file, &files))
}

/// Why particle arrays cannot become a volume: a bad setting, or bad data
/// (to be attributed to the file or argument that holds it).
pub(crate) enum BuildError {
    Setting(SceneError),
    Data(ParticleError),
}

impl BuildError {
    /// The error, naming the file (or array) that holds the bad values.
    pub(crate) fn blame(self, main_file: PathBuf, files: &[(&str, PathBuf)]) -> SceneError {
        match self {
            BuildError::Setting(e) => e,
            BuildError::Data(e) => blame(main_file, files, e),
        }
    }
}

impl From<SceneError> for BuildError {
    fn from(e: SceneError) -> Self {
        BuildError::Setting(e)
    }
}

/// A particle volume from arrays and the description's settings, with the
/// data's defaults: the SPH cubic spline when `sph_defaults`, and a radius
/// from the particle spacing when neither a radius nor radii are given
/// (said in `notes`).
pub(crate) fn build_particles(
    mut data: ParticleData,
    p: &ParticlesDesc,
    sph_defaults: bool,
    notes: &mut Vec<String>,
) -> Result<ParticleVolume, BuildError> {
    super::scale::scale_arrays(&mut data, p)?;
    let kernel = if sph_defaults {
        Kernel::CubicSpline
    } else {
        kernel_of(p, p.kernel.unwrap_or(KernelName::Gaussian3))
    };
    let radius = match (p.radius, &data.radii) {
        (Some(r), _) => r,
        (None, Some(_)) => 1.0,
        (None, None) => {
            let r = default_radius(&data.positions, kernel);
            notes.push(format!(
                "no radius given: using {r:.4} ({} kernel, support = 2.5 × mean particle spacing)",
                kernel.name()
            ));
            r
        }
    };
    // The radius scale acts on the global radius too (radii were scaled above).
    let radius = radius * super::scale::scales(p)?.0;
    let classification = match p.classification.unwrap_or(ClassificationName::Post) {
        ClassificationName::Post => Classification::Post,
        ClassificationName::Pre => Classification::Pre,
    };
    let attribute_range = p
        .attribute_range
        .map(|[a, b]| range("particles.attribute_range", a, b))
        .transpose()?;
    let settings = ParticleSettings {
        kernel,
        radius,
        radius_map: control_points("radius map", &p.radius_map)?,
        weight_map: control_points("weight map", &p.weight_map)?,
        cluster_size: p.cluster.unwrap_or(8),
        attribute_range,
        classification,
    };
    ParticleVolume::new(data, settings).map_err(BuildError::Data)
}

/// Number of frames the scene's data source names: the files of a sequence
/// (see [`frames`]), the frames of a multi-frame file (LAMMPS dump, XYZ,
/// `.particles`), else 1.
pub fn frame_count(desc: &voxless_scene::SceneDesc, base: &Path) -> Result<usize, SceneError> {
    match &desc.particles {
        Some(ParticlesDesc { file: Some(f), .. }) if frames::is_sequence(f, base) => {
            Ok(frames::expand(f, base)?.len())
        }
        Some(ParticlesDesc { file: Some(f), .. }) => {
            let path = base.join(f);
            match ParticleFormat::detect(&path)? {
                Some(format) => formats::frames_in(&path, format),
                None => Ok(1),
            }
        }
        _ => Ok(1),
    }
}

/// Support radius 2.5× the mean particle spacing, converted to the kernel's
/// radius parameter. The spacing is `(occupied volume / N)^(1/3)`, with the
/// occupied volume counted on a coarse grid (about four particles per cell if
/// the data were uniform), so clustered data — a thin disc in a big box — get
/// the spacing where the particles actually are.
pub fn default_radius(positions: &[Vec3], kernel: Kernel) -> f32 {
    let mut b = Aabb::EMPTY;
    for p in positions {
        b.grow(*p);
    }
    let n = positions.len();
    let longest = b.extent().max_elem().max(1e-12);
    let res = ((n as f32 / 4.0).cbrt().round() as usize).clamp(1, 128);
    let cell = longest / res as f32;
    let dims = b.extent().mul_elem(Vec3::splat(1.0 / cell));
    let dim = |a: f32| (a.ceil() as usize).clamp(1, res);
    let (nx, ny, nz) = (dim(dims.x), dim(dims.y), dim(dims.z));
    let mut occupied = vec![false; nx * ny * nz];
    for p in positions {
        let q = (*p - b.min) * (1.0 / cell);
        let (i, j, k) = (
            (q.x as usize).min(nx - 1),
            (q.y as usize).min(ny - 1),
            (q.z as usize).min(nz - 1),
        );
        occupied[(k * ny + j) * nx + i] = true;
    }
    let count = occupied.iter().filter(|&&o| o).count().max(1);
    let spacing = (count as f32 * cell * cell * cell / n as f32).cbrt();
    2.5 * spacing / kernel.support_factor()
}
