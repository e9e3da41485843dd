//! Command-line flags that mirror the scene file, and how they override it.

use std::path::{Path, PathBuf};

use anyhow::bail;
use clap::Args;
use voxless::{
    AmrDesc, ClassificationName, FreeFlightName, KernelName, LightDesc, NoiseName, ParticlesDesc,
    ProjectionName, ReconstructionName, SceneDesc, Species, TetModeName, TetsDesc,
};

/// What data to read and how to reconstruct its field: every command that
/// loads data takes these (they override the scene file).
#[derive(Args, Debug, Default, Clone)]
pub struct DataArgs {
    /// Scene file (TOML); optional when --particles is given.
    pub scene: Option<PathBuf>,
    /// Particle file: .npy N×3 (float32/float64), CSV with x, y, z columns,
    /// .vtp/.vtu, .xyz/.extxyz, a LAMMPS dump (dump.*, .lammpstrj, .dump),
    /// .particles, or .h5/.hdf5 (PySPH, SWIFT/Gadget; JaxPM with
    /// --lagrangian/--snapshot, or alone; needs --features hdf5). A
    /// multi-frame file, pattern, glob or directory is a time series.
    #[arg(long, help_heading = "Particles")]
    pub particles: Option<PathBuf>,
    /// Per-particle attribute: a column of the particle file (case-insensitive),
    /// or .npy with N values.
    #[arg(long, help_heading = "Particles")]
    pub attribute: Option<String>,
    /// Global radius parameter, world units (support for gaussian3, std-dev for
    /// gaussian, h for cubic-spline). Default: a support of the median
    /// nearest-neighbour distance (printed).
    #[arg(long, help_heading = "Particles", allow_negative_numbers = true)]
    pub radius: Option<f32>,
    /// Per-particle radii: a column name, or .npy with N values.
    #[arg(long, help_heading = "Particles")]
    pub radii: Option<String>,
    /// Per-particle weights (masses for cubic-spline): a column name or .npy
    /// (default 1).
    #[arg(long, help_heading = "Particles")]
    pub weights: Option<String>,
    /// PySPH particle array to read (default: fluid if present, else the first).
    #[arg(long, value_name = "NAME", help_heading = "Particles")]
    pub group: Option<String>,
    /// SWIFT/Gadget particle type N: the group PartTypeN (default 0).
    #[arg(long, value_name = "N", help_heading = "Particles")]
    pub part_type: Option<u32>,
    /// Keep only particles whose `type` column is T (LAMMPS type number; XYZ
    /// type number or element symbol).
    #[arg(long, value_name = "T", help_heading = "Particles")]
    pub species: Option<String>,
    /// RBF kernel (default gaussian3; SPH files: cubic-spline).
    #[arg(long, value_enum, help_heading = "Particles")]
    pub kernel: Option<KernelName>,
    /// Global density scale κ of the gaussian kernel (default 1).
    #[arg(long, help_heading = "Particles", allow_negative_numbers = true)]
    pub kappa: Option<f32>,
    /// Truncation σ of the gaussian kernel, in radii (default 2).
    #[arg(long, help_heading = "Particles", allow_negative_numbers = true)]
    pub sigma: Option<f32>,
    /// Particles per BVH leaf cluster, 1..=16 (default 8).
    #[arg(long, help_heading = "Particles")]
    pub cluster: Option<usize>,
    /// Treat --particles as N³ N-body particles on a Lagrangian grid (Lagrangian
    /// order, k fastest) and render their phase-space tessellation. A JaxPM
    /// .h5 file gives N (and L) itself.
    #[arg(long, value_name = "N", help_heading = "Phase-space tessellation")]
    pub lagrangian: Option<usize>,
    /// JaxPM snapshot K of a .h5 run, the group snap_K (default: the last);
    /// implies a tessellation.
    #[arg(long, value_name = "K", help_heading = "Phase-space tessellation")]
    pub snapshot: Option<usize>,
    /// Periodic box size L (positions in [0, L)³; a JaxPM file's by default).
    #[arg(
        long = "box",
        value_name = "L",
        help_heading = "Phase-space tessellation",
        allow_negative_numbers = true
    )]
    pub box_size: Option<f32>,
    /// Mass per particle, world units (default: the mean density is 1, so
    /// densities read as the overdensity 1 + δ).
    #[arg(long, help_heading = "Phase-space tessellation")]
    pub particle_mass: Option<f64>,
    /// ExaBricks cells: .cells (int32 x, y, z, level per cell).
    #[arg(long, help_heading = "AMR")]
    pub cells: Option<PathBuf>,
    /// ExaBricks .scalars file, one per field (repeat the flag).
    #[arg(long, help_heading = "AMR")]
    pub scalars: Vec<PathBuf>,
    /// AMRClaw ASCII output fort.qNNNN (fields q0, q1, …).
    #[arg(long, help_heading = "AMR")]
    pub amrclaw: Option<PathBuf>,
    /// World position of cell coordinate 0 (default: .meta.json beside the cells, else 0).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "AMR", allow_negative_numbers = true)]
    pub origin: Option<Vec<f64>>,
    /// World width of a finest cell (default: .meta.json, else 1).
    #[arg(long, help_heading = "AMR")]
    pub cell_size: Option<f32>,
    /// Field driving opacity (default: the first).
    #[arg(long, help_heading = "AMR")]
    pub field: Option<String>,
    /// Reconstruction between cell centres (default basis).
    #[arg(long, value_enum, help_heading = "AMR")]
    pub reconstruction: Option<ReconstructionName>,
}

