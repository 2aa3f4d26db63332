//! The [`Communicator`] of a run over MPI ranks (cargo feature `mpi`; rsmpi over the system's
//! MPI library). Every reduction that must give the same bits on any number of ranks is formed
//! here from gathered values added in rank order, never by MPI's own reduction operators,
//! whose association order the standard leaves open.

use std::thread::ThreadId;

use mpi::datatype::PartitionMut;
use mpi::topology::{Communicator as _, SimpleCommunicator};
use mpi::traits::*;

use std::sync::atomic::{AtomicU64, Ordering};

use crate::parallel::comm::{Communicator, Peer, Traffic};

/// `MPI_COMM_WORLD` of an initialised MPI (funneled: only the thread that initialised it calls
/// MPI).
pub struct MpiWorld {
    /// Finalises MPI when dropped.
    _universe: mpi::environment::Universe,
    world: SimpleCommunicator,
    /// The one thread that may call MPI.
    caller: ThreadId,
    /// Calls made (see [`Traffic`]).
    calls: AtomicU64,
    /// Point-to-point messages sent.
    messages: AtomicU64,
    /// Their bytes.
    bytes: AtomicU64,
}

// SAFETY: MPI was initialised at the funneled level, so its calls are valid from the thread
// that initialised it, whichever thread owns this value; every method checks (in debug builds)
// that it runs on that thread, and the engine calls the communicator only from its driving
// thread, never from its worker team.
unsafe impl Send for MpiWorld {}
// SAFETY: as for `Send`: shared references are only used by the initialising thread.
unsafe impl Sync for MpiWorld {}

impl std::fmt::Debug for MpiWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MpiWorld")
            .field("rank", &self.world.rank())
            .field("ranks", &self.world.size())
            .finish()
    }
}

impl MpiWorld {
    /// Initialises MPI on this thread (`None` when it was initialised already or the library
    /// does not offer the funneled threading level).
    pub fn init() -> Option<Self> {
        let (universe, level) = mpi::initialize_with_threading(mpi::Threading::Funneled)?;
        if level < mpi::Threading::Funneled {
            return None;
        }
        let world = universe.world();
        Some(MpiWorld {
            _universe: universe,
            world,
            caller: std::thread::current().id(),
            calls: AtomicU64::new(0),
            messages: AtomicU64::new(0),
            bytes: AtomicU64::new(0),
        })
    }

    /// Every call passes here: checks the thread and counts the call.
    fn on_caller(&self) {
        self.calls.fetch_add(1, Ordering::Relaxed);
        debug_assert_eq!(
            std::thread::current().id(),
            self.caller,
            "MPI called from a thread other than the one that initialised it"
        );
    }

    /// Sizes from every rank, then their offsets.
    fn counts(&self, local: usize) -> (Vec<i32>, Vec<i32>) {
        let mut counts = vec![0i32; self.ranks()];
        let n = i32::try_from(local).expect("a message under 2^31 values");
        self.world.all_gather_into(&n, &mut counts[..]);
        let displs = offsets(&counts);
        (counts, displs)
    }

    /// Non-blocking sends and receives with the given ranks, all in flight at once.
    fn point_to_point<T: Equivalence>(
        &self,
        sends: &[(usize, &[T])],
        recvs: &mut [(usize, &mut [T])],
    ) {
        self.on_caller();
        self.messages
            .fetch_add(sends.len() as u64, Ordering::Relaxed);
        let bytes: usize = sends.iter().map(|(_, v)| std::mem::size_of_val(*v)).sum();
        self.bytes.fetch_add(bytes as u64, Ordering::Relaxed);
        mpi::request::scope(|scope| {
            let incoming: Vec<_> = recvs
                .iter_mut()
                .map(|(from, buffer)| {
                    self.world
                        .process_at_rank(*from as i32)
                        .immediate_receive_into(scope, &mut buffer[..])
                })
                .collect();
            let outgoing: Vec<_> = sends
                .iter()
                .map(|(to, values)| {
                    self.world
                        .process_at_rank(*to as i32)
                        .immediate_send(scope, *values)
                })
                .collect();
            for r in incoming {
                r.wait();
            }
            for r in outgoing {
                r.wait();
            }
        });
    }

    fn all_gather_f64(&self, local: &[f64]) -> Vec<f64> {
        let mut out = Vec::new();
        self.all_gather(local, &mut out);
        out
    }
}

/// Exclusive prefix sums of `counts`.
fn offsets(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0i32, |acc, &c| {
            let at = *acc;
            *acc += c;
            Some(at)
        })
        .collect()
}

impl Communicator for MpiWorld {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    fn ranks(&self) -> usize {
        self.world.size() as usize
    }

    fn sum(&self, local: f64) -> f64 {
        // Added in rank order on every rank: the same bits everywhere.
        self.all_gather_f64(&[local]).iter().fold(0.0, |a, b| a + b)
    }

    // Minimum, maximum and integer sums do not depend on the order: MPI's own all-reduce
    // (log P steps), with NaN, which MPI's MIN and MAX leave undefined, taken out first as
    // `f64::min` and `f64::max` do.
    fn min(&self, local: f64) -> f64 {
        self.on_caller();
        let mut out = 0.0;
        let local = if local.is_nan() { f64::INFINITY } else { local };
        self.world
            .all_reduce_into(&local, &mut out, mpi::collective::SystemOperation::min());
        out
    }

