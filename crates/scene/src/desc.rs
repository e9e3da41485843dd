//! The serde description of a scene: what a TOML file (or the command line)
//! says, before any file is read. Every field is optional; the `voxless`
//! library fills defaults from the data.

use serde::{Deserialize, Serialize};

use crate::enums::{
    AxisName, ClassificationName, FollowName, FreeFlightName, KernelName, NoiseName, PixelsName,
    ProjectionName, ReconstructionName, Species, TetModeName,
};

#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    pub particles: Option<ParticlesDesc>,
    pub amr: Option<AmrDesc>,
    pub tets: Option<TetsDesc>,
    #[serde(default)]
    pub camera: CameraDesc,
    #[serde(default)]
    pub image: ImageDesc,
    #[serde(default)]
    pub transfer: TransferDesc,
    #[serde(default)]
    pub render: RenderDesc,
    pub light: Option<LightDesc>,
    /// Opaque triangle meshes drawn with the volume (`[[meshes]]`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub meshes: Vec<MeshDesc>,
    /// Instances (`[[instances]]`): the volume and its meshes drawn again,
    /// mirrored about a plane, without copying data.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub instances: Vec<InstanceDesc>,
}

/// A triangle mesh: `.ply`, `.obj`, `.stl` or `.vtp` (polygons), in the
/// data's coordinates. Paths are relative to the scene file.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    pub file: String,
    /// sRGB colour in [0, 1] (default light grey 0.8 0.8 0.8).
    pub color: Option<[f32; 3]>,
    /// Colour by this per-vertex field (PLY vertex property, VTP point
    /// data) through `colormap` instead.
    pub field: Option<String>,
    /// Colormap of `field` (default viridis).
    pub colormap: Option<String>,
    /// Range of `field` mapped to the colormap (default: the field's).
    pub range: Option<[f32; 2]>,
}

/// One mirror instance: everything reflected about the plane
/// `axis = at` (default: the data's lower face along `axis`). The data's
/// own side of the plane is drawn as it is; the other side shows its
/// mirror image.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InstanceDesc {
    pub mirror: AxisName,
    pub at: Option<f64>,
}

/// A particle data source. Paths are relative to the scene file.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ParticlesDesc {
    /// Particle file in any supported format, picked by extension and
    /// content: `.npy` N×3 (float32/float64), CSV with a header naming x, y,
    /// z, `.vtp`/`.vtu`, `.xyz`/`.extxyz`, a LAMMPS dump, `.particles`, or
    /// (feature `hdf5`) PySPH/SWIFT/Gadget `.h5`/`.hdf5`. Multi-frame files,
    /// patterns and directories are time series.
    pub file: Option<String>,
    /// The built-in demo particles instead of a file.
    pub demo: Option<bool>,
    /// PySPH particle array to read (default: `fluid` if present, else the
    /// first).
    pub group: Option<String>,
    /// Snapshot particle type: a number 0–6 or a name (`gas`, `dm`, `disk`,
    /// `bulge`, `stars`, `bh`); several, comma-separated (`"gas,stars"`),
    /// become materials with their own transfer functions. Default: gas
    /// when the snapshot has any, else the first type with particles.
    pub part_type: Option<Species>,
    /// Snapshots: load only the particles that can touch the box
    /// `[x0, y0, z0, x1, y1, z1]` (periodic-aware), with a margin for the
    /// kernels reaching in (the support of `radius`, else a tenth of the
    /// region's longest side). A cutout of a periodic box is unwrapped
    /// around the region and is not periodic itself.
    pub region: Option<[f64; 6]>,
    /// Keep only particles whose `type` column equals this (LAMMPS type
    /// number; XYZ type number or element symbol).
    pub species: Option<Species>,
    /// Multi-material rendering: one entry per species, each with its own
    /// radius and transfer function (`[[particles.materials]]`).
    pub materials: Option<Vec<MaterialDesc>>,
    /// `.npy` with N values, or the name of a column of the particle file
    /// (case-insensitive).
    pub attribute: Option<String>,
    /// Global radius parameter (support radius for gaussian3, standard
    /// deviation for gaussian, smoothing length h for the SPH kernels).
    pub radius: Option<f32>,
    /// Per-particle radii: `.npy` with N values or a column name.
    pub radii: Option<String>,
    /// Per-particle weights (masses for the SPH kernels): `.npy` or a
    /// column name.
    pub weights: Option<String>,
    /// gaussian3 (default), gaussian, or an SPH kernel: cubic-spline,
    /// quartic-spline, quintic-spline, wendland-c2, wendland-c4, wendland-c6.
    pub kernel: Option<KernelName>,
    pub kappa: Option<f32>,
    pub sigma: Option<f32>,
    /// Particles per BVH leaf, 1..=16 (default 8).
    pub cluster: Option<usize>,
    /// post (default) or pre.
    pub classification: Option<ClassificationName>,
    /// `[[attribute, fraction], ...]` over the normalised attribute.
    pub radius_map: Option<Vec<[f32; 2]>>,
    /// `[[attribute, weight], ...]` over the normalised attribute.
    pub weight_map: Option<Vec<[f32; 2]>>,
    pub attribute_range: Option<[f32; 2]>,
    /// Multiplies every particle's radius (global, per-particle or SPH h);
    /// default 1.
    pub radius_scale: Option<f32>,
    /// Multiplies every particle's weight (mass); default 1.
    pub weight_scale: Option<f32>,
    /// A periodic box: its side L (the box `[0, L)³`) or
    /// `[x0, y0, z0, x1, y1, z1]`. Default: the box the file states as
    /// periodic (SWIFT/Gadget `BoxSize`, LAMMPS `pp` bounds, extended-XYZ
    /// `Lattice` with `pbc`). The field then sums every periodic image.
    #[serde(rename = "box")]
    pub periodic_box: Option<BoxDesc>,
    /// `false`: ignore the periodic box the file states.
    pub periodic: Option<bool>,
    /// Wrap particles into the box even when they span more than one box
    /// (default: positions outside are wrapped, with a note, but data wider
    /// than the box is refused as the wrong box).
    pub wrap: Option<bool>,
    /// Smoothing lengths from neighbours: each particle's radius makes its
    /// support reach its N-th nearest neighbour (itself counted; periodic
    /// distances in a box). Default: on (N = 32) for particle types of
    /// cosmological snapshots that carry no smoothing length.
    pub neighbours: Option<usize>,
    /// How projections integrate each pixel: centre (default; the column
    /// through the pixel's centre) or area (the column averaged over the
    /// pixel's square, so every kernel's mass is conserved however small it
    /// is against a pixel; orthographic views of whole lines of sight, one
    /// process).
    pub pixels: Option<PixelsName>,
}

