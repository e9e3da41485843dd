//! Flags: every scene setting a one-off run needs, as named options that
//! override a scene description — the CLI's flags (`--kernel`, `--eye`, …)
//! and the Python package's keyword arguments (`kernel=`, `eye=`, …) are
//! these structs, so both front-ends apply them by the same rules
//! ([`SceneFlags::apply`]): which data kind the flags describe, that a
//! colormap file replaces the scene's colours, that any light setting turns
//! the light on, and so on.
//!
//! They come in three groups, so that a command takes only the flags it
//! uses: [`DataFlags`] (what data to read and how to reconstruct its field;
//! every command that loads data), [`KindFlags`] (how a render shows a data
//! kind) and [`ViewFlags`] (image, transfer function, camera, rendering,
//! lighting). clap parses each from a command line (feature `clap`, which
//! the CLI enables); serde from a table of names (a Python dict of keyword
//! arguments; [`SceneFlags::group_of`] says which group a name belongs to),
//! with unknown names refused. Names are the CLI's long flags with `_` for
//! `-` (`light_dir`, `box`).

use std::path::{Path, PathBuf};

use serde::Deserialize;
use voxless_scene::{
    AmrDesc, ClassificationName, FreeFlightName, KernelName, LightDesc, NoiseName, ParticlesDesc,
    ProjectionName, ReconstructionName, SceneDesc, Species, TetModeName, TetsDesc,
};

use crate::SceneError;

