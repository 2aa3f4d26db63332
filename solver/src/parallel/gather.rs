//! The data layout of the parallel step: particles kept sorted by element, fixed per-thread
//! ranges of elements, particles and nodes, and the race-free, deterministic particle-to-grid
//! sum (docs/design.md §5).
//!
//! A sum over particles onto nodes is done in two passes. Each thread goes over its elements
//! and, for each, over that element's particles in storage order, adding into the slots of the
//! element's nodes (`slots[NODES e + k]`); then each thread forms the nodes of its range by adding
//! the slots of the node's elements in element order. Every node's sum is thus taken in an
//! order fixed by the mesh and the particle order, whatever the thread count, with no locks or
//! atomics.

use std::ops::Range;

use crate::element::mesh::Mesh;
use crate::element::tet4::Tet4;
use crate::element::Element;
use crate::parallel::comm::Communicator;
use crate::parallel::exact::{self, ExactSum};
use crate::parallel::halo::Halo;
use crate::parallel::team::{aligned_to_blocks, balanced_ranges, Shared, Team};
use crate::real::Real;
use crate::state::particles::{Field, FieldVisitor, Particles, Value};

/// Widest slot (values per element node) a pass uses.
pub const WIDTH: usize = 12;

pub use crate::parallel::team::ELEMENT_BLOCK;

/// Layout and scratch of the parallel step.
#[derive(Debug)]
///
/// The fields are private: the parallel passes write through raw pointers into the ranges they
/// describe, so only this module may change them, keeping the element ranges disjoint and
/// covering `0..elements` and `elem_start` non-decreasing (checked in debug builds).
pub struct Layout<R: Real, E: Element = Tet4> {
    /// First particle of each element (particles are sorted by element), `elements + 1` long.
    elem_start: Vec<u32>,
    /// Elements of each thread (contiguous along the mesh order, balanced by particles).
    element_ranges: Vec<Range<usize>>,
    /// Nodes of each thread (balanced by their number of element corners).
    node_ranges: Vec<Range<usize>>,
    /// For each node, where its slots start in `node_slot` (`nodes + 1` long).
    node_start: Vec<u32>,
    /// Slots (NODES e + k) of every node, in element order.
    node_slot: Vec<u32>,
    /// For each block of owned elements, where its owned nodes start in `owned_node`
    /// (`blocks + 1` long).
    owned_start: Vec<u32>,
    /// Nodes owned per element block: a node belongs to the first element (in global order)
    /// that touches it, and is listed under that element's block, by element and corner. A sum
    /// over nodes formed block by block in this order is the same for any thread or rank count.
    owned_node: Vec<u32>,
    /// The exchange of border slots with other ranks (`None` on one process).
    halo: Option<std::sync::Arc<Halo>>,
    /// The local elements in global order, on a rank of several.
    order: Option<Vec<u32>>,
    /// Number of owned elements (the halo's follow).
    owned: usize,
    _types: std::marker::PhantomData<(R, E)>,
}

/// Per-node partial sums: room for `NODES × elements` slots of up to [`WIDTH`] values. A pass
/// of width W packs its slots W values apart, so that it writes and reads W values per slot,
/// not [`WIDTH`] (a 2-wide pass moves a sixth of the bytes of a 12-wide one).
pub type Slots<R> = Vec<R>;

/// The slots of one element's nodes in a scatter's closure, `width` values each: `width` must
/// be the scatter's W (checked in debug builds).
#[inline(always)]
pub fn node_slots<E: Element, R>(
    four: &mut [R],
    width: usize,
) -> std::slice::ChunksExactMut<'_, R> {
    debug_assert_eq!(
        four.len(),
        E::NODES * width,
        "a slot width other than the scatter's"
    );
    four.chunks_exact_mut(width)
}

impl<R: Real, E: Element> Layout<R, E> {
    /// The layout of `mesh` for `threads` threads, with particles `p` (sorted by element).
    pub fn new(mesh: &Mesh<E, R>, p: &Particles<R>, threads: usize) -> Self {
        Self::ordered(mesh, p, threads, None, mesh.elements(), None)
    }