/// A periodic box: a side L (`[0, L)³`) or `[x0, y0, z0, x1, y1, z1]`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum BoxDesc {
    Side(f64),
    Corners([f64; 6]),
}

impl BoxDesc {
    /// The lower and upper corners.
    pub fn corners(&self) -> ([f64; 3], [f64; 3]) {
        match *self {
            BoxDesc::Side(l) => ([0.0; 3], [l; 3]),
            BoxDesc::Corners(b) => ([b[0], b[1], b[2]], [b[3], b[4], b[5]]),
        }
    }
}

/// One material of a multi-material particle scene: the particles of one
/// species, their radius, and how their density is classified.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// The species: a `type` number (LAMMPS, XYZ) or an XYZ element symbol.
    pub species: Species,
    /// A label for messages (default: the species).
    pub name: Option<String>,
    /// Radius parameter of this material's kernel (default: the particles'
    /// `radius`, else estimated from this material's particles).
    pub radius: Option<f32>,
    /// Colormap preset applied to this material's density (default viridis).
    pub colormap: Option<String>,
    /// One fixed sRGB colour instead of the colormap (categorical colour).
    pub color: Option<[f32; 3]>,
    /// Opacity preset (default linear).
    pub opacity: Option<String>,
    /// `[[x, opacity], ...]`; overrides `opacity`.
    pub opacity_points: Option<Vec<[f32; 2]>>,
    /// Density range mapped to [0, 1] (default: this material's own range).
    pub value_range: Option<[f32; 2]>,
}