/// What data to read and how to reconstruct its field: every command that
/// loads data takes these (they override the scene file).
#[derive(Deserialize, Debug, Default, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct DataFlags {
    /// Particle file: .npy N×3 (float32/float64), CSV with x, y, z columns,
    /// .vtp/.vtu, .xyz/.extxyz, a LAMMPS dump (dump.*, .lammpstrj, .dump),
    /// .particles, or .h5/.hdf5 (PySPH, SWIFT/Gadget; JaxPM with
    /// --lagrangian/--snapshot, or alone; needs --features hdf5). A
    /// multi-frame file, pattern, glob or directory is a time series.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub particles: Option<PathBuf>,
    /// Per-particle attribute: a column of the particle file (case-insensitive),
    /// or .npy with N values.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub attribute: Option<String>,
    /// Global radius parameter, world units (support for gaussian3, std-dev for
    /// gaussian, smoothing length h for the SPH kernels). Default: a support of the median
    /// nearest-neighbour distance (printed).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Particles", allow_negative_numbers = true)
    )]
    pub radius: Option<f32>,
    /// Per-particle radii: a column name, or .npy with N values.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub radii: Option<String>,
    /// Per-particle weights (masses for the SPH kernels): a column name or .npy
    /// (default 1).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub weights: Option<String>,
    /// PySPH particle array to read (default: fluid if present, else the first).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "NAME", help_heading = "Particles")
    )]
    pub group: Option<String>,
    /// Snapshot particle type: 0–6 or gas, dm, disk, bulge, stars, bh;
    /// several (gas,stars) become materials, each with its own transfer
    /// function (default: gas if present, else the first type with particles).
    #[cfg_attr(feature = "clap", arg(long, value_name = "T", help_heading = "Particles", value_parser = species))]
    pub part_type: Option<Species>,
    /// Snapshots: load only the particles that can touch this box
    /// (periodic-aware; SWIFT reads only the cells that overlap it), with a
    /// margin for the kernels reaching in: the support of --radius, else a
    /// tenth of the region. The view defaults to what was loaded.
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            num_args = 6,
            value_names = ["X0", "Y0", "Z0", "X1", "Y1", "Z1"],
            allow_negative_numbers = true,
            help_heading = "Particles"
        )
    )]
    pub region: Option<Vec<f64>>,
    /// Keep only particles whose `type` column is T (LAMMPS type number; XYZ
    /// type number or element symbol).
    #[cfg_attr(feature = "clap", arg(long, value_name = "T", help_heading = "Particles", value_parser = species))]
    pub species: Option<Species>,
    /// RBF kernel (default gaussian3; SPH files: cubic-spline). The SPH
    /// kernels take h as radius: cubic-spline and wendland-c2/c4/c6 reach 2h,
    /// quartic-spline 2.5h, quintic-spline 3h.
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = "Particles"))]
    pub kernel: Option<KernelName>,
    /// Global density scale κ of the gaussian kernel (default 1).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Particles", allow_negative_numbers = true)
    )]
    pub kappa: Option<f32>,
    /// Truncation σ of the gaussian kernel, in radii (default 2).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Particles", allow_negative_numbers = true)
    )]
    pub sigma: Option<f32>,
    /// Particles per BVH leaf cluster, 1..=16 (default 8).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub cluster: Option<usize>,
    /// Treat --particles as N³ N-body particles on a Lagrangian grid (Lagrangian
    /// order, k fastest) and render their phase-space tessellation. A JaxPM
    /// .h5 file gives N (and L) itself.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "N", help_heading = "Phase-space tessellation")
    )]
    pub lagrangian: Option<usize>,
    /// JaxPM snapshot K of a .h5 run, the group snap_K (default: the last);
    /// implies a tessellation.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "K", help_heading = "Phase-space tessellation")
    )]
    pub snapshot: Option<usize>,
    /// Periodic box: a side L (the box [0, L)³) or its corners X0 Y0 Z0 X1 Y1
    /// Z1. Particles: the field sums every periodic image (default: the box
    /// the file states as periodic: SWIFT/Gadget BoxSize, LAMMPS pp bounds,
    /// extended-XYZ Lattice with pbc). Tessellations: L (a JaxPM file's by
    /// default).
    #[serde(rename = "box", deserialize_with = "one_or_six")]
    #[cfg_attr(
        feature = "clap",
        arg(
            long = "box",
            value_name = "L",
            num_args = 1..=6,
            allow_negative_numbers = true
        )
    )]
    pub box_size: Option<Vec<f64>>,
    /// Ignore the periodic box the particle file states.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub no_box: bool,
    /// Wrap particles into the periodic box even when they span more than
    /// one box (positions just outside it are always wrapped, with a note).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub wrap: bool,
    /// Radii from neighbours: each particle's support reaches its N-th
    /// nearest neighbour (itself counted; periodic distances in a box).
    /// Default for cosmological snapshots' particle types without smoothing
    /// lengths: 32.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "N", help_heading = "Particles")
    )]
    pub neighbours: Option<usize>,
    /// Mass per particle, world units (default: the mean density is 1, so
    /// densities read as the overdensity 1 + δ).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Phase-space tessellation"))]
    pub particle_mass: Option<f64>,
    /// ExaBricks cells: .cells (int32 x, y, z, level per cell).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub cells: Option<PathBuf>,
    /// ExaBricks .scalars file, one per field (repeat the flag).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub scalars: Vec<PathBuf>,
    /// AMRClaw ASCII output fort.qNNNN (fields q0, q1, …).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub amrclaw: Option<PathBuf>,
    /// Any AMR output, format detected: an AMReX/BoxLib plotfile directory,
    /// FLASH HDF5, an Enzo parameter file, Athena++ .athdf (the HDF5 ones
    /// with the `hdf5` feature), AMRClaw fort.qNNNN or ExaBricks .cells.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub amr: Option<PathBuf>,
    /// World position of cell coordinate 0 (default: .meta.json beside the cells, else 0).
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "AMR", allow_negative_numbers = true))]
    pub origin: Option<Vec<f64>>,
    /// World width of a finest cell (default: .meta.json, else 1).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub cell_size: Option<f32>,
    /// Field driving opacity (default: the first).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub field: Option<String>,
    /// Reconstruction between cell centres (default basis).
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = "AMR"))]
    pub reconstruction: Option<ReconstructionName>,
}

/// How `render` shows a particular data kind (particle attributes,
/// tessellation modes, AMR colour fields).
#[derive(Deserialize, Debug, Default, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct KindFlags {
    /// Attribute classification (default post).
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = "Particles"))]
    pub classification: Option<ClassificationName>,
    /// Attribute range mapped to the colormap / maps (default: over the
    /// data, every frame of a time series).
    #[cfg_attr(feature = "clap", arg(long, num_args = 2, value_names = ["LO", "HI"], help_heading = "Particles", allow_negative_numbers = true))]
    pub attribute_range: Option<Vec<f32>>,
    /// How crossing events become colour (default exact).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_enum, help_heading = "Phase-space tessellation")
    )]
    pub tet_mode: Option<TetModeName>,
    /// k-buffer depth for --tet-mode kbuffer (default 16).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Phase-space tessellation"))]
    pub k: Option<usize>,
    /// Log-spaced depth layers behind the k-buffer (default 64).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Phase-space tessellation"))]
    pub layers: Option<usize>,
    /// Level of detail: blocks smaller than this many pixels on screen use a
    /// 2^r-subsampled Lagrangian grid (off by default).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "PIXELS", help_heading = "Phase-space tessellation")
    )]
    pub lod: Option<f32>,
    /// Field driving colour (multi-field rendering; default: --field).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub color_field: Option<String>,
}

