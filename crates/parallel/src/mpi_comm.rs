//! [`Comm`] over MPI (the `mpi` feature: rsmpi over the system's MPI
//! library). Messages of any size: each exchange first tells every rank
//! how many bytes to expect, then moves them in rounds of bounded size (so
//! the transient buffers stay small and MPI's 32-bit counts and offsets
//! suffice); a rank's message to itself is moved, not copied.

use mpi::Count;
use mpi::collective::SystemOperation;
use mpi::datatype::{Partition, PartitionMut};
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::{Comm, CommError};

/// At most about this many bytes leave a rank per round (split evenly over
/// the destinations), so the round's send and receive buffers stay small
/// next to the messages themselves, and far below MPI's 2³¹ limit.
pub const ROUND_BYTES: usize = 64 << 20;

/// Per destination and round at least this many bytes, so many ranks do
/// not make rounds of tiny messages.
const MIN_CHUNK: usize = 64 << 10;

/// The world communicator of an MPI run.
pub struct MpiComm {
    world: SimpleCommunicator,
    // Finalises MPI when dropped, after the communicator.
    _universe: Universe,
}

impl MpiComm {
    /// Initialises MPI; `None` when it was already initialised or fails.
    pub fn init() -> Option<MpiComm> {
        let universe = mpi::initialize()?;
        let world = universe.world();
        Some(MpiComm {
            world,
            _universe: universe,
        })
    }

    /// Whether this process was started by an MPI launcher (`mpirun`,
    /// `srun`, …), judged by the environment the common launchers set.
    pub fn launched() -> bool {
        [
            "OMPI_COMM_WORLD_SIZE",
            "PMI_SIZE",
            "PMIX_RANK",
            "MPI_LOCALNRANKS",
            "SLURM_PROCID",
        ]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
    }

    /// Ends every rank of the run with exit code `code` (after an error
    /// that could leave other ranks waiting).
    pub fn abort(&self, code: i32) -> ! {
        self.world.abort(code)
    }

    /// Every rank's `value`, maximum.
    fn max_u64(&self, value: u64) -> u64 {
        let mut out = 0u64;
        self.world
            .all_reduce_into(&value, &mut out, SystemOperation::max());
        out
    }
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    fn size(&self) -> usize {
        self.world.size() as usize
    }

    fn exchange(&self, mut send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError> {
        let k = self.size();
        let me = self.rank();
        if send.len() != k {
            return Err(CommError::Transport(format!(
                "{} messages for {k} ranks",
                send.len()
            )));
        }
        // This rank's message to itself is moved, not sent.
        let own = std::mem::take(&mut send[me]);
        // How much comes from every rank.
        let lens: Vec<u64> = send.iter().map(|m| m.len() as u64).collect();
        let mut incoming = vec![0u64; k];
        self.world.all_to_all_into(&lens[..], &mut incoming[..]);
        let chunk = (ROUND_BYTES / k).max(MIN_CHUNK);
        let most = lens.iter().chain(&incoming).copied().max().unwrap_or(0) as usize;
        let rounds = self.max_u64(most.div_ceil(chunk) as u64) as usize;
        let mut got: Vec<Vec<u8>> = incoming
            .iter()
            .map(|&n| Vec::with_capacity(n as usize))
            .collect();
        for round in 0..rounds {
            let part = |len: usize| {
                let start = (round * chunk).min(len);
                start..(start + chunk).min(len)
            };
            let mut flat = Vec::new();
            let mut counts: Vec<Count> = Vec::with_capacity(k);
            for m in &mut send {
                let r = part(m.len());
                counts.push(r.len() as Count);
                flat.extend_from_slice(&m[r.clone()]);
                if r.end == m.len() {
                    // Sent in full: free it now.
                    *m = Vec::new();
                }
            }
            let rcounts: Vec<Count> = incoming
                .iter()
                .map(|&n| part(n as usize).len() as Count)
                .collect();
            let offsets = |c: &[Count]| -> Vec<Count> {
                c.iter()
                    .scan(0, |acc, &x| {
                        let at = *acc;
                        *acc += x;
                        Some(at)
                    })
                    .collect()
            };
            let (sdispl, rdispl) = (offsets(&counts), offsets(&rcounts));
            let total: usize = rcounts.iter().map(|&c| c as usize).sum();
            // Never two empty buffers: they would share Rust's dangling
            // pointer, and MPI refuses a send buffer equal to the receive
            // buffer.
            flat.push(0);
            let mut buf = vec![0u8; total + 1];
            {
                let s = Partition::new(&flat[..], counts, &sdispl[..]);
                let mut r = PartitionMut::new(&mut buf[..], &rcounts[..], &rdispl[..]);
                self.world.all_to_all_varcount_into(&s, &mut r);
            }
            for (src, msg) in got.iter_mut().enumerate() {
                let at = rdispl[src] as usize;
                msg.extend_from_slice(&buf[at..at + rcounts[src] as usize]);
            }
        }
        got[me] = own;
        Ok(got)
    }
}
