//! `mpirun -n K voxless render|project|sample …` (the `mpi` feature): the
//! same commands and flags as one process, with the data held by the ranks
//! of the MPI job ([`voxless::Placement::Ranks`]) instead of this process.
//! Rank 0 prints and writes; every rank renders its box. Commands without
//! data to share run on rank 0 alone.

use voxless::Placement;
use voxless::parallel::MpiComm;

use crate::Cli;

/// Runs `cli` on every rank of the MPI job this process belongs to, then
/// exits: 0 when every rank succeeded, 1 otherwise (rank 0 says why).
pub fn main(cli: Cli) -> ! {
    let Some(comm) = MpiComm::init() else {
        eprintln!("error: MPI could not be initialised");
        std::process::exit(1);
    };
    let placement = Placement::Ranks(&comm);
    let code = match crate::run(cli, placement) {
        Ok(()) => 0,
        Err(e) => {
            if placement.is_root() {
                eprintln!("error: {}", crate::describe(&e));
            }
            1
        }
    };
    drop(comm);
    std::process::exit(code)
}
