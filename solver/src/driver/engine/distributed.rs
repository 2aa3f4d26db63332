//! What a run over several MPI ranks adds to the engine: the points gathered to rank 0 for
//! outputs, points handed to the rank owning their new element, and the curve cut again when the
//! ranks' shares of points drift apart.

use std::ops::Range;
use std::sync::Arc;
use std::time::Instant;

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::input::case::Case;
use crate::parallel::comm::{Communicator, SingleProcess};
use crate::parallel::partition::Partition;
use crate::real::Real;
use crate::state::grid::{Grid, LiquidNodes};
use crate::state::particles::Particles;
use crate::step::stress::GuardSums;
use crate::step::wall_friction::Walls;
use crate::step::{grid_update, nodal_energy};

use super::setup::{critical_element, first_touch, layout_of, NodeInputs};
use super::{Engine, SetupError, RELOOK_AFTER_MIGRATIONS};

impl<R: Real, E: Element> Engine<R, E> {
    /// Runs `f` on rank 0 with every rank's points gathered there in their global order (the
    /// order one process keeps, elements numbered globally) and the reductions of one process,
    /// so that the output files and sums over points are those of a one-process run; the other
    /// ranks get `None`. On one process, `f(self)`. Collective.
    pub fn on_root<T>(&mut self, f: impl FnOnce(&Self) -> T) -> Option<T> {
        if self.partition.is_whole() {
            return Some(f(self));
        }
        let mut bytes = Vec::with_capacity(self.particles.len() * self.particles.encoded_len());
        for i in 0..self.particles.len() {
            let local = self.particles.element[i];
            self.particles.element[i] = self.partition.global_element(local as usize) as u32;
            self.particles.put_point(i, &mut bytes);
            self.particles.element[i] = local;
        }
        let all = self.comm.gather_bytes(&bytes)?;
        let mut everyone = self.particles.clone();
        everyone.retain(&vec![false; everyone.len()]);
        for part in &all {
            if !part.is_empty() {
                everyone.push_encoded(part);
            }
        }
        let own = std::mem::replace(&mut self.particles, everyone);
        let comm = std::mem::replace(&mut self.comm, Arc::new(SingleProcess));
        let out = f(self);
        self.particles = own;
        self.comm = comm;
        Some(out)
    }

    /// Per rank (on rank 0; `None` elsewhere): its points, seconds per phase, and halo: the
    /// elements it sends and receives per exchange and the bytes it has sent. Collective.
    pub fn rank_report(&self) -> Option<Vec<serde_json::Value>> {
        let halo = self.layout.halo();
        let mine = serde_json::json!({
            "rank": self.comm.rank(),
            "elements": self.partition.owned(),
            "halo_elements": self.partition.halo().len(),
            "points": self.particles.len(),
            "phase_seconds": self.phase_seconds,
            "neighbours": halo.map(|h| h.sizes().iter().map(|&(r, s, g)| serde_json::json!({"rank": r, "sends": s, "receives": g})).collect::<Vec<_>>()).unwrap_or_default(),
            "bytes_sent": self.balance.bytes_before + halo.map_or(0, |h| h.bytes_sent()),
            "pinned_cores": self.team.pinned,
            "steps": self.steps,
            "communicator_calls": self.comm.traffic().calls,
            "messages": self.comm.traffic().messages,
            "message_bytes": self.comm.traffic().bytes,
            "points_moved_by_repartitions": self.balance.points_moved,
            "repartition_seconds": self.balance.seconds,
        });
        let all = self.comm.gather_bytes(mine.to_string().as_bytes())?;
        Some(
            all.iter()
                .map(|b| serde_json::from_slice(b).expect("a rank's report"))
                .collect(),
        )
    }

    /// Sends the points that moved into halo elements to the ranks owning those elements and
    /// takes in the points coming here, in the global point order (see [`exchange_points`]).
    /// Returns whether any point came or went. Collective.
    pub(super) fn migrate(&mut self) -> bool {
        let owned = self.partition.owned() as u32;
        let p = &mut self.particles;
        let leaving = p.element.iter().filter(|&&e| e >= owned).count() as u64;
        if self.comm.sum_count(leaving) == 0 {
            return false;
        }
        let partition = &self.partition;
        exchange_points(
            self.comm.as_ref(),
            p,
            |e| {
                (e >= owned).then(|| {
                    let g = partition.global_element(e as usize);
                    (partition.rank_of(g), g as u32)
                })
            },
            |g| {
                partition
                    .local_element(g as usize)
                    .expect("a point sent to the rank owning its element") as u32
            },
        );
        self.balance.stale = true;
        self.balance.migrations_since_decline += 1;
        true
    }