/// An AMR data source: any AMR output by path (format detected),
/// ExaBricks cells + scalars, or AMRClaw output.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AmrDesc {
    /// Any AMR output, format detected: an AMReX/BoxLib plotfile
    /// directory, FLASH HDF5, an Enzo parameter file, Athena++ `.athdf`,
    /// AMRClaw `fort.qNNNN` or ExaBricks `.cells` (with its `.scalars`).
    pub file: Option<String>,
    /// ExaBricks `.cells` (int32 x, y, z, level per cell).
    pub cells: Option<String>,
    /// ExaBricks `.scalars` files, one per field (float32 per cell).
    pub scalars: Option<Vec<String>>,
    /// AMRClaw `fort.qNNNN` (with `fort.tNNNN` beside it); fields q0, q1, …
    pub amrclaw: Option<String>,
    /// World position of cell coordinate 0 (default: from a `.meta.json`
    /// beside the cells, else 0).
    pub origin: Option<[f64; 3]>,
    /// World width of a finest cell (default: from `.meta.json`, else 1).
    pub cell_size: Option<f32>,
    /// Field driving opacity (default: the first).
    pub field: Option<String>,
    /// Field driving colour (multi-field rendering; default: `field`).
    pub color_field: Option<String>,
    /// basis (default) or nearest.
    pub reconstruction: Option<ReconstructionName>,
}

/// N-body particles on a Lagrangian grid, rendered as a phase-space
/// tessellation (6 tets per Lagrangian cell).
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TetsDesc {
    /// `.npy` N³×3 positions in Lagrangian order `(i·N + j)·N + k`, k
    /// fastest, or a JaxPM `.h5` run (feature `hdf5`).
    pub file: Option<String>,
    /// N (particles per axis of the Lagrangian grid); a JaxPM file's by
    /// default.
    pub lagrangian: Option<usize>,
    /// Periodic box size L (positions in `[0, L)³`); a JaxPM file's by
    /// default.
    pub box_size: Option<f32>,
    /// JaxPM snapshot K (the group `snap_<K>`; default: the last).
    pub snapshot: Option<usize>,
    /// Mass per particle, world units (default: the mean density is 1, so
    /// densities read as the overdensity 1 + δ).
    pub particle_mass: Option<f64>,
    /// exact (default) or kbuffer.
    pub mode: Option<TetModeName>,
    /// k-buffer depth (kbuffer mode; default 16).
    pub k: Option<usize>,
    /// Log-spaced depth layers behind the k-buffer (default 64).
    pub layers: Option<usize>,
    /// Level of detail: blocks (8³ Lagrangian cells) whose screen box is
    /// smaller than this many pixels are drawn from a 2^r-subsampled grid.
    /// Off by default.
    pub lod_pixels: Option<f32>,
    /// Coarser levels of detail, each halving N (default: 3 when
    /// `lod_pixels` is set, else none), built when a render first uses
    /// them. Interactive viewers use them for their coarse images; each
    /// level costs 1/8 of the one before.
    pub lod_levels: Option<usize>,
    /// How projections integrate each pixel: centre (default; the column
    /// through the pixel's centre) or area (the column averaged over the
    /// pixel's square, exactly, so the projected mass does not depend on
    /// the resolution; orthographic views without a depth slab; 4–6× the
    /// time).
    pub pixels: Option<PixelsName>,
}

#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// World position of the eye (float64: positions far from the origin
    /// keep their digits).
    pub eye: Option<[f64; 3]>,
    /// World position the camera looks at.
    pub look_at: Option<[f64; 3]>,
    pub up: Option<[f32; 3]>,
    /// Vertical field of view in degrees (perspective).
    pub fov: Option<f32>,
    /// perspective (default) or orthographic.
    pub projection: Option<ProjectionName>,
    /// World-space height of the view (orthographic).
    pub ortho_height: Option<f32>,
    /// Degrees to orbit the eye about the up vector through the look-at
    /// point (positive: towards the camera's right).
    pub orbit: Option<f32>,
    /// Degrees to raise the eye towards the up vector (negative: lower it);
    /// the resulting angle above the horizontal stays within ±89.9°.
    pub elevation: Option<f32>,
    /// Zoom factor > 0: the eye's distance to the look-at point is divided by
    /// it (orthographic: the view height is).
    pub zoom: Option<f32>,
    /// A camera path: keyframes in increasing `frame` order, interpolated
    /// smoothly between them (see `voxless::camera_path`). A render of
    /// `--frames A..B` follows the path; `orbit`, `elevation` and `zoom`
    /// still apply on top of it.
    pub keyframes: Option<Vec<KeyframeDesc>>,
    /// Which data frame a path frame shows: hold (default: the last data
    /// frame numbered at or before it), nearest (the data frame numbered
    /// nearest to it) or stretch (the data frames spread evenly over the
    /// path's frames, nearest).
    pub follow: Option<FollowName>,
    /// Path frames per second: what a keyframe's `time` is counted in
    /// (default [`DEFAULT_PATH_FPS`]; a movie's frame rate when unset).
    pub fps: Option<f64>,
}

