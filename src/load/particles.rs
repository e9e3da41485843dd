//! Particles: one frame of any particle file (or a sequence of files), or
//! arrays in memory, through one constructor that fills the data's own
//! defaults (the radius from the particle spacing, SPH kernels for SPH
//! files) — every failure a [`SceneError`] naming the file at fault.
//!
//! Positions are read in float64 and placed in the scene's [`WorldFrame`]
//! (chosen from the first data read, see [`crate::frame`]) before they
//! become float32; radii and the description's radius are world lengths and
//! are divided by the frame's scale, and weights of the SPH kernels (whose
//! kernels are normalised per unit volume) by its cube, so densities stay in
//! world units.

use rayon::prelude::*;
use std::path::{Path, PathBuf};

use voxless_core::Vec3;
use voxless_particles::{
    Classification, Kernel, ParticleData, ParticleError, ParticleSettings, ParticleVolume,
};
use voxless_scene::{ClassificationName, KernelName, ParticlesDesc};
use voxless_transfer::ControlPoints;

use voxless_particles::neighbours::PeriodicBox;

use super::formats::{self, ParticleFormat};
use super::periodic;
use super::reach::{Reach, Unresolvable};
pub(crate) use super::snapshot::selection;
use super::spacing;
use super::table::is_npy;
use super::{Share, frames, table as load};
use crate::checks::{positive, range};
use crate::{SceneError, WorldFrame, demo};

