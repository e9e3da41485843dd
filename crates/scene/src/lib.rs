//! The description of a scene: what a TOML scene file (or the command line,
//! or a Python dictionary) says, before any file is read — data sources,
//! camera, image, transfer function, render and light settings. Every field
//! is optional; the `voxless` library fills defaults from the data.
//!
//! Closed choices (kernels, reconstructions, modes, …) are typed
//! enumerations ([`enums`]): serde names them in TOML and, with the `clap`
//! feature, clap lists them in `--help`. Unknown keys are errors, so a typo
//! in a scene file surfaces instead of being ignored.

mod desc;
pub mod enums;

pub use desc::*;
pub use enums::*;
