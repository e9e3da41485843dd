//! Flags: every scene setting a one-off run needs, as one flat set of named
//! options that override a scene description — the CLI's flags (`--kernel`,
//! `--eye`, …) and the Python package's keyword arguments (`kernel=`,
//! `eye=`, …) are this one struct, so both front-ends apply them by the
//! same rules ([`SceneFlags::apply`]): which data kind the flags describe,
//! that a colormap file replaces the scene's colours, that any light setting
//! turns the light on, and so on.
//!
//! clap parses it from a command line (feature `clap`, which the CLI
//! enables); serde from a table of names (a Python dict of keyword
//! arguments), with unknown names refused. Names are the CLI's long flags
//! with `_` for `-` (`light_dir`, `box`).

use std::path::{Path, PathBuf};

use serde::Deserialize;
use voxless_scene::{
    AmrDesc, ClassificationName, FreeFlightName, KernelName, LightDesc, NoiseName, ParticlesDesc,
    ProjectionName, ReconstructionName, SceneDesc, Species, TetModeName, TetsDesc,
};

use crate::SceneError;

/// Every scene setting as a flag (see the module docs); each overrides the
/// description it is applied to.
#[derive(Deserialize, Debug, Default, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct SceneFlags {
    // ---- data ----
    /// Particle file: .npy N×3 (float32/float64), CSV with x, y, z columns,
    /// .vtp/.vtu, .xyz/.extxyz, a LAMMPS dump (dump.*, .lammpstrj, .dump),
    /// .particles, or .h5/.hdf5 (PySPH, SWIFT/Gadget; JaxPM with
    /// --lagrangian/--snapshot; needs --features hdf5). A multi-frame file,
    /// pattern or directory is a time series (--frames).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub particles: Option<PathBuf>,
    /// Per-particle attribute: a column of the particle file (case-insensitive),
    /// or .npy with N values.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub attribute: Option<String>,
    /// Global radius parameter (support for gaussian3, std-dev for gaussian, h for cubic-spline).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Particles", allow_negative_numbers = true)
    )]
    pub radius: Option<f32>,
    /// Per-particle radii: a column name, or .npy with N values.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub radii: Option<String>,
    /// Per-particle weights (masses for cubic-spline): a column name or .npy.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Particles"))]
    pub weights: Option<String>,
    /// PySPH particle array to read (default: fluid if present, else the first).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "NAME", help_heading = "Particles")
    )]
    pub group: Option<String>,
    /// SWIFT/Gadget particle type N: the group PartTypeN (default 0).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "N", help_heading = "Particles")
    )]
    pub part_type: Option<u32>,
    /// Keep only particles whose `type` column is T (LAMMPS type number; XYZ
    /// type number or element symbol).
    #[cfg_attr(feature = "clap", arg(long, value_name = "T", help_heading = "Particles", value_parser = species))]
    pub species: Option<Species>,
    /// RBF kernel (default gaussian3; SPH files: cubic-spline).
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
    /// Attribute classification (default post).
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = "Particles"))]
    pub classification: Option<ClassificationName>,
    /// Attribute range mapped to the colormap / maps.
    #[cfg_attr(feature = "clap", arg(long, num_args = 2, value_names = ["LO", "HI"], help_heading = "Particles", allow_negative_numbers = true))]
    pub attribute_range: Option<Vec<f32>>,

    // ---- phase-space tessellation ----
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
    /// Periodic box size L (positions in [0, L)³).
    #[serde(rename = "box")]
    #[cfg_attr(
        feature = "clap",
        arg(
            long = "box",
            value_name = "L",
            help_heading = "Phase-space tessellation",
            allow_negative_numbers = true
        )
    )]
    pub box_size: Option<f32>,
    /// Mass per particle (default: total mass 1).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Phase-space tessellation"))]
    pub particle_mass: Option<f64>,
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

    // ---- AMR ----
    /// ExaBricks cells: .cells (int32 x, y, z, level per cell).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub cells: Option<PathBuf>,
    /// ExaBricks .scalars file, one per field (repeat the flag).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub scalars: Vec<PathBuf>,
    /// AMRClaw ASCII output fort.qNNNN (fields q0, q1, …).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub amrclaw: Option<PathBuf>,
    /// World position of cell coordinate 0 (default: .meta.json beside the cells, else 0).
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "AMR", allow_negative_numbers = true))]
    pub origin: Option<Vec<f64>>,
    /// World width of a finest cell (default: .meta.json, else 1).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub cell_size: Option<f32>,
    /// Field driving opacity (default: the first).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub field: Option<String>,
    /// Field driving colour (multi-field rendering).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "AMR"))]
    pub color_field: Option<String>,
    /// Reconstruction between cell centres (default basis).
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = "AMR"))]
    pub reconstruction: Option<ReconstructionName>,

    // ---- image ----
    /// Image size in pixels.
    #[cfg_attr(feature = "clap", arg(long, num_args = 2, value_names = ["W", "H"], help_heading = "Image"))]
    pub size: Option<Vec<u32>>,
    /// Samples per pixel (progressively accumulated).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Image"))]
    pub spp: Option<u32>,

    // ---- transfer function ----
    /// Colormap preset (see `voxless colormaps`).
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
    /// Opacity preset: linear, constant, ramp-high, ramp-low.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Transfer function"))]
    pub opacity: Option<String>,
    /// Value range mapped to [0, 1] (default: from the data).
    #[cfg_attr(feature = "clap", arg(long, num_args = 2, value_names = ["LO", "HI"], help_heading = "Transfer function", allow_negative_numbers = true))]
    pub value_range: Option<Vec<f32>>,

    // ---- camera ----
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true))]
    pub eye: Option<Vec<f64>>,
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true))]
    pub look_at: Option<Vec<f64>>,
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true))]
    pub up: Option<Vec<f32>>,
    /// Vertical field of view in degrees.
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Camera", allow_negative_numbers = true)
    )]
    pub fov: Option<f32>,
    /// Orthographic projection with this view height (world units).
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

    // ---- render ----
    /// Ray-marching step in world units (default: 1/8 of the median support radius).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub step: Option<f32>,
    /// Stop marching at this opacity (default 0.99).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub early_termination: Option<f32>,
    /// Extinction per unit length at opacity 1 (default 8 / bounds diagonal).
    #[cfg_attr(
        feature = "clap",
        arg(long, help_heading = "Render", allow_negative_numbers = true)
    )]
    pub opacity_scale: Option<f32>,
    /// Background colour, linear RGB.
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["R", "G", "B"], help_heading = "Render"))]
    pub background: Option<Vec<f32>>,
    /// Gradient shading with a directional light.
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Render"))]
    pub shade: bool,
    /// Direction towards the light (implies --shade).
    #[cfg_attr(feature = "clap", arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Render", allow_negative_numbers = true))]
    pub light_dir: Option<Vec<f32>>,
    /// Single scattering with volumetric shadows (implies --shade's light).
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
    /// Random seed for jitter.
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
    /// Sample particles point by point instead of in ray packets (same
    /// image, slower; for comparisons).
    #[cfg_attr(feature = "clap", arg(long, help_heading = "Render"))]
    pub no_packets: bool,
    /// Render only what lies inside this box.
    #[cfg_attr(feature = "clap", arg(long, num_args = 6, value_names = ["X0", "Y0", "Z0", "X1", "Y1", "Z1"], help_heading = "Render", allow_negative_numbers = true))]
    pub clip: Option<Vec<f64>>,
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