/// How `render` shows a particular data kind (particle attributes,
/// tessellation modes, AMR colour fields).
#[derive(Args, Debug, Default, Clone)]
pub struct KindArgs {
    /// Attribute classification (default post).
    #[arg(long, value_enum, help_heading = "Particles")]
    pub classification: Option<ClassificationName>,
    /// Attribute range mapped to the colormap / maps (default: over the
    /// data, every frame of a time series).
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], help_heading = "Particles", allow_negative_numbers = true)]
    pub attribute_range: Option<Vec<f32>>,
    /// How crossing events become colour (default exact).
    #[arg(long, value_enum, help_heading = "Phase-space tessellation")]
    pub tet_mode: Option<TetModeName>,
    /// k-buffer depth for --tet-mode kbuffer (default 16).
    #[arg(long, help_heading = "Phase-space tessellation")]
    pub k: Option<usize>,
    /// Log-spaced depth layers behind the k-buffer (default 64).
    #[arg(long, help_heading = "Phase-space tessellation")]
    pub layers: Option<usize>,
    /// Level of detail: blocks smaller than this many pixels on screen use a
    /// 2^r-subsampled Lagrangian grid (off by default).
    #[arg(long, value_name = "PIXELS", help_heading = "Phase-space tessellation")]
    pub lod: Option<f32>,
    /// Field driving colour (multi-field rendering; default: --field).
    #[arg(long, help_heading = "AMR")]
    pub color_field: Option<String>,
}