    /// [`Layout::new`] for one rank of several: each node sums its elements' slots in the
    /// order of `order` (the local elements in global order), and every scatter exchanges the
    /// border slots through `halo` before the nodes are formed.
    pub fn ordered(
        mesh: &Mesh<E, R>,
        p: &Particles<R>,
        threads: usize,
        order: Option<&[u32]>,
        owned: usize,
        halo: Option<std::sync::Arc<Halo>>,
    ) -> Self {
        let (ne, nn) = (mesh.elements(), mesh.nodes());
        let elem_start = element_starts(&p.element, ne);
        let element_ranges = aligned_to_blocks(
            balanced_ranges(
                (0..ne).map(|e| E::NODES as u64 * u64::from(elem_start[e + 1] - elem_start[e])),
                threads,
            ),
            ne,
        );
        let mut node_start = vec![0u32; nn + 1];
        for c in &mesh.corners {
            for &n in c.as_ref() {
                node_start[n as usize + 1] += 1;
            }
        }
        for n in 0..nn {
            node_start[n + 1] += node_start[n];
        }
        let mut fill = node_start.clone();
        let mut node_slot = vec![0u32; E::NODES * ne];
        let natural: Vec<u32>;
        let order = match order {
            Some(o) => o,
            None => {
                natural = (0..ne as u32).collect();
                &natural
            }
        };
        assert_eq!(order.len(), ne, "an order of every element");
        for &e in order {
            let e = e as usize;
            for (k, &n) in mesh.corners[e].as_ref().iter().enumerate() {
                node_slot[fill[n as usize] as usize] = (E::NODES * e + k) as u32;
                fill[n as usize] += 1;
            }
        }
        let node_ranges = balanced_ranges(
            (0..nn).map(|n| u64::from(node_start[n + 1] - node_start[n])),
            threads,
        );
        // Each node's first element in global order is its owner; the node is this rank's
        // when that element is owned here.
        let mut owner = vec![u32::MAX; nn];
        for &e in order {
            for &n in mesh.corners[e as usize].as_ref() {
                if owner[n as usize] == u32::MAX {
                    owner[n as usize] = e;
                }
            }
        }
        let blocks = owned.div_ceil(ELEMENT_BLOCK);
        let mut owned_start = Vec::with_capacity(blocks + 1);
        let mut owned_node = Vec::new();
        for b in 0..blocks {
            owned_start.push(owned_node.len() as u32);
            for e in b * ELEMENT_BLOCK..((b + 1) * ELEMENT_BLOCK).min(owned) {
                for &n in mesh.corners[e].as_ref() {
                    if owner[n as usize] == e as u32 {
                        owned_node.push(n);
                    }
                }
            }
        }
        owned_start.push(owned_node.len() as u32);
        let layout = Layout {
            elem_start,
            element_ranges,
            node_ranges,
            node_start,
            node_slot,
            owned_start,
            owned_node,
            halo: halo.clone(),
            order: halo.as_ref().map(|_| order.to_vec()),
            owned,
            _types: std::marker::PhantomData,
        };
        layout.debug_check();
        layout
    }

    /// The invariants the unsafe passes rely on: contiguous element ranges covering all
    /// elements in order (so disjoint), and particle starts that never decrease.
    fn debug_check(&self) {
        if cfg!(debug_assertions) {
            let ne = self.elem_start.len() - 1;
            let mut next = 0;
            for r in &self.element_ranges {
                assert!(
                    r.start == next && r.end >= r.start,
                    "element ranges not contiguous"
                );
                assert!(
                    r.start % ELEMENT_BLOCK == 0,
                    "element range does not start a block"
                );
                next = r.end;
            }
            assert_eq!(next, ne, "element ranges do not cover the mesh");
            assert!(
                self.elem_start.windows(2).all(|w| w[0] <= w[1]),
                "particle starts decrease"
            );
        }
    }