impl SceneFlags {
    /// The flags' names, in declaration order (as in a table of them:
    /// `light_dir`, `box`; on the command line `--light-dir`, `--box`).
    pub const NAMES: &'static [&'static str] = &[
        "particles",
        "attribute",
        "radius",
        "radii",
        "weights",
        "group",
        "part_type",
        "species",
        "kernel",
        "kappa",
        "sigma",
        "cluster",
        "classification",
        "attribute_range",
        "lagrangian",
        "snapshot",
        "box",
        "particle_mass",
        "tet_mode",
        "k",
        "layers",
        "lod",
        "cells",
        "scalars",
        "amrclaw",
        "origin",
        "cell_size",
        "field",
        "color_field",
        "reconstruction",
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
    ];

    /// [`SceneFlags::NAMES`] as strings.
    pub fn names() -> Vec<String> {
        Self::NAMES.iter().map(|n| n.to_string()).collect()
    }

    /// The names of every data flag (see [`SceneFlags::data_flags`]).
    pub fn data_names() -> Vec<&'static str> {
        let none = SceneFlags::default();
        let (p, t, a) = (none.particle_flags(), none.tet_flags(), none.amr_flags());
        p.iter().chain(&t).chain(&a).map(|f| f.0).collect()
    }

    /// The names of the data flags among the given ones — those that say
    /// what data to read or how to build the volume (particles, tessellation
    /// and AMR flags), as opposed to the view (image, camera, transfer
    /// function, render, light).
    pub fn data_flags(&self) -> Vec<&'static str> {
        let (p, t, a) = (self.particle_flags(), self.tet_flags(), self.amr_flags());
        p.into_iter()
            .chain(t)
            .chain(a)
            .filter_map(|(name, given)| given.then_some(name))
            .collect()
    }

    fn particle_flags(&self) -> [(&'static str, bool); 14] {
        [
            ("particles", self.particles.is_some()),
            ("attribute", self.attribute.is_some()),
            ("radius", self.radius.is_some()),
            ("radii", self.radii.is_some()),
            ("weights", self.weights.is_some()),
            ("kernel", self.kernel.is_some()),
            ("kappa", self.kappa.is_some()),
            ("sigma", self.sigma.is_some()),
            ("cluster", self.cluster.is_some()),
            ("classification", self.classification.is_some()),
            ("attribute_range", self.attribute_range.is_some()),
            ("group", self.group.is_some()),
            ("part_type", self.part_type.is_some()),
            ("species", self.species.is_some()),
        ]
    }

    fn tet_flags(&self) -> [(&'static str, bool); 8] {
        [
            ("lagrangian", self.lagrangian.is_some()),
            ("snapshot", self.snapshot.is_some()),
            ("box", self.box_size.is_some()),
            ("particle_mass", self.particle_mass.is_some()),
            ("tet_mode", self.tet_mode.is_some()),
            ("k", self.k.is_some()),
            ("layers", self.layers.is_some()),
            ("lod", self.lod.is_some()),
        ]
    }

    fn amr_flags(&self) -> [(&'static str, bool); 8] {
        [
            ("cells", self.cells.is_some()),
            ("scalars", !self.scalars.is_empty()),
            ("amrclaw", self.amrclaw.is_some()),
            ("origin", self.origin.is_some()),
            ("cell_size", self.cell_size.is_some()),
            ("field", self.field.is_some()),
            ("color_field", self.color_field.is_some()),
            ("reconstruction", self.reconstruction.is_some()),
        ]
    }

    /// Applies the flags over `d`. Relative paths are relative to `cwd`
    /// (the working directory of the command line or the Python process).
    /// Errors name the flag: a value of the wrong length, or particle flags
    /// for a phase-space tessellation (they would be dropped).
    pub fn apply(&self, d: &mut SceneDesc, cwd: &Path) -> Result<(), SceneError> {
        if self.log && self.linear {
            return Err(SceneError::setting("log", "give log or linear, not both"));
        }
        let given = |flags: &[(&'static str, bool)]| flags.iter().find(|f| f.1).map(|f| f.0);
        let particle_flags = self.particle_flags();
        let path = |p: &PathBuf| cwd_path(cwd, &p.to_string_lossy());
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
            if let Some(f) = &self.particles {
                t.file = Some(path(f));
            }
            set(&mut t.lagrangian, self.lagrangian);
            set(&mut t.snapshot, self.snapshot);
            set(&mut t.box_size, self.box_size);
            set(&mut t.particle_mass, self.particle_mass);
            set(&mut t.mode, self.tet_mode);
            set(&mut t.k, self.k);
            set(&mut t.layers, self.layers);
            set(&mut t.lod_pixels, self.lod);
        } else if given(&particle_flags).is_some() {
            let p = d.particles.get_or_insert_with(ParticlesDesc::default);
            if let Some(f) = &self.particles {
                p.file = Some(path(f));
                p.demo = None;
            }
            let column = |s: &Option<String>| s.as_deref().map(|s| cwd_path(cwd, s));
            set(&mut p.attribute, column(&self.attribute));
            set(&mut p.radius, self.radius);
            set(&mut p.radii, column(&self.radii));
            set(&mut p.weights, column(&self.weights));
            set(&mut p.kernel, self.kernel);
            set(&mut p.group, self.group.clone());
            set(&mut p.part_type, self.part_type);
            set(&mut p.species, self.species.clone());
            set(&mut p.kappa, self.kappa);
            set(&mut p.sigma, self.sigma);
            set(&mut p.cluster, self.cluster);
            set(&mut p.classification, self.classification);
            set(
                &mut p.attribute_range,
                fixed("attribute_range", &self.attribute_range)?,
            );
        }
        if given(&self.amr_flags()).is_some() {
            let a = d.amr.get_or_insert_with(AmrDesc::default);
            if let Some(c) = &self.cells {
                a.cells = Some(path(c));
                a.amrclaw = None;
            }
            if !self.scalars.is_empty() {
                a.scalars = Some(self.scalars.iter().map(path).collect());
            }
            if let Some(q) = &self.amrclaw {
                a.amrclaw = Some(path(q));
                a.cells = None;
            }
            set(&mut a.origin, fixed("origin", &self.origin)?);
            set(&mut a.cell_size, self.cell_size);
            set(&mut a.field, self.field.clone());
            set(&mut a.color_field, self.color_field.clone());
            set(&mut a.reconstruction, self.reconstruction);
        }
        self.apply_view(d, cwd)
    }

    /// The image, transfer-function, camera, render and light flags.
    fn apply_view(&self, d: &mut SceneDesc, cwd: &Path) -> Result<(), SceneError> {
        if let Some([w, h]) = fixed("size", &self.size)? {
            d.image.width = Some(w);
            d.image.height = Some(h);
        }
        set(&mut d.image.spp, self.spp);
        let t = &mut d.transfer;
        if let Some(f) = &self.colormap_file {
            // The file replaces the scene's colours; --colormap picks in it.
            t.colormap_file = Some(cwd.join(f).to_string_lossy().into_owned());
            t.colormap_points = None;
            t.colormap = None;
        } else if self.colormap.is_some() {
            t.colormap_file = None;
        }
        if self.colormap.is_some() {
            t.colormap_points = None;
        }
        set(&mut t.colormap, self.colormap.clone());
        if self.opacity.is_some() {
            t.opacity_points = None;
        }
        set(&mut t.opacity, self.opacity.clone());
        set(&mut t.value_range, fixed("value_range", &self.value_range)?);
        let c = &mut d.camera;
        set(&mut c.eye, fixed("eye", &self.eye)?);
        set(&mut c.look_at, fixed("look_at", &self.look_at)?);
        set(&mut c.up, fixed("up", &self.up)?);
        set(&mut c.fov, self.fov);
        set(&mut c.orbit, self.orbit);
        set(&mut c.elevation, self.elevation);
        set(&mut c.zoom, self.zoom);
        if let Some(h) = self.orthographic {
            c.projection = Some(ProjectionName::Orthographic);
            c.ortho_height = Some(h);
        }
        let r = &mut d.render;
        set(&mut r.step, self.step);
        set(&mut r.early_termination, self.early_termination);
        set(&mut r.opacity_scale, self.opacity_scale);
        set(&mut r.background, fixed("background", &self.background)?);
        set(&mut r.seed, self.seed);
        if !self.iso.is_empty() {
            r.iso = Some(self.iso.clone());
        }
        set(&mut r.iso_opacity, self.iso_opacity);
        if self.iso_only {
            r.volume = Some(false);
        }
        if self.log {
            r.log_scale = Some(true);
        }
        if self.linear {
            r.log_scale = Some(false);
        }
        if self.no_packets {
            r.packets = Some(false);
        }
        set(&mut r.clip, fixed("clip", &self.clip)?);
        let lighting = self.light_pos.is_some()
            || self.light_intensity.is_some()
            || self.ambient.is_some()
            || self.free_flight.is_some()
            || self.noise.is_some();
        if self.shade || self.shadows || self.light_dir.is_some() || lighting {
            let l = d.light.get_or_insert_with(LightDesc::default);
            set(&mut l.direction, fixed("light_dir", &self.light_dir)?);
            set(&mut l.position, fixed("light_pos", &self.light_pos)?);
            set(&mut l.intensity, self.light_intensity);
            set(&mut l.ambient, self.ambient);
            set(&mut l.free_flight, self.free_flight);
            set(&mut l.noise, self.noise);
            if self.shadows {
                l.shadows = Some(true);
            }
        }
        Ok(())
    }
}