    /// Between steps of a run over several ranks: measures how evenly the ranks share the
    /// points (after points migrated) and, when the largest rank holds more than `threshold`
    /// times the mean, cuts the curve again, balanced by the points each element holds now,
    /// and moves the points and the rank's share to it. Nothing in the results changes (the
    /// sums are formed per block of elements, in global order, for any cut). Returns whether
    /// it re-partitioned. Collective.
    pub fn rebalance(&mut self, case: &Case, threshold: f64) -> Result<bool, SetupError> {
        if self.partition.is_whole() || !self.balance.stale {
            return Ok(false);
        }
        self.balance.stale = false;
        let mut counts = Vec::new();
        self.comm
            .all_gather(&[self.particles.len() as f64], &mut counts);
        let imbalance = imbalance_of(&counts);
        self.balance.imbalance = imbalance;
        self.balance.worst = self.balance.worst.max(imbalance);
        // After a declined look, look again once the imbalance has grown or the points have
        // migrated for a while (they may have spread so that a cut can do better now).
        let relook = imbalance > self.balance.declined_at
            || self.balance.migrations_since_decline >= RELOOK_AFTER_MIGRATIONS;
        if !(threshold > 0.0 && imbalance > threshold && relook) {
            return Ok(false);
        }
        let t0 = Instant::now();
        // Every element's points, in global element order (the ranks' ranges follow each other).
        let mut mine = vec![0.0; self.partition.owned()];
        for &e in &self.particles.element {
            mine[e as usize] += 1.0;
        }
        let mut weights = Vec::new();
        self.comm.all_gather(&mine, &mut weights);
        let weight: Vec<u64> = weights.iter().map(|&w| w as u64).collect();
        let (me, ranks) = (self.comm.rank(), self.comm.ranks());
        // The cut `Partition::along_curve` will make, judged before the mesh is built for it:
        // taken when it at least halves the excess over an even share (a smaller gain does not
        // pay for the move).
        let ranges = crate::parallel::team::aligned_to_blocks(
            crate::parallel::team::balanced_ranges(weight.iter().copied(), ranks),
            weight.len(),
        );
        let predicted = imbalance_of(
            &ranges
                .iter()
                .map(|r| weight[r.clone()].iter().sum::<u64>() as f64)
                .collect::<Vec<_>>(),
        );
        if ranges.len() != ranks
            || ranges.iter().any(|r| r.is_empty())
            || predicted - 1.0 > 0.5 * (imbalance - 1.0)
        {
            self.balance.declined_at = imbalance;
            self.balance.migrations_since_decline = 0;
            self.balance.seconds += t0.elapsed().as_secs_f64();
            return Ok(false);
        }
        let global = case.mesh::<E, R>()?;
        let mut parts = Partition::along_curve(&global, &weight, ranks);
        debug_assert!(parts.iter().zip(&ranges).all(|(p, r)| p.elements() == *r));
        let new = parts.swap_remove(me);
        let old = std::mem::replace(&mut self.partition, new);
        let partition = &self.partition;
        let p = &mut self.particles;
        let mut sent = 0;
        let kept = exchange_points(
            self.comm.as_ref(),
            p,
            |e| {
                let g = old.global_element(e as usize);
                let to = partition.rank_of(g);
                (to != me).then(|| {
                    sent += 1;
                    (to, g as u32)
                })
            },
            |g| {
                partition
                    .local_element(g as usize)
                    .expect("a point sent to the rank owning its element") as u32
            },
        );
        for e in &mut p.element[kept] {
            let g = old.global_element(*e as usize);
            *e = partition.local_element(g).expect("a point kept here") as u32;
        }
        self.balance.points_moved += sent;
        self.balance.bytes_before += self.layout.halo().map_or(0, |h| h.bytes_sent());
        self.share(case, global);
        self.balance.repartitions += 1;
        self.balance.declined_at = 0.0;
        self.balance.migrations_since_decline = 0;
        self.balance.stale = true;
        self.balance.seconds += t0.elapsed().as_secs_f64();
        log::info!(
            "step {}: points per rank {:.3}× the mean; re-partitioned along the curve (rank {me} now owns global elements {:?}, {} points)",
            self.steps,
            imbalance,
            self.partition.elements(),
            self.particles.len(),
        );
        Ok(true)
    }