pub(crate) fn kernel_of(p: &ParticlesDesc, name: KernelName) -> Kernel {
    match name {
        KernelName::Gaussian3 => Kernel::Gaussian3,
        KernelName::Gaussian => Kernel::Gaussian {
            kappa: p.kappa.unwrap_or(1.0),
            sigma: p.sigma.unwrap_or(2.0),
        },
        KernelName::CubicSpline => Kernel::CubicSpline,
        KernelName::QuarticSpline => Kernel::QuarticSpline,
        KernelName::QuinticSpline => Kernel::QuinticSpline,
        KernelName::WendlandC2 => Kernel::WendlandC2,
        KernelName::WendlandC4 => Kernel::WendlandC4,
        KernelName::WendlandC6 => Kernel::WendlandC6,
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
    /// World positions (float64).
    pub positions: Vec<[f64; 3]>,
    /// Radii, weights and attribute in world units; no positions yet
    /// (see [`FrameData::place`]).
    pub data: ParticleData,
    pub main_file: PathBuf,
    pub files: Vec<(&'static str, PathBuf)>,
    /// The kernel of the SPH defaults (SPH data and no kernel given).
    pub sph_defaults: Option<Kernel>,
    pub notes: Vec<String>,
    /// The row number of the first row read, and the set's row count: a
    /// share of a decomposed set holds rows `offset..` of `total`.
    pub offset: usize,
    pub total: usize,
    /// The periodic box (world): the file's, until [`read_rows`] settles
    /// it with the description's.
    pub periodic: Option<PeriodicBox>,
    /// A cosmological snapshot (SWIFT/Gadget): its particle types without
    /// smoothing lengths get radii from neighbours by default.
    pub snapshot: bool,
}

impl FrameData {
    /// The kernel these particles get: the description's, or the cubic
    /// spline of the SPH defaults.
    pub fn kernel(&self, p: &ParticlesDesc) -> Kernel {
        self.sph_defaults
            .unwrap_or_else(|| kernel_of(p, p.kernel.unwrap_or(KernelName::Gaussian3)))
    }

    /// The world box the particles' supports reach (positions grown by the
    /// largest support the description or the radii give), for choosing a
    /// frame; `None` for non-finite positions (reported when building).
    pub fn world_reach(&self, p: &ParticlesDesc) -> Option<([f64; 3], [f64; 3])> {
        if let Some(b) = &self.periodic {
            return Some(super::periodic::corners(b));
        }
        let reach = Reach::of(&self.positions, self.data.radii.as_deref());
        reach.world_box(p, self.kernel(p), self.total)
    }

    /// The arrays with positions in `frame`'s local coordinates (radii and
    /// weights stay in world units until [`build_particles`]).
    pub fn place(
        self,
        frame: &WorldFrame,
    ) -> (ParticleData, PathBuf, Vec<(&'static str, PathBuf)>) {
        self.place_into(frame, Vec::new())
    }

    /// [`FrameData::place`] writing the local positions into `local`
    /// (emptied first; its allocation reused when large enough).
    pub fn place_into(
        mut self,
        frame: &WorldFrame,
        mut local: Vec<Vec3>,
    ) -> (ParticleData, PathBuf, Vec<(&'static str, PathBuf)>) {
        local.clear();
        local.par_extend(self.positions.par_iter().map(|&q| frame.to_local(q)));
        self.data.positions = local;
        (self.data, self.main_file, self.files)
    }
}

/// The frame for data reaching over the world box `reach` (see
/// [`WorldFrame::fit`]).
pub(crate) fn frame_for(reach: Option<([f64; 3], [f64; 3])>) -> WorldFrame {
    reach.map_or_else(WorldFrame::default, |(lo, hi)| WorldFrame::fit(lo, hi))
}

/// The file of `spec` for frame number `frame` (see [`frames`]): the file
/// numbered `frame` of a sequence, or the file itself (the same for every
/// frame).
pub(crate) fn frame_file(spec: &str, base: &Path, frame: usize) -> Result<PathBuf, SceneError> {
    if frames::is_sequence(spec, base) {
        frames::file_numbered(spec, base, frame)
    } else {
        Ok(base.join(spec))
    }
}

/// The particle file of frame number `frame` and the frame to read in it:
/// the file numbered `frame` (its first frame) of a sequence, else frame
/// `frame` of the file itself, which must have it.
pub(crate) fn locate(
    spec: &str,
    base: &Path,
    frame: usize,
) -> Result<(PathBuf, usize), SceneError> {
    if frames::is_sequence(spec, base) {
        return Ok((frames::file_numbered(spec, base, frame)?, 0));
    }
    let path = base.join(spec);
    if frame > 0
        && let Some(format) = ParticleFormat::detect(&path)?
    {
        let count = formats::frames_in(&path, format)?;
        if frame >= count {
            return Err(SceneError::data(
                &path,
                format!("frame {frame} was asked for, but the file holds frames 0..{count}"),
            ));
        }
    }
    Ok((path, frame))
}

/// The particle set's periodic box in `frame`'s local coordinates.
pub(crate) fn local_box(b: Option<&PeriodicBox>, frame: &WorldFrame) -> Option<voxless_core::Aabb> {
    b.map(|b| {
        let (lo, hi) = super::periodic::corners(b);
        frame.box_to_local([lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]])
    })
}

/// Every row of frame `frame` of the particles `p` names.
pub(crate) fn read_frame(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
) -> Result<FrameData, SceneError> {
    read_rows(p, base, frame, Share::WHOLE)
}

/// Share `share` of the rows of frame `frame` (world positions; no local
/// positions yet): by offset when the positions and every per-particle
/// array are `.npy` files, by hyperslab from HDF5 columns, else the frame
/// read whole and cut (its rows are not at known offsets).
pub(crate) fn read_rows(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    share: Share,
) -> Result<FrameData, SceneError> {
    let mut fd = read_share(p, base, frame, share)?;
    let kernel = fd.kernel(p);
    fd.periodic = periodic::settle(
        p,
        fd.periodic,
        &mut fd.positions,
        &mut fd.data.radii,
        (fd.snapshot, share.is_whole()),
        kernel,
        &fd.main_file,
        &mut fd.notes,
    )?;
    Ok(fd)
}

/// [`read_rows`] before the box and the neighbours.
fn read_share(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    share: Share,
) -> Result<FrameData, SceneError> {
    if share.is_whole() {
        return Ok(read_frame_share(p, base, frame, None)?.0);
    }
    if let Some(rows) = npy_rows(p, base, frame, share)? {
        return Ok(rows);
    }
    let part = by_rows(p, base).then_some((share.rank, share.ranks));
    let (mut fd, shared) = read_frame_share(p, base, frame, part)?;
    if shared {
        return Ok(fd);
    }
    let r = share.rows(fd.total);
    let cut = |v: Option<Vec<f32>>| v.map(|v| v[r.clone()].to_vec());
    fd.positions = fd.positions[r.clone()].to_vec();
    fd.data.radii = cut(fd.data.radii);
    fd.data.attribute = cut(fd.data.attribute);
    fd.data.weights = cut(fd.data.weights);
    fd.offset = r.start;
    Ok(fd)
}

/// Whether a share of the file's rows can be asked of its reader: HDF5,
/// Gadget binary and Tipsy files read only the share's rows when the
/// per-particle arrays are columns of the file (not `.npy` files beside
/// it). A region's rows are known only once read (every rank reads the
/// region, bounded by it, and keeps its share), and PySPH species are
/// picked after reading.
fn by_rows(p: &ParticlesDesc, base: &Path) -> bool {
    let columns_only = [&p.attribute, &p.radii, &p.weights]
        .into_iter()
        .flatten()
        .all(|spec| !is_npy(&base.join(spec)));
    p.species.is_none() && p.region.is_none() && columns_only
}

/// Share `share` of the rows of frame `frame` (as [`read_rows`] before
/// the box and the neighbours), when only those rows are read: `.npy`
/// files by offset ([`npy_rows`]), HDF5, Gadget binary and Tipsy snapshots
/// by row range ([`by_rows`]). `None` for every other file, which is read
/// whole (its errors are the whole read's to word).
pub(crate) fn rows_of(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    share: Share,
) -> Result<Option<FrameData>, SceneError> {
    if let Some(rows) = npy_rows(p, base, frame, share)? {
        return Ok(Some(rows));
    }
    let Some(f) = &p.file else {
        return Ok(None);
    };
    let (path, _) = locate(f, base, frame)?;
    let format = ParticleFormat::detect(&path).ok().flatten();
    let ranged = matches!(
        format,
        Some(ParticleFormat::Hdf5 | ParticleFormat::GadgetBinary | ParticleFormat::Tipsy)
    );
    if !(ranged && by_rows(p, base)) {
        return Ok(None);
    }
    let (fd, shared) = read_frame_share(p, base, frame, Some((share.rank, share.ranks)))?;
    Ok(shared.then_some(fd))
}

/// Share `share` of the rows read by offset, when the positions and every
/// per-particle array are `.npy` files of the right shapes; `None` sends
/// the read down the general path (which also words any error).
pub(crate) fn npy_rows(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    share: Share,
) -> Result<Option<FrameData>, SceneError> {
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
    let rows = share.rows(total);
    let mut files = Vec::new();
    let mut per = |spec: &Option<String>,
                   what: &'static str|
     -> Result<Option<Option<Vec<f32>>>, SceneError> {
        let Some(s) = spec else {
            return Ok(Some(None));
        };
        let spec = frame_file(s, base, frame)?;
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
    // The rows as triples in place (a chunk's 1.5 MB were copied), or
    // copied where the buffer's capacity is not a whole number of triples.
    let positions = bytemuck::allocation::try_cast_vec::<f64, [f64; 3]>(a.data)
        .unwrap_or_else(|(_, data)| data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
    Ok(Some(FrameData {
        positions,
        data: ParticleData {
            positions: Vec::new(),
            radii,
            attribute,
            weights,
        },
        main_file: path,
        files,
        sph_defaults: None,
        notes: Vec::new(),
        offset: rows.start,
        total,
        periodic: None,
        snapshot: false,
    }))
}

/// [`read_frame`], asking for share `r` of `k` of the rows (`share =
/// Some((r, k))`; see `TableOptions::share`): formats that can read part of
/// their rows (HDF5) read only those and say so in [`FrameData::offset`]
/// and [`FrameData::total`]; the others read every row. Per-particle arrays
/// must then be columns of the file, not files of their own. Says whether
/// only the share was read.
fn read_frame_share(
    p: &ParticlesDesc,
    base: &Path,
    frame: usize,
    share: Option<(usize, usize)>,
) -> Result<(FrameData, bool), SceneError> {
    let mut rows: Option<(usize, usize)> = None;
    let mut files: Vec<(&'static str, PathBuf)> = Vec::new();
    let mut notes = Vec::new();
    let mut sph_defaults = None;
    let (mut file_box, mut snapshot) = (None, false);
    let world_positions: Vec<[f64; 3]>;
    let (data, main_file) = match (&p.file, p.demo.unwrap_or(false)) {
        (Some(f), _) => {
            let (path, in_file) = locate(f, base, frame)?;
            super::snapshot::check_region(p)?;
            let select = selection(p, share);
            let (positions, source, note) = load::open(&path, in_file, &select)?;
            notes.extend(note);
            notes.extend(super::snapshot::describe(&source.table, source.format));
            rows = source.table.rows;
            snapshot = source.table.sph.is_some();
            if source.table.periodic
                && let Some((lo, hi)) = source.table.domain
            {
                file_box = Some(PeriodicBox {
                    lo,
                    size: std::array::from_fn(|a| hi[a] - lo[a]),
                });
            }
            let n = positions.len();
            world_positions = positions;
            let mut data = ParticleData::default();
            let (mut radii, mut weights) = (p.radii.clone(), p.weights.clone());
            let mut h_scale = None;
            if let Some((kernel, scale, said)) =
                super::snapshot::defaults(p, &source, &mut radii, &mut weights)
            {
                sph_defaults = kernel;
                h_scale = scale;
                notes.extend(said);
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
            // (Its masses are the weights already: `defaults` above.)
            if let Some((r, said)) = super::snapshot::cell_radii(p, &source.table) {
                notes.push(said);
                data.radii = Some(r);
            }
            // The file's smoothing lengths in voxless's h (same support).
            if let (Some(f), Some(r)) = (h_scale, data.radii.as_mut())
                && f != 1.0
            {
                r.iter_mut().for_each(|v| *v *= f);
            }
            data.weights = per(&weights, "weights")?;
            (data, path)
        }
        (None, true) => {
            let mut g = demo::galaxy(120_000);
            world_positions = g
                .positions
                .iter()
                .map(|p| p.to_array().map(f64::from))
                .collect();
            g.positions.clear();
            (g, PathBuf::from("<demo>"))
        }
        (None, false) => {
            return Err(SceneError::setting(
                "particles.file",
                "no particle file given (or set demo = true)",
            ));
        }
    };
    let (offset, total) = rows.unwrap_or((0, world_positions.len()));
    let fd = FrameData {
        positions: world_positions,
        data,
        main_file,
        files,
        sph_defaults,
        notes,
        offset,
        total,
        periodic: file_box,
        snapshot,
    };
    Ok((fd, rows.is_some()))
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

/// Loads frame `frame` of the particles `p` names, in `world` (or the frame
/// the policy picks for them), and returns the volume with its frame.
pub(crate) fn load_particles(
    p: &ParticlesDesc,
    base: &Path,
    notes: &mut Vec<String>,
    frame: usize,
    world: Option<&WorldFrame>,
) -> Result<(ParticleVolume, WorldFrame), SceneError> {
    let mut fd = read_frame(p, base, frame)?;
    notes.append(&mut fd.notes);
    let world = world
        .copied()
        .unwrap_or_else(|| frame_for(fd.world_reach(p)));
    let v = build_frame(fd, p, &world, notes)?;
    Ok((v, world))
}

/// A volume of read particles placed in `world`.
pub(crate) fn build_frame(
    fd: FrameData,
    p: &ParticlesDesc,
    world: &WorldFrame,
    notes: &mut Vec<String>,
) -> Result<ParticleVolume, SceneError> {
    let sph_defaults = fd.sph_defaults;
    let periodic = local_box(fd.periodic.as_ref(), world);
    let (data, main_file, files) = fd.place(world);
    build_particles(data, p, sph_defaults, periodic, notes, world.scale)
        .map_err(|e| e.blame(main_file, &files))
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
/// (said in `notes`). Positions are local to a frame of scale `scale`;
/// radii, weights and the description's radius are in world units and are
/// converted here (see the module docs).
pub(crate) fn build_particles(
    mut data: ParticleData,
    p: &ParticlesDesc,
    sph_defaults: Option<Kernel>,
    periodic: Option<voxless_core::Aabb>,
    notes: &mut Vec<String>,
    scale: f64,
) -> Result<ParticleVolume, BuildError> {
    let kernel = prepare_arrays(&mut data, p, sph_defaults, scale)?;
    let mut settings = particle_settings(
        p,
        kernel,
        data.radii.is_some(),
        &mut |kernel| default_radius_with(&data.positions, kernel),
        scale,
        notes,
    )?;
    check_resolvable(&data, settings.radius * kernel.support_factor(), scale)?;
    settings.periodic = periodic;
    ParticleVolume::new(data, settings).map_err(|e| BuildError::Data(in_world_units(e, scale)))
}

/// The description's radius and weight scales applied to `data`, and its
/// radii and weights converted from world units into a frame of scale
/// `scale` (see the module docs); returns the kernel. Row by row, so a
/// share of a decomposed set converts as the whole set does.
pub(crate) fn prepare_arrays(
    data: &mut ParticleData,
    p: &ParticlesDesc,
    sph_defaults: Option<Kernel>,
    scale: f64,
) -> Result<Kernel, SceneError> {
    check_kernel_and_attribute(p, data.attribute.is_some())?;
    super::scale::scale_arrays(data, p)?;
    let kernel =
        sph_defaults.unwrap_or_else(|| kernel_of(p, p.kernel.unwrap_or(KernelName::Gaussian3)));
    localise(data, kernel, scale);
    Ok(kernel)
}

/// The Gaussian's κ and σ must be finite and positive, and the settings
/// that act on an attribute need one (they would be ignored without a
/// word).
fn check_kernel_and_attribute(p: &ParticlesDesc, has_attribute: bool) -> Result<(), SceneError> {
    for (name, v) in [
        ("particles.kappa (--kappa)", p.kappa),
        ("particles.sigma (--sigma)", p.sigma),
    ] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(SceneError::setting(
                name,
                format!("{v}: the Gaussian's parameters must be finite numbers > 0"),
            ));
        }
    }
    if !has_attribute {
        for (name, given) in [
            (
                "particles.attribute_range (--attribute-range)",
                p.attribute_range.is_some(),
            ),
            (
                "particles.classification (--classification pre)",
                p.classification == Some(ClassificationName::Pre),
            ),
        ] {
            if given {
                return Err(SceneError::setting(
                    name,
                    "acts on a per-particle attribute, and none is given: add --attribute \
                     (a column or a .npy)",
                ));
            }
        }
    }
    Ok(())
}

/// The particle settings `p` describes for `kernel`, in a frame of scale
/// `scale`: when neither a radius nor radii (`has_radii`) are given, the
/// radius `default_radius(kernel)` (with how it was found, said in
/// `notes`).
pub(crate) fn particle_settings(
    p: &ParticlesDesc,
    kernel: Kernel,
    has_radii: bool,
    default_radius: &mut dyn FnMut(Kernel) -> (f32, String),
    scale: f64,
    notes: &mut Vec<String>,
) -> Result<ParticleSettings, SceneError> {
    let to_local = |r: f32| (r as f64 / scale) as f32;
    if let Some(given) = p.radius {
        positive("particles.radius (--radius)", given)?;
    }
    let radius = match (p.radius, has_radii) {
        (Some(r), _) => to_local(r),
        (None, true) => 1.0,
        (None, false) => {
            let (r, how) = default_radius(kernel);
            notes.push(format!(
                "no radius given: using {:.4e} ({} kernel, {how}; change with --radius)",
                r as f64 * scale,
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
    Ok(ParticleSettings {
        kernel,
        radius,
        radius_map: control_points("radius map", &p.radius_map)?,
        weight_map: control_points("weight map", &p.weight_map)?,
        cluster_size: p.cluster.unwrap_or(8),
        attribute_range,
        classification,
        periodic: None,
        pixels: crate::projection::pixel_integral(p.pixels),
    })
}

/// A particle error's lengths in world units (they are local to a frame of
/// scale `scale`).
pub(crate) fn in_world_units(e: ParticleError, scale: f64) -> ParticleError {
    match e {
        ParticleError::HugeRadius {
            support,
            extent,
            count,
        } => ParticleError::HugeRadius {
            support: (support as f64 * scale) as f32,
            extent: (extent as f64 * scale) as f32,
            count,
        },
        other => other,
    }
}

/// The frame numbers of the scene's data (see [`frames`]): the numbers of
/// a sequence's files — over every sequence the particles pair (positions,
/// attribute, radii, weights), so a number one of them lacks is found when
/// that frame is loaded — the frames 0, 1, … of a multi-frame file (LAMMPS
/// dump, XYZ, `.particles`), else just 0.
pub fn frame_numbers(
    desc: &voxless_scene::SceneDesc,
    base: &Path,
) -> Result<Vec<usize>, SceneError> {
    // A tessellation over numbered position files (one grid per frame).
    if let Some(f) = desc.tets.as_ref().and_then(|t| t.file.as_ref())
        && frames::is_sequence(f, base)
    {
        return Ok(frames::numbered(f, base)?
            .into_iter()
            .map(|(n, _)| n)
            .collect());
    }
    // Numbered AMR outputs (fort.q%04d, plt*).
    if let Some((spec, _)) = desc.amr.as_ref().and_then(|a| super::amr_sequence(a, base)) {
        return Ok(frames::numbered(&spec, base)?
            .into_iter()
            .map(|(n, _)| n)
            .collect());
    }
    let Some(p) = &desc.particles else {
        return Ok(vec![0]);
    };
    let Some(f) = &p.file else {
        return Ok(vec![0]);
    };
    if frames::is_sequence(f, base) {
        let mut numbers = Vec::new();
        let specs = [
            Some(f),
            p.attribute.as_ref(),
            p.radii.as_ref(),
            p.weights.as_ref(),
        ];
        for spec in specs.into_iter().flatten() {
            if frames::is_sequence(spec, base) {
                numbers.extend(frames::numbered(spec, base)?.into_iter().map(|(n, _)| n));
            }
        }
        numbers.sort_unstable();
        numbers.dedup();
        return Ok(numbers);
    }
    let path = base.join(f);
    let count = match ParticleFormat::detect(&path)? {
        Some(format) => formats::frames_in(&path, format)?,
        None => 1,
    };
    Ok((0..count.max(1)).collect())
}

/// Supports below what float32 resolves across the data's extent (one
/// particle 10³⁸ away from the rest, say) would collapse the particles onto
/// each other: an error naming the particle farthest from the rest.
fn check_resolvable(data: &ParticleData, support: f32, scale: f64) -> Result<(), BuildError> {
    let mut radii = data.radii.clone();
    let bounds = spacing::bounds(&data.positions);
    let n = data.positions.len();
    let Some(centre) =
        Unresolvable::find(support, radii.as_deref_mut(), &data.positions, bounds, n)
    else {
        return Ok(());
    };
    let (far, _) = centre.farthest(&data.positions);
    Err(BuildError::Setting(centre.error(far, scale)))
}

/// Number of frames of the scene's data ([`frame_numbers`]).
pub fn frame_count(desc: &voxless_scene::SceneDesc, base: &Path) -> Result<usize, SceneError> {
    Ok(frame_numbers(desc, base)?.len())
}

/// Radii and weights of `data` from world units into a frame of scale
/// `scale` (see the module docs): radii ÷ scale, and for the SPH kernels
/// (normalised per unit volume) weights ÷ scale³.
pub(crate) fn localise(data: &mut ParticleData, kernel: Kernel, scale: f64) {
    if scale == 1.0 {
        return;
    }
    if let Some(r) = &mut data.radii {
        r.iter_mut().for_each(|v| *v = (*v as f64 / scale) as f32);
    }
    if kernel.is_sph() {
        let per_volume = scale.powi(3);
        let n = data.positions.len();
        let w = data.weights.get_or_insert_with(|| vec![1.0; n]);
        w.iter_mut()
            .for_each(|v| *v = (*v as f64 / per_volume) as f32);
    }
}

/// Support radius per nearest-neighbour spacing of the default radius.
pub const SUPPORT_PER_SPACING: f32 = 1.0;

/// The default radius parameter of `kernel` for particles at `positions`:
/// a support of [`SUPPORT_PER_SPACING`] × the median nearest-neighbour
/// distance (see `spacing`), so neighbouring kernels overlap enough for
/// a continuous field while single atoms stay visible. Particles without
/// any spacing (one particle, or all at one point) get support 1: there is
/// no length in the data to size them by, and a render frames them
/// whatever their size.
pub fn default_radius(positions: &[Vec3], kernel: Kernel) -> f32 {
    default_radius_with(positions, kernel).0
}

/// [`default_radius`] and how it was found, for the note.
pub(crate) fn default_radius_with(positions: &[Vec3], kernel: Kernel) -> (f32, String) {
    radius_from_spacing(
        spacing::nearest_neighbour_spacing(positions),
        positions.len(),
        kernel,
    )
}

/// The default radius for a median nearest-neighbour `spacing` (`None`:
/// no spacing) of `n` particles, and how it was found.
pub(crate) fn radius_from_spacing(spacing: Option<f32>, n: usize, kernel: Kernel) -> (f32, String) {
    let (support, how) = match spacing {
        Some(d) => (
            SUPPORT_PER_SPACING * d,
            format!("support = {SUPPORT_PER_SPACING} × median nearest-neighbour distance"),
        ),
        None => (
            1.0,
            if n == 1 {
                "one particle, so no spacing to size it by: support 1".to_string()
            } else {
                format!(
                    "all {n} particles lie at one point, so no spacing to size them by: support 1"
                )
            },
        ),
    };
    (support / kernel.support_factor(), how)
}
