//! K ranks as K threads of one process: the same collectives as MPI, for
//! tests and for running the parallel pipeline without MPI.

use std::sync::{Arc, Condvar, Mutex, MutexGuard};

use crate::comm::{Comm, CommError};

/// One rank's end of a group of threads (see [`run_local`]).
pub struct LocalComm {
    rank: usize,
    size: usize,
    shared: Arc<Shared>,
}

struct Shared {
    state: Mutex<State>,
    cv: Condvar,
}

struct State {
    /// Messages in flight, `slots[src][dst]`.
    slots: Vec<Vec<Option<Vec<u8>>>>,
    /// Ranks waiting at the barrier, and how many barriers have completed.
    arrived: usize,
    generation: u64,
    /// A rank has left (dropped its end) while others may still wait.
    left: bool,
}

impl LocalComm {
    /// `size` connected ends, rank 0 first.
    pub fn group(size: usize) -> Vec<LocalComm> {
        let size = size.max(1);
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                slots: vec![vec![None; size]; size],
                arrived: 0,
                generation: 0,
                left: false,
            }),
            cv: Condvar::new(),
        });
        (0..size)
            .map(|rank| LocalComm {
                rank,
                size,
                shared: shared.clone(),
            })
            .collect()
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A rank that panicked while holding the lock leaves the state as
        // consistent as any: each step below is complete under the lock.
        self.shared
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Waits until every rank has arrived; fails if one has left instead.
    fn barrier<'a>(
        &'a self,
        mut st: MutexGuard<'a, State>,
    ) -> Result<MutexGuard<'a, State>, CommError> {
        if st.left {
            return Err(CommError::Aborted);
        }
        let generation = st.generation;
        st.arrived += 1;
        if st.arrived == self.size {
            st.arrived = 0;
            st.generation += 1;
            self.shared.cv.notify_all();
            return Ok(st);
        }
        loop {
            st = self
                .shared
                .cv
                .wait(st)
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            // A completed barrier counts even if a rank left right after.
            if st.generation != generation {
                return Ok(st);
            }
            if st.left {
                return Err(CommError::Aborted);
            }
        }
    }
}

impl Drop for LocalComm {
    fn drop(&mut self) {
        let mut st = self.lock();
        st.left = true;
        self.shared.cv.notify_all();
    }
}

impl Comm for LocalComm {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }
    fn exchange(&self, send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError> {
        if send.len() != self.size {
            return Err(CommError::Transport(format!(
                "{} messages for {} ranks",
                send.len(),
                self.size
            )));
        }
        let mut st = self.lock();
        for (dst, msg) in send.into_iter().enumerate() {
            st.slots[self.rank][dst] = Some(msg);
        }
        // Everything is deposited once all have arrived; take this rank's
        // column, then wait again so no rank refills a slot before its
        // receiver has emptied it.
        let mut st = self.barrier(st)?;
        let got = (0..self.size)
            .map(|src| st.slots[src][self.rank].take().unwrap_or_default())
            .collect();
        drop(self.barrier(st)?);
        Ok(got)
    }
}

/// Runs `f` on `ranks` threads, each with its own end of one group, and
/// returns their results by rank. A rank that returns (or panics) early
/// makes the others' pending collectives fail rather than hang.
pub fn run_local<R: Send>(ranks: usize, f: impl Fn(&LocalComm) -> R + Sync) -> Vec<R> {
    let ends = LocalComm::group(ranks);
    std::thread::scope(|s| {
        let handles: Vec<_> = ends
            .into_iter()
            .map(|end| {
                let f = &f;
                s.spawn(move || f(&end))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CommExt;

    #[test]
    fn exchange_delivers_by_source_and_reductions_agree() {
        let out = run_local(3, |c| {
            let send = (0..3).map(|d| vec![c.rank() as u8, d as u8]).collect();
            let got = c.exchange(send).unwrap();
            let sum = c.all_sum(&[c.rank() as f64 + 1.0]).unwrap();
            (got, sum)
        });
        for (rank, (got, sum)) in out.iter().enumerate() {
            for (src, m) in got.iter().enumerate() {
                assert_eq!(m, &vec![src as u8, rank as u8]);
            }
            assert_eq!(sum, &vec![6.0]);
        }
    }

    #[test]
    fn a_rank_that_fails_stops_the_others_without_a_hang() {
        let out = run_local(3, |c| {
            let local: Result<(), String> = if c.rank() == 1 {
                Err("cannot read part 1".into())
            } else {
                Ok(())
            };
            c.agree(local).map(|r| r.is_ok())
        });
        assert!(matches!(&out[0], Err(CommError::Remote { rank: 1, .. })));
        assert_eq!(out[1], Ok(false));
        // A rank that leaves early: the others' next collective fails.
        let out = run_local(2, |c| {
            if c.rank() == 0 {
                return Ok(Vec::new());
            }
            c.all_gather(&[1])
        });
        assert!(out[1].is_err());
    }
}
