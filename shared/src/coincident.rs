//! Coincident duplicate nodes: nodes stored twice at exactly the same position. A mesher that
//! glues volumes badly leaves such copies, and elements that meet only through them are not
//! connected, which no reader can see from the ids. Both tools warn about them.

use rayon::prelude::*;

use crate::Model;

/// How many pairs a warning lists before it only counts the rest.
pub const LISTED: usize = 10;

/// The coordinates of node `i` as exact bit patterns; `-0.0` counts as `0.0` (adding `0.0`
/// turns the one into the other), so a node written at `-0` is still found at the origin.
fn bits(model: &Model, i: usize) -> [u64; 3] {
    let mut b = [0u64; 3];
    for (slot, &v) in b.iter_mut().zip(model.node(i)) {
        *slot = (v + 0.0).to_bits();
    }
    b
}

/// A well-mixed 64-bit hash of a position (SplitMix64's finaliser on each word), so that nodes
/// can be sorted by 16-byte (hash, id) pairs instead of 32-byte (position, id) ones.
fn hash(b: [u64; 3]) -> u64 {
    let mix = |mut z: u64| {
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    mix(b[0]) ^ mix(b[1] ^ 0x9e37_79b9_7f4a_7c15).rotate_left(21) ^ mix(b[2]).rotate_left(42)
}

/// Nodes at exactly the same position as another node: `(first, other)` with 0-based ids,
/// where `first` is the lowest-numbered node at that position and `other` each later one,
/// sorted. O(n log n) (a parallel sort of hashes; equal hashes are compared exactly, so a hash
/// collision never makes a false pair).
pub fn pairs(model: &Model) -> Vec<(u32, u32)> {
    let n = model.node_count();
    let mut keyed: Vec<(u64, u32)> = (0..n)
        .into_par_iter()
        .with_min_len(1 << 14)
        .map(|i| (hash(bits(model, i)), i as u32))
        .collect();
    keyed.par_sort_unstable();
    let mut out = Vec::new();
    let mut run = Vec::new();
    let mut start = 0;
    while start < keyed.len() {
        let mut end = start + 1;
        while end < keyed.len() && keyed[end].0 == keyed[start].0 {
            end += 1;
        }
        if end - start > 1 {
            // Within a run of equal hashes, sorting by (position, id) puts each position's
            // nodes together, lowest id first.
            run.clear();
            run.extend(
                keyed[start..end]
                    .iter()
                    .map(|&(_, i)| (bits(model, i as usize), i)),
            );
            run.sort_unstable();
            let mut g = 0;
            for k in 1..run.len() {
                if run[k].0 == run[g].0 {
                    out.push((run[g].1, run[k].1));
                } else {
                    g = k;
                }
            }
        }
        start = end;
    }
    out.par_sort_unstable();
    out
}

/// The warning for `pairs` found in `file` (`None` when there are none): the first [`LISTED`]
/// pairs by their 1-based node numbers, then how many more.
pub fn warning(file: &str, pairs: &[(u32, u32)]) -> Option<String> {
    if pairs.is_empty() {
        return None;
    }
    let listed: Vec<String> = pairs
        .iter()
        .take(LISTED)
        .map(|&(a, b)| format!("{} and {}", a + 1, b + 1))
        .collect();
    let more = match pairs.len().saturating_sub(LISTED) {
        0 => String::new(),
        m => format!(", and {m} more"),
    };
    Some(format!(
        "{file}: {} node(s) have exactly the coordinates of an earlier node (coincident duplicates; elements that meet only through them are not connected): nodes {}{more}",
        pairs.len(),
        listed.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{generate, ElementType};

    #[test]
    fn finds_exact_copies_only() {
        let mut m = generate::box_mesh([2, 1, 1], [2.0, 1.0, 1.0], ElementType::Tet4);
        assert!(pairs(&m).is_empty());
        let n = m.node_count();
        // Three copies of node 2 (0-based 1), one of node 5 written with -0.0 for its zeros,
        // and one that differs in the last bit.
        let p1 = m.node(1).to_vec();
        let p4: Vec<f64> = m
            .node(4)
            .iter()
            .map(|&v| if v == 0.0 { -0.0 } else { v })
            .collect();
        let near: Vec<f64> = m
            .node(3)
            .iter()
            .map(|&v| f64::from_bits(v.to_bits() + 1))
            .collect();
        for p in [&p1, &p4, &p1, &near, &p1] {
            m.coords.extend_from_slice(p);
        }
        let n = n as u32;
        assert_eq!(pairs(&m), vec![(1, n), (1, n + 2), (1, n + 4), (4, n + 1)]);
    }

    #[test]
    fn warning_lists_ten_pairs_and_counts_the_rest() {
        assert_eq!(warning("a.GOM", &[]), None);
        let many: Vec<(u32, u32)> = (0..13).map(|i| (i, 100 + i)).collect();
        let w = warning("a.GOM", &many).unwrap();
        assert!(w.starts_with("a.GOM: 13 node(s)"), "{w}");
        assert!(w.contains("nodes 1 and 101, 2 and 102,"), "{w}");
        assert!(w.contains("10 and 110, and 3 more"), "{w}");
        assert!(!w.contains("11 and 111"), "{w}");
    }
}