/// How an image looks: size, transfer function, camera, rendering and
/// lighting (`render` and `demo`).
#[derive(Deserialize, Debug, Default, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct ViewFlags {
    /// Image size in pixels (default 800 600).
    #[cfg_attr(feature = "clap", arg(long, num_args = 2, value_names = ["W", "H"], help_heading = "Image"))]
    pub size: Option<Vec<u32>>,
    /// Samples per pixel, progressively accumulated (default 1).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Image"))]
    pub spp: Option<u32>,
    /// Colormap preset (see `voxless colormaps`; default viridis).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Transfer function"))]
    pub colormap: Option<String>,
    /// Colormap file: ParaView preset JSON ("Export preset") or a JSON list of
    /// [r, g, b] / [x, r, g, b] sRGB colours; --colormap NAME picks a preset in
    /// it. Its opacity points apply unless --opacity is given.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "FILE", help_heading = "Transfer function")
    )]
    pub colormap_file: Option<PathBuf>,
    /// Opacity preset: linear, constant, ramp-high, ramp-low (default linear).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Transfer function"))]
    pub opacity: Option<String>,
    /// Value range mapped to [0, 1] (default: robust percentiles of the field
    /// over the data, every frame of a time series; printed).
    #[cfg_attr(feature = "clap", arg(long, num_args = 2, value_names = ["LO", "HI"], help_heading = "Transfer function", allow_negative_numbers = true))]
    pub value_range: Option<Vec<f32>>,
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true))]
    /// Eye position, world coordinates (default: a three-quarter view from
    /// 25° above the horizontal, the data's long horizontal side across the
    /// image, far enough to keep all of it in frame).
    pub eye: Option<Vec<f64>>,
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true))]
    /// Point the camera looks at, world coordinates (default: the centre of
    /// the data's bounds).
    pub look_at: Option<Vec<f64>>,
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true))]
    /// Up vector of the view (default 0 0 1: +z up, as in SPH, cosmology and
    /// most CFD; the default eye is chosen around it).
    pub up: Option<Vec<f32>>,
    /// Vertical field of view in degrees (default 30).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Camera", allow_negative_numbers = true)
    )]
    pub fov: Option<f32>,
    /// Orthographic projection with this view height, world units (default:
    /// perspective).
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_name = "HEIGHT",
            help_heading = "Camera",
            allow_negative_numbers = true
        )
    )]
    pub orthographic: Option<f32>,
    /// Orbit the eye about the up axis through the look-at point (the data
    /// centre by default), in degrees; positive turns towards the right.
    #[cfg_attr(feature = "clap", arg(long, value_name = "DEG", help_heading = "Camera", allow_negative_numbers = true, value_parser = degrees))]
    pub orbit: Option<f32>,
    /// Raise the eye towards the up vector, in degrees (negative lowers it;
    /// the view stays within ±89.9° of the horizontal).
    #[cfg_attr(feature = "clap", arg(long, value_name = "DEG", help_heading = "Camera", allow_negative_numbers = true, value_parser = degrees))]
    pub elevation: Option<f32>,
    /// Zoom by F > 0: the eye's distance to the look-at point ÷ F
    /// (orthographic: the view height ÷ F).
    #[cfg_attr(feature = "clap", arg(long, value_name = "F", help_heading = "Camera", allow_negative_numbers = true, value_parser = zoom))]
    pub zoom: Option<f32>,
    /// Ray-marching step in world units (default: 1/8 of the median support radius).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub step: Option<f32>,
    /// Samples per nominal step when no --step is given (default 1: for AMR
    /// two per finest cell of each region; 0.5 is one per cell).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub sampling_rate: Option<f32>,
    /// Stop marching at this opacity (default 0.99).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub early_termination: Option<f32>,
    /// Extinction per unit length at opacity 1 (default: chosen so a typical
    /// ray through the data reaches optical depth 2; printed).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub opacity_scale: Option<f32>,
    /// Background colour, linear RGB ≥ 0 (default 0 0 0).
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["R", "G", "B"], help_heading = "Render"))]
    pub background: Option<Vec<f32>>,
    /// Gradient shading with a directional light (default off).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Render"))]
    pub shade: bool,
    /// Direction towards the light (implies --shade; default: over the
    /// camera's left shoulder).
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Render", allow_negative_numbers = true))]
    pub light_dir: Option<Vec<f32>>,
    /// Single scattering with volumetric shadows (implies --shade's light;
    /// default off).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Lighting"))]
    pub shadows: bool,
    /// A point light at this position (with --shadows).
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Lighting", allow_negative_numbers = true))]
    pub light_pos: Option<Vec<f64>>,
    /// Light intensity (with --shadows; default 1).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Lighting"))]
    pub light_intensity: Option<f32>,
    /// Fraction of colour kept in full shade (default 0.3).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Lighting"))]
    pub ambient: Option<f32>,
    /// Free-flight sampling with shadows (default marching).
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = "Lighting"))]
    pub free_flight: Option<FreeFlightName>,
    /// Random numbers with shadows (default blue).
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = "Lighting"))]
    pub noise: Option<NoiseName>,
    /// Random seed for jitter (default 0).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Render"))]
    pub seed: Option<u64>,
    /// Implicit iso-surface at this value of the opacity field (repeat for more).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub iso: Vec<f32>,
    /// Opacity of the iso-surfaces (default 1).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Render"))]
    pub iso_opacity: Option<f32>,
    /// Render only the iso-surfaces, not the volume.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Render"))]
    pub iso_only: bool,
    /// Map log10(value) through the transfer function (default for tessellations).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Transfer function", conflicts_with = "linear")
    )]
    pub log: bool,
    /// Map the value linearly (default except for tessellations).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Transfer function"))]
    pub linear: bool,
    /// Sample particles and AMR cells point by point instead of in ray
    /// packets (same image; for comparisons).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Render"))]
    pub no_packets: bool,
    /// Render only what lies inside this box, world coordinates (default: all).
    #[cfg_attr(feature = "clap", arg(long, num_args = 6, value_names = ["X0", "Y0", "Z0", "X1", "Y1", "Z1"], help_heading = "Render", allow_negative_numbers = true))]
    pub clip: Option<Vec<f64>>,
    /// An opaque triangle mesh drawn with the volume: .ply, .obj, .stl or
    /// .vtp, in the data's coordinates (repeat for more; colours and
    /// fields in a scene file's `[[meshes]]`).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "FILE", help_heading = "Surfaces")
    )]
    pub mesh: Vec<PathBuf>,
    /// Ambient occlusion on mesh and iso-surface hits: N rays per hit (1–4096).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "N", help_heading = "Surfaces")
    )]
    pub ao: Option<u32>,
    /// How far ambient-occlusion rays look, world units (default: a tenth
    /// of the data's diagonal).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "D", help_heading = "Surfaces")
    )]
    pub ao_distance: Option<f64>,
    /// Draw the volume and meshes again, mirrored about the plane x, y or z
    /// = the data's lower face, or AXIS=VALUE (repeat for more axes).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "AXIS[=AT]", help_heading = "Surfaces")
    )]
    pub mirror: Vec<String>,
}