/// Path frames per second when a scene gives none.
pub const DEFAULT_PATH_FPS: f64 = 24.0;

/// One keyframe of a camera path: where the camera is at path frame
/// `frame` (or at `time` seconds, `time × fps` frames). Settings left out
/// are those of the camera (or the defaults).
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct KeyframeDesc {
    /// The path frame this keyframe is at (the number `--frames` counts).
    pub frame: Option<f64>,
    /// Or its time in seconds from the path's start.
    pub time: Option<f64>,
    pub eye: Option<[f64; 3]>,
    pub look_at: Option<[f64; 3]>,
    pub up: Option<[f32; 3]>,
    /// Vertical field of view in degrees (perspective).
    pub fov: Option<f32>,
    /// World-space height of the view: an orthographic camera.
    pub orthographic: Option<f32>,
}

impl KeyframeDesc {
    /// The path frame this keyframe is at: `frame`, else `time × fps`.
    pub fn path_frame(&self, fps: f64) -> Option<f64> {
        self.frame.or(self.time.map(|t| t * fps))
    }
}

#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImageDesc {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
}

#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TransferDesc {
    /// A preset name (see `voxless colormaps`).
    pub colormap: Option<String>,
    /// `[[x, r, g, b], ...]` sRGB control points; overrides `colormap`.
    pub colormap_points: Option<Vec<[f32; 4]>>,
    /// A colormap file (relative to the scene file): ParaView preset JSON or
    /// a JSON list of `[r, g, b]` / `[x, r, g, b]` sRGB colours. `colormap`
    /// then names the preset to take from it (default: the first). Its
    /// opacity points are used unless `opacity` or `opacity_points` is given.
    pub colormap_file: Option<String>,
    /// An opacity preset: linear (default), constant, ramp-high, ramp-low.
    pub opacity: Option<String>,
    /// `[[x, opacity], ...]`; overrides `opacity`.
    pub opacity_points: Option<Vec<[f32; 2]>>,
    /// Value range mapped to [0, 1]; from the data by default.
    pub value_range: Option<[f32; 2]>,
}

#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// World-space step; default: the data's nominal step / sampling_rate.
    pub step: Option<f32>,
    pub sampling_rate: Option<f32>,
    pub early_termination: Option<f32>,
    /// Extinction per unit length at opacity 1; default 8 / bounds diagonal.
    pub opacity_scale: Option<f32>,
    /// Linear RGB background.
    pub background: Option<[f32; 3]>,
    pub seed: Option<u64>,
    /// Implicit iso-surfaces at these values of the opacity field.
    pub iso: Option<Vec<f32>>,
    /// Opacity of the iso-surfaces (default 1).
    pub iso_opacity: Option<f32>,
    /// Render the volume itself (default true; false = iso-surfaces only).
    pub volume: Option<bool>,
    /// Clip box `[x0, y0, z0, x1, y1, z1]`: only what is inside is rendered.
    pub clip: Option<[f64; 6]>,
    /// Map log10(value) through the transfer function (default: on for
    /// tessellations, whose densities span decades; off otherwise). The value
    /// range is then given in log10 units.
    pub log_scale: Option<bool>,
    /// Particles: march rays in packets that share one BVH traversal per
    /// pass (default true); false samples point by point. Same image.
    pub packets: Option<bool>,
    /// Ambient occlusion: this many rays per mesh or iso-surface hit (1 to 4096).
    pub ao: Option<u32>,
    /// How far ambient-occlusion rays look (default a tenth of the data's
    /// diagonal).
    pub ao_distance: Option<f64>,
}

#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// Direction towards the light, world space; default: over the camera's
    /// left shoulder.
    pub direction: Option<[f32; 3]>,
    /// Fraction of colour kept in full shade (default 0.3).
    pub ambient: Option<f32>,
    /// Single scattering with volumetric shadows (one shadow ray per
    /// scattering point) instead of gradient shading.
    pub shadows: Option<bool>,
    /// A point light at this position instead of a directional light
    /// (shadows only).
    pub position: Option<[f64; 3]>,
    /// Light intensity (default 1; shadows only).
    pub intensity: Option<f32>,
    /// Free-flight sampling: marching (default; stochastic ray marching) or
    /// delta (delta tracking with interval majorants).
    pub free_flight: Option<FreeFlightName>,
    /// Random numbers of the free flights: blue (default; spatiotemporal
    /// blue noise) or white.
    pub noise: Option<NoiseName>,
}
