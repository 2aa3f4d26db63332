//! Locality and partition metrics for the report (docs/design.md §3, step 8).

use mpm_shared::Model;
use rayon::prelude::*;
use serde::Serialize;

/// How close together an element's vertices are in memory.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Locality {
    /// Mean over elements of (largest - smallest vertex id) within the element.
    pub mean_id_spread: f64,
    /// Largest such spread.
    pub max_id_spread: u32,
    /// Mean number of distinct 64-byte cache lines holding an element's vertices, with 24 bytes
    /// (three f64 coordinates) per vertex.
    pub mean_cache_lines: f64,
}

/// Locality of `model`'s current numbering, over each element's full node list.
pub fn locality(model: &Model) -> Locality {
    let n = model.element_count();
    let (spread_sum, spread_max, lines_sum) = (0..n)
        .into_par_iter()
        .with_min_len(8192)
        .map(|e| {
            let el = model.element(e);
            let (lo, hi) = el
                .iter()
                .fold((u32::MAX, 0), |(lo, hi), &v| (lo.min(v), hi.max(v)));
            let mut lines = [0u64; 10];
            for (k, &v) in el.iter().enumerate() {
                lines[k] = v as u64 * 24 / 64;
            }
            let l = &mut lines[..el.len()];
            l.sort_unstable();
            let distinct = 1 + l.windows(2).filter(|w| w[0] != w[1]).count();
            (u64::from(hi - lo), hi - lo, distinct as u64)
        })
        .reduce(|| (0, 0, 0), |a, b| (a.0 + b.0, a.1.max(b.1), a.2 + b.2));
    let nf = n.max(1) as f64;
    Locality {
        mean_id_spread: spread_sum as f64 / nf,
        max_id_spread: spread_max,
        mean_cache_lines: lines_sum as f64 / nf,
    }
}

/// Pairs of elements sharing a face (3D: a triangle of corners; 2D: an edge), each pair once,
/// sorted.
pub fn face_neighbours(model: &Model) -> Vec<(u32, u32)> {
    let corners = model.element_type.corners();
    let faces: &[&[usize]] = if corners == 4 {
        &[&[0, 1, 2], &[0, 1, 3], &[0, 2, 3], &[1, 2, 3]]
    } else {
        &[&[0, 1], &[1, 2], &[0, 2]]
    };
    let n = model.element_count();
    let mut keys: Vec<([u32; 3], u32)> = (0..n)
        .into_par_iter()
        .with_min_len(8192)
        .flat_map_iter(|e| {
            let el = model.element(e);
            faces.iter().map(move |f| {
                let mut k = [u32::MAX; 3];
                for (i, &c) in f.iter().enumerate() {
                    k[i] = el[c];
                }
                k.sort_unstable();
                (k, e as u32)
            })
        })
        .collect();
    keys.par_sort_unstable();
    let mut pairs: Vec<(u32, u32)> = keys
        .windows(2)
        .filter(|w| w[0].0 == w[1].0)
        .map(|w| (w[0].1.min(w[1].1), w[0].1.max(w[1].1)))
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// Quality of a partition of the elements.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PartitionQuality {
    /// Number of parts.
    pub parts: u32,
    /// Element faces whose two elements lie in different parts.
    pub edge_cut: u64,
    /// Nodes used by elements of more than one part.
    pub interface_nodes: u64,
    /// Face-connected pieces of each part (1 is ideal).
    pub pieces: Vec<u32>,
    /// Pieces beyond one per part, summed.
    pub extra_pieces: u32,
    /// Largest part weight over the mean part weight.
    pub imbalance: f64,
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[parent[x as usize] as usize];
        parent[x as usize] = p;
        x = p;
    }
    x
}

