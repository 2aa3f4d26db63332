//! Element ordering along the curve, vertex renumbering by first use, and partitions
//! (docs/design.md §3, steps 1-7).

use mpm_shared::{Error, Model};
use rayon::prelude::*;

pub use crate::morton::BoundsError;
use crate::morton::Grid;

/// The space-filling curve that orders the elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Curve {
    /// Z-order (bit interleaving).
    Morton,
    /// Hilbert curve on the same grid.
    Hilbert,
}

/// Options of one ordering.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// The curve.
    pub curve: Curve,
    /// Curve levels N.
    pub levels: u32,
    /// One cube for all axes (the default) rather than per-axis extents.
    pub cubic: bool,
}

/// The result of ordering a model.
#[derive(Debug, Clone, PartialEq)]
pub struct Ordering {
    /// New position → old element (0-based).
    pub order: Vec<u32>,
    /// Old node → new node (0-based).
    pub node_new: Vec<u32>,
    /// Curve key of each element in the new order.
    pub keys: Vec<u64>,
    /// Elements whose key equals the previous element's key.
    pub shared_keys: usize,
    /// Seconds spent on centroids and keys, the sort, and the vertex renumbering.
    pub seconds: [f64; 3],
}

/// Element centroids: corner coordinates summed in stored order, left to right, then divided
/// by the corner count.
pub fn centroid(model: &Model, e: usize, out: &mut [f64; 3]) {
    let d = model.dimension.coords();
    let corners = model.element_type.corners();
    let el = model.element(e);
    *out = [0.0; 3];
    for &n in &el[..corners] {
        let p = model.node(n as usize);
        for a in 0..d {
            out[a] += p[a];
        }
    }
    for v in out.iter_mut().take(d) {
        *v /= corners as f64;
    }
}

/// Orders the elements of `model` along the curve of their centroids and renumbers the vertices
/// in order of first use. The result does not depend on the number of threads.
///
/// Fails when a coordinate is NaN or infinite or an axis's extent is not finite (the error
/// names the node or the axis; callers add the file).
pub fn order(model: &Model, opts: Options) -> Result<Ordering, BoundsError> {
    let d = model.dimension.coords();
    let t0 = std::time::Instant::now();
    let grid = Grid::bounding(&model.coords, d, opts.levels, opts.cubic)?;
    let n = model.element_count();
    let per = model.element_type.nodes();
    let corners = model.element_type.corners();
    let conn = &model.connectivity;
    let mut pairs = vec![(0u64, 0u32); n];
    const BLOCK: usize = 8192;
    pairs
        .par_chunks_mut(BLOCK)
        .enumerate()
        .for_each(|(b, out)| {
            let first = b * BLOCK;
            for (i, slot) in out.iter_mut().enumerate() {
                let e = first + i;
                // The corners of a later element are fetched while this one is computed:
                // the coordinate reads are the random accesses that dominate.
                if e + PREFETCH < n {
                    for &v in &conn[(e + PREFETCH) * per..(e + PREFETCH) * per + corners] {
                        prefetch(&model.coords[v as usize * d]);
                    }
                }
                let mut c = [0.0; 3];
                centroid(model, e, &mut c);
                let key = match opts.curve {
                    Curve::Morton => grid.key(&c),
                    Curve::Hilbert => {
                        let q = [grid.cell(c[0], 0), grid.cell(c[1], 1), grid.cell(c[2], 2)];
                        crate::hilbert::key(&q[..d], opts.levels)
                    }
                };
                *slot = (key, e as u32);
            }
        });
    // Pairs are made in index order, so a stable sort by key gives (key, index) order.
    let t1 = std::time::Instant::now();
    sort_pairs(&mut pairs);
    let t2 = std::time::Instant::now();
    let order: Vec<u32> = pairs.iter().map(|p| p.1).collect();
    let keys: Vec<u64> = pairs.iter().map(|p| p.0).collect();
    let shared_keys = keys.windows(2).filter(|w| w[0] == w[1]).count();
    let node_new = first_use_numbering(model, &order);
    let t3 = std::time::Instant::now();
    Ok(Ordering {
        order,
        node_new,
        keys,
        shared_keys,
        seconds: [
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64(),
            (t3 - t2).as_secs_f64(),
        ],
    })
}

/// How many elements ahead the random reads are prefetched.
const PREFETCH: usize = 8;

/// Hints the processor to load the cache line holding `x`.
#[inline(always)]
fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: prefetching is a hint; it never faults, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch(x as *const T as *const i8, std::arch::x86_64::_MM_HINT_T0)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// Raw pointer that may be shared by the scatter tasks of one radix pass (they write disjoint
/// positions).
#[derive(Clone, Copy)]
struct Dst {
    ptr: *mut (u64, u32),
    len: usize,
}
// SAFETY: `Dst` only hands out writes through `write`, whose callers guarantee that no two
// threads write the same slot.
unsafe impl Send for Dst {}
unsafe impl Sync for Dst {}