/// An angle in degrees: any finite number.
pub fn degrees(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("{s} is not a finite angle (degrees)")),
        Err(_) => Err(format!("'{s}' is not a number of degrees")),
    }
}

/// A zoom factor: finite and > 0.
pub fn zoom(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "'{s}' is not a zoom factor: it must be a finite number > 0 (2 = twice as close)"
        )),
    }
}

/// A species: a type number or an element symbol.
#[cfg(feature = "clap")]
fn species(s: &str) -> Result<Species, String> {
    Ok(Species::from(s))
}

/// `v` as an array of exactly `N` values; `name` is the flag.
fn fixed<const N: usize, T: Copy>(
    name: &str,
    v: &Option<Vec<T>>,
) -> Result<Option<[T; N]>, SceneError> {
    match v {
        None => Ok(None),
        Some(v) => <[T; N]>::try_from(v.as_slice()).map(Some).map_err(|_| {
            SceneError::setting(name, format!("expected {N} numbers, got {}", v.len()))
        }),
    }
}

/// A path from the command line (or the caller's working directory `cwd`)
/// made absolute, so resolving against a scene file's directory leaves it
/// be; a name without an extension may be a column name and is left alone.
fn cwd_path(cwd: &Path, s: &str) -> String {
    let p = Path::new(s);
    if p.is_absolute() || p.extension().is_none() {
        return s.to_string();
    }
    cwd.join(p).to_string_lossy().into_owned()
}

fn set<T>(slot: &mut Option<T>, v: Option<T>) {
    if v.is_some() {
        *slot = v;
    }
}

