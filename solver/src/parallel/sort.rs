//! Keeping the points sorted by element after they move (docs/design.md §5), on every thread.
//!
//! The step's passes walk elements and, within each, its points; so after the points are
//! located, the points must again be sorted by element, in a stable order (points of one
//! element keep their relative order), which makes the new order a function of the old one
//! alone: the same for any thread count. In a quasi-static run few points change element and
//! those that do stay in order, and only where each element's points start is read again; in a
//! collapse or a run-out points cross element faces out of the curve's order at nearly every
//! step, and every per-point array is permuted. Both are done by the whole team:
//!
//! 1. Each thread checks that its share of the points is in order.
//! 2. In order: each thread finds where the points of its elements start (a merge of its
//!    elements with the sorted points).
//! 3. Out of order, a stable counting sort in three passes: each thread counts its points by
//!    the thread whose elements they now lie in; a prefix over that small matrix gives each
//!    (source, destination) pair a place; each thread moves its points' indices there, in
//!    index order; each destination thread then sorts its arrivals by element (they arrive in
//!    index order, so the sort is stable) and writes where its elements' points start.
//! 4. Every per-point array is gathered in the new order into a spare array of its type, each
//!    thread its own new range, and the two are swapped: the old array is the spare for the
//!    next array of that type. The spares (one per value type, about 90 bytes per point in
//!    f64) are kept once a run has re-sorted, so that a re-sort allocates nothing; the
//!    gather and the swap move half the bytes that a gather and a copy back would.

use std::any::{Any, TypeId};
use std::ops::Range;

use crate::parallel::team::{Shared, Team};
use crate::real::Real;
use crate::state::particles::{Field, FieldVisitor, Particles, Value};

/// Scratch of [`resort`], kept between steps: a re-sort allocates only the first time it needs
/// more room than before.
#[derive(Debug, Default)]
pub struct SortScratch {
    /// New index → old index (after a re-sort that permuted).
    pub order: Vec<u32>,
    /// Old index → new index, for callers that need it.
    pub inverse: Vec<u32>,
    /// Old indices grouped by the thread whose elements they now lie in.
    stage: Vec<u32>,
    /// Threads × threads: points of source thread t going to thread d, then where they go.
    counts: Vec<u32>,
    /// Per element: a cursor of the counting sort.
    next: Vec<u32>,
    /// Per thread: whether its share of the points is in order.
    in_order: Vec<bool>,
    /// A spare array per value type and values per point: each per-point array is gathered
    /// into its spare in the new order, and the two are swapped (no copy back).
    spares: Spares,
}

/// Spare arrays, one per value type and values per point, held without knowing the types.
#[derive(Default)]
struct Spares(Vec<((TypeId, usize), Box<dyn Any + Send + Sync>)>);

impl std::fmt::Debug for Spares {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Spares({} arrays)", self.0.len())
    }
}

impl Spares {
    /// The spare of `T` arrays of `k` values per point (empty the first time).
    fn take<T: Send + Sync + 'static>(&mut self, k: usize) -> Vec<T> {
        let key = (TypeId::of::<T>(), k);
        self.0
            .iter_mut()
            .find(|(id, _)| *id == key)
            .and_then(|(_, b)| b.downcast_mut::<Vec<T>>())
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// Keeps `v` as the spare of `T` arrays of `k` values per point.
    fn put<T: Send + Sync + 'static>(&mut self, k: usize, v: Vec<T>) {
        let key = (TypeId::of::<T>(), k);
        // Into the box already there (emptied by `take`): no allocation after the first time.
        let slot = self
            .0
            .iter_mut()
            .find(|(id, _)| *id == key)
            .and_then(|(_, b)| b.downcast_mut::<Vec<T>>());
        match slot {
            Some(slot) => *slot = v,
            None => self.0.push((key, Box::new(v))),
        }
    }
}