    /// Re-reads where each element's particles start after the particles were re-sorted by
    /// element (`element`: each particle's element, non-decreasing).
    pub fn set_particle_elements(&mut self, element: &[u32]) {
        // In place: this runs inside the time step, which allocates nothing.
        let start = &mut self.elem_start;
        start.fill(0);
        for &e in element {
            start[e as usize + 1] += 1;
        }
        for e in 0..start.len() - 1 {
            start[e + 1] += start[e];
        }
        self.debug_check();
    }

    /// Elements of thread `k`.
    pub fn element_range(&self, k: usize) -> Range<usize> {
        self.element_ranges[k].clone()
    }

    /// The element blocks ([`ELEMENT_BLOCK`]) of thread `k`: its elements' blocks, which no
    /// other thread's elements share.
    pub fn block_range(&self, k: usize) -> Range<usize> {
        let r = &self.element_ranges[k];
        r.start / ELEMENT_BLOCK..r.end.div_ceil(ELEMENT_BLOCK)
    }

    /// Number of element blocks of the mesh.
    pub fn blocks(&self) -> usize {
        (self.elem_start.len() - 1).div_ceil(ELEMENT_BLOCK)
    }

    /// Zeroed slots for this layout (allocated zeroed, so pages are placed by the threads that
    /// first write them).
    pub fn new_slots(&self) -> Slots<R> {
        vec![R::ZERO; WIDTH * E::NODES * (self.elem_start.len() - 1)]
    }

    /// Particles of thread `k`.
    pub fn particle_range(&self, k: usize) -> Range<usize> {
        let r = &self.element_ranges[k];
        self.elem_start[r.start] as usize..self.elem_start[r.end] as usize
    }

    /// Particles of element `e`.
    #[inline]
    pub fn particles_of(&self, e: usize) -> Range<usize> {
        self.elem_start[e] as usize..self.elem_start[e + 1] as usize
    }

    /// Pass 1: on every thread, for each of its elements, zeroes the slots of the element's
    /// nodes ([`Element::NODES`] slots of `W` values, one after the other) and calls
    /// `element(e, slots)`; [`node_slots`] splits them by node.
    pub fn scatter<const W: usize, F>(&self, team: &Team, slots: &mut Slots<R>, element: F)
    where
        F: Fn(usize, &mut [R]) + Sync,
    {
        const { assert!(W <= WIDTH) };
        let per_element = E::NODES * W;
        let shared = Shared::new(slots);
        let ranges = &self.element_ranges;
        team.run(|k| {
            let r = ranges[k].clone();
            // SAFETY: the element ranges are disjoint, so are their slots.
            let mine = unsafe { shared.range(per_element * r.start..per_element * r.end) };
            for (own, e) in mine.chunks_exact_mut(per_element).zip(r) {
                own.fill(R::ZERO);
                element(e, own);
            }
        });
        if let Some(h) = &self.halo {
            h.exchange(&mut slots[..], per_element);
        }
    }

    /// The same layout (element order, halo) for another thread count.
    pub fn for_threads(&self, mesh: &Mesh<E, R>, p: &Particles<R>, threads: usize) -> Self {
        Self::ordered(
            mesh,
            p,
            threads,
            self.order.as_deref(),
            self.owned,
            self.halo.clone(),
        )
    }

    /// Blocks of owned elements (the partial sums of [`Layout::sum_owned`]).
    pub fn owned_blocks(&self) -> usize {
        self.owned_start.len() - 1
    }

