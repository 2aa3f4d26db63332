//! The global reductions of a run, made explicit: every value that needs all of the mesh (sums
//! of energies, work and force norms, the smallest time step, counts of lost points) passes
//! through one [`Communicator`]. One process computes everything, so [`SingleProcess`] returns
//! its argument; a distributed run (MPI ranks along the curve partitions) implements the same
//! trait with collective calls, and the engine does not change.

/// Reductions over every process of a run. Each call is collective: every process calls it,
/// in the same order, with its own part.
pub trait Communicator: Send + Sync + std::fmt::Debug {
    /// This process's number, 0-based.
    fn rank(&self) -> usize;
    /// Number of processes.
    fn ranks(&self) -> usize;
    /// Sum of every process's `local` (in rank order, so the result is the same everywhere).
    fn sum(&self, local: f64) -> f64;
    /// Smallest of every process's `local`.
    fn min(&self, local: f64) -> f64;
    /// Largest of every process's `local`.
    fn max(&self, local: f64) -> f64;
    /// Sum of counts.
    fn sum_count(&self, local: u64) -> u64;
    /// Every process's `local` added elementwise into `out` (as long; integer sums: exact, in
    /// any order). The accumulators of [`crate::parallel::exact::ExactSum`] merge this way.
    fn sum_integers(&self, local: &[i64], out: &mut [i64]);
    /// Every process's `local`, concatenated in rank order, into `out` (which is resized; its
    /// capacity is kept between calls, so a step that reuses it allocates nothing once warm).
    /// Each process may give a different number of values.
    fn all_gather(&self, local: &[f64], out: &mut Vec<f64>);
    /// Point-to-point exchange with neighbours: sends `send[peer.send]` to each peer's rank and
    /// fills `receive[peer.receive]` with what that rank sends here (the lengths must match;
    /// the peers' receive ranges follow each other, increasing). Every pair must appear on both
    /// sides; the messages travel concurrently.
    fn exchange(&self, peers: &[Peer], send: &[f64], receive: &mut [f64]);
    /// Bytes from each rank to each rank (`sends[q]` goes to rank q); returns what each rank
    /// sent here, by rank. Every process calls it, with a `sends` as long as [`ranks`].
    ///
    /// [`ranks`]: Communicator::ranks
    fn all_to_all_bytes(&self, sends: &[Vec<u8>]) -> Vec<Vec<u8>>;
    /// What this process has sent so far: calls, point-to-point messages and their bytes
    /// (zero for one process).
    fn traffic(&self) -> Traffic {
        Traffic::default()
    }
    /// Rank 0 receives every process's bytes, in rank order (its own first); the others get
    /// `None`.
    fn gather_bytes(&self, local: &[u8]) -> Option<Vec<Vec<u8>>>;
}

/// One neighbour of a [`Communicator::exchange`]: its rank, and where its message lies in the
/// send buffer and its answer in the receive buffer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Peer {
    /// The neighbour's rank.
    pub rank: usize,
    /// Values sent to it.
    pub send: std::ops::Range<usize>,
    /// Values received from it.
    pub receive: std::ops::Range<usize>,
}

/// What a process has sent through its [`Communicator`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Traffic {
    /// Calls: collectives and point-to-point exchanges (each a round of messages).
    pub calls: u64,
    /// Point-to-point messages sent.
    pub messages: u64,
    /// Bytes in those messages.
    pub bytes: u64,
}

/// One process: every reduction is its own value.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SingleProcess;

impl Communicator for SingleProcess {
    fn rank(&self) -> usize {
        0
    }

    fn ranks(&self) -> usize {
        1
    }

    fn sum(&self, local: f64) -> f64 {
        local
    }

    fn min(&self, local: f64) -> f64 {
        local
    }

    fn max(&self, local: f64) -> f64 {
        local
    }

    fn sum_count(&self, local: u64) -> u64 {
        local
    }

    fn all_gather(&self, local: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend_from_slice(local);
    }

    fn sum_integers(&self, local: &[i64], out: &mut [i64]) {
        out.copy_from_slice(local);
    }

    fn exchange(&self, peers: &[Peer], send: &[f64], receive: &mut [f64]) {
        // One process has no neighbours; a message to itself is a copy.
        for p in peers {
            receive[p.receive.clone()].copy_from_slice(&send[p.send.clone()]);
        }
    }

    fn all_to_all_bytes(&self, sends: &[Vec<u8>]) -> Vec<Vec<u8>> {
        sends.to_vec()
    }

    fn gather_bytes(&self, local: &[u8]) -> Option<Vec<Vec<u8>>> {
        Some(vec![local.to_vec()])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_process_reduces_to_its_own_values() {
        let c: &dyn Communicator = &SingleProcess;
        assert_eq!((c.rank(), c.ranks()), (0, 1));
        assert_eq!(c.sum(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(c.min(3.5), 3.5);
        assert_eq!(c.max(f64::INFINITY), f64::INFINITY);
        assert_eq!(c.sum_count(7), 7);
    }
}
