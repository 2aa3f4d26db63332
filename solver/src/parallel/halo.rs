//! The exchange of element slots between ranks: after each scatter, the slots of a rank's
//! owned elements that another rank's nodes need go there, and the halo elements' slots come
//! in, so that every node of an owned element sums the slots of all its elements, in global
//! element order, as one process would (the same bits for any rank count).

use std::sync::{Arc, Mutex};

use crate::parallel::comm::{Communicator, Peer};
use crate::parallel::partition::Neighbour;
use crate::real::Real;

/// The message buffers of the exchanges, kept between steps (resized in place, so a warm
/// exchange allocates nothing).
#[derive(Debug, Default)]
struct Buffers {
    /// Per neighbour, where its values lie in `out` and `into` (for the current width).
    peers: Vec<Peer>,
    /// Values sent, neighbour after neighbour.
    out: Vec<f64>,
    /// Values received, neighbour after neighbour.
    into: Vec<f64>,
}

/// The halo exchange of one rank.
pub struct Halo {
    comm: Arc<dyn Communicator>,
    neighbours: Vec<Neighbour>,
    buffers: Mutex<Buffers>,
    /// Values sent per step so far (all passes), for run.json.
    sent: std::sync::atomic::AtomicU64,
}

impl std::fmt::Debug for Halo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Halo")
            .field("rank", &self.comm.rank())
            .finish_non_exhaustive()
    }
}

impl Halo {
    /// The exchange with `neighbours` over `comm`.
    pub fn new(comm: Arc<dyn Communicator>, neighbours: &[Neighbour]) -> Self {
        Halo {
            comm,
            neighbours: neighbours.to_vec(),
            buffers: Mutex::new(Buffers {
                peers: neighbours
                    .iter()
                    .map(|n| Peer {
                        rank: n.rank,
                        send: 0..0,
                        receive: 0..0,
                    })
                    .collect(),
                ..Buffers::default()
            }),
            sent: std::sync::atomic::AtomicU64::new(0),
        }
    }

    /// Bytes this rank has sent in slot exchanges so far.
    pub fn bytes_sent(&self) -> u64 {
        8 * self.sent.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Elements sent to and received from each neighbour per exchange: (rank, sent, received).
    pub fn sizes(&self) -> Vec<(usize, usize, usize)> {
        self.neighbours
            .iter()
            .map(|n| (n.rank, n.send.len(), n.receive.len()))
            .collect()
    }

    /// Sends the `per_element` values of each owned border element of `slots` and writes the
    /// neighbours' into their halo elements. Called on the driving thread between the passes.
    pub fn exchange<R: Real>(&self, slots: &mut [R], per_element: usize) {
        let mut guard = self.buffers.lock().expect("halo buffers");
        let Buffers { peers, out, into } = &mut *guard;
        out.clear();
        let mut received = 0;
        for (p, n) in peers.iter_mut().zip(&self.neighbours) {
            let start = out.len();
            for &e in &n.send {
                let at = per_element * e as usize;
                out.extend(slots[at..at + per_element].iter().map(|v| v.f64()));
            }
            p.send = start..out.len();
            let count = per_element * n.receive.len();
            p.receive = received..received + count;
            received += count;
        }
        into.clear();
        into.resize(received, 0.0);
        self.sent
            .fetch_add(out.len() as u64, std::sync::atomic::Ordering::Relaxed);
        self.comm.exchange(peers, out, into);
        for (p, n) in peers.iter().zip(&self.neighbours) {
            let values = into[p.receive.clone()].chunks_exact(per_element);
            for (&e, v) in n.receive.iter().zip(values) {
                let at = per_element * e as usize;
                for (s, &x) in slots[at..at + per_element].iter_mut().zip(v) {
                    *s = R::of(x);
                }
            }
        }
    }
}