/// Whether `v` never decreases. Checked every step on every point, so taken in runs of 256
/// whose comparisons are all made (no exit at the first pair out of order), which the
/// compiler turns into vector compares: 7 instructions per point became under one.
fn non_decreasing(v: &[u32]) -> bool {
    const RUN: usize = 256;
    let Some(pairs) = v.len().checked_sub(1) else {
        return true;
    };
    let (before, after) = (&v[..pairs], &v[1..]);
    before
        .chunks(RUN)
        .zip(after.chunks(RUN))
        .all(|(a, b)| a.iter().zip(b).fold(true, |ok, (x, y)| ok & (x <= y)))
}

/// Re-sorts the points `p` by element (stable) after they were located, updating `elem_start`
/// (the first point of each element, `elements + 1` long) when a point changed element
/// (`moved`) or the order changed. `ranges`: each thread's elements (contiguous, covering
/// every element, one per thread of `team`). Returns true when the points were permuted;
/// `scratch.order` then maps new indices to old ones.
pub fn resort<R: Real>(
    team: &Team,
    ranges: &[Range<usize>],
    elem_start: &mut [u32],
    p: &mut Particles<R>,
    moved: bool,
    scratch: &mut SortScratch,
) -> bool {
    let threads = team.threads;
    assert_eq!(ranges.len(), threads, "an element range per thread");
    let elements = elem_start.len() - 1;
    let n = p.len();
    let sort = Sort {
        team,
        ranges,
        element: &p.element,
    };
    // 1. Is every share in order, and each share's last point before the next share's first?
    if sort.in_order(&mut scratch.in_order) {
        if moved {
            starts_of_sorted(team, ranges, elem_start, &p.element);
        }
        return false;
    }
    // 2. Stable counting sort of the indices, by destination thread, then by element.
    scratch.counts.clear();
    scratch.counts.resize(threads * threads, 0);
    scratch.stage.resize(n, 0);
    scratch.order.resize(n, 0);
    scratch.next.resize(elements + 1, 0);
    sort.count(&mut scratch.counts);
    let placed = places(&mut scratch.counts, threads);
    debug_assert_eq!(placed as usize, n);
    sort.stage(&mut scratch.counts, &mut scratch.stage);
    sort.by_element(scratch, elem_start);
    debug_assert!(
        is_permutation(&scratch.order),
        "the order is not a permutation"
    );
    // 3. Every per-point array in the new order.
    p.visit_fields(&mut Permute {
        team,
        ranges,
        elem_start,
        order: &scratch.order,
        spares: &mut scratch.spares,
    });
    true
}

/// The steps of [`resort`] over the points' elements: each thread takes a share of the points
/// in index order, and sends each point to the thread whose elements (`ranges`) hold it.
struct Sort<'a> {
    team: &'a Team,
    ranges: &'a [Range<usize>],
    /// Each point's element.
    element: &'a [u32],
}