/// How an image looks: size, transfer function, camera, rendering and
/// lighting (`render` and `demo`).
#[derive(Args, Debug, Default, Clone)]
pub struct ViewArgs {
    /// Image size in pixels (default 800 600).
    #[arg(long, num_args = 2, value_names = ["W", "H"], help_heading = "Image")]
    pub size: Option<Vec<u32>>,
    /// Samples per pixel, progressively accumulated (default 1).
    #[arg(long, help_heading = "Image")]
    pub spp: Option<u32>,
    /// Colormap preset (see `voxless colormaps`; default viridis).
    #[arg(long, help_heading = "Transfer function")]
    pub colormap: Option<String>,
    /// Colormap file: ParaView preset JSON ("Export preset") or a JSON list of
    /// [r, g, b] / [x, r, g, b] sRGB colours; --colormap NAME picks a preset in
    /// it. Its opacity points apply unless --opacity is given.
    #[arg(long, value_name = "FILE", help_heading = "Transfer function")]
    pub colormap_file: Option<PathBuf>,
    /// Opacity preset: linear, constant, ramp-high, ramp-low (default linear).
    #[arg(long, help_heading = "Transfer function")]
    pub opacity: Option<String>,
    /// Value range mapped to [0, 1] (default: robust percentiles of the field
    /// over the data, every frame of a time series; printed).
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], help_heading = "Transfer function", allow_negative_numbers = true)]
    pub value_range: Option<Vec<f32>>,
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true)]
    /// Eye position, world coordinates (default: a three-quarter view from
    /// 25° above the horizontal, the data's long horizontal side across the
    /// image, far enough to keep all of it in frame).
    pub eye: Option<Vec<f64>>,
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true)]
    /// Point the camera looks at, world coordinates (default: the centre of
    /// the data's bounds).
    pub look_at: Option<Vec<f64>>,
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Camera", allow_negative_numbers = true)]
    /// Up vector of the view (default 0 0 1: +z up, as in SPH, cosmology and
    /// most CFD; the default eye is chosen around it).
    pub up: Option<Vec<f32>>,
    /// Vertical field of view in degrees (default 30).
    #[arg(long, help_heading = "Camera", allow_negative_numbers = true)]
    pub fov: Option<f32>,
    /// Orthographic projection with this view height, world units (default:
    /// perspective).
    #[arg(
        long,
        value_name = "HEIGHT",
        help_heading = "Camera",
        allow_negative_numbers = true
    )]
    pub orthographic: Option<f32>,
    /// Orbit the eye about the up axis through the look-at point (the data
    /// centre by default), in degrees; positive turns towards the right.
    #[arg(long, value_name = "DEG", help_heading = "Camera", allow_negative_numbers = true, value_parser = crate::view::degrees)]
    pub orbit: Option<f32>,
    /// Raise the eye towards the up vector, in degrees (negative lowers it;
    /// the view stays within ±89.9° of the horizontal).
    #[arg(long, value_name = "DEG", help_heading = "Camera", allow_negative_numbers = true, value_parser = crate::view::degrees)]
    pub elevation: Option<f32>,
    /// Zoom by F > 0: the eye's distance to the look-at point ÷ F
    /// (orthographic: the view height ÷ F).
    #[arg(long, value_name = "F", help_heading = "Camera", allow_negative_numbers = true, value_parser = crate::view::zoom)]
    pub zoom: Option<f32>,
    /// Ray-marching step in world units (default: 1/8 of the median support radius).
    #[arg(long, help_heading = "Render", allow_negative_numbers = true)]
    pub step: Option<f32>,
    /// Stop marching at this opacity (default 0.99).
    #[arg(long, help_heading = "Render", allow_negative_numbers = true)]
    pub early_termination: Option<f32>,
    /// Extinction per unit length at opacity 1 (default: chosen so a typical
    /// ray through the data reaches optical depth 2; printed).
    #[arg(long, help_heading = "Render", allow_negative_numbers = true)]
    pub opacity_scale: Option<f32>,
    /// Background colour, linear RGB ≥ 0 (default 0 0 0).
    #[arg(long, num_args = 3, value_names = ["R", "G", "B"], help_heading = "Render")]
    pub background: Option<Vec<f32>>,
    /// Gradient shading with a directional light (default off).
    #[arg(long, help_heading = "Render")]
    pub shade: bool,
    /// Direction towards the light (implies --shade; default: over the
    /// camera's left shoulder).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Render", allow_negative_numbers = true)]
    pub light_dir: Option<Vec<f32>>,
    /// Single scattering with volumetric shadows (implies --shade's light;
    /// default off).
    #[arg(long, help_heading = "Lighting")]
    pub shadows: bool,
    /// A point light at this position (with --shadows).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], help_heading = "Lighting", allow_negative_numbers = true)]
    pub light_pos: Option<Vec<f64>>,
    /// Light intensity (with --shadows; default 1).
    #[arg(long, help_heading = "Lighting")]
    pub light_intensity: Option<f32>,
    /// Fraction of colour kept in full shade (default 0.3).
    #[arg(long, help_heading = "Lighting")]
    pub ambient: Option<f32>,
    /// Free-flight sampling with shadows (default marching).
    #[arg(long, value_enum, help_heading = "Lighting")]
    pub free_flight: Option<FreeFlightName>,
    /// Random numbers with shadows (default blue).
    #[arg(long, value_enum, help_heading = "Lighting")]
    pub noise: Option<NoiseName>,
    /// Random seed for jitter (default 0).
    #[arg(long, help_heading = "Render")]
    pub seed: Option<u64>,
    /// Implicit iso-surface at this value of the opacity field (repeat for more).
    #[arg(long, help_heading = "Render", allow_negative_numbers = true)]
    pub iso: Vec<f32>,
    /// Opacity of the iso-surfaces (default 1).
    #[arg(long, help_heading = "Render")]
    pub iso_opacity: Option<f32>,
    /// Render only the iso-surfaces, not the volume.
    #[arg(long, help_heading = "Render")]
    pub iso_only: bool,
    /// Map log10(value) through the transfer function (default for tessellations).
    #[arg(long, help_heading = "Transfer function", conflicts_with = "linear")]
    pub log: bool,
    /// Map the value linearly (default except for tessellations).
    #[arg(long, help_heading = "Transfer function")]
    pub linear: bool,
    /// Sample particles point by point instead of in ray packets (same
    /// image, slower; for comparisons).
    #[arg(long, help_heading = "Render")]
    pub no_packets: bool,
    /// Render only what lies inside this box, world coordinates (default: all).
    #[arg(long, num_args = 6, value_names = ["X0", "Y0", "Z0", "X1", "Y1", "Z1"], help_heading = "Render", allow_negative_numbers = true)]
    pub clip: Option<Vec<f64>>,
}