    /// Sets up this rank's share of `global` for the (new) partition, with the points already
    /// there: the local mesh, its nodes' inputs, the layout and halo, and every buffer sized by
    /// elements, nodes or blocks.
    pub(super) fn share(&mut self, case: &Case, global: Mesh<E, R>) {
        self.mesh = self.partition.local_mesh(global);
        let mesh = &self.mesh;
        let inputs = NodeInputs::of(case, mesh, &self.partition);
        self.fixed = inputs.fixed;
        self.liquid_fixed = inputs.liquid_fixed;
        // The walls are the rank's wall nodes (a case without walls has no such constraint).
        self.constraints.replace(Walls(inputs.walls));
        self.traction = inputs.traction;
        self.liquid_traction = inputs.liquid_traction;
        self.input_element = inputs.input_element;
        self.input_node = inputs.input_node;
        self.courant.1 = critical_element(case, &self.partition, mesh);
        let two_phase = self.grid.liquid.is_some();
        self.grid = Grid::new(mesh.nodes());
        if two_phase {
            self.grid.liquid = Some(LiquidNodes::new(mesh.nodes()));
        }
        self.layout = layout_of(
            &self.partition,
            mesh,
            &self.particles,
            self.team.threads,
            &self.comm,
        );
        if self.first_touch {
            let p = std::mem::take(&mut self.particles);
            self.particles = first_touch(&self.team, &self.layout, p);
        }
        self.slots = self.layout.new_slots();
        if !self.guard_slots.is_empty() {
            self.guard_slots = vec![GuardSums::EMPTY; self.layout.blocks()];
        }
        self.grid_scratch = grid_update::GridScratch::new(mesh.nodes());
        self.energy_blocks = vec![(); mesh.nodes().div_ceil(nodal_energy::NODE_BLOCK)];
        self.energy_values = vec![[0.0; 4]; mesh.nodes()];
        self.owned_partials = vec![[0.0; 4]; self.layout.owned_blocks()];
    }
}

/// The largest of `counts` over their mean (1 for an even share, 0 for none at all).
pub(super) fn imbalance_of(counts: &[f64]) -> f64 {
    let total: f64 = counts.iter().sum();
    if total == 0.0 {
        return 0.0;
    }
    counts.iter().copied().fold(0.0, f64::max) * counts.len() as f64 / total
}

/// Sends every point `to` names, as (rank, global element), to that rank with its element
/// numbered globally, keeps the rest in order, and takes in the points sent here, their
/// elements numbered by `local`. The points end in the global order one process keeps: those
/// from lower ranks (earlier along the curve), the kept ones, those from higher ranks, so that
/// a stable sort by element orders them as one process would. Returns the kept points' new
/// index range. Collective.
pub(super) fn exchange_points<R: Real>(
    comm: &dyn Communicator,
    p: &mut Particles<R>,
    mut to: impl FnMut(u32) -> Option<(usize, u32)>,
    local: impl Fn(u32) -> u32,
) -> Range<usize> {
    let (me, ranks) = (comm.rank(), comm.ranks());
    let mut sends = vec![Vec::new(); ranks];
    let mut keep = vec![true; p.len()];
    let mut leaving = false;
    for i in 0..p.len() {
        let Some((rank, g)) = to(p.element[i]) else {
            continue;
        };
        let e = std::mem::replace(&mut p.element[i], g);
        p.put_point(i, &mut sends[rank]);
        p.element[i] = e;
        keep[i] = false;
        leaving = true;
    }
    if leaving {
        p.retain(&keep);
    }
    let got = comm.all_to_all_bytes(&sends);
    let kept = p.len();
    let mut before = 0;
    for (q, bytes) in got.iter().enumerate() {
        if q == me || bytes.is_empty() {
            continue;
        }
        let n = p.push_encoded(bytes);
        if q < me {
            before += n;
        }
    }
    // [kept, lower ranks', higher ranks'] → [lower ranks', kept, higher ranks'].
    p.rotate_front(kept + before, before);
    for i in (0..before).chain(kept + before..p.len()) {
        p.element[i] = local(p.element[i]);
    }
    before..before + kept
}
