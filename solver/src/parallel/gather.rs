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
//!
//! On one process most nodes have all their elements in one thread's range. Their slots would be
//! written and read back only to be added in element order, which that thread's own element loop
//! already follows: it adds such a node's values straight into an accumulator per node instead
//! (the first element's as 0 + v, as the slot pass starts its sum from 0, so that even the
//! sign of a zero is the same). Only the nodes at the ranges' borders go through the slots, and
//! those that a piece another thread took shares with its owner's other pieces (`NodeSum`).
//! The sums are the same bits either way; the slots' bytes, the largest stream of the pass,
//! are spared for the interior (docs/design.md §5).

use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::element::mesh::Mesh;
use crate::element::tet4::Tet4;
use crate::element::Element;
use crate::parallel::avx2;
use crate::parallel::comm::Communicator;
use crate::parallel::exact::{self, ExactSum};
use crate::parallel::halo::Halo;
use crate::parallel::sort::{resort, SortScratch};
use crate::parallel::team::{aligned_to_blocks, balanced_ranges, Shared, Team};
use crate::real::Real;
use crate::state::particles::Particles;

/// Widest slot (values per element node) a pass uses: particle to grid's, the solid's 10 and
/// the liquid's 12 values of a tetrahedron's node.
pub const WIDTH: usize = 22;

pub use crate::parallel::team::ELEMENT_BLOCK;

/// Element blocks per chunk of the passes that hand out work while they run (1,024 elements,
/// about 4,000 points: a few dozen chunks per thread on a million points, each long enough
/// that claiming it costs nothing next to its work), at most: see [`MIN_CHUNKS`].
pub const CHUNK_BLOCKS: usize = 16;

/// Chunks per thread at least, where the thread has that many element blocks: a small model's
/// thread holds only a few chunks of [`CHUNK_BLOCKS`] (the 2,400-point BCN column collapse,
/// 4,600 elements: three per thread at two threads), too few to even out points whose update
/// costs differ (a plastic zone's Mohr-Coulomb returns), so its chunks are made smaller.
pub const MIN_CHUNKS: usize = 8;

/// Where the scatter cuts each thread's elements into pieces, in thousandths of the thread's
/// points: a first piece of three quarters, then two eighths. A thread takes its own pieces
/// in order, then the pieces still left of the others from their back ([`Team::run_pieces`]),
/// so a thread that its core slows down hands its last quarter to the others instead of
/// holding them at the barrier. The scatter's chunks are few and large, unlike the stress
/// pass's ([`CHUNK_BLOCKS`]): a node whose elements lie in two pieces that different threads
/// run goes through the slots, so every piece taken adds slot traffic (docs/design.md §5).
pub const SCATTER_CUTS: [u64; 2] = [750, 875];

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
    /// For each slot (NODES e + k), the node it adds straight into ([`DIRECT_FIRST`] set on the
    /// node's first element), or [`TO_SLOT`] for a node whose elements more than one thread
    /// holds (and for every slot on a rank of several, whose sums cross the halo). Every node
    /// it names is below `node_sum.len()`: the scatter indexes the accumulators unchecked on
    /// it.
    direct: Vec<u32>,
    /// `direct` for a piece another thread took from its owner: the entries of nodes whose
    /// elements lie in several pieces of the owner ([`NodeSum::Chain`]) go to their slots.
    direct_taken: Vec<u32>,
    /// How each node's sum is formed.
    node_sum: Vec<NodeSum>,
    /// Per thread: the first element of the pieces of its range that other threads took in
    /// the last scatter ([`Team::run_pieces`]: always the last pieces of the range), or
    /// `usize::MAX` where it ran all its own. Written by the scatter, read by the gather.
    taken_from: Vec<AtomicUsize>,
    /// The elements of each chunk that [`Team::run_chunks`] hands out: each thread's elements
    /// cut, in order, into pieces of [`CHUNK_BLOCKS`] whole blocks.
    chunks: Vec<Range<usize>>,
    /// The chunks of each thread.
    thread_chunks: Vec<Range<usize>>,
    /// The elements of each piece of the scatter ([`SCATTER_CUTS`]): contiguous, in order,
    /// whole blocks, covering the mesh.
    pieces: Vec<Range<usize>>,
    /// The pieces of each thread.
    thread_pieces: Vec<Range<usize>>,
    _types: std::marker::PhantomData<(R, E)>,
}

/// Per-node partial sums: room for `NODES × elements` slots of up to [`WIDTH`] values, then one
/// accumulator of up to [`WIDTH`] values per node. A pass of width W packs its slots (and its
/// accumulators) W values apart, so that it writes and reads W values per slot, not [`WIDTH`]
/// (a 2-wide pass moves a sixth of the bytes of a 12-wide one).
pub type Slots<R> = Vec<R>;

/// The first `len` values of `slots`, zeroed, as scratch for a pass that does not scatter
/// through them (the stencil passes of [`crate::basis`]): grown the first time it is short,
/// so that the time step allocates nothing after its first.
pub fn scratch<R: Real>(slots: &mut Slots<R>, len: usize) -> &mut [R] {
    if slots.len() < len {
        slots.resize(len, R::ZERO);
    }
    let out = &mut slots[..len];
    out.fill(R::ZERO);
    out
}

