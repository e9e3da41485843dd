//! The communicator the parallel pipeline runs on: the few collectives it
//! needs, implemented by MPI (the `voxless` crate's `mpi` feature) and by
//! threads in one process ([`crate::LocalComm`], for tests and for
//! simulating K ranks without MPI).

use crate::wire::{Reader, WireError, Writer};

/// Why a collective failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommError {
    /// Another rank left the computation (it failed, or stopped early).
    #[error("another rank stopped before this collective finished")]
    Aborted,
    /// Another rank reported an error through [`CommExt::agree`].
    #[error("rank {rank}: {message}")]
    Remote { rank: usize, message: String },
    /// The transport failed.
    #[error("communication failed: {0}")]
    Transport(String),
    /// A message could not be decoded.
    #[error(transparent)]
    Wire(#[from] WireError),
}

/// A group of `size()` ranks that run the same sequence of collectives.
pub trait Comm {
    /// This rank, `0..size()`.
    fn rank(&self) -> usize;
    /// How many ranks there are.
    fn size(&self) -> usize;
    /// Personalised all-to-all: `send[r]` goes to rank `r` (`send.len()` is
    /// `size()`); returns what every rank sent here, by source rank.
    fn exchange(&self, send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError>;
    /// Every rank's `mine`, by rank.
    fn all_gather(&self, mine: &[u8]) -> Result<Vec<Vec<u8>>, CommError> {
        self.exchange(vec![mine.to_vec(); self.size()])
    }
}

/// Collectives built on [`Comm`]'s two.
pub trait CommExt: Comm {
    /// Whether this is rank 0 (which writes outputs and reports progress).
    fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// `f64`s of every rank, by rank.
    fn all_gather_f64(&self, mine: &[f64]) -> Result<Vec<Vec<f64>>, CommError> {
        let mut w = Writer::new();
        w.f64s(mine);
        self.all_gather(&w.into_bytes())?
            .iter()
            .map(|b| Ok(Reader::new(b).f64s()?))
            .collect()
    }

    /// Element-wise minimum over the ranks.
    fn all_min(&self, mine: &[f64]) -> Result<Vec<f64>, CommError> {
        reduce(self.all_gather_f64(mine)?, mine.len(), f64::min)
    }

    /// Element-wise maximum over the ranks.
    fn all_max(&self, mine: &[f64]) -> Result<Vec<f64>, CommError> {
        reduce(self.all_gather_f64(mine)?, mine.len(), f64::max)
    }

    /// Element-wise sum over the ranks, added in rank order (the same
    /// result on every rank and in every run).
    fn all_sum(&self, mine: &[f64]) -> Result<Vec<f64>, CommError> {
        reduce(self.all_gather_f64(mine)?, mine.len(), |a, b| a + b)
    }

    /// `bytes` of rank `root` on every rank (others pass anything).
    fn broadcast(&self, root: usize, bytes: &[u8]) -> Result<Vec<u8>, CommError> {
        let mine = if self.rank() == root { bytes } else { &[] };
        let send = vec![mine.to_vec(); self.size()];
        let mut got = self.exchange(send)?;
        Ok(std::mem::take(&mut got[root]))
    }

    /// Every rank's outcome of a step that can fail: `Ok` on every rank when
    /// all succeeded; otherwise every rank returns an error — its own, or
    /// the first failing rank's message ([`CommError::Remote`]). Ranks call
    /// this after each fallible local step, so a failure on one rank stops
    /// all of them at the same point instead of leaving them waiting.
    fn agree<T, E: std::fmt::Display>(
        &self,
        local: Result<T, E>,
    ) -> Result<Result<T, E>, CommError> {
        let mut w = Writer::new();
        match &local {
            Ok(_) => w.u8(0),
            Err(e) => {
                w.u8(1);
                w.str(&e.to_string());
            }
        }
        let all = self.all_gather(&w.into_bytes())?;
        if local.is_err() {
            return Ok(local);
        }
        for (rank, b) in all.iter().enumerate() {
            let mut r = Reader::new(b);
            if r.u8()? == 1 {
                return Err(CommError::Remote {
                    rank,
                    message: r.str()?,
                });
            }
        }
        Ok(local)
    }
}

impl<C: Comm + ?Sized> CommExt for C {}

fn reduce(
    all: Vec<Vec<f64>>,
    n: usize,
    f: impl Fn(f64, f64) -> f64,
) -> Result<Vec<f64>, CommError> {
    let mut out: Option<Vec<f64>> = None;
    for v in all {
        if v.len() != n {
            return Err(CommError::Transport(format!(
                "ranks reduce {} and {n} values",
                v.len()
            )));
        }
        out = Some(match out {
            None => v,
            Some(acc) => acc.iter().zip(&v).map(|(&a, &b)| f(a, b)).collect(),
        });
    }
    Ok(out.unwrap_or_default())
}

/// One rank alone: the one-process case of the parallel pipeline.
#[derive(Clone, Copy, Debug, Default)]
pub struct SingleComm;

impl Comm for SingleComm {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn exchange(&self, send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError> {
        Ok(send)
    }
}