/// Edge cut, interface nodes, pieces per part and imbalance of `part` (one entry per element).
pub fn partition_quality(
    model: &Model,
    neighbours: &[(u32, u32)],
    part: &[u32],
    weights: &[u64],
    parts: u32,
) -> PartitionQuality {
    let n = model.element_count();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut edge_cut = 0u64;
    for &(a, b) in neighbours {
        if part[a as usize] != part[b as usize] {
            edge_cut += 1;
        } else {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    let mut pieces = vec![0u32; parts as usize];
    for e in 0..n as u32 {
        if find(&mut parent, e) == e {
            pieces[part[e as usize] as usize] += 1;
        }
    }
    let mut owner = vec![u32::MAX; model.node_count()];
    let mut shared = vec![false; model.node_count()];
    for (e, &pe) in part.iter().enumerate().take(n) {
        for &v in model.element(e) {
            let o = &mut owner[v as usize];
            if *o == u32::MAX {
                *o = pe;
            } else if *o != pe {
                shared[v as usize] = true;
            }
        }
    }
    let mut load = vec![0u64; parts as usize];
    for (e, &w) in weights.iter().enumerate() {
        load[part[e] as usize] += w;
    }
    let total: u64 = load.iter().sum();
    let mean = total as f64 / parts as f64;
    let imbalance = if mean > 0.0 {
        *load.iter().max().unwrap_or(&0) as f64 / mean
    } else {
        1.0
    };
    PartitionQuality {
        parts,
        edge_cut,
        interface_nodes: shared.iter().filter(|&&s| s).count() as u64,
        extra_pieces: pieces.iter().map(|&p| p.saturating_sub(1)).sum(),
        pieces,
        imbalance,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpm_shared::{generate, ElementType};

    #[test]
    fn box_faces_and_partition_counts() {
        let m = generate::box_mesh([2, 2, 2], [1.0; 3], ElementType::Tet4);
        let nb = face_neighbours(&m);
        // 48 tets x 4 faces = 192; boundary faces 6 sides x 4 squares x 2 = 48; interior (192-48)/2.
        assert_eq!(nb.len(), 72);
        let one = partition_quality(&m, &nb, &[0; 48], &[1; 48], 1);
        assert_eq!(
            (
                one.edge_cut,
                one.interface_nodes,
                one.pieces.clone(),
                one.imbalance
            ),
            (0, 0, vec![1], 1.0)
        );
        // Split by cell layer in x (cells are written x fastest: cell c = i + 2 j + 4 k).
        let part: Vec<u32> = (0..48).map(|e| ((e / 6) % 2) as u32).collect();
        let q = partition_quality(&m, &nb, &part, &[1; 48], 2);
        assert_eq!(q.pieces, vec![1, 1]);
        assert_eq!(q.edge_cut, 8); // the x = 0.5 plane: 4 squares x 2 triangles
        assert_eq!(q.interface_nodes, 9);
    }

    #[test]
    fn non_finite_numbers_become_null() {
        // The report is built with json! and written with to_string_pretty (main.rs); a NaN or
        // infinity must come out as null, never as a bare NaN/Infinity token.
        let l = Locality {
            mean_id_spread: f64::NAN,
            max_id_spread: 3,
            mean_cache_lines: f64::INFINITY,
        };
        let text =
            serde_json::to_string_pretty(&serde_json::json!({ "l": l, "x": f64::NEG_INFINITY }))
                .unwrap();
        let back: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(
            back["l"]["mean_id_spread"],
            serde_json::Value::Null,
            "{text}"
        );
        assert_eq!(
            back["l"]["mean_cache_lines"],
            serde_json::Value::Null,
            "{text}"
        );
        assert_eq!(back["x"], serde_json::Value::Null, "{text}");
        assert_eq!(back["l"]["max_id_spread"], 3);
    }

    #[test]
    fn locality_counts_lines_and_spread() {
        let m = generate::box_mesh([1, 1, 1], [1.0; 3], ElementType::Tet4);
        let l = locality(&m);
        assert!(l.mean_cache_lines >= 1.0 && l.mean_cache_lines <= 4.0);
        assert_eq!(l.max_id_spread, 7);
    }
}

/// Moves every face-connected piece of a part other than its heaviest one to the neighbouring
/// part it shares most faces with (ties: the lower part), repeating until no piece moves (at most
/// `rounds` times). Parts stop being contiguous ranges of the curve, which suits process
/// partitions more than thread ranges. Pieces that touch no other part (separate bodies of the
/// mesh) stay. Deterministic.
pub fn merge_pieces(
    n: usize,
    neighbours: &[(u32, u32)],
    part: &mut [u32],
    weights: &[u64],
    rounds: usize,
) -> usize {
    let mut moved_total = 0;
    for _ in 0..rounds {
        let mut parent: Vec<u32> = (0..n as u32).collect();
        for &(a, b) in neighbours {
            if part[a as usize] == part[b as usize] {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
        let roots: Vec<u32> = (0..n as u32).map(|e| find(&mut parent, e)).collect();
        let mut piece_weight = vec![0u64; n];
        for e in 0..n {
            piece_weight[roots[e] as usize] += weights[e].max(1);
        }
        // Heaviest piece of each part (ties: the piece whose first element comes first).
        let mut main: std::collections::BTreeMap<u32, (u64, u32)> = Default::default();
        for e in 0..n {
            if roots[e] as usize == e {
                let w = piece_weight[e];
                let entry = main.entry(part[e]).or_insert((w, e as u32));
                if w > entry.0 {
                    *entry = (w, e as u32);
                }
            }
        }
        let is_main = |r: u32| main.get(&part[r as usize]).is_some_and(|m| m.1 == r);
        let mut contacts: Vec<(u32, u32)> = Vec::new();
        for &(a, b) in neighbours {
            let (pa, pb) = (part[a as usize], part[b as usize]);
            if pa != pb {
                let (ra, rb) = (roots[a as usize], roots[b as usize]);
                if !is_main(ra) {
                    contacts.push((ra, pb));
                }
                if !is_main(rb) {
                    contacts.push((rb, pa));
                }
            }
        }
        contacts.sort_unstable();
        let mut target: std::collections::BTreeMap<u32, u32> = Default::default();
        let mut i = 0;
        while i < contacts.len() {
            let root = contacts[i].0;
            let (mut best, mut best_count) = (0u32, 0usize);
            while i < contacts.len() && contacts[i].0 == root {
                let p = contacts[i].1;
                let mut c = 0;
                while i < contacts.len() && contacts[i] == (root, p) {
                    c += 1;
                    i += 1;
                }
                if c > best_count {
                    (best, best_count) = (p, c);
                }
            }
            target.insert(root, best);
        }
        if target.is_empty() {
            break;
        }
        for e in 0..n {
            if let Some(&p) = target.get(&roots[e]) {
                part[e] = p;
            }
        }
        moved_total += target.len();
    }
    moved_total
}

#[cfg(test)]
mod merge_tests {
    use super::*;
    use mpm_shared::{generate, ElementType};

    #[test]
    fn detached_pieces_join_a_neighbour() {
        let m = generate::box_mesh([4, 1, 1], [4.0, 1.0, 1.0], ElementType::Tet4);
        let nb = face_neighbours(&m);
        // Cells 0..4 along x, 6 tets each: part 0 = cells 0 and 2 (two pieces), part 1 = 1 and 3.
        let mut part: Vec<u32> = (0..24).map(|e| ((e / 6) % 2) as u32).collect();
        let w = vec![1u64; 24];
        let before = partition_quality(&m, &nb, &part, &w, 2);
        assert_eq!(before.extra_pieces, 2);
        let moved = merge_pieces(24, &nb, &mut part, &w, 10);
        assert!(moved >= 1);
        let after = partition_quality(&m, &nb, &part, &w, 2);
        assert_eq!(after.extra_pieces, 0, "{:?}", after.pieces);
        assert!(after.edge_cut < before.edge_cut);
    }
}