impl Dst {
    /// Writes `v` into slot `i` (taking `&self` makes closures capture the whole wrapper).
    ///
    /// # Safety
    /// No other thread may write slot `i` at the same time; `i` is checked against the length.
    unsafe fn write(&self, i: usize, v: (u64, u32)) {
        assert!(i < self.len, "slot {i} outside 0..{}", self.len);
        // SAFETY: `i` is inside the allocation (checked above); exclusivity is the caller's.
        unsafe { self.ptr.add(i).write(v) }
    }
}

/// Bits of the most-significant digit that splits the pairs into cache-sized buckets.
const RADIX_BITS: u32 = 11;
const BUCKETS: usize = 1 << RADIX_BITS;

/// Sorts `(key, index)` pairs by key, then index: one parallel scatter by the top 11 bits in use
/// (memory-bound, done once), then each bucket, small enough for the cache, sorted on its own in
/// parallel. The order is the unique (key, index) order whatever the number of threads.
pub fn sort_pairs(pairs: &mut Vec<(u64, u32)>) {
    let n = pairs.len();
    if n < 1 << 12 {
        pairs.sort_unstable();
        return;
    }
    let max = pairs.par_iter().map(|p| p.0).max().unwrap_or(0);
    let used = 64 - max.leading_zeros();
    let shift = used.saturating_sub(RADIX_BITS);
    let digit = |p: &(u64, u32)| ((p.0 >> shift) as usize) & (BUCKETS - 1);
    let threads = rayon::current_num_threads().max(1);
    let chunk = n.div_ceil(threads).max(4096);
    let hists: Vec<Box<[usize; BUCKETS]>> = pairs
        .par_chunks(chunk)
        .map(|c| {
            let mut h = Box::new([0usize; BUCKETS]);
            for p in c {
                h[digit(p)] += 1;
            }
            h
        })
        .collect();
    let mut starts = vec![0usize; BUCKETS + 1];
    let mut offsets = vec![Box::new([0usize; BUCKETS]); hists.len()];
    let mut base = 0;
    for b in 0..BUCKETS {
        starts[b] = base;
        for (t, h) in hists.iter().enumerate() {
            offsets[t][b] = base;
            base += h[b];
        }
    }
    starts[BUCKETS] = n;
    let mut out = vec![(0u64, 0u32); n];
    let dst = Dst {
        ptr: out.as_mut_ptr(),
        len: n,
    };
    pairs
        .par_chunks(chunk)
        .zip(offsets.into_par_iter())
        .for_each(|(c, mut off)| {
            for p in c {
                let b = digit(p);
                // SAFETY: the offsets partition 0..n among chunks and buckets, so each position
                // is written exactly once.
                unsafe { dst.write(off[b], *p) };
                off[b] += 1;
            }
        });
    // Cut `out` into its buckets and sort each.
    let mut buckets: Vec<&mut [(u64, u32)]> = Vec::with_capacity(BUCKETS);
    let mut rest = &mut out[..];
    for b in 0..BUCKETS {
        let (head, tail) = rest.split_at_mut(starts[b + 1] - starts[b]);
        buckets.push(head);
        rest = tail;
    }
    buckets
        .into_par_iter()
        .with_min_len(16)
        .for_each(|b| b.sort_unstable());
    *pairs = out;
}

/// Vertex numbers in order of first appearance when walking the elements in `order` and each
/// element's full node list in stored order; unused vertices follow in their original order.
pub fn first_use_numbering(model: &Model, order: &[u32]) -> Vec<u32> {
    let nn = model.node_count();
    let per = model.element_type.nodes();
    // Each contiguous chunk of the sorted elements lists its nodes in local first-use order,
    // using a bitmap small enough to stay in cache; merging the lists in chunk order and
    // keeping each node's first appearance gives the global first-use order. The result is
    // the same for any chunking, and the serial merge touches each node about once instead of
    // every element's every node.
    let threads = rayon::current_num_threads().max(1);
    let chunk = order.len().div_ceil(threads).max(1 << 14);
    let lists: Vec<Vec<u32>> = order
        .par_chunks(chunk)
        .map(|part| {
            let mut seen = vec![0u64; nn.div_ceil(64)];
            let mut list = Vec::with_capacity((part.len() * 2).min(nn));
            for (i, &e) in part.iter().enumerate() {
                // Elements arrive in curve order, scattered in memory: fetch ahead.
                if let Some(&ahead) = part.get(i + PREFETCH) {
                    prefetch(&model.connectivity[ahead as usize * per]);
                }
                for &v in model.element(e as usize) {
                    let (w, bit) = (v as usize / 64, 1u64 << (v % 64));
                    if seen[w] & bit == 0 {
                        seen[w] |= bit;
                        list.push(v);
                    }
                }
            }
            list
        })
        .collect();
    let mut node_new = vec![u32::MAX; nn];
    let mut next = 0u32;
    for list in &lists {
        for &v in list {
            let slot = &mut node_new[v as usize];
            if *slot == u32::MAX {
                *slot = next;
                next += 1;
            }
        }
    }
    for slot in node_new.iter_mut() {
        if *slot == u32::MAX {
            *slot = next;
            next += 1;
        }
    }
    node_new
}

