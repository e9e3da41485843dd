//! Data-parallel rendering without volume knowledge: how space is split
//! among ranks, in which order their images stack up for a camera, and how
//! the images are composited — over a [`Comm`] that an MPI binding or K
//! threads in one process ([`LocalComm`]) implement alike.
//!
//! **Model (sort-last).** A k-d tree ([`Decomposition`]) cuts the data's
//! bounds into K boxes of about equal work, one per rank. Each rank holds
//! what reconstructs its box exactly and renders only the samples whose
//! positions lie in it (half-open boxes, so every sample belongs to exactly
//! one box). The boxes of a k-d tree are convex and can be ordered front to
//! back for any camera by walking the tree near side first
//! ([`Decomposition::front_to_back`]); compositing the ranks' images
//! premultiplied-"over" in that order gives the one-process image.
//!
//! **Compositing** ([`composite`]) is direct-send by image tiles: tile `t`
//! belongs to rank `t mod K`; each rank sends only its non-empty tiles
//! (partitioned particle data leaves most tiles of a rank empty) to their
//! owners, which composite them and finally send their tiles to rank 0. No
//! step reduces a full image onto one rank. Renders composite "over", with
//! early termination made exact: where the opacity in front of a box plus
//! the box's own would pass the threshold, the box's rank renders those
//! pixels again starting from the opacity in front ([`composite::over`]).
//! Projections and sampled fields add up instead ([`composite::sum`]).
//!
//! **Invariants.** Every rank runs the same sequence of collectives; a rank
//! that fails tells the others through the next collective
//! ([`CommExt::agree`]) or, when it leaves early, makes their collectives
//! fail ([`CommError::Aborted`]) — a failure never hangs the other ranks.
//! Results never depend on timing: tiles composite in visibility order and
//! sums add in rank order.

pub mod comm;
pub mod composite;
pub mod kdtree;
mod local;
pub mod memory;
#[cfg(feature = "mpi")]
mod mpi_comm;
pub mod wire;

pub use comm::{Comm, CommError, CommExt, SingleComm};
pub use composite::TileGrid;
pub use kdtree::Decomposition;
pub use local::{LocalComm, run_local};
#[cfg(feature = "mpi")]
pub use mpi_comm::MpiComm;
pub use wire::{Reader, WireError, Writer};