    fn max(&self, local: f64) -> f64 {
        self.on_caller();
        let mut out = 0.0;
        let local = if local.is_nan() {
            f64::NEG_INFINITY
        } else {
            local
        };
        self.world
            .all_reduce_into(&local, &mut out, mpi::collective::SystemOperation::max());
        out
    }

    fn sum_count(&self, local: u64) -> u64 {
        self.on_caller();
        let mut out = 0u64;
        self.world
            .all_reduce_into(&local, &mut out, mpi::collective::SystemOperation::sum());
        out
    }

    fn sum_integers(&self, local: &[i64], out: &mut [i64]) {
        self.on_caller();
        self.world
            .all_reduce_into(local, out, mpi::collective::SystemOperation::sum());
    }

    fn traffic(&self) -> Traffic {
        Traffic {
            calls: self.calls.load(Ordering::Relaxed),
            messages: self.messages.load(Ordering::Relaxed),
            bytes: self.bytes.load(Ordering::Relaxed),
        }
    }

    fn all_gather(&self, local: &[f64], out: &mut Vec<f64>) {
        self.on_caller();
        let (counts, displs) = self.counts(local.len());
        let total = counts.iter().map(|&c| c as usize).sum();
        out.clear();
        out.resize(total, 0.0);
        let mut part = PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
        self.world.all_gather_varcount_into(local, &mut part);
    }

    fn exchange(&self, peers: &[Peer], send: &[f64], receive: &mut [f64]) {
        self.on_caller();
        let bytes: usize = peers.iter().map(|p| 8 * p.send.len()).sum();
        self.messages
            .fetch_add(peers.len() as u64, Ordering::Relaxed);
        self.bytes.fetch_add(bytes as u64, Ordering::Relaxed);
        mpi::request::scope(|scope| {
            // The receive buffer cut into the peers' ranges, in order (the requests are MPI's
            // handles, a few words per neighbour).
            let mut rest = receive;
            let mut at = 0;
            let mut requests = Vec::with_capacity(2 * peers.len());
            for p in peers {
                assert!(p.receive.start >= at, "receive ranges in increasing order");
                let (_, tail) = rest.split_at_mut(p.receive.start - at);
                let (mine, tail) = tail.split_at_mut(p.receive.len());
                rest = tail;
                at = p.receive.end;
                requests.push(
                    self.world
                        .process_at_rank(p.rank as i32)
                        .immediate_receive_into(scope, mine),
                );
            }
            for p in peers {
                requests.push(
                    self.world
                        .process_at_rank(p.rank as i32)
                        .immediate_send(scope, &send[p.send.clone()]),
                );
            }
            for r in requests {
                r.wait();
            }
        });
    }

    fn all_to_all_bytes(&self, sends: &[Vec<u8>]) -> Vec<Vec<u8>> {
        self.on_caller();
        assert_eq!(sends.len(), self.ranks(), "one message per rank");
        let send_counts: Vec<u64> = sends.iter().map(|m| m.len() as u64).collect();
        let mut recv_counts = vec![0u64; self.ranks()];
        self.world
            .all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        let me = self.rank();
        let mut received: Vec<Vec<u8>> =
            recv_counts.iter().map(|&c| vec![0u8; c as usize]).collect();
        received[me] = sends[me].clone();
        // Only the non-empty messages travel, point to point.
        let (mine, others): (Vec<_>, Vec<_>) =
            received.iter_mut().enumerate().partition(|(q, _)| *q == me);
        drop(mine);
        let mut recvs: Vec<(usize, &mut [u8])> = others
            .into_iter()
            .filter(|(_, b)| !b.is_empty())
            .map(|(q, b)| (q, &mut b[..]))
            .collect();
        let sends: Vec<(usize, &[u8])> = sends
            .iter()
            .enumerate()
            .filter(|(q, m)| *q != me && !m.is_empty())
            .map(|(q, m)| (q, &m[..]))
            .collect();
        self.point_to_point(&sends, &mut recvs);
        drop(recvs);
        received
    }

    fn gather_bytes(&self, local: &[u8]) -> Option<Vec<Vec<u8>>> {
        self.on_caller();
        let root = self.world.process_at_rank(0);
        let n = i32::try_from(local.len()).expect("a message under 2 GiB");
        if self.rank() == 0 {
            let mut counts = vec![0i32; self.ranks()];
            root.gather_into_root(&n, &mut counts[..]);
            let displs = offsets(&counts);
            let mut all = vec![0u8; counts.iter().map(|&c| c as usize).sum()];
            {
                let mut part = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
                root.gather_varcount_into_root(local, &mut part);
            }
            Some(
                counts
                    .iter()
                    .zip(&displs)
                    .map(|(&c, &d)| all[d as usize..(d + c) as usize].to_vec())
                    .collect(),
            )
        } else {
            root.gather_into(&n);
            root.gather_varcount_into(local);
            None
        }
    }
}