/// Integer weight of each element: its material points (solid + liquid) when the model has
/// `$$START_NUMBER_OF_MATERIAL_POINTS`, else 1.
pub fn weights(model: &Model) -> Vec<u64> {
    match model.per_element("START_NUMBER_OF_MATERIAL_POINTS") {
        Some(t) => t
            .rows()
            .map(|r| {
                r.iter()
                    .take(2)
                    .filter_map(|t| t.as_int())
                    .map(|v| v.max(0) as u64)
                    .sum()
            })
            .collect(),
        None => vec![1; model.element_count()],
    }
}

/// Contiguous parts along the element order: part(e) = min(P - 1, floor(P S_e / W)) with S_e the
/// weight before element e and W the total (all weights 1 when W = 0).
pub fn partitions(weights: &[u64], parts: u32) -> Vec<u32> {
    let total: u64 = weights.iter().sum();
    let unit = total == 0;
    let w_total = if unit {
        weights.len() as u128
    } else {
        total as u128
    };
    let p = parts as u128;
    let mut before: u128 = 0;
    let mut out = Vec::with_capacity(weights.len());
    for &w in weights {
        let part = (p * before).checked_div(w_total).unwrap_or(0).min(p - 1);
        out.push(part as u32);
        before += if unit { 1 } else { w as u128 };
    }
    out
}

/// Maps material-point ids (1-based, numbered in element order with `points[e]` per element) of
/// the old order to the new one.
pub fn remap_material_points(
    points: &[u32],
    order: &[u32],
    ids: &[u32],
) -> Result<Vec<u32>, Error> {
    let n = points.len();
    let mut first_old = Vec::with_capacity(n + 1);
    let mut acc = 0u64;
    for &p in points {
        first_old.push(acc);
        acc += p as u64;
    }
    first_old.push(acc);
    let mut first_new = vec![0u64; n];
    let mut acc = 0u64;
    for &e in order {
        first_new[e as usize] = acc;
        acc += points[e as usize] as u64;
    }
    ids.iter()
        .map(|&id| {
            let k = id as u64 - 1;
            if id == 0 || k >= acc {
                return Err(Error::Unremappable {
                    section: "$$OUTPUT_MATERIAL_POINTS".into(),
                    reason: format!("names material point {id}, but the mesh has {acc}"),
                });
            }
            let e = first_old.partition_point(|&f| f <= k) - 1;
            Ok((first_new[e] + (k - first_old[e]) + 1) as u32)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pair_sort_orders_by_key_then_index() {
        let mut seed = 1u64;
        let mut v: Vec<(u64, u32)> = (0..100_000u32)
            .map(|i| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((seed >> 1) % if i % 3 == 0 { 50 } else { u64::MAX >> 1 }, i)
            })
            .collect();
        let mut want = v.clone();
        want.sort_by_key(|p| p.0);
        // Shuffle the indices' order of arrival: the result must still be by (key, index).
        v.reverse();
        sort_pairs(&mut v);
        assert_eq!(v, want);
    }

    #[test]
    fn partitions_follow_the_formula() {
        assert_eq!(partitions(&[1, 1, 1, 1], 2), vec![0, 0, 1, 1]);
        assert_eq!(partitions(&[4, 0, 0, 4], 2), vec![0, 1, 1, 1]);
        assert_eq!(partitions(&[1, 1, 1], 5), vec![0, 1, 3]);
        assert_eq!(partitions(&[0, 0], 3), vec![0, 1]);
    }

    #[test]
    fn material_points_follow_their_elements() {
        // Elements with 2, 1, 3 points; new order 2, 0, 1.
        let points = [2, 1, 3];
        // Old ids: e0 -> 1,2; e1 -> 3; e2 -> 4,5,6. New: e2 -> 1,2,3; e0 -> 4,5; e1 -> 6.
        assert_eq!(
            remap_material_points(&points, &[2, 0, 1], &[1, 2, 3, 4, 6]).unwrap(),
            vec![4, 5, 6, 1, 3]
        );
        assert!(remap_material_points(&points, &[2, 0, 1], &[7]).is_err());
    }
}
