//! The command line's scene: a scene file and the flags that override it.
//! The flags are the library's ([`voxless::flags`], shared with the Python
//! package), in three groups so that a command takes only those it uses.

use std::path::{Path, PathBuf};

use clap::Args;
use voxless::flags::{DataFlags, KindFlags, ViewFlags};
use voxless::{SceneDesc, SceneFlags};

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