impl DataFlags {
    /// The flags' names, in declaration order.
    pub const NAMES: &'static [&'static str] = &[
        "particles",
        "attribute",
        "radius",
        "radii",
        "weights",
        "group",
        "part_type",
        "region",
        "species",
        "kernel",
        "kappa",
        "sigma",
        "cluster",
        "lagrangian",
        "snapshot",
        "box",
        "no_box",
        "wrap",
        "neighbours",
        "particle_mass",
        "cells",
        "scalars",
        "amrclaw",
        "amr",
        "origin",
        "cell_size",
        "field",
        "reconstruction",
    ];
}

impl KindFlags {
    /// The flags' names, in declaration order.
    pub const NAMES: &'static [&'static str] = &[
        "classification",
        "attribute_range",
        "tet_mode",
        "k",
        "layers",
        "lod",
        "color_field",
    ];
}

impl ViewFlags {
    /// The flags' names, in declaration order.
    pub const NAMES: &'static [&'static str] = &[
        "size",
        "spp",
        "colormap",
        "colormap_file",
        "opacity",
        "value_range",
        "eye",
        "look_at",
        "up",
        "fov",
        "orthographic",
        "orbit",
        "elevation",
        "zoom",
        "step",
        "sampling_rate",
        "early_termination",
        "opacity_scale",
        "background",
        "shade",
        "light_dir",
        "shadows",
        "light_pos",
        "light_intensity",
        "ambient",
        "free_flight",
        "noise",
        "seed",
        "iso",
        "iso_opacity",
        "iso_only",
        "log",
        "linear",
        "no_packets",
        "clip",
        "mesh",
        "ao",
        "ao_distance",
        "mirror",
    ];
}

/// One of the three groups of flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlagGroup {
    Data,
    Kind,
    View,
}

/// A box given as one number (a side) or a list of them.
fn one_or_six<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Vec<f64>>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum OneOrMany {
        One(f64),
        Many(Vec<f64>),
    }
    Ok(Option::<OneOrMany>::deserialize(d)?.map(|v| match v {
        OneOrMany::One(l) => vec![l],
        OneOrMany::Many(v) => v,
    }))
}

/// Every flag: the three groups (a command lacking a group leaves it at its
/// defaults, which change nothing). serde reads it from one table of named
/// values (any self-describing format: a TOML table, a JSON object), each
/// name going to its group; an error names the flag at fault.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneFlags {
    pub data: DataFlags,
    pub kind: KindFlags,
    pub view: ViewFlags,
}

impl<'de> Deserialize<'de> for SceneFlags {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let table = toml::Table::deserialize(d)?;
        SceneFlags::from_table(table).map_err(serde::de::Error::custom)
    }
}

/// A group of flags from its part of the table; the error names the flag
/// at fault (found by reading the flags one at a time).
fn group<T: serde::de::DeserializeOwned>(table: toml::Table) -> Result<T, String> {
    T::deserialize(toml::Value::Table(table.clone())).map_err(|e| {
        for (name, value) in table {
            let one = toml::Table::from_iter([(name.clone(), value)]);
            if let Err(e) = T::deserialize(toml::Value::Table(one)) {
                return format!("{name}: {e}");
            }
        }
        e.to_string()
    })
}

impl SceneFlags {
    /// The flags of a table of named values (see [`SceneFlags`]).
    pub fn from_table(table: toml::Table) -> Result<SceneFlags, String> {
        let mut parts = [toml::Table::new(), toml::Table::new(), toml::Table::new()];
        for (name, value) in table {
            let part = match SceneFlags::group_of(&name) {
                Some(FlagGroup::Data) => 0,
                Some(FlagGroup::Kind) => 1,
                Some(FlagGroup::View) => 2,
                None => {
                    return Err(format!(
                        "unknown flag `{name}`, expected one of {}",
                        SceneFlags::names().join(", ")
                    ));
                }
            };
            parts[part].insert(name, value);
        }
        let [data, kind, view] = parts;
        Ok(SceneFlags {
            data: group(data)?,
            kind: group(kind)?,
            view: group(view)?,
        })
    }
}

impl SceneFlags {
    /// Every flag's name (as in a table of them: `light_dir`, `box`; on the
    /// command line `--light-dir`, `--box`): data, kind, then view flags.
    pub fn names() -> Vec<String> {
        DataFlags::NAMES
            .iter()
            .chain(KindFlags::NAMES)
            .chain(ViewFlags::NAMES)
            .map(|n| n.to_string())
            .collect()
    }

