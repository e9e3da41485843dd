//! Data-parallel rendering: one scene decomposed over the ranks of a
//! communicator (MPI with the `mpi` feature, or K threads of one process),
//! rendering, projecting and sampling exactly what one process would. This
//! module holds what only ranks do — decompose, send data to the boxes it
//! reaches (ghosts included), composite — and nothing a single process
//! also does.
//!
//! **Model.** Each rank reads a share of the data through the one-process
//! loaders ([`crate::load::Share`]: rows of a `.npy`, cells of an ExaBricks
//! file, Lagrangian slabs of a tessellation), and the ranks agree on the
//! whole data's statistics — bounds, value ranges, the default radius, the
//! sampling step — from mergeable pieces (minima, maxima, probe samples
//! chosen by row number; see `crate::load::whole_set`). A k-d tree over a sample of the data
//! ([`Decomposition`]) gives each rank one box of about equal work; every
//! rank sends each item to the boxes it reaches into — particles whose
//! kernel support overlaps a box, AMR cells whose basis support does, tets
//! whose bounds do — so each rank ends up holding exactly what reconstructs
//! its box, and never the whole data set. The view (camera, transfer
//! function, settings) is resolved from the whole data's summary, so it is
//! the one-process view.
//!
//! - **Render**: each rank renders the samples whose positions lie in its
//!   box ([`voxless_render::Domain`]: the sample lattice is fixed per ray,
//!   so the boxes split the one-process samples between them), pass by
//!   pass; the passes composite "over" in the camera's visibility order by
//!   direct send, with early termination reproduced exactly
//!   ([`voxless_parallel::composite`]).
//! - **Project**: each rank integrates the part of every pixel's line inside
//!   its box (tessellations: the tets whose centroids lie in it, whole), and
//!   the images add up.
//! - **Sample**: each point goes to the rank whose box holds it, which
//!   evaluates it with canonical sums — the same bits as one process.
//!
//! What a box cannot reproduce alone is refused by name under more than one
//! rank (`crate::checks`): iso-surfaces (a crossing between two samples in
//! different boxes), single scattering (shadow rays cross boxes), the
//! tessellation's level of detail and k-buffer (both approximate per box,
//! not per ray), a tessellation's pixel-area projection.

mod amr;
mod particles;
mod probe;
mod render;
mod share;
mod tets;

use std::path::Path;

use voxless_scene::SceneDesc;

#[cfg(feature = "mpi")]
pub use voxless_parallel::MpiComm;
pub use voxless_parallel::memory::{available_bytes, peak_rss_bytes, ranks_on_this_node};
pub use voxless_parallel::{
    Comm, CommError, CommExt, Decomposition, LocalComm, SingleComm, run_local,
};

pub(crate) use particles::Earlier;
pub(crate) use probe::probe;
pub(crate) use render::{COMPOSITE_TILE, gather_images, project, render, sample, work};

pub use crate::ParallelError;
use crate::load::whole_set::agree;
use crate::load::{self, Purpose, Source};
use crate::{AnyVolume, Fields, VolumeSummary, WorldFrame};

/// Where one rank's time went in a render, in seconds: rendering its box's
/// passes, and compositing (waiting for the others included).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    pub render: f64,
    pub composite: f64,
}

/// How many items a rank read and holds, for memory reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PartCounts {
    /// Items (particles, cells, Lagrangian particles) read from files.
    pub read: u64,
    /// Items (particles, cells, tets) held for the rank's box, ghosts
    /// included.
    pub held: u64,
}

/// One rank's part of the data, before the view is resolved.
pub struct Part {
    /// What this rank holds (`None`: no data reaches its box).
    pub volume: Option<AnyVolume>,
    pub frame: WorldFrame,
    /// The whole data's kind, bounds and ranges.
    pub summary: VolumeSummary,
    /// The boxes of all ranks.
    pub decomposition: Decomposition,
    pub fields: Fields,
    pub counts: PartCounts,
    pub notes: Vec<String>,
    /// A particle set's radius parameters of this rank's share of the
    /// rows (world units): what `--save-radii` gathers.
    pub radii: Option<Box<crate::load::whole_set::RowRadii>>,
}

/// This rank's part of frame `frame` of the data `desc` names (`earlier`:
/// what a later frame of a series keeps of the first): its share read
/// through the loaders, the whole data's statistics agreed, the data sent
/// to the boxes it reaches.
pub(crate) fn open_part(
    comm: &dyn Comm,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    purpose: Purpose,
    earlier: Option<Earlier>,
) -> Result<Part, ParallelError> {
    let source = agree(comm, load::source_at(desc, base, frame))?;
    let tets = match &source {
        Source::Tets(t) => Some(&**t),
        _ => None,
    };
    let projecting = purpose == Purpose::Project;
    crate::checks::check_ranks(desc, tets, comm.size(), projecting)?;
    match source {
        Source::Particles(p) => particles::open(comm, &p, base, frame, earlier),
        Source::Amr(a) => amr::open(comm, &a, base),
        Source::Tets(t) => tets::open(comm, &t, base, purpose),
    }
}

/// How the ranks share the frames of a time series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FramePlan {
    /// Each rank renders whole frames, one process each (frame `A + r`,
    /// `A + r + K`, … on rank `r`).
    ByFrame,
    /// The ranks render every frame together, decomposed.
    BySpace,
}

/// Whole frames per rank when there are at least as many frames as ranks
/// and one frame fits a rank comfortably (`frame_bytes`, the data of one
/// frame, at most a quarter of `memory_per_rank`): every rank then works
/// all the time, nothing is exchanged or composited, and each frame costs
/// what one process takes — the fastest way through a movie. Otherwise
/// (fewer frames than ranks, or frames too big for one rank) each frame is
/// decomposed over all ranks in turn.
pub fn frame_plan(
    frames: usize,
    ranks: usize,
    frame_bytes: u64,
    memory_per_rank: u64,
) -> FramePlan {
    if ranks > 1 && frames >= ranks && frame_bytes.saturating_mul(4) <= memory_per_rank {
        FramePlan::ByFrame
    } else {
        FramePlan::BySpace
    }
}
