//! The exchange of element slots between ranks: after each scatter, the slots of a rank's
//! owned elements that another rank's nodes need go there, and the halo elements' slots come
//! in, so that every node of an owned element sums the slots of all its elements, in global
//! element order, as one process would (the same bits for any rank count).

use std::sync::{Arc, Mutex};

use crate::parallel::comm::Communicator;
use crate::parallel::partition::Neighbour;
use crate::real::Real;

/// One neighbour's element lists and message buffers (kept between steps).
#[derive(Debug)]
struct Link {
    neighbour: Neighbour,
    out: Vec<f64>,
    into: Vec<f64>,
}

/// The halo exchange of one rank.
pub struct Halo {
    comm: Arc<dyn Communicator>,
    links: Mutex<Vec<Link>>,
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
            links: Mutex::new(
                neighbours
                    .iter()
                    .map(|n| Link {
                        neighbour: n.clone(),
                        out: Vec::new(),
                        into: Vec::new(),
                    })
                    .collect(),
            ),
            sent: std::sync::atomic::AtomicU64::new(0),
        }
    }

    /// Bytes this rank has sent in slot exchanges so far.
    pub fn bytes_sent(&self) -> u64 {
        8 * self.sent.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Elements sent to and received from each neighbour per exchange: (rank, sent, received).
    pub fn sizes(&self) -> Vec<(usize, usize, usize)> {
        let links = self.links.lock().expect("halo buffers");
        links
            .iter()
            .map(|l| {
                (
                    l.neighbour.rank,
                    l.neighbour.send.len(),
                    l.neighbour.receive.len(),
                )
            })
            .collect()
    }

    /// Sends the `per_element` values of each owned border element of `slots` and writes the
    /// neighbours' into their halo elements. Called on the driving thread between the passes.
    pub fn exchange<R: Real>(&self, slots: &mut [R], per_element: usize) {
        let mut links = self.links.lock().expect("halo buffers");
        let mut sent = 0;
        for l in links.iter_mut() {
            l.out.clear();
            for &e in &l.neighbour.send {
                let at = per_element * e as usize;
                l.out
                    .extend(slots[at..at + per_element].iter().map(|v| v.f64()));
            }
            l.into.clear();
            l.into.resize(per_element * l.neighbour.receive.len(), 0.0);
            sent += l.out.len();
        }
        self.sent
            .fetch_add(sent as u64, std::sync::atomic::Ordering::Relaxed);
        // Split each link into its send and receive buffers, which the exchange reads and
        // fills at once.
        let (ranks, outs, mut intos): (Vec<usize>, Vec<&Vec<f64>>, Vec<&mut Vec<f64>>) = {
            let mut ranks = Vec::with_capacity(links.len());
            let mut outs = Vec::with_capacity(links.len());
            let mut intos = Vec::with_capacity(links.len());
            for l in links.iter_mut() {
                ranks.push(l.neighbour.rank);
                let Link { out, into, .. } = l;
                outs.push(&*out);
                intos.push(into);
            }
            (ranks, outs, intos)
        };
        let sends: Vec<(usize, &[f64])> =
            ranks.iter().zip(&outs).map(|(&r, o)| (r, &o[..])).collect();
        let mut recvs: Vec<(usize, &mut [f64])> = ranks
            .iter()
            .zip(intos.iter_mut())
            .map(|(&r, i)| (r, &mut i[..]))
            .collect();
        self.comm.exchange(&sends, &mut recvs);
        drop(recvs);
        drop(sends);
        for l in links.iter() {
            for (k, &e) in l.neighbour.receive.iter().enumerate() {
                let at = per_element * e as usize;
                for (s, &v) in slots[at..at + per_element]
                    .iter_mut()
                    .zip(&l.into[per_element * k..per_element * (k + 1)])
                {
                    *s = R::of(v);
                }
            }
        }
    }
}