impl Sort<'_> {
    /// The points of thread `t`'s share.
    #[inline(always)]
    fn share(&self, t: usize) -> Range<usize> {
        let (n, threads) = (self.element.len(), self.team.threads);
        t * n / threads..(t + 1) * n / threads
    }

    /// The thread whose elements hold element `e`, for a point of thread `t`'s share: most
    /// points stay in the thread's own elements, so those are looked at first.
    #[inline(always)]
    fn destination(&self, t: usize, e: u32) -> usize {
        if self.ranges[t].contains(&(e as usize)) {
            t
        } else {
            self.ranges.partition_point(|r| r.end <= e as usize)
        }
    }

    /// Whether every point's element is at least its predecessor's: each thread checks its
    /// share and the first point of the next share, recording its answer in `in_order`.
    fn in_order(&self, in_order: &mut Vec<bool>) -> bool {
        let (element, n) = (self.element, self.element.len());
        in_order.resize(self.team.threads, true);
        {
            let in_order = Shared::new(in_order);
            self.team.run(|t| {
                let r = self.share(t);
                let upto = (r.end + 1).min(n);
                let ok = non_decreasing(&element[r.start..upto]);
                // SAFETY: slot t is this thread's only.
                unsafe { in_order.write(t, ok) };
            });
        }
        in_order.iter().all(|&ok| ok)
    }

    /// Counts each thread's points by destination into row t of `counts` (threads × threads,
    /// zero).
    fn count(&self, counts: &mut [u32]) {
        let threads = self.team.threads;
        let counts = Shared::new(counts);
        self.team.run(|t| {
            // SAFETY: row t of the matrix is this thread's only.
            let row = unsafe { counts.range(t * threads..(t + 1) * threads) };
            for &e in &self.element[self.share(t)] {
                row[self.destination(t, e)] += 1;
            }
        });
    }

    /// Each thread's point indices into `stage` at its places for each destination, in index
    /// order: `counts` holds the places ([`places`]) and is left holding each pair's end.
    fn stage(&self, counts: &mut [u32], stage: &mut [u32]) {
        let threads = self.team.threads;
        let counts = Shared::new(counts);
        let stage = Shared::new(stage);
        self.team.run(|t| {
            // SAFETY: row t of the matrix is this thread's only.
            let cursor = unsafe { counts.range(t * threads..(t + 1) * threads) };
            let r = self.share(t);
            for (i, &e) in r.clone().zip(&self.element[r]) {
                let d = self.destination(t, e);
                // SAFETY: the prefix gave each (source, destination) pair its own places, and
                // each source writes only its own pairs' places.
                unsafe { stage.write(cursor[d] as usize, i as u32) };
                cursor[d] += 1;
            }
        });
    }

    /// Each destination thread sorts its arrivals in `scratch.stage` by element into
    /// `scratch.order` (stable: they arrived in index order), and writes where its elements'
    /// points start into `elem_start`. `scratch.counts` holds each (source, destination)
    /// pair's end ([`Sort::stage`]).
    fn by_element(&self, scratch: &mut SortScratch, elem_start: &mut [u32]) {
        let (threads, n) = (self.team.threads, self.element.len());
        let elements = elem_start.len() - 1;
        let element = self.element;
        let counts = &scratch.counts;
        let stage = &scratch.stage;
        // Destination d's points end where the last source's do, and start where d - 1's end.
        let end_of = |d: usize| counts[(threads - 1) * threads + d] as usize;
        let starts = Shared::new(elem_start);
        let next = Shared::new(&mut scratch.next);
        let order = Shared::new(&mut scratch.order);
        self.team.run(|d| {
            let from = if d == 0 { 0 } else { end_of(d - 1) };
            let to = end_of(d);
            let er = self.ranges[d].clone();
            // SAFETY: the element range and the new point range of thread d are its only (the
            // ranges are disjoint, and the prefix makes the point ranges so).
            let (start, cursor, out) = unsafe {
                (
                    starts.range(er.clone()),
                    next.range(er.clone()),
                    order.range(from..to),
                )
            };
            cursor.fill(0);
            for &i in &stage[from..to] {
                cursor[element[i as usize] as usize - er.start] += 1;
            }
            let mut s = from as u32;
            for (st, c) in start.iter_mut().zip(cursor.iter_mut()) {
                let count = *c;
                *st = s;
                *c = s;
                s += count;
            }
            for &i in &stage[from..to] {
                let c = &mut cursor[element[i as usize] as usize - er.start];
                out[*c as usize - from] = i;
                *c += 1;
            }
            if d == threads - 1 {
                // SAFETY: the entry past the last element is the last thread's only.
                unsafe { starts.write(elements, n as u32) };
            }
        });
    }
}

/// Turns `counts` (threads × threads: points of source t going to destination d) into where
/// each pair's points go: destination d's points start after those of d - 1, and within
/// them, source t's after those of t - 1. Returns the number of points placed.
fn places(counts: &mut [u32], threads: usize) -> u32 {
    let mut at = 0u32;
    for d in 0..threads {
        for t in 0..threads {
            let c = counts[t * threads + d];
            counts[t * threads + d] = at;
            at += c;
        }
    }
    at
}

/// Where each element's points start, for points in order: each thread merges its elements
/// with the points.
fn starts_of_sorted(team: &Team, ranges: &[Range<usize>], elem_start: &mut [u32], element: &[u32]) {
    let elements = elem_start.len() - 1;
    let n = element.len();
    let starts = Shared::new(elem_start);
    team.run(|t| {
        let er = ranges[t].clone();
        // SAFETY: thread t's elements are its only.
        let start = unsafe { starts.range(er.clone()) };
        let mut i = element.partition_point(|&e| (e as usize) < er.start);
        for (e, s) in er.zip(start.iter_mut()) {
            while i < n && (element[i] as usize) < e {
                i += 1;
            }
            *s = i as u32;
        }
        if t == ranges.len() - 1 {
            // SAFETY: the entry past the last element is the last thread's only.
            unsafe { starts.write(elements, n as u32) };
        }
    });
}

