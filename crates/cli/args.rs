//! The command line's scene: a scene file and the flags that override it.
//! The flags are the library's ([`voxless::flags`], shared with the Python
//! package), in three groups so that a command takes only those it uses.

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use voxless::flags::{DataFlags, KindFlags, ViewFlags};
use voxless::{ProjectionDesc, SceneDesc, SceneFlags};

/// What data to read and how to reconstruct its field: every command that
/// loads data takes these (they override the scene file).
#[derive(Args, Debug, Default, Clone)]
pub struct DataArgs {
    /// Scene file (TOML); optional when --particles is given.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub flags: DataFlags,
    /// Write the radius parameter each particle was given (float32 .npy, in
    /// the file's row order, world units, in the kernel's convention: h for
    /// the SPH kernels), e.g. the smoothing lengths --neighbours found.
    #[arg(long, value_name = "OUT.npy", help_heading = "Particles")]
    pub save_radii: Option<PathBuf>,
}

/// How `render` shows a particular data kind (particle attributes,
/// tessellation modes, AMR colour fields).
pub type KindArgs = KindFlags;

/// How an image looks: size, transfer function, camera, rendering and
/// lighting (`render` and `demo`).
pub type ViewArgs = ViewFlags;

/// Every flag of a command (those a command lacks stay at their defaults),
/// applied on top of the scene file.
#[derive(Debug, Default, Clone)]
pub struct SceneArgs {
    pub data: DataArgs,
    pub kind: KindArgs,
    pub view: ViewArgs,
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
        let flags = SceneFlags {
            data: self.data.flags.clone(),
            kind: self.kind.clone(),
            view: self.view.clone(),
        };
        // Paths on the command line are relative to the working directory.
        let cwd = std::env::current_dir().unwrap_or_default();
        flags.apply(&mut d, &cwd)?;
        Ok((d, base))
    }
}

/// Where the image of `project` and `slice` lies: looking along an axis or
/// a normal (the plane's normal, for a slice), centred and sized.
#[derive(Args, Debug, Default, Clone)]
pub struct PlaneArgs {
    /// The axis looked along (a projection) or across (a slice's plane);
    /// default z.
    #[arg(long, value_enum, conflicts_with = "normal")]
    pub axis: Option<Axis>,
    /// Override the bounds the default footprint covers: x0 y0 z0 x1 y1 z1
    /// (default: the data's).
    #[arg(long, num_args = 6, value_names = ["X0", "Y0", "Z0", "X1", "Y1", "Z1"], allow_negative_numbers = true)]
    pub bounds: Option<Vec<f64>>,
    /// Off-axis: this direction instead (image right = north × normal).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub normal: Option<Vec<f64>>,
    /// The image's up direction with --normal (default: yt's rule, so that
    /// --normal 0 0 1 equals --axis z).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true, requires = "normal")]
    pub north: Option<Vec<f64>>,
    /// World position of the image centre (a slice's plane passes through
    /// it; default: the bounds' centre).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub center: Option<Vec<f64>>,
    /// World width (and height; default: the width) the image covers
    /// (default: the bounds' extent across the view).
    #[arg(long, num_args = 1..=2, value_names = ["W", "H"])]
    pub width: Option<Vec<f64>>,
    /// Image size in pixels (default 800 600).
    #[arg(long, num_args = 2, value_names = ["W", "H"])]
    pub size: Option<Vec<u32>>,
}

impl PlaneArgs {
    /// The projection these flags describe (with a slab `depth`, for
    /// `project`).
    pub fn desc(&self, depth: Option<f64>) -> ProjectionDesc {
        let v3 = |v: &Option<Vec<f64>>| v.as_ref().map(|v| [v[0], v[1], v[2]]);
        ProjectionDesc {
            axis: self.axis.map(|a| a as usize),
            normal: v3(&self.normal),
            north: v3(&self.north),
            center: v3(&self.center),
            width: self
                .width
                .as_ref()
                .map(|w| [w[0], *w.get(1).unwrap_or(&w[0])]),
            bounds: self
                .bounds
                .as_ref()
                .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]]),
            depth,
        }
    }
}

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Axis {
    #[value(alias = "X")]
    X,
    #[value(alias = "Y")]
    Y,
    #[value(alias = "Z")]
    Z,
}

/// Where a render or projection runs.
#[derive(Args, Debug, Default, Clone)]
pub struct DeviceArgs {
    /// cpu (default); gpu: the GPU backend (a build with `--features gpu`
    /// and a Vulkan, Metal or DirectX 12 driver — Mesa's software Vulkan
    /// will do), an error when it is missing or cannot do the work; auto:
    /// the GPU when there is one and it does the work, else the CPU, with a
    /// note saying why.
    #[arg(long, default_value = "cpu", value_name = "cpu|gpu|auto")]
    pub device: voxless::device::DeviceChoice,
}

impl DeviceArgs {
    /// Opens the device, printing the note when `auto` falls back (on
    /// `root`).
    pub fn open(&self, root: bool) -> anyhow::Result<voxless::device::Device> {
        let (device, note) = voxless::device::Device::open(self.device)?;
        if let (Some(n), true) = (note, root) {
            eprintln!("note: {n}");
        }
        Ok(device)
    }
}
