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
use crate::parallel::team::{balanced_ranges, Shared, Team};
use crate::real::Real;
use crate::state::particles::{Field, FieldVisitor, Particles, Value};

/// Widest slot (values per element node) a pass uses.
pub const WIDTH: usize = 12;

/// The threads' element ranges start at multiples of this many elements (the last ends with
/// the mesh), so that a sum over a block of consecutive elements is formed by one thread in
/// element order: per-block partial sums (the guard rails') are the same for any thread count,
/// and there are 64 times fewer of them to write and add than per-element ones.
pub const ELEMENT_BLOCK: usize = 64;

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
        let (ne, nn) = (mesh.elements(), mesh.nodes());
        let elem_start = element_starts(&p.element, ne);
        let element_ranges = aligned(
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
        for (e, c) in mesh.corners.iter().enumerate() {
            for (k, &n) in c.as_ref().iter().enumerate() {
                node_slot[fill[n as usize] as usize] = (E::NODES * e + k) as u32;
                fill[n as usize] += 1;
            }
        }
        let node_ranges = balanced_ranges(
            (0..nn).map(|n| u64::from(node_start[n + 1] - node_start[n])),
            threads,
        );
        let layout = Layout {
            elem_start,
            element_ranges,
            node_ranges,
            node_start,
            node_slot,
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
        let slots = Shared::new(slots);
        let ranges = &self.element_ranges;
        team.run(|k| {
            let r = ranges[k].clone();
            // SAFETY: the element ranges are disjoint, so are their slots.
            let mine = unsafe { slots.range(per_element * r.start..per_element * r.end) };
            for (own, e) in mine.chunks_exact_mut(per_element).zip(r) {
                own.fill(R::ZERO);
                element(e, own);
            }
        });
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

/// `ranges` (contiguous, covering `0..elements`) with every boundary between two moved to the
/// nearest multiple of [`ELEMENT_BLOCK`] (at most `elements`): a change of balance of at most
/// half a block per thread.
fn aligned(ranges: Vec<Range<usize>>, elements: usize) -> Vec<Range<usize>> {
    let round = |b: usize| ((b + ELEMENT_BLOCK / 2) / ELEMENT_BLOCK * ELEMENT_BLOCK).min(elements);
    let last = ranges.len() - 1;
    let mut start = 0;
    ranges
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let end = if k == last { elements } else { round(r.end) };
            let out = start..end;
            start = end;
            out
        })
        .collect()
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