/// [`Layout`]'s `direct` entry of a slot that goes through the slots.
const TO_SLOT: u32 = u32::MAX;

/// Set in a `direct` entry on the node's first element: its accumulator starts there.
const DIRECT_FIRST: u32 = 1 << 31;

/// How a node's sum is formed from the scatter's values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NodeSum {
    /// Its slots, in element order (its elements lie in more than one thread's range).
    Slots,
    /// Its accumulator (all its elements lie in one piece).
    Direct,
    /// Its accumulator, then the slots of its elements in pieces other threads took, in
    /// element order (its elements lie in several pieces of one thread). The pieces a thread
    /// runs of its own are a first run of its range, run in order ([`Team::run_pieces`]), so
    /// the accumulator holds the sum of the node's first elements taken in element order, and
    /// the slots add the rest in the same order: the same bits as the slots alone.
    Chain,
}

/// Most nodes an element has (the scatter's element buffer is sized for it).
const MAX_NODES: usize = 4;

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
        let (pieces, thread_pieces) = pieces_of(&element_ranges, &elem_start);
        let (direct, direct_taken, node_sum) = if halo.is_none() {
            direct_slots::<E>(&pieces, &thread_pieces, &node_start, &node_slot)
        } else {
            let all = vec![TO_SLOT; E::NODES * ne];
            (all.clone(), all, vec![NodeSum::Slots; nn])
        };
        let taken_from = (0..threads).map(|_| AtomicUsize::new(usize::MAX)).collect();
        let (chunks, thread_chunks) = chunks_of(&element_ranges);
        let layout = Layout {
            elem_start,
            chunks,
            thread_chunks,
            pieces,
            thread_pieces,
            element_ranges,
            node_ranges,
            node_start,
            node_slot,
            owned_start,
            owned_node,
            halo: halo.clone(),
            order: halo.as_ref().map(|_| order.to_vec()),
            owned,
            direct,
            direct_taken,
            node_sum,
            taken_from,
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
            let mut next = 0;
            for (r, own) in self.element_ranges.iter().zip(&self.thread_pieces) {
                let p = &self.pieces[own.clone()];
                assert!(
                    p.first().map_or(r.is_empty(), |f| f.start == r.start)
                        && p.last().map_or(true, |l| l.end == r.end),
                    "a thread's pieces are not its elements"
                );
                for q in p {
                    assert!(
                        q.start == next && q.end > q.start && q.start % ELEMENT_BLOCK == 0,
                        "scatter pieces not contiguous, non-empty and on blocks"
                    );
                    next = q.end;
                }
            }
            assert_eq!(next, ne, "scatter pieces do not cover the mesh");
            assert!(
                self.elem_start.windows(2).all(|w| w[0] <= w[1]),
                "particle starts decrease"
            );
        }
    }

    /// After the points were located: sorts them by element again (stable, every per-point
    /// array, by the whole team) and re-reads where each element's points start, when a point
    /// changed element (`moved`) or the order changed ([`crate::parallel::sort`]). Returns
    /// true when the points were permuted; `scratch.order` then maps new indices to old ones.
    pub fn resort(
        &mut self,
        team: &Team,
        p: &mut Particles<R>,
        moved: bool,
        scratch: &mut SortScratch,
    ) -> bool {
        let permuted = resort(
            team,
            &self.element_ranges,
            &mut self.elem_start,
            p,
            moved,
            scratch,
        );
        self.debug_check();
        permuted
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

    /// Zeroed slots and node accumulators for this layout (allocated zeroed, so pages are
    /// placed by the threads that first write them).
    pub fn new_slots(&self) -> Slots<R> {
        vec![R::ZERO; self.accumulators() + WIDTH * self.node_sum.len()]
    }

    /// Where the node accumulators start in the slots.
    fn accumulators(&self) -> usize {
        WIDTH * E::NODES * (self.elem_start.len() - 1)
    }

    /// The share of element corners whose sums go through the slots (the rest add straight into
    /// their node's accumulator): what the slot traffic of a pass is scaled by. (A piece that
    /// another thread takes sends its nodes shared with the owner's other pieces through the
    /// slots too, only when it is taken.)
    pub fn slot_share(&self) -> f64 {
        let through = self.direct.iter().filter(|&&d| d == TO_SLOT).count();
        through as f64 / self.direct.len().max(1) as f64
    }

    /// The chunks of each thread, for [`Team::run_chunks`].
    pub fn thread_chunks(&self) -> &[Range<usize>] {
        &self.thread_chunks
    }

    /// Elements of chunk `c` (whole blocks, but for the last of a thread).
    pub fn chunk_elements(&self, c: usize) -> Range<usize> {
        self.chunks[c].clone()
    }

    /// Particles of chunk `c`.
    pub fn chunk_particles(&self, c: usize) -> Range<usize> {
        let r = &self.chunks[c];
        self.elem_start[r.start] as usize..self.elem_start[r.end] as usize
    }

    /// The element blocks of chunk `c`, which no other chunk's elements share.
    pub fn chunk_blocks(&self, c: usize) -> Range<usize> {
        let r = &self.chunks[c];
        r.start / ELEMENT_BLOCK..r.end.div_ceil(ELEMENT_BLOCK)
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

    /// Pass 1: for each element, on some thread, zeroes a buffer for the values of the element's
    /// nodes ([`Element::NODES`] slots of `W` values, one after the other), calls
    /// `element(e, points, buffer)` with the element's points (the range of
    /// [`Layout::particles_of`], read once by the scatter beside its own test of it;
    /// [`node_slots`] splits the buffer by node), and hands each node's values on:
    /// into the node's accumulator when all the node's elements lie in this piece
    /// ([`SCATTER_CUTS`]), or in pieces of this piece's thread that it runs itself, else into
    /// its slot (`NodeSum`). The pieces are handed out while the pass runs
    /// ([`Team::run_pieces`]), each to one thread, which takes its elements in order: `element`
    /// must write only what belongs to its element.
    ///
    /// An element without points must add nothing to its buffer (checked in debug builds):
    /// `element` is still called for it (for what else it records of the element), but its
    /// buffer is not read: its slots take zeros and its nodes' accumulators nothing, which
    /// are the same bits (an accumulator starts at `0 + v` and so is never −0, and `x + 0` is
    /// `x` for every other `x`), and the next element starts from that buffer, still zero. A
    /// mesh mostly void, as around a collapsing column or a run-out, then costs little per
    /// empty element.
    pub fn scatter<const W: usize, F>(&self, team: &Team, slots: &mut Slots<R>, element: F)
    where
        F: Fn(usize, Range<usize>, &mut [R]) + Sync,
    {
        self.scatter_with::<W, false, false, (), _>(
            team,
            slots,
            |_| (),
            |e, points, own, _| element(e, points, own),
        );
    }

    /// [`Layout::scatter`] with a state of each piece's own, made by `init(thread)` before the
    /// piece's first element and handed to every `element(e, points, buffer, state)` call of the
    /// piece, in element order (for sums a pass keeps beside its slots; a piece holds whole
    /// [`ELEMENT_BLOCK`]s).
    ///
    /// With `WIDE`, each thread's elements run compiled with AVX2 ([`avx2::call`]: `element`
    /// is inlined there, so pass a closure of its own to each instantiation); it panics where
    /// the processor lacks AVX2 (choose `WIDE` by [`avx2::use_avx2`]).
    ///
    /// With `WRITES`, `element` writes every value of its buffer for an element with points
    /// (sums it formed itself from 0, stored, rather than added into the buffer), so the
    /// buffer is not cleared after each element: its stale values are never read (an element
    /// without points still writes nothing, and its buffer is not read). In debug builds the
    /// buffer is filled with a marker before each such call and checked to hold none after.
    pub fn scatter_with<const W: usize, const WIDE: bool, const WRITES: bool, S, F>(
        &self,
        team: &Team,
        slots: &mut Slots<R>,
        init: impl Fn(usize) -> S + Sync,
        element: F,
    ) where
        F: Fn(usize, Range<usize>, &mut [R], &mut S) + Sync,
    {
        const { assert!(W <= WIDTH) };
        const { assert!(E::NODES <= MAX_NODES) };
        let per_element = E::NODES * W;
        let acc_at = self.accumulators();
        let nodes = self.node_sum.len();
        debug_assert_eq!(slots.len(), acc_at + WIDTH * nodes);
        // Every `direct` entry names a node below `nodes` (`direct_slots`), so this one check
        // bounds every accumulator the loop below hands values to.
        assert!(
            slots.len() >= acc_at + W * nodes,
            "slots too short for the accumulators"
        );
        let shared = Shared::new(slots);
        let pieces = &self.pieces;
        assert!(!WIDE || avx2::present(), "an AVX2 scatter without AVX2");
        for t in &self.taken_from {
            t.store(usize::MAX, Ordering::Relaxed);
        }
        let taken_from = &self.taken_from;
        // The team's broadcast orders the stores above before every claim, and its join the
        // claims' records before the gather reads them.
        team.run_pieces(&self.thread_pieces, |k, c, owner| {
            let r = pieces[c].clone();
            // A piece another thread took: its nodes shared with the owner's other pieces go
            // through their slots (the owner's pieces it runs itself come first, so the
            // smallest start taken is where the slots begin: `NodeSum::Chain`).
            let taken = k != owner;
            let direct = if taken {
                taken_from[owner].fetch_min(r.start, Ordering::Relaxed);
                &self.direct_taken
            } else {
                &self.direct
            };
            // SAFETY: the pieces are disjoint and each is handed out once, so are their slots.
            let mine = unsafe { shared.range(per_element * r.start..per_element * r.end) };
            let piece = Piece {
                elements: r,
                direct,
                slots: mine,
                shared: &shared,
            };
            let mut state = init(k);
            if WIDE {
                // SAFETY: the processor has AVX2 (asserted above).
                unsafe {
                    avx2::call(|| {
                        self.scatter_piece::<W, WRITES, S, F>(piece, &element, &mut state)
                    })
                }
            } else {
                self.scatter_piece::<W, WRITES, S, F>(piece, &element, &mut state)
            }
        });
        if let Some(h) = &self.halo {
            h.exchange(&mut slots[..], per_element);
        }
    }

    /// The elements of one piece of [`Layout::scatter_with`], in order: calls `element` on
    /// each and hands its buffer's values on to the element's slots or its nodes'
    /// accumulators. Inlined into the scatter, so that an AVX2 scatter's piece (and `element`
    /// with it) is compiled with AVX2.
    #[inline(always)]
    fn scatter_piece<const W: usize, const WRITES: bool, S, F>(
        &self,
        piece: Piece<'_, '_, R>,
        element: &F,
        state: &mut S,
    ) where
        F: Fn(usize, Range<usize>, &mut [R], &mut S),
    {
        let per_element = E::NODES * W;
        let (acc_at, nodes) = (self.accumulators(), self.node_sum.len());
        let Piece {
            elements: r,
            direct,
            slots: mine,
            shared,
        } = piece;
        // The buffer made here, not by the caller and handed in: the compiler then knows that
        // nothing else reaches it, and keeps more of `element`'s values in registers (the AVX2
        // passes of the dry bench ran 5 % fewer instructions, the whole run 2 % fewer).
        let mut buffer = [R::ZERO; WIDTH * MAX_NODES];
        let own = &mut buffer[..per_element];
        // A NaN with a payload no arithmetic produces (debug builds, `WRITES`).
        let marker = R::of(f64::from_bits(0x7ff4_0000_0bad_ca7e));
        // Without `WRITES` the buffer is zero at the top of the loop: it starts so, an element
        // without points leaves it so, and the others' values are cleared once handed on (runs
        // of empty elements, as in a void mesh, zero nothing). With `WRITES` it holds the last
        // element's values, which the next element with points overwrites and an element
        // without points leaves unread.
        // The piece's `direct` entries and point starts sliced once and walked beside its
        // slots, so that the loop indexes nothing (a void mesh's empty elements paid a bounds
        // check per access).
        let targets_of = direct[E::NODES * r.start..E::NODES * r.end].chunks_exact(E::NODES);
        let starts = &self.elem_start[r.start..=r.end];
        let bounds = starts.iter().zip(&starts[1..]);
        for (((slot, e), targets), (first, end)) in mine
            .chunks_exact_mut(per_element)
            .zip(r)
            .zip(targets_of)
            .zip(bounds)
        {
            if WRITES && cfg!(debug_assertions) && first != end {
                own.fill(marker);
            }
            element(e, *first as usize..*end as usize, own, state);
            if WRITES && cfg!(debug_assertions) && first != end {
                debug_assert!(
                    own.iter()
                        .all(|v| v.f64().to_bits() != marker.f64().to_bits()),
                    "element {e} left values of its buffer unwritten"
                );
            }
            if first == end {
                debug_assert!(
                    WRITES || own.iter().all(|v| v.f64().to_bits() == 0),
                    "element {e} has no points but added to its buffer"
                );
                // Only a slot or a node's first element takes zeros: most empty elements have
                // neither (the test of one bit, which `TO_SLOT` has too, unrolled over the
                // element's nodes).
                const { assert!(TO_SLOT & DIRECT_FIRST != 0) };
                if targets.iter().any(|&t| t & DIRECT_FIRST != 0) {
                    // SAFETY: as for `hand_on`.
                    unsafe { empty_element::<R, W>(slot, targets, shared, acc_at) };
                }
                continue;
            }
            // SAFETY: a node with a `direct` entry has every element in this piece
            // (`direct_slots`), which one thread takes in element order, so no other thread
            // touches its accumulator; a node whose elements lie in several pieces of one
            // thread is added to only by that thread, which runs the pieces it keeps one after
            // the other in element order (the pieces others take use `direct_taken`, which
            // sends the node's values to slots). The accumulators lie past every slot; every
            // node named is below `nodes` (`direct_slots`), whose accumulators the slots hold
            // (asserted by the scatter).
            unsafe { hand_on::<R, W>(own, slot, targets, shared, (acc_at, nodes)) };
            if !WRITES {
                own.fill(R::ZERO);
            }
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

    /// Both passes: [`Layout::scatter_with`] with `element`, which writes every value of its
    /// buffer for an element with points (`WRITES`), then [`Layout::gather`] handing each
    /// node's `W` sums to `node` as a slice (so that one `node` serves passes of any width).
    pub fn sum_to_nodes<const W: usize, const WIDE: bool, F, G>(
        &self,
        team: &Team,
        slots: &mut Slots<R>,
        element: F,
        node: G,
    ) where
        F: Fn(usize, Range<usize>, &mut [R]) + Sync,
        G: Fn(usize, &[R]) + Sync,
    {
        self.scatter_with::<W, WIDE, true, (), _>(
            team,
            slots,
            |_| (),
            |e, points, own, _| element(e, points, own),
        );
        self.gather::<W, _>(team, slots, |n, s| node(n, &s));
    }

    /// Pass 2: on every thread, for each node of its range, the sum of the first `W` values of
    /// the node's slots, in element order, handed to `node(n, sum)`.
    pub fn gather<const W: usize, F>(&self, team: &Team, slots: &Slots<R>, node: F)
    where
        F: Fn(usize, [R; W]) + Sync,
    {
        let acc_at = self.accumulators();
        let slot_sum = |sum: &mut [R; W], s: u32| {
            let v = &slots[W * s as usize..W * s as usize + W];
            for c in 0..W {
                sum[c] += v[c];
            }
        };
        team.run(|k| {
            for n in self.node_ranges[k].clone() {
                let kind = self.node_sum[n];
                if kind == NodeSum::Slots {
                    let mut sum = [R::ZERO; W];
                    for &s in &self.node_slot
                        [self.node_start[n] as usize..self.node_start[n + 1] as usize]
                    {
                        slot_sum(&mut sum, s);
                    }
                    node(n, sum);
                    continue;
                }
                // Sliced once: one bounds check per node, not one per value.
                let acc = &slots[acc_at + W * n..acc_at + W * n + W];
                let mut sum: [R; W] = std::array::from_fn(|c| acc[c]);
                if kind == NodeSum::Chain {
                    let list = &self.node_slot
                        [self.node_start[n] as usize..self.node_start[n + 1] as usize];
                    let element = |s: u32| s as usize / E::NODES;
                    let first = element(list[0]);
                    let home = self.element_ranges.partition_point(|r| r.end <= first);
                    let from = self.taken_from[home].load(Ordering::Relaxed);
                    if element(list[list.len() - 1]) >= from {
                        // Some of its elements' pieces were taken: their slots follow the
                        // accumulator (which holds nothing when the first was taken too).
                        if first >= from {
                            sum = [R::ZERO; W];
                        }
                        for &s in list.iter().filter(|&&s| element(s) >= from) {
                            slot_sum(&mut sum, s);
                        }
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

/// The `direct` entries of [`Layout`] (and how each node's sum is formed) for one process,
/// from the scatter's `pieces` and each thread's run of them (`thread_pieces`): a node all of
/// whose slots (`node_slot[node_start[n]..node_start[n + 1]]`, in element order) belong to
/// elements of one piece adds straight into its accumulator, its first element marked; one
/// whose slots lie in several pieces of one thread does too, but through its slots in the
/// entries for a taken piece (the second table); the others go through their slots.
fn direct_slots<E: Element>(
    pieces: &[Range<usize>],
    thread_pieces: &[Range<usize>],
    node_start: &[u32],
    node_slot: &[u32],
) -> (Vec<u32>, Vec<u32>, Vec<NodeSum>) {
    let elements = pieces.last().map_or(0, |r| r.end);
    // Each element's piece and thread.
    let mut piece = vec![0u32; elements];
    let mut thread = vec![0u32; elements];
    for (k, own) in thread_pieces.iter().enumerate() {
        for c in own.clone() {
            piece[pieces[c].clone()].fill(c as u32);
            thread[pieces[c].clone()].fill(k as u32);
        }
    }
    let nodes = node_start.len() - 1;
    assert!(
        nodes < DIRECT_FIRST as usize,
        "more nodes than a slot entry can name"
    );
    let mut direct = vec![TO_SLOT; E::NODES * elements];
    let mut node_sum = vec![NodeSum::Slots; nodes];
    let element = |s: u32| s as usize / E::NODES;
    for n in 0..nodes {
        let list = &node_slot[node_start[n] as usize..node_start[n + 1] as usize];
        let Some(&first) = list.first() else {
            continue;
        };
        let (home, home_piece) = (thread[element(first)], piece[element(first)]);
        if list.iter().any(|&s| thread[element(s)] != home) {
            continue;
        }
        debug_assert!(
            list.windows(2).all(|w| w[0] < w[1]),
            "a node's slots out of element order"
        );
        node_sum[n] = if list.iter().all(|&s| piece[element(s)] == home_piece) {
            NodeSum::Direct
        } else {
            NodeSum::Chain
        };
        direct[first as usize] = n as u32 | DIRECT_FIRST;
        for &s in &list[1..] {
            direct[s as usize] = n as u32;
        }
    }
    // A taken piece runs beside its owner's: only nodes within one piece add straight in.
    let mut direct_taken = direct.clone();
    for (t, &d) in direct_taken.iter_mut().zip(&direct) {
        if d != TO_SLOT && node_sum[(d & !DIRECT_FIRST) as usize] == NodeSum::Chain {
            *t = TO_SLOT;
        }
    }
    (direct, direct_taken, node_sum)
}

/// One piece of a scatter, as the thread that runs it sees it.
struct Piece<'a, 's, R> {
    /// Its elements.
    elements: Range<usize>,
    /// Where each slot of the layout goes: the layout's `direct`, or `direct_taken` for a
    /// piece another thread took.
    direct: &'a [u32],
    /// Its elements' slots.
    slots: &'a mut [R],
    /// The slots and accumulators, for the accumulators.
    shared: &'a Shared<'s, R>,
}

/// Hands on the values of one element with points (`own`, a node's `W` values after
/// another): into the node's slot in `slot` where its `targets` entry is [`TO_SLOT`], else
/// into the node's accumulator (`acc_at`: where the accumulators start in `shared`; `nodes`:
/// their number), started there on the node's first element ([`DIRECT_FIRST`]).
///
/// A node's values as one array of `W`: its copy or sum is formed whole and then stored, so
/// the compiler moves it in vector registers (element by element through slices it cannot
/// tell apart from the accumulators, it loaded, added and stored each value on its own, and
/// called `memcpy` for a slot's copy).
///
/// # Safety
/// No other thread touches the accumulators of `targets`' direct nodes while this runs, and
/// each lies inside `shared`.
#[inline(always)]
unsafe fn hand_on<R: Real, const W: usize>(
    own: &[R],
    slot: &mut [R],
    targets: &[u32],
    shared: &Shared<'_, R>,
    (acc_at, nodes): (usize, usize),
) {
    for ((values, to), &target) in own
        .chunks_exact(W)
        .zip(slot.chunks_exact_mut(W))
        .zip(targets)
    {
        let values: &[R; W] = values.try_into().expect("chunks of W");
        if target == TO_SLOT {
            let to: &mut [R; W] = to.try_into().expect("chunks of W");
            *to = *values;
            continue;
        }
        let n = (target & !DIRECT_FIRST) as usize;
        debug_assert!(n < nodes, "a direct entry past the nodes");
        // SAFETY: the caller's.
        let acc = unsafe { shared.array_unchecked::<W>(acc_at + W * n) };
        *acc = if target & DIRECT_FIRST != 0 {
            // 0 + v, not v: the slot pass's sum starts from 0 (and 0 + -0 is +0).
            values.map(|v| R::ZERO + v)
        } else {
            std::array::from_fn(|i| acc[i] + values[i])
        };
    }
}

/// The scatter's hand-on for an element without points (its buffer all zeros): its slots
/// take zeros, a node's accumulator that starts at it zero, and the other accumulators
/// nothing (`x + 0` is `x` for every `x` an accumulator holds: it starts at `0 + v`, never
/// −0). Kept out of the element loop, which inlines each pass's element there.
///
/// # Safety
/// `acc_at` and `targets` as in [`Layout::scatter_with`]: no other thread touches the
/// accumulators of `targets`' direct nodes while this runs.
#[inline(never)]
unsafe fn empty_element<R: Real, const W: usize>(
    slot: &mut [R],
    targets: &[u32],
    shared: &Shared<'_, R>,
    acc_at: usize,
) {
    for (to, &target) in slot.chunks_exact_mut(W).zip(targets) {
        if target == TO_SLOT {
            to.fill(R::ZERO);
        } else if target & DIRECT_FIRST != 0 {
            let n = (target & !DIRECT_FIRST) as usize;
            // SAFETY: the caller's.
            *unsafe { shared.array::<W>(acc_at + W * n) } = [R::ZERO; W];
        }
    }
}

/// The threads' element ranges cut into chunks of [`CHUNK_BLOCKS`] blocks, or fewer so that a
/// thread has [`MIN_CHUNKS`] (the ranges start on block boundaries, so every chunk holds whole
/// blocks but a thread's last): the chunks, and each thread's.
fn chunks_of(ranges: &[Range<usize>]) -> (Vec<Range<usize>>, Vec<Range<usize>>) {
    let mut chunks = Vec::new();
    let mut own = Vec::with_capacity(ranges.len());
    for r in ranges {
        let blocks = r.len().div_ceil(ELEMENT_BLOCK);
        let size = blocks.div_ceil(MIN_CHUNKS).clamp(1, CHUNK_BLOCKS) * ELEMENT_BLOCK;
        let first = chunks.len();
        let mut e = r.start;
        while e < r.end {
            chunks.push(e..(e + size).min(r.end));
            e += size;
        }
        own.push(first..chunks.len());
    }
    (chunks, own)
}

/// Each thread's elements cut into the scatter's pieces at [`SCATTER_CUTS`] of its points, the
/// cuts on block boundaries and empty pieces left out (a team of one keeps one piece): the
/// pieces, and each thread's.
fn pieces_of(
    ranges: &[Range<usize>],
    elem_start: &[u32],
) -> (Vec<Range<usize>>, Vec<Range<usize>>) {
    let mut pieces = Vec::new();
    let mut own = Vec::with_capacity(ranges.len());
    let cuts: &[u64] = if ranges.len() > 1 { &SCATTER_CUTS } else { &[] };
    for r in ranges {
        let first = pieces.len();
        let points = |e: usize| u64::from(elem_start[e] - elem_start[r.start]);
        let total = points(r.end);
        let mut start = r.start;
        for &cut in cuts {
            // The first block boundary past the cut's share of the points.
            let want = total * cut / 1000;
            let mut end = start;
            while end < r.end && points(end) < want {
                end = (end + ELEMENT_BLOCK).min(r.end);
            }
            if end > start && end < r.end {
                pieces.push(start..end);
                start = end;
            }
        }
        if start < r.end {
            pieces.push(start..r.end);
        }
        own.push(first..pieces.len());
    }
    (pieces, own)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::mesh::TetMesh;
    use crate::parallel::team::Pin;
    use mpm_shared::{generate, ElementType};
    use std::sync::atomic::AtomicU64;

    /// Points in element order, 0 to 3 per element (some elements empty).
    fn points_of(elements: usize) -> Particles<f64> {
        let element: Vec<u32> = (0..elements as u32)
            .flat_map(|e| std::iter::repeat_n(e, (e as usize * 7 + e as usize / 5) % 4))
            .collect();
        Particles::at_rest(element)
    }

    /// A value whose sums depend on the order they are taken in: magnitudes 1e-8 to 1e8.
    fn value(e: usize, k: usize, c: usize) -> f64 {
        let h = ((e * 4 + k) * 3 + c) as u64 * 2_654_435_761 % 1_000_003;
        (h as f64 / 7.0 - 70_000.0) * 10f64.powi((h % 17) as i32 - 8)
    }

    /// Each node's sum of [`value`] over its element corners that have points, scattered and
    /// gathered on `layout`; `slow(thread, piece owner, element)` the elements that sleep.
    fn node_sums(
        team: &Team,
        layout: &Layout<f64, Tet4>,
        slow: impl Fn(usize, usize) -> bool + Sync,
    ) -> Vec<[u64; 3]> {
        let mut slots = layout.new_slots();
        let thread_of = |e: usize| {
            layout
                .element_ranges
                .iter()
                .position(|r| r.contains(&e))
                .unwrap()
        };
        layout.scatter_with::<3, false, false, usize, _>(
            team,
            &mut slots,
            |k| k,
            |e, points, own, &mut k| {
                if points.is_empty() {
                    return;
                }
                // A slow element waits until another thread took a piece of its thread's (at
                // most 2 s: a loaded machine may start the workers late).
                let owner = thread_of(e);
                if slow(owner, e) && k == owner {
                    let start = std::time::Instant::now();
                    while layout.taken_from[owner].load(Ordering::Relaxed) == usize::MAX
                        && start.elapsed().as_secs() < 2
                    {
                        std::thread::sleep(std::time::Duration::from_millis(1));
                    }
                }
                for (kk, to) in own.chunks_exact_mut(3).enumerate() {
                    for (c, t) in to.iter_mut().enumerate() {
                        *t += value(e, kk, c);
                    }
                }
            },
        );
        let sums: Vec<[AtomicU64; 3]> = (0..layout.node_sum.len())
            .map(|_| std::array::from_fn(|_| AtomicU64::new(0)))
            .collect();
        layout.gather::<3, _>(team, &slots, |n, s| {
            for c in 0..3 {
                sums[n][c].store(s[c].to_bits(), Ordering::Relaxed);
            }
        });
        sums.iter()
            .map(|s| std::array::from_fn(|c| s[c].load(Ordering::Relaxed)))
            .collect()
    }

    #[test]
    fn taken_pieces_give_the_sums_of_one_thread_bit_for_bit() {
        let mesh =
            TetMesh::new(&generate::box_mesh([8, 8, 8], [1.0; 3], ElementType::Tet4)).unwrap();
        let p = points_of(mesh.elements());
        let one = Layout::new(&mesh, &p, 1);
        let want = node_sums(&Team::new(1, Pin::None).unwrap(), &one, |_, _| false);
        for threads in [2, 3] {
            let team = Team::new(threads, Pin::None).unwrap();
            let layout = one.for_threads(&mesh, &p, threads);
            assert!(
                layout.node_sum.contains(&NodeSum::Chain),
                "no node spans two pieces of a thread"
            );
            // Nobody slow; thread 0 slow on its first element (the others take its last
            // pieces); every thread but the last slow.
            for slow_threads in [0, 1, threads - 1] {
                let first: Vec<usize> = (0..threads)
                    .map(|k| {
                        let r = layout.element_ranges[k].clone();
                        r.clone()
                            .find(|&e| p.element.contains(&(e as u32)))
                            .unwrap()
                    })
                    .collect();
                let got = node_sums(&team, &layout, |k, e| k < slow_threads && e == first[k]);
                assert_eq!(got, want, "{threads} threads, {slow_threads} slow");
                let taken = layout.taken_from[0].load(Ordering::Relaxed) != usize::MAX;
                if slow_threads > 0 {
                    assert!(taken, "{threads} threads: no piece of thread 0 was taken");
                }
            }
        }
    }

    #[test]
    fn chunks_cut_each_thread_in_whole_blocks() {
        let size = CHUNK_BLOCKS * ELEMENT_BLOCK;
        let large = 8 * size;
        let ranges = [
            0..large + 64,
            large + 64..large + 64,
            large + 64..large + 2 * size + 100,
        ];
        let (chunks, own) = chunks_of(&ranges);
        // The first thread: eight chunks of the largest size and its last block.
        let mut expected: Vec<Range<usize>> = (0..8).map(|c| c * size..(c + 1) * size).collect();
        expected.push(large..large + 64);
        // The third: 34 blocks (its last part-filled), chunks of 5 blocks (8 × 5 ≥ 34): six
        // and the rest.
        let (start, five) = (large + 64, 5 * ELEMENT_BLOCK);
        for c in 0..6 {
            expected.push(start + c * five..start + (c + 1) * five);
        }
        expected.push(start + 6 * five..large + 2 * size + 100);
        assert_eq!(chunks, expected);
        assert_eq!(own, [0..9, 9..9, 9..16]);
        // A small thread: a chunk per block.
        let small = std::iter::once(0..3 * ELEMENT_BLOCK - 5).collect::<Vec<_>>();
        let (chunks, own) = chunks_of(&small);
        assert_eq!(chunks, [0..64, 64..128, 128..187]);
        assert_eq!(own.len(), 1);
        assert_eq!(own[0], 0..3);
    }

    #[test]
    fn pieces_cut_each_thread_at_its_shares_of_points_on_blocks() {
        // Two threads of 64 blocks each, one point per element but for a crowded block 60
        // (ten per element), and a third thread with nothing.
        let elements = 128 * ELEMENT_BLOCK;
        let mut elem_start = vec![0u32; elements + 1];
        for e in 0..elements {
            let here = if e / ELEMENT_BLOCK == 60 { 10 } else { 1 };
            elem_start[e + 1] = elem_start[e] + here;
        }
        let ranges = [
            0..64 * ELEMENT_BLOCK,
            64 * ELEMENT_BLOCK..elements,
            elements..elements,
        ];
        let (pieces, own) = pieces_of(&ranges, &elem_start);
        assert_eq!(own, [0..3, 3..6, 6..6]);
        let b = |k: usize| k * ELEMENT_BLOCK;
        // Thread 0 holds 63 * 64 + 640 = 4,672 points: 3/4 of them (3,504) are reached at the
        // end of block 54 (3,520), 7/8 (4,088) only past the crowded block 60 (4,480).
        assert_eq!(pieces[0..3], [0..b(55), b(55)..b(61), b(61)..b(64)]);
        // Thread 1, one point per element: 48 blocks, then 8 and 8.
        assert_eq!(
            pieces[3..6],
            [b(64)..b(112), b(112)..b(120), b(120)..b(128)]
        );
        for w in pieces.windows(2) {
            assert_eq!(w[0].end, w[1].start);
            assert_eq!(w[0].end % ELEMENT_BLOCK, 0);
        }
        // A team of one: one piece.
        let one_thread: [Range<usize>; 1] = [Range {
            start: 0,
            end: elements,
        }];
        let (pieces, own) = pieces_of(&one_thread, &elem_start);
        assert_eq!(pieces.len(), 1);
        assert_eq!((pieces[0].clone(), own[0].clone()), (0..elements, 0..1));
    }

    #[test]
    fn nodes_of_one_thread_sum_directly_and_border_nodes_through_slots() {
        // Three tetrahedra in a row: 0 (nodes 0 1 2 3), 1 (1 2 3 4), 2 (2 3 4 5); thread 0
        // holds elements 0 and 1, thread 1 element 2.
        let corners = [[0u32, 1, 2, 3], [1, 2, 3, 4], [2, 3, 4, 5]];
        let mut node_start = vec![0u32; 7];
        for c in &corners {
            for &n in c {
                node_start[n as usize + 1] += 1;
            }
        }
        for n in 0..6 {
            node_start[n + 1] += node_start[n];
        }
        let mut fill = node_start.clone();
        let mut node_slot = vec![0u32; 12];
        for (e, c) in corners.iter().enumerate() {
            for (k, &n) in c.iter().enumerate() {
                node_slot[fill[n as usize] as usize] = (4 * e + k) as u32;
                fill[n as usize] += 1;
            }
        }
        let (direct, taken, nodes) =
            direct_slots::<Tet4>(&[0..2, 2..3], &[0..1, 1..2], &node_start, &node_slot);
        assert_eq!(direct, taken);
        // Nodes 0 and 1 are thread 0's alone, 5 thread 1's; 2, 3 and 4 straddle the border.
        use NodeSum::{Chain, Direct, Slots};
        assert_eq!(nodes, [Direct, Direct, Slots, Slots, Slots, Direct]);
        let first = |n: u32| n | DIRECT_FIRST;
        let on_owner = [
            first(0),
            first(1),
            TO_SLOT,
            TO_SLOT,
            1,
            TO_SLOT,
            TO_SLOT,
            TO_SLOT,
            TO_SLOT,
            TO_SLOT,
            TO_SLOT,
            first(5),
        ];
        assert_eq!(direct, on_owner);
        // Thread 0's elements in two pieces: node 1, on elements 0 and 1, chains from one to
        // the other; node 0 lies in one piece.
        let (direct, taken, nodes) =
            direct_slots::<Tet4>(&[0..1, 1..2, 2..3], &[0..2, 2..3], &node_start, &node_slot);
        assert_eq!(nodes, [Direct, Chain, Slots, Slots, Slots, Direct]);
        // On the owner, the entries of the one-piece-per-thread layout.
        assert_eq!(direct, on_owner);
        // In a piece another thread took, node 1 goes through its slots.
        let mut on_taker = on_owner;
        on_taker[1] = TO_SLOT;
        on_taker[4] = TO_SLOT;
        assert_eq!(taken, on_taker);
        // One thread: every node direct, each first on its first element.
        let one_thread: [Range<usize>; 1] = [Range { start: 0, end: 3 }];
        let one_thread_pieces: [Range<usize>; 1] = [Range { start: 0, end: 1 }];
        let (direct, _, nodes) =
            direct_slots::<Tet4>(&one_thread, &one_thread_pieces, &node_start, &node_slot);
        assert!(nodes.iter().all(|&d| d == Direct));
        assert_eq!(direct[4..8], [1, 2, 3, first(4)]);
    }
}