/// Every flag of a command (those a command lacks stay at their defaults),
/// applied on top of the scene file.
#[derive(Debug, Default, Clone)]
pub struct SceneArgs {
    pub data: DataArgs,
    pub kind: KindArgs,
    pub view: ViewArgs,
}

fn arr3<T: Copy>(v: &Option<Vec<T>>) -> Option<[T; 3]> {
    v.as_ref().map(|v| [v[0], v[1], v[2]])
}
fn arr2(v: &Option<Vec<f32>>) -> Option<[f32; 2]> {
    v.as_ref().map(|v| [v[0], v[1]])
}

/// Paths from the command line are relative to the working directory; make
/// them absolute so resolving against the scene's directory leaves them be.
fn cwd_path(s: &str) -> String {
    let p = Path::new(s);
    if p.is_absolute() || p.extension().is_none() {
        // No extension: possibly a CSV column name; leave it alone.
        return s.to_string();
    }
    std::env::current_dir()
        .map(|d| d.join(p).to_string_lossy().into_owned())
        .unwrap_or_else(|_| s.to_string())
}

impl SceneArgs {
    /// Loads the scene file (if any) and applies the flags on top. Returns the
    /// description and the directory its relative paths are relative to.
    pub fn scene(&self) -> anyhow::Result<(SceneDesc, PathBuf)> {
        let (mut d, base) = match &self.data.scene {
            Some(path) => {
                let d = voxless::read_scene(path)?;
                let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
                (d, base)
            }
            None => (SceneDesc::default(), PathBuf::from(".")),
        };
        self.apply(&mut d)?;
        Ok((d, base))
    }