    /// The group the flag `name` belongs to (None: no such flag).
    pub fn group_of(name: &str) -> Option<FlagGroup> {
        if DataFlags::NAMES.contains(&name) {
            Some(FlagGroup::Data)
        } else if KindFlags::NAMES.contains(&name) {
            Some(FlagGroup::Kind)
        } else if ViewFlags::NAMES.contains(&name) {
            Some(FlagGroup::View)
        } else {
            None
        }
    }

    /// The names of every data flag (see [`SceneFlags::data_flags`]).
    pub fn data_names() -> Vec<&'static str> {
        let none = SceneFlags::default();
        let (p, t, a) = (none.particle_flags(), none.tet_flags(), none.amr_flags());
        let shared = none.shared_flags();
        p.iter()
            .chain(&t)
            .chain(&a)
            .chain(&shared)
            .map(|f| f.0)
            .collect()
    }

    /// The names of the given flags that describe the data — what to read,
    /// how to reconstruct it and how a data kind is shown (the data and kind
    /// groups: they set the particles, tessellation or AMR table) — as
    /// opposed to the view (image, camera, transfer function, render,
    /// light).
    pub fn data_flags(&self) -> Vec<&'static str> {
        let (p, t, a) = (self.particle_flags(), self.tet_flags(), self.amr_flags());
        p.into_iter()
            .chain(t)
            .chain(a)
            .chain(self.shared_flags())
            .filter_map(|(name, given)| given.then_some(name))
            .collect()
    }

    /// Data flags of more than one kind: a periodic box holds particles or
    /// a tessellation.
    fn shared_flags(&self) -> [(&'static str, bool); 1] {
        [("box", self.data.box_size.is_some())]
    }

    fn particle_flags(&self) -> [(&'static str, bool); 18] {
        let (d, k) = (&self.data, &self.kind);
        [
            ("particles", d.particles.is_some()),
            ("attribute", d.attribute.is_some()),
            ("radius", d.radius.is_some()),
            ("radii", d.radii.is_some()),
            ("weights", d.weights.is_some()),
            ("kernel", d.kernel.is_some()),
            ("kappa", d.kappa.is_some()),
            ("sigma", d.sigma.is_some()),
            ("cluster", d.cluster.is_some()),
            ("classification", k.classification.is_some()),
            ("attribute_range", k.attribute_range.is_some()),
            ("group", d.group.is_some()),
            ("part_type", d.part_type.is_some()),
            ("region", d.region.is_some()),
            ("species", d.species.is_some()),
            ("no_box", d.no_box),
            ("wrap", d.wrap),
            ("neighbours", d.neighbours.is_some()),
        ]
    }

    fn tet_flags(&self) -> [(&'static str, bool); 7] {
        let (d, k) = (&self.data, &self.kind);
        [
            ("lagrangian", d.lagrangian.is_some()),
            ("snapshot", d.snapshot.is_some()),
            ("particle_mass", d.particle_mass.is_some()),
            ("tet_mode", k.tet_mode.is_some()),
            ("k", k.k.is_some()),
            ("layers", k.layers.is_some()),
            ("lod", k.lod.is_some()),
        ]
    }

    fn amr_flags(&self) -> [(&'static str, bool); 9] {
        let (d, k) = (&self.data, &self.kind);
        [
            ("cells", d.cells.is_some()),
            ("scalars", !d.scalars.is_empty()),
            ("amrclaw", d.amrclaw.is_some()),
            ("amr", d.amr.is_some()),
            ("origin", d.origin.is_some()),
            ("cell_size", d.cell_size.is_some()),
            ("field", d.field.is_some()),
            ("color_field", k.color_field.is_some()),
            ("reconstruction", d.reconstruction.is_some()),
        ]
    }

    /// Applies the flags over `d`. Relative paths are relative to `cwd`
    /// (the working directory of the command line or the Python process).
    /// Errors name the flag: a value of the wrong length, or particle flags
    /// for a phase-space tessellation (they would be dropped).
    pub fn apply(&self, d: &mut SceneDesc, cwd: &Path) -> Result<(), SceneError> {
        if self.view.log && self.view.linear {
            return Err(SceneError::setting("log", "give log or linear, not both"));
        }
        let given = |flags: &[(&'static str, bool)]| flags.iter().find(|f| f.1).map(|f| f.0);
        let particle_flags = self.particle_flags();
        let path = |p: &PathBuf| cwd_path(cwd, &p.to_string_lossy());
        let periodic_box = match self.data.box_size.as_deref() {
            None => None,
            Some(&[l]) => Some(voxless_scene::BoxDesc::Side(l)),
            Some(&[x0, y0, z0, x1, y1, z1]) => {
                Some(voxless_scene::BoxDesc::Corners([x0, y0, z0, x1, y1, z1]))
            }
            Some(other) => {
                return Err(SceneError::setting(
                    "box",
                    format!(
                        "takes 1 value (a side L) or 6 (corners X0 Y0 Z0 X1 Y1 Z1), not {}",
                        other.len()
                    ),
                ));
            }
        };
        if given(&self.tet_flags()).is_some() || d.tets.is_some() {
            // Positions on a Lagrangian grid: a tessellation, not RBF
            // particles: the particle flags but the file would be dropped.
            if let Some(flag) = given(&particle_flags[1..]) {
                return Err(SceneError::setting(
                    flag,
                    "applies to particles rendered as RBFs, not to a phase-space \
                     tessellation (lagrangian, box, snapshot, or a [tets] scene), whose \
                     density comes from the tets and has no per-particle attribute",
                ));
            }
            let t = d.tets.get_or_insert_with(TetsDesc::default);
            if let Some(f) = &self.data.particles {
                t.file = Some(path(f));
            }
            set(&mut t.lagrangian, self.data.lagrangian);
            set(&mut t.snapshot, self.data.snapshot);
            match periodic_box {
                Some(voxless_scene::BoxDesc::Side(l)) => t.box_size = Some(l as f32),
                Some(voxless_scene::BoxDesc::Corners(_)) => {
                    return Err(SceneError::setting(
                        "box",
                        "a tessellation's box is [0, L)³: give its side L",
                    ));
                }
                None => {}
            }
            set(&mut t.particle_mass, self.data.particle_mass);
            set(&mut t.mode, self.kind.tet_mode);
            set(&mut t.k, self.kind.k);
            set(&mut t.layers, self.kind.layers);
            set(&mut t.lod_pixels, self.kind.lod);
        } else if given(&particle_flags).is_some()
            || (periodic_box.is_some() && d.particles.is_some())
        {
            let p = d.particles.get_or_insert_with(ParticlesDesc::default);
            set(&mut p.periodic_box, periodic_box);
            if self.data.no_box {
                if periodic_box.is_some() {
                    return Err(SceneError::setting(
                        "no_box",
                        "give either a box or no_box, not both",
                    ));
                }
                p.periodic = Some(false);
            }
            if self.data.wrap {
                p.wrap = Some(true);
            }
            set(&mut p.neighbours, self.data.neighbours);
            if let Some(f) = &self.data.particles {
                p.file = Some(path(f));
                p.demo = None;
            }
            let column = |s: &Option<String>| s.as_deref().map(|s| cwd_path(cwd, s));
            set(&mut p.attribute, column(&self.data.attribute));
            set(&mut p.radius, self.data.radius);
            set(&mut p.radii, column(&self.data.radii));
            set(&mut p.weights, column(&self.data.weights));
            set(&mut p.kernel, self.data.kernel);
            set(&mut p.group, self.data.group.clone());
            set(&mut p.part_type, self.data.part_type.clone());
            set(&mut p.region, fixed::<6, f64>("region", &self.data.region)?);
            set(&mut p.species, self.data.species.clone());
            set(&mut p.kappa, self.data.kappa);
            set(&mut p.sigma, self.data.sigma);
            set(&mut p.cluster, self.data.cluster);
            set(&mut p.classification, self.kind.classification);
            set(
                &mut p.attribute_range,
                fixed("attribute_range", &self.kind.attribute_range)?,
            );
        } else if periodic_box.is_some() {
            return Err(SceneError::setting(
                "box",
                "applies to particles (a periodic box) or a phase-space tessellation, and the \
                 scene has neither",
            ));
        }
        if let Some(flag) = given(&self.amr_flags()) {
            // Settings of AMR cells on a scene of particles or tets would be
            // ignored (or read as a second data source): say which flag.
            let amr_source = self.data.cells.is_some()
                || self.data.amrclaw.is_some()
                || self.data.amr.is_some()
                || !self.data.scalars.is_empty()
                || d.amr.is_some();
            if !amr_source && (d.particles.is_some() || d.tets.is_some()) {
                return Err(SceneError::setting(
                    flag,
                    "applies to AMR cells (--amr, --cells with --scalars, or --amrclaw), and the \
                     scene's data are particles or a tessellation",
                ));
            }
            let a = d.amr.get_or_insert_with(AmrDesc::default);
            if let Some(c) = &self.data.cells {
                a.cells = Some(path(c));
                (a.amrclaw, a.file) = (None, None);
            }
            if !self.data.scalars.is_empty() {
                a.scalars = Some(self.data.scalars.iter().map(path).collect());
            }
            if let Some(q) = &self.data.amrclaw {
                a.amrclaw = Some(path(q));
                (a.cells, a.file) = (None, None);
            }
            if let Some(f) = &self.data.amr {
                a.file = Some(path(f));
                (a.cells, a.amrclaw) = (None, None);
            }
            set(&mut a.origin, fixed("origin", &self.data.origin)?);
            set(&mut a.cell_size, self.data.cell_size);
            set(&mut a.field, self.data.field.clone());
            set(&mut a.color_field, self.kind.color_field.clone());
            set(&mut a.reconstruction, self.data.reconstruction);
        }
        self.apply_view(d, cwd)
    }

    /// The image, transfer-function, camera, render and light flags.
    fn apply_view(&self, d: &mut SceneDesc, cwd: &Path) -> Result<(), SceneError> {
        if let Some([w, h]) = fixed("size", &self.view.size)? {
            d.image.width = Some(w);
            d.image.height = Some(h);
        }
        set(&mut d.image.spp, self.view.spp);
        let t = &mut d.transfer;
        if let Some(f) = &self.view.colormap_file {
            // The file replaces the scene's colours; --colormap picks in it.
            t.colormap_file = Some(cwd.join(f).to_string_lossy().into_owned());
            t.colormap_points = None;
            t.colormap = None;
        } else if self.view.colormap.is_some() {
            t.colormap_file = None;
        }
        if self.view.colormap.is_some() {
            t.colormap_points = None;
        }
        set(&mut t.colormap, self.view.colormap.clone());
        if self.view.opacity.is_some() {
            t.opacity_points = None;
        }
        set(&mut t.opacity, self.view.opacity.clone());
        set(
            &mut t.value_range,
            fixed("value_range", &self.view.value_range)?,
        );
        let c = &mut d.camera;
        set(&mut c.eye, fixed("eye", &self.view.eye)?);
        set(&mut c.look_at, fixed("look_at", &self.view.look_at)?);
        set(&mut c.up, fixed("up", &self.view.up)?);
        set(&mut c.fov, self.view.fov);
        set(&mut c.orbit, self.view.orbit);
        set(&mut c.elevation, self.view.elevation);
        set(&mut c.zoom, self.view.zoom);
        if let Some(h) = self.view.orthographic {
            c.projection = Some(ProjectionName::Orthographic);
            c.ortho_height = Some(h);
        }
        let r = &mut d.render;
        set(&mut r.step, self.view.step);
        set(&mut r.sampling_rate, self.view.sampling_rate);
        set(&mut r.early_termination, self.view.early_termination);
        set(&mut r.opacity_scale, self.view.opacity_scale);
        set(
            &mut r.background,
            fixed("background", &self.view.background)?,
        );
        set(&mut r.seed, self.view.seed);
        if !self.view.iso.is_empty() {
            r.iso = Some(self.view.iso.clone());
        }
        set(&mut r.iso_opacity, self.view.iso_opacity);
        if self.view.iso_only {
            r.volume = Some(false);
        }
        if self.view.log {
            r.log_scale = Some(true);
        }
        if self.view.linear {
            r.log_scale = Some(false);
        }
        if self.view.no_packets {
            r.packets = Some(false);
        }
        set(&mut r.clip, fixed("clip", &self.view.clip)?);
        set(&mut r.ao, self.view.ao);
        set(&mut r.ao_distance, self.view.ao_distance);
        crate::surfaces::apply_flags(&self.view.mesh, &self.view.mirror, d, cwd)?;
        let lighting = self.view.light_pos.is_some()
            || self.view.light_intensity.is_some()
            || self.view.ambient.is_some()
            || self.view.free_flight.is_some()
            || self.view.noise.is_some();
        if self.view.shade || self.view.shadows || self.view.light_dir.is_some() || lighting {
            let l = d.light.get_or_insert_with(LightDesc::default);
            set(&mut l.direction, fixed("light_dir", &self.view.light_dir)?);
            set(&mut l.position, fixed("light_pos", &self.view.light_pos)?);
            set(&mut l.intensity, self.view.light_intensity);
            set(&mut l.ambient, self.view.ambient);
            set(&mut l.free_flight, self.view.free_flight);
            set(&mut l.noise, self.view.noise);
            if self.view.shadows {
                l.shadows = Some(true);
            }
        }
        Ok(())
    }
}
