//! voxless: render particles, block-structured AMR cells and N-body
//! phase-space tessellations in their native form — without resampling
//! them onto a voxel grid.
//!
//! This crate is the library every front-end uses (the `voxless` command,
//! the browser viewer, the Python package, MPI rendering). The model:
//!
//! ```text
//! files (load) ─┐
//!               ├─► AnyVolume ──► resolve(desc) ──► camera, transfer function, settings
//! memory ───────┘        │                                   │
//!                        └──► render / project / sample ◄────┘   (passes, progress, cancel)
//! ```
//!
//! - **Loading** ([`load()`], [`AnyVolume::from_particles`],
//!   [`AnyVolume::from_amr`], [`AnyVolume::from_tessellation`]) turns files
//!   or arrays into an [`AnyVolume`], filling the data's own defaults.
//! - **Resolving** ([`resolve()`]) turns a volume and a [`SceneDesc`] (a
//!   TOML scene, the CLI's flags, a Python dictionary) into a [`Resolved`]
//!   view: camera, transfer function, render settings — the same defaults
//!   for every front-end. [`Scene`] holds a volume with its view;
//!   [`DistributedScene`] holds one rank's part of a volume decomposed over
//!   a communicator with the same view ([`parallel`]). What a command does
//!   with either is written once over a [`Placement`] (one process, or the
//!   ranks), and every refusal it can meet is the library's, so each
//!   front-end refuses the same things in the same words.
//! - **Rendering** ([`AnyVolume::render`], [`AnyVolume::render_passes`]),
//!   **projecting** ([`AnyVolume::project`]) and **sampling**
//!   ([`AnyVolume::sample_points`]) report progress and stop when their
//!   [`Control`]'s [`CancelToken`] is cancelled. [`ProjectionView`] places
//!   a projection (along an axis or an off-axis normal) in the world.
//! - **Interactive front-ends** move a camera [`Pose`] and write it back
//!   into the description ([`pose`]), render a coarse image first and then
//!   pass by pass ([`render_progressive`]), draw a [`field_histogram`]
//!   under the transfer function, and save the view as a scene file that
//!   `voxless render` reproduces ([`save`]).
//! - **Flags**: every front-end's options by one set of rules
//!   ([`SceneFlags`]: the CLI's flags, the Python package's keywords).
//!
//! Volumes are immutable after they are built and `Sync`: one volume serves
//! several renders at once, each with its own camera and transfer function.
//! The crates underneath (`voxless-core`, `-render`, `-particles`, `-amr`,
//! `-tets`, `-io`, `-transfer`, `-scene`) are re-exported for what this
//! facade does not wrap. See `docs/architecture.md` for how a camera ray and
//! a particle flow through them.
//!
//! ```no_run
//! use voxless::{AnyVolume, Control, ParticleArrays, Scene, SceneDesc, Vec3};
//!
//! let positions: Vec<Vec3> = (0..1000)
//!     .map(|i| Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32))
//!     .collect();
//! let loaded = AnyVolume::from_particles(
//!     ParticleArrays { positions, ..Default::default() },
//!     &Default::default(),
//! )?;
//! let scene = Scene::with_loaded(loaded, &SceneDesc::default(), ".".as_ref())?;
//! let image = scene.render(&Control::new())?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod annotate;
pub mod autorange;
pub mod budget;
mod camera;
pub mod camera_path;
mod checks;
mod columns;
pub mod demo;
pub mod device;
mod error;
mod fields;
pub mod flags;
mod frame;
pub mod histogram;
pub mod huge_pages;
mod label;
pub mod load;
pub mod map_fits;
mod memory;
pub mod movie;
pub mod output;
pub mod parallel;
mod placement;
pub mod pose;
pub mod progressive;
pub mod projection;
mod resolve;
pub mod save;
mod scene;
pub mod series;
pub mod slice;
pub mod stream;
mod surfaces;
mod view;
mod volume;

pub use checks::set_projection_pixels;
pub use error::{Error, ParallelError, SceneError};
pub use fields::Fields;
pub use flags::SceneFlags;
pub use frame::WorldFrame;
pub use load::AmrArrays;
pub use load::{
    Loaded, Purpose, Share, data_flag_for, frame_count, frame_numbers, load, read_points,
    read_scene,
};
pub use memory::ParticleArrays;
pub use placement::{Placed, PlacedData, Placement, Rendered};
pub use projection::{ProjectionDesc, ProjectionView};
pub use resolve::{
    Resolved, check_settings, resolve, resolve_in, resolve_summary, resolve_with,
    transfer_function, transfer_function_at,
};
pub use scene::{DistributedScene, Scene};
pub use volume::{AnyVolume, VolumeKind, VolumeSummary};

// For interactive front-ends (the browser viewer, notebooks): camera poses
// written back into descriptions, progressive renders, histograms, saving.
pub use columns::particle_columns;
pub use histogram::{Histogram, field_histogram};
pub use label::frame_label;
pub use pose::Pose;
pub use progressive::{CoarseBudget, Stage, render_progressive, render_progressive_on};
pub use save::{scene_toml, with_absolute_paths};

/// File formats: which reader a path needs and one frame of any of them.
pub use load::formats;
/// Time series: numbered files, patterns, globs, directories.
pub use load::frames;

pub use voxless_core::{
    Aabb, Camera, CancelToken, Cancelled, Control, Image, Projection, Range1, Vec3,
};
pub use voxless_render::{Film, RenderSettings};
pub use voxless_scene::*;
pub use voxless_transfer::TransferFunction;

pub use voxless_amr as amr;
pub use voxless_core as core;
pub use voxless_io as io;
pub use voxless_particles as particles;
pub use voxless_render as render;
pub use voxless_tets as tets;
pub use voxless_transfer as transfer;

#[cfg(test)]
mod tests;