/// Whether `order` holds every index below its length once.
fn is_permutation(order: &[u32]) -> bool {
    let mut seen = vec![false; order.len()];
    order
        .iter()
        .all(|&i| (i as usize) < seen.len() && !std::mem::replace(&mut seen[i as usize], true))
}

/// Permutes every per-point array by `order` (new index → old index) through the spares.
struct Permute<'a> {
    team: &'a Team,
    ranges: &'a [Range<usize>],
    elem_start: &'a [u32],
    order: &'a [u32],
    spares: &'a mut Spares,
}

impl FieldVisitor for Permute<'_> {
    fn field<T: Value>(&mut self, field: Field, v: &mut Vec<T>) {
        let k = field.per_point;
        if k == 0 || v.is_empty() {
            return;
        }
        assert_eq!(
            v.len(),
            k * self.order.len(),
            "{}: not {k} per point",
            field.name
        );
        let (order, ranges, elem_start) = (self.order, self.ranges, self.elem_start);
        // Each thread its new points: the ones it computes on next.
        let points = |t: usize| {
            let r = &ranges[t];
            elem_start[r.start] as usize..elem_start[r.end] as usize
        };
        // The threads' new ranges cover every point once: the gather writes every value.
        let threads = ranges.len();
        assert!(
            points(0).start == 0
                && points(threads - 1).end == self.order.len()
                && (1..threads).all(|t| points(t).start == points(t - 1).end),
            "the threads' points do not cover the points"
        );
        let mut spare: Vec<T> = self.spares.take(k);
        spare.clear();
        // Grows only the first time (or when points came in); the threads first touch it.
        spare.reserve(v.len());
        {
            let old: &[T] = v;
            let out = Shared::new(&mut spare.spare_capacity_mut()[..old.len()]);
            self.team.run(|t| {
                let r = points(t);
                // SAFETY: thread t's new points are its only.
                let dst = unsafe { out.range(k * r.start..k * r.end) };
                if k == 1 {
                    // One value per point (all but the laws' state): a plain gather, not a
                    // copy call per point.
                    for (d, &i) in dst.iter_mut().zip(&order[r]) {
                        d.write(old[i as usize]);
                    }
                } else {
                    for (chunk, &i) in dst.chunks_exact_mut(k).zip(&order[r]) {
                        let i = i as usize;
                        for (d, s) in chunk.iter_mut().zip(&old[k * i..k * i + k]) {
                            d.write(*s);
                        }
                    }
                }
            });
        }
        // SAFETY: the gather wrote all `v.len()` values (the ranges cover every point, asserted
        // above, and each thread wrote `k` values per point of its range).
        unsafe { spare.set_len(v.len()) };
        std::mem::swap(v, &mut spare);
        self.spares.put(k, spare);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::team::{balanced_ranges, Pin};
    use proptest::prelude::*;

    /// The run-wise check agrees with the pair-by-pair one, wherever in a run (or across two
    /// runs' boundary) the one pair out of order lies.
    #[test]
    fn non_decreasing_finds_any_pair_out_of_order() {
        assert!(non_decreasing(&[]));
        assert!(non_decreasing(&[7]));
        for len in [2usize, 255, 256, 257, 513, 1000] {
            let sorted: Vec<u32> = (0..len as u32).map(|i| i / 3).collect();
            assert!(non_decreasing(&sorted), "len {len}");
            for at in 0..len - 1 {
                let mut v = sorted.clone();
                v[at] = v[at + 1] + 1;
                assert_eq!(
                    non_decreasing(&v),
                    v.windows(2).all(|w| w[0] <= w[1]),
                    "len {len}, at {at}"
                );
                assert!(!non_decreasing(&v), "len {len}, at {at}");
            }
        }
    }

    /// The serial stable counting sort the threads' sort must equal.
    fn serial_order(element: &[u32], elements: usize) -> (Vec<u32>, Vec<u32>) {
        let mut start = vec![0u32; elements + 1];
        for &e in element {
            start[e as usize + 1] += 1;
        }
        for e in 0..elements {
            start[e + 1] += start[e];
        }
        let mut next = start.clone();
        let mut order = vec![0u32; element.len()];
        for (i, &e) in element.iter().enumerate() {
            order[next[e as usize] as usize] = i as u32;
            next[e as usize] += 1;
        }
        (order, start)
    }

    fn points(element: &[u32]) -> Particles<f64> {
        let n = element.len();
        let f = |i: usize| i as f64;
        Particles::<f64> {
            x: (0..n).map(|i| [f(i), 2.0 * f(i), -f(i)]).collect(),
            u: vec![[0.0; 3]; n],
            v: vec![[0.0; 3]; n],
            mass: (0..n).map(f).collect(),
            volume: vec![1.0; n],
            stress: (0..n).map(|i| [0.0, 0.0, 0.0, 0.0, 0.0, f(i)]).collect(),
            element: element.to_vec(),
            material: vec![1; n],
            id: (0..n as u32).collect(),
            active: (0..n).map(|i| i % 3 != 0).collect(),
            // Two values per point: the chunks move together.
            state: (0..2 * n).map(f).collect(),
            state_len: 2,
            liquid: None,
            bulk: Some(crate::state::particles::BulkPoints {
                pressure: (0..n).map(|i| 3.0 * f(i)).collect(),
                rate: (0..n).map(|i| -f(i)).collect(),
            }),
        }
    }

    proptest! {
        #[test]
        fn the_threads_sort_as_the_serial_counting_sort(
            elements in 1usize..40,
            raw in proptest::collection::vec(0u32..1000, 0..300),
            threads in 1usize..5,
        ) {
            let element: Vec<u32> = raw.iter().map(|&e| e % elements as u32).collect();
            let (want_order, want_start) = serial_order(&element, elements);
            let team = Team::new(threads, Pin::None).unwrap();
            let ranges = balanced_ranges((0..elements).map(|_| 1), threads);
            let mut p = points(&element);
            let mut start = vec![0u32; elements + 1];
            let mut scratch = SortScratch::default();
            let permuted = resort(&team, &ranges, &mut start, &mut p, true, &mut scratch);
            let sorted = element.windows(2).all(|w| w[0] <= w[1]);
            prop_assert_eq!(permuted, !sorted);
            prop_assert_eq!(&start, &want_start);
            if permuted {
                prop_assert_eq!(&scratch.order, &want_order);
            }
            for (j, &i) in want_order.iter().enumerate() {
                let i = i as f64;
                prop_assert_eq!(p.x[j], [i, 2.0 * i, -i]);
                prop_assert_eq!(p.stress[j][5], i);
                prop_assert_eq!(p.element[j], element[i as usize]);
                prop_assert_eq!(p.active[j], (i as usize) % 3 != 0);
                prop_assert_eq!(&p.state[2 * j..2 * j + 2], &[2.0 * i, 2.0 * i + 1.0]);
            }
        }
    }

    #[test]
    fn points_in_order_only_have_their_starts_read_again() {
        let element = [0u32, 0, 2, 2, 2, 5];
        let team = Team::new(3, Pin::None).unwrap();
        let ranges = vec![0..2, 2..4, 4..6];
        let mut p = points(&element);
        let mut start = vec![0u32; 7];
        let mut scratch = SortScratch::default();
        assert!(!resort(
            &team,
            &ranges,
            &mut start,
            &mut p,
            true,
            &mut scratch
        ));
        assert_eq!(start, [0, 2, 2, 5, 5, 5, 6]);
        // Not moved: the starts are left alone.
        let mut stale = vec![9u32; 7];
        assert!(!resort(
            &team,
            &ranges,
            &mut stale,
            &mut p,
            false,
            &mut scratch
        ));
        assert_eq!(stale, [9; 7]);
    }
}
