//! Loading each data kind a scene names: particles (with time series),
//! AMR cells, and phase-space tessellations — every failure a [`SceneError`]
//! naming the file at fault.

use std::path::{Path, PathBuf};

use voxless_amr::{AmrCells, AmrSettings, AmrVolume, Reconstruction};
use voxless_core::{Aabb, Range1, Vec3};
use voxless_particles::{
    Classification, Kernel, ParticleData, ParticleError, ParticleSettings, ParticleVolume,
};
use voxless_tets::{LagrangianGrid, TetMode, TetOptions, TetSettings, TetVolume};
use voxless_transfer::ControlPoints;

use crate::formats::{self, ParticleFormat, TableOptions};
use crate::{
    AmrDesc, AnyVolume, LoadedScene, ParticlesDesc, SceneDesc, SceneError, TetsDesc, demo, frames,
    load,
};

pub(crate) fn load_amr(a: &AmrDesc, base: &Path) -> Result<AmrVolume, SceneError> {
    let (data, path) = match (&a.cells, &a.amrclaw) {
        (Some(cells), None) => {
            let scalars: Vec<PathBuf> = a.scalars.iter().flatten().map(|s| base.join(s)).collect();
            if scalars.is_empty() {
                return Err(SceneError::setting(
                    "amr.scalars",
                    "ExaBricks cells need at least one .scalars file (--scalars FILE)",
                ));
            }
            let path = base.join(cells);
            (voxless_io::read_exabricks(&path, &scalars)?, path)
        }
        (None, Some(q)) => {
            let path = base.join(q);
            (voxless_io::read_amrclaw(&path)?, path)
        }
        (Some(_), Some(_)) => {
            return Err(SceneError::setting(
                "amr",
                "give either cells (ExaBricks) or amrclaw, not both",
            ));
        }
        (None, None) => {
            return Err(SceneError::setting(
                "amr",
                "no cells: give cells + scalars (ExaBricks) or amrclaw (fort.qNNNN)",
            ));
        }
    };
    let names: Vec<&str> = data.fields.iter().map(|f| f.0.as_str()).collect();
    let index = |what: &str, name: &str| {
        names.iter().position(|n| *n == name).ok_or_else(|| {
            SceneError::data(
                &path,
                format!(
                    "no field '{name}' for {what} (fields: {})",
                    names.join(", ")
                ),
            )
        })
    };
    let field = a
        .field
        .as_deref()
        .map(|n| index("the opacity field", n))
        .transpose()?
        .unwrap_or(0);
    let color_field = a
        .color_field
        .as_deref()
        .map(|n| index("the colour field", n))
        .transpose()?;
    let reconstruction = match a.reconstruction.as_deref().unwrap_or("basis") {
        "basis" => Reconstruction::Basis,
        "nearest" => Reconstruction::Nearest,
        other => {
            return Err(SceneError::setting(
                "amr.reconstruction",
                format!("'{other}' is not 'basis' or 'nearest'"),
            ));
        }
    };
    let origin = a.origin.unwrap_or(data.origin.map(|v| v as f32));
    let cells = AmrCells {
        cells: data.cells,
        fields: data.fields,
        origin: Vec3::from_array(origin),
        cell_size: a.cell_size.unwrap_or(data.finest_cell_size as f32),
    };
    AmrVolume::new(
        cells,
        AmrSettings {
            field,
            color_field,
            reconstruction,
        },
    )
    .map_err(|source| SceneError::Amr { path, source })
}

pub(crate) fn load_tets(
    t: &TetsDesc,
    base: &Path,
    notes: &mut Vec<String>,
) -> Result<AnyVolume, SceneError> {
    let file = t.file.as_ref().ok_or_else(|| {
        SceneError::setting(
            "tets.file",
            "no positions file given (--particles FILE.npy with --lagrangian N --box L, or a \
             JaxPM FILE.h5)",
        )
    })?;
    let path = base.join(file);
    let grid = if ParticleFormat::detect(&path)? == Some(ParticleFormat::Hdf5) {
        crate::jaxpm::grid(t, &path, notes)?
    } else {
        if t.snapshot.is_some() {
            return Err(SceneError::setting(
                "tets.snapshot",
                format!(
                    "--snapshot picks a snapshot of a JaxPM .h5 run, but {} is not one",
                    path.display()
                ),
            ));
        }
        let (positions, _) = load::read_positions(&path)?;
        let n = match t.lagrangian {
            Some(n) => n,
            None => {
                return Err(SceneError::setting(
                    "tets.lagrangian",
                    "the Lagrangian grid size N is needed (--lagrangian N)",
                ));
            }
        };
        let box_size = t.box_size.ok_or_else(|| {
            SceneError::setting("tets.box_size", "the periodic box size is needed (--box L)")
        })?;
        LagrangianGrid {
            n,
            box_size,
            positions,
        }
    };
    let settings = TetSettings {
        particle_mass: t.particle_mass,
        ..Default::default()
    };
    let mode = match t.mode.as_deref().unwrap_or("exact") {
        "exact" => TetMode::Exact,
        "kbuffer" | "k-buffer" => TetMode::KBuffer {
            k: t.k.unwrap_or(16).max(1),
            layers: t.layers.unwrap_or(64).max(1),
        },
        other => {
            return Err(SceneError::setting(
                "tets.mode",
                format!("'{other}' is not 'exact' or 'kbuffer'"),
            ));
        }
    };
    if let Some(p) = t.lod_pixels {
        positive("tets.lod_pixels", p)?;
    }
    let levels = if t.lod_pixels.is_some() { 3 } else { 0 };
    let v = TetVolume::new(&grid, &settings, levels)
        .map_err(|source| SceneError::Tets { path, source })?;
    let options = TetOptions {
        lod_pixels: t.lod_pixels,
        ..Default::default()
    };
    Ok(AnyVolume::Tets(Box::new(v), mode, options))
}

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