    /// Per block of owned elements, the sum of `values` over the block's owned nodes, in
    /// order, into `partials` (at least [`Layout::owned_blocks`] long). Added up in block order
    /// over every rank ([`exact_total`]), these give a sum over the mesh's nodes that is the
    /// same for any thread and rank count.
    pub fn sum_owned<const K: usize>(
        &self,
        team: &Team,
        values: &[[f64; K]],
        partials: &mut [[f64; K]],
    ) {
        let (start, node) = (&self.owned_start, &self.owned_node);
        team.for_blocks(self.owned_blocks(), 1, partials, |r| {
            let mut s = [0.0; K];
            for &n in &node[start[r.start] as usize..start[r.start + 1] as usize] {
                for c in 0..K {
                    s[c] += values[n as usize][c];
                }
            }
            s
        });
    }

    /// The halo exchange, on a rank of several.
    pub fn halo(&self) -> Option<&Halo> {
        self.halo.as_deref()
    }

    /// Both passes: [`Layout::scatter`] with `element`, then [`Layout::gather`] handing each
    /// node's `W` sums to `node` as a slice (so that one `node` serves passes of any width).
    pub fn sum_to_nodes<const W: usize, F, G>(
        &self,
        team: &Team,
        slots: &mut Slots<R>,
        element: F,
        node: G,
    ) where
        F: Fn(usize, &mut [R]) + Sync,
        G: Fn(usize, &[R]) + Sync,
    {
        self.scatter::<W, _>(team, slots, element);
        self.gather::<W, _>(team, slots, |n, s| node(n, &s));
    }

    /// Pass 2: on every thread, for each node of its range, the sum of the first `W` values of
    /// the node's slots, in element order, handed to `node(n, sum)`.
    pub fn gather<const W: usize, F>(&self, team: &Team, slots: &Slots<R>, node: F)
    where
        F: Fn(usize, [R; W]) + Sync,
    {
        team.run(|k| {
            for n in self.node_ranges[k].clone() {
                let mut sum = [R::ZERO; W];
                for &s in
                    &self.node_slot[self.node_start[n] as usize..self.node_start[n + 1] as usize]
                {
                    let v = &slots[W * s as usize..W * s as usize + W];
                    for c in 0..W {
                        sum[c] += v[c];
                    }
                }
                node(n, sum);
            }
        });
    }
}

/// The sum of every rank's block `partials`, component by component, exact and rounded once
/// ([`ExactSum`]): the same bits on every rank and for any thread or rank count, for one
/// small all-reduce whatever the number of blocks.
pub fn exact_total<const K: usize>(comm: &dyn Communicator, partials: &[[f64; K]]) -> [f64; K] {
    let mut sums = [ExactSum::default(); K];
    for block in partials {
        for (s, &v) in sums.iter_mut().zip(block) {
            s.add(v);
        }
    }
    let mut local = [[0i64; exact::WIDTH]; K];
    for (l, s) in local.iter_mut().zip(&mut sums) {
        *l = *s.words_mut();
    }
    let mut all = [[0i64; exact::WIDTH]; K];
    comm.sum_integers(local.as_flattened(), all.as_flattened_mut());
    std::array::from_fn(|c| ExactSum::from_words(all[c]).value())
}

/// First particle of each element for particles sorted by `element`.
pub fn element_starts(element: &[u32], elements: usize) -> Vec<u32> {
    let mut start = vec![0u32; elements + 1];
    for &e in element {
        start[e as usize + 1] += 1;
    }
    for e in 0..elements {
        start[e + 1] += start[e];
    }
    start
}

/// Scratch of [`sort_by_element`], kept between steps so that re-sorting allocates nothing.
#[derive(Debug, Default)]
pub struct SortScratch {
    /// New index → old index.
    pub order: Vec<u32>,
    /// Old index → new index, for callers that need it.
    pub inverse: Vec<u32>,
    next: Vec<u32>,
    done: Vec<bool>,
}