    /// Particle-only flags given with a tessellation: they would be
    /// dropped, so they are errors naming them.
    fn refuse_particle_flags_with_tets(&self) -> anyhow::Result<()> {
        let given = [
            ("--attribute", self.data.attribute.is_some()),
            ("--radius", self.data.radius.is_some()),
            ("--radii", self.data.radii.is_some()),
            ("--weights", self.data.weights.is_some()),
            ("--kernel", self.data.kernel.is_some()),
            ("--kappa", self.data.kappa.is_some()),
            ("--sigma", self.data.sigma.is_some()),
            ("--cluster", self.data.cluster.is_some()),
            ("--classification", self.kind.classification.is_some()),
            ("--attribute-range", self.kind.attribute_range.is_some()),
            ("--group", self.data.group.is_some()),
            ("--part-type", self.data.part_type.is_some()),
            ("--species", self.data.species.is_some()),
        ];
        if let Some((flag, _)) = given.iter().find(|g| g.1) {
            bail!(
                "{flag} applies to particles rendered as RBFs, not to a phase-space \
                 tessellation (--lagrangian, --box, --snapshot, or a [tets] scene), whose \
                 density comes from the tets and has no per-particle attribute"
            );
        }
        Ok(())
    }

    fn apply(&self, d: &mut SceneDesc) -> anyhow::Result<()> {
        let has_particle_flags = self.data.particles.is_some()
            || self.data.attribute.is_some()
            || self.data.radius.is_some()
            || self.data.radii.is_some()
            || self.data.weights.is_some()
            || self.data.kernel.is_some()
            || self.data.kappa.is_some()
            || self.data.sigma.is_some()
            || self.data.cluster.is_some()
            || self.kind.classification.is_some()
            || self.kind.attribute_range.is_some()
            || self.data.group.is_some()
            || self.data.part_type.is_some()
            || self.data.species.is_some();
        let has_tet_flags = self.data.lagrangian.is_some()
            || self.data.snapshot.is_some()
            || self.data.box_size.is_some()
            || self.data.particle_mass.is_some()
            || self.kind.tet_mode.is_some()
            || self.kind.k.is_some()
            || self.kind.layers.is_some()
            || self.kind.lod.is_some();
        if has_tet_flags || d.tets.is_some() {
            // Positions on a Lagrangian grid: a tessellation, not RBF particles.
            self.refuse_particle_flags_with_tets()?;
            let t = d.tets.get_or_insert_with(TetsDesc::default);
            if let Some(f) = &self.data.particles {
                t.file = Some(cwd_path(&f.to_string_lossy()));
            }
            set(&mut t.lagrangian, self.data.lagrangian);
            set(&mut t.snapshot, self.data.snapshot);
            set(&mut t.box_size, self.data.box_size);
            set(&mut t.particle_mass, self.data.particle_mass);
            set(&mut t.mode, self.kind.tet_mode);
            set(&mut t.k, self.kind.k);
            set(&mut t.layers, self.kind.layers);
            set(&mut t.lod_pixels, self.kind.lod);
        } else if has_particle_flags {
            let p = d.particles.get_or_insert_with(ParticlesDesc::default);
            if let Some(f) = &self.data.particles {
                let f = f.to_string_lossy();
                p.file = Some(cwd_path(&f));
                p.demo = None;
            }
            set(
                &mut p.attribute,
                self.data.attribute.as_deref().map(cwd_path),
            );
            set(&mut p.radius, self.data.radius);
            set(&mut p.radii, self.data.radii.as_deref().map(cwd_path));
            set(&mut p.weights, self.data.weights.as_deref().map(cwd_path));
            set(&mut p.kernel, self.data.kernel);
            set(&mut p.group, self.data.group.clone());
            set(&mut p.part_type, self.data.part_type);
            set(
                &mut p.species,
                self.data.species.as_deref().map(Species::from),
            );
            set(&mut p.kappa, self.data.kappa);
            set(&mut p.sigma, self.data.sigma);
            set(&mut p.cluster, self.data.cluster);
            set(&mut p.classification, self.kind.classification);
            set(&mut p.attribute_range, arr2(&self.kind.attribute_range));
        }
        let has_amr_flags = self.data.cells.is_some()
            || !self.data.scalars.is_empty()
            || self.data.amrclaw.is_some()
            || self.data.origin.is_some()
            || self.data.cell_size.is_some()
            || self.data.field.is_some()
            || self.kind.color_field.is_some()
            || self.data.reconstruction.is_some();
        if has_amr_flags {
            let a = d.amr.get_or_insert_with(AmrDesc::default);
            let abs = |p: &PathBuf| cwd_path(&p.to_string_lossy());
            if let Some(c) = &self.data.cells {
                a.cells = Some(abs(c));
                a.amrclaw = None;
            }
            if !self.data.scalars.is_empty() {
                a.scalars = Some(self.data.scalars.iter().map(abs).collect());
            }
            if let Some(q) = &self.data.amrclaw {
                a.amrclaw = Some(abs(q));
                a.cells = None;
            }
            set(&mut a.origin, arr3(&self.data.origin));
            set(&mut a.cell_size, self.data.cell_size);
            set(&mut a.field, self.data.field.clone());
            set(&mut a.color_field, self.kind.color_field.clone());
            set(&mut a.reconstruction, self.data.reconstruction);
        }
        if let Some(s) = &self.view.size {
            d.image.width = Some(s[0]);
            d.image.height = Some(s[1]);
        }
        set(&mut d.image.spp, self.view.spp);
        if let Some(f) = &self.view.colormap_file {
            // The file replaces the scene's colours; --colormap picks in it.
            let f = std::env::current_dir().map_or_else(|_| f.clone(), |d| d.join(f));
            d.transfer.colormap_file = Some(f.to_string_lossy().into_owned());
            d.transfer.colormap_points = None;
            d.transfer.colormap = None;
        } else if self.view.colormap.is_some() {
            d.transfer.colormap_file = None;
        }
        if self.view.colormap.is_some() {
            d.transfer.colormap_points = None;
        }
        set(&mut d.transfer.colormap, self.view.colormap.clone());
        if self.view.opacity.is_some() {
            d.transfer.opacity_points = None;
        }
        set(&mut d.transfer.opacity, self.view.opacity.clone());
        set(&mut d.transfer.value_range, arr2(&self.view.value_range));
        set(&mut d.camera.eye, arr3(&self.view.eye));
        set(&mut d.camera.look_at, arr3(&self.view.look_at));
        set(&mut d.camera.up, arr3(&self.view.up));
        set(&mut d.camera.fov, self.view.fov);
        set(&mut d.camera.orbit, self.view.orbit);
        set(&mut d.camera.elevation, self.view.elevation);
        set(&mut d.camera.zoom, self.view.zoom);
        if let Some(h) = self.view.orthographic {
            d.camera.projection = Some(ProjectionName::Orthographic);
            d.camera.ortho_height = Some(h);
        }
        set(&mut d.render.step, self.view.step);
        set(&mut d.render.early_termination, self.view.early_termination);
        set(&mut d.render.opacity_scale, self.view.opacity_scale);
        set(&mut d.render.background, arr3(&self.view.background));
        set(&mut d.render.seed, self.view.seed);
        if !self.view.iso.is_empty() {
            d.render.iso = Some(self.view.iso.clone());
        }
        set(&mut d.render.iso_opacity, self.view.iso_opacity);
        if self.view.iso_only {
            d.render.volume = Some(false);
        }
        if self.view.log {
            d.render.log_scale = Some(true);
        }
        if self.view.linear {
            d.render.log_scale = Some(false);
        }
        if self.view.no_packets {
            d.render.packets = Some(false);
        }
        if let Some(c) = &self.view.clip {
            d.render.clip = Some([c[0], c[1], c[2], c[3], c[4], c[5]]);
        }
        let lighting = self.view.light_pos.is_some()
            || self.view.light_intensity.is_some()
            || self.view.ambient.is_some()
            || self.view.free_flight.is_some()
            || self.view.noise.is_some();
        if self.view.shade || self.view.shadows || self.view.light_dir.is_some() || lighting {
            let l = d.light.get_or_insert_with(LightDesc::default);
            set(&mut l.direction, arr3(&self.view.light_dir));
            set(&mut l.position, arr3(&self.view.light_pos));
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

fn set<T>(slot: &mut Option<T>, v: Option<T>) {
    if v.is_some() {
        *slot = v;
    }
}