fn parse_kernel(p: &ParticlesDesc) -> Result<Kernel, SceneError> {
    let name = p.kernel.as_deref().unwrap_or("gaussian3");
    match name.to_ascii_lowercase().as_str() {
        "gaussian3" => Ok(Kernel::Gaussian3),
        "gaussian" => Ok(Kernel::Gaussian {
            kappa: p.kappa.unwrap_or(1.0),
            sigma: p.sigma.unwrap_or(2.0),
        }),
        "cubic-spline" | "cubic" | "m4" => Ok(Kernel::CubicSpline),
        _ => Err(SceneError::setting(
            "particles.kernel",
            format!(
                "unknown kernel '{name}' (available: {})",
                voxless_particles::KERNEL_NAMES.join(", ")
            ),
        )),
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
struct FrameData {
    data: ParticleData,
    main_file: PathBuf,
    files: Vec<(&'static str, PathBuf)>,
    sph_defaults: bool,
    notes: Vec<String>,
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

fn read_frame(p: &ParticlesDesc, base: &Path, frame: usize) -> Result<FrameData, SceneError> {
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
                species: p.species.as_deref(),
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
fn blame(main_file: PathBuf, files: &[(&str, PathBuf)], source: ParticleError) -> SceneError {
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
    let mut kernel = parse_kernel(p)?;
    let mut fd = read_frame(p, base, frame)?;
    notes.append(&mut fd.notes);
    if fd.sph_defaults {
        kernel = Kernel::CubicSpline;
    }
    let radius = match (p.radius, &fd.data.radii) {
        (Some(r), _) => r,
        (None, Some(_)) => 1.0,
        (None, None) => {
            let r = default_radius(&fd.data.positions, kernel);
            notes.push(format!(
                "no radius given: using {r:.4} ({} kernel, support = 2.5 × mean particle spacing)",
                kernel.name()
            ));
            r
        }
    };
    let classification = match p.classification.as_deref().unwrap_or("post") {
        "post" => Classification::Post,
        "pre" => Classification::Pre,
        other => {
            return Err(SceneError::setting(
                "particles.classification",
                format!("'{other}' is not 'post' or 'pre'"),
            ));
        }
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
    let FrameData {
        data,
        main_file,
        files,
        ..
    } = fd;
    ParticleVolume::new(data, settings).map_err(|source| blame(main_file, &files, source))
}

/// Number of frames the scene's data source names: the files of a sequence
/// (see [`frames`]), the frames of a multi-frame file (LAMMPS dump, XYZ,
/// `.particles`), else 1.
pub fn frame_count(desc: &SceneDesc, base: &Path) -> Result<usize, SceneError> {
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

impl LoadedScene {
    /// Moves a particle scene to frame `frame` of its sequence: the BVH is
    /// rebuilt in its buffers, and camera, value range and attribute range stay
    /// as resolved for the first frame, so a sequence does not flicker.
    pub fn load_frame(
        &mut self,
        desc: &SceneDesc,
        base: &Path,
        frame: usize,
    ) -> Result<(), SceneError> {
        if let (AnyVolume::Materials(_), Some(p)) = (&self.volume, &desc.particles) {
            // Each material is rebuilt from the new frame (no buffer reuse).
            let mats = p.materials.as_deref().unwrap_or_default();
            let v = crate::materials::load_materials(p, mats, base, &mut Vec::new(), frame)?;
            self.volume = AnyVolume::Materials(Box::new(v));
            return Ok(());
        }
        let (AnyVolume::Particles(v), Some(p)) = (&mut self.volume, &desc.particles) else {
            return Err(SceneError::setting(
                "frames",
                "time series are supported for particle data",
            ));
        };
        let FrameData {
            data,
            main_file,
            files,
            ..
        } = read_frame(p, base, frame)?;
        v.load_frame(data)
            .map_err(|source| blame(main_file, &files, source))?;
        v.classify(&self.tf);
        Ok(())
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