/// Stable counting sort of the particles by element when some are out of order, permuting
/// every array in place (cycle by cycle). Returns true when it permuted; `scratch.order` then
/// holds the permutation (new index → old index).
pub fn sort_by_element<R: Real>(
    p: &mut Particles<R>,
    elements: usize,
    scratch: &mut SortScratch,
) -> bool {
    if p.element.windows(2).all(|w| w[0] <= w[1]) {
        return false;
    }
    let n = p.len();
    scratch.next.clear();
    scratch.next.resize(elements + 1, 0);
    for &e in &p.element {
        scratch.next[e as usize + 1] += 1;
    }
    for e in 0..elements {
        scratch.next[e + 1] += scratch.next[e];
    }
    scratch.order.resize(n, 0);
    for (i, &e) in p.element.iter().enumerate() {
        scratch.order[scratch.next[e as usize] as usize] = i as u32;
        scratch.next[e as usize] += 1;
    }
    struct Permute<'a> {
        order: &'a [u32],
        done: &'a mut Vec<bool>,
    }
    impl FieldVisitor for Permute<'_> {
        fn field<T: Value>(&mut self, field: Field, v: &mut Vec<T>) {
            match field.per_point {
                0 => {}
                1 => v.permute(self.order, self.done),
                k => permute_chunks(v, k, self.order, self.done),
            }
        }
    }
    p.visit_fields(&mut Permute {
        order: &scratch.order,
        done: &mut scratch.done,
    });
    true
}

/// `new[i] = old[order[i]]` for the `k`-value chunks of `v`, following the permutation's cycles
/// by swapping chunks (no scratch copy).
fn permute_chunks<T>(v: &mut [T], k: usize, order: &[u32], done: &mut Vec<bool>) {
    done.clear();
    done.resize(order.len(), false);
    for start in 0..order.len() {
        if done[start] {
            continue;
        }
        // Position i takes the chunk at order[i]; swapping i with order[i] moves the carried
        // start chunk along the cycle until it lands where order points back to start.
        let mut i = start;
        done[i] = true;
        while order[i] as usize != start {
            let j = order[i] as usize;
            let (lo, hi) = (i.min(j), i.max(j));
            let (a, b) = v.split_at_mut(hi * k);
            a[lo * k..lo * k + k].swap_with_slice(&mut b[..k]);
            done[j] = true;
            i = j;
        }
    }
}

/// An array that can be permuted in place.
trait Permutable {
    /// `new[i] = old[order[i]]`, following the permutation's cycles; `done` is scratch.
    fn permute(&mut self, order: &[u32], done: &mut Vec<bool>);
}

impl<T: Copy> Permutable for Vec<T> {
    fn permute(&mut self, order: &[u32], done: &mut Vec<bool>) {
        done.clear();
        done.resize(order.len(), false);
        for start in 0..order.len() {
            if done[start] {
                continue;
            }
            let first = self[start];
            let mut i = start;
            loop {
                done[i] = true;
                let j = order[i] as usize;
                if j == start {
                    self[i] = first;
                    break;
                }
                self[i] = self[j];
                i = j;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_permute_like_their_first_values() {
        // A permutation with a fixed point, a 2-cycle and a 4-cycle.
        let order = [0u32, 2, 1, 6, 3, 4, 5];
        let mut done = Vec::new();
        let mut single: Vec<u32> = (0..7).collect();
        single.permute(&order, &mut done);
        let mut chunks: Vec<u32> = (0..7)
            .flat_map(|i| [10 * i, 10 * i + 1, 10 * i + 2])
            .collect();
        permute_chunks(&mut chunks, 3, &order, &mut done);
        let want: Vec<u32> = single
            .iter()
            .flat_map(|&i| [10 * i, 10 * i + 1, 10 * i + 2])
            .collect();
        assert_eq!(chunks, want);
        assert_eq!(single, [0, 2, 1, 6, 3, 4, 5]);
    }

    #[test]
    fn in_place_permutation_matches_a_gather() {
        let order: Vec<u32> = vec![3, 0, 4, 1, 2, 6, 5, 7];
        let old: Vec<u32> = (10..18).collect();
        let mut v = old.clone();
        v.permute(&order, &mut Vec::new());
        let want: Vec<u32> = order.iter().map(|&i| old[i as usize]).collect();
        assert_eq!(v, want);
    }
}
