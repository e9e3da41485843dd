//! The command line's scene: a scene file and the flags that override it
//! (the library's [`SceneFlags`], shared with the Python package).

use std::path::{Path, PathBuf};

use clap::Args;
use voxless::{SceneDesc, SceneFlags};

/// A scene file and every scene setting as flags (they override the file).
#[derive(Args, Debug, Default, Clone)]
pub struct SceneArgs {
    /// Scene file (TOML); optional when --particles is given.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub flags: SceneFlags,
}

impl SceneArgs {
    /// Loads the scene file (if any) and applies the flags on top. Returns the
    /// description and the directory its relative paths are relative to.
    pub fn scene(&self) -> anyhow::Result<(SceneDesc, PathBuf)> {
        let (mut d, base) = match &self.scene {
            Some(path) => {
                let d = voxless::read_scene(path)?;
                let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
                (d, base)
            }
            None => (SceneDesc::default(), PathBuf::from(".")),
        };
        // Paths on the command line are relative to the working directory.
        let cwd = std::env::current_dir().unwrap_or_default();
        self.flags.apply(&mut d, &cwd)?;
        Ok((d, base))
    }
}
