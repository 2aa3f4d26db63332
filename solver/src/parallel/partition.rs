//! One process's share of the mesh: a contiguous range of elements along the curve order (the
//! order `sfcb` and the solver's reordering give the mesh), the nodes those elements touch
//! numbered locally in global order, the maps between local and global numbers, and the nodes
//! shared with other processes (where a distributed run adds up nodal sums).
//!
//! The engine computes on [`Partition::local_mesh`]: for one process that is the whole mesh,
//! unchanged; for several, each gets its elements with neighbours across the cut marked
//! [`REMOTE`], so a point walking out of the share is told apart from one leaving the mesh.

use std::ops::Range;

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::parallel::team::{aligned_to_blocks, balanced_ranges};
use crate::real::Real;

pub use crate::element::mesh::REMOTE;

/// The elements and nodes of one process (rank) of a run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Partition {
    rank: usize,
    ranks: usize,
    /// Global elements owned, contiguous along the curve (starting a block of
    /// [`crate::parallel::team::ELEMENT_BLOCK`] elements, so that per-block sums are the same for any rank count).
    elements: Range<usize>,
    /// Global elements of the halo: other ranks' elements that touch a node of an owned one,
    /// increasing. Locally they follow the owned elements.
    halo: Vec<u32>,
    /// Global node of each local node, increasing (local order follows the global order).
    node_global: Vec<u32>,
    /// Local nodes that elements of other processes touch too, increasing.
    shared: Vec<u32>,
    /// Number of global nodes.
    global_nodes: usize,
    /// The ranks this one exchanges element slots with.
    neighbours: Vec<Neighbour>,
    /// First global element of every rank, and the number of elements after the last.
    starts: Vec<usize>,
}

/// A rank whose elements share nodes with this one's: the element slots that go there and
/// come from there, in global element order (both sides list the same pairs in the same order).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Neighbour {
    /// The other rank.
    pub rank: usize,
    /// Local numbers of owned elements in that rank's halo.
    pub send: Vec<u32>,
    /// Local numbers of halo elements that rank owns.
    pub receive: Vec<u32>,
}

impl Partition {
    /// The one partition of a single-process run: every element and node, identity maps.
    pub fn whole<E: Element, R: Real>(mesh: &Mesh<E, R>) -> Self {
        Partition {
            rank: 0,
            ranks: 1,
            elements: 0..mesh.elements(),
            halo: Vec::new(),
            node_global: (0..mesh.nodes() as u32).collect(),
            shared: Vec::new(),
            global_nodes: mesh.nodes(),
            neighbours: Vec::new(),
            starts: vec![0, mesh.elements()],
        }
    }

    /// `ranks` partitions of `mesh` along its element order, balanced by `weight[e]` (for
    /// instance each element's material points), as the threads of one process are, with every
    /// boundary on a multiple of [`crate::parallel::team::ELEMENT_BLOCK`] elements.
    pub fn along_curve<E: Element, R: Real>(
        mesh: &Mesh<E, R>,
        weight: &[u64],
        ranks: usize,
    ) -> Vec<Partition> {
        assert_eq!(weight.len(), mesh.elements(), "one weight per element");
        let ranges = aligned_to_blocks(
            balanced_ranges(weight.iter().copied(), ranks),
            mesh.elements(),
        );
        let ranks = ranges.len();
        let rank_of = |e: usize| ranges.partition_point(|r| r.end <= e);
        let starts: Vec<usize> = ranges
            .iter()
            .map(|r| r.start)
            .chain([mesh.elements()])
            .collect();
        // The ranks touching each node, increasing (elements are visited in rank order).
        let mut touching: Vec<Vec<u32>> = vec![Vec::new(); mesh.nodes()];
        for (r, range) in ranges.iter().enumerate() {
            for c in &mesh.corners[range.clone()] {
                for &n in c.as_ref() {
                    let t = &mut touching[n as usize];
                    if t.last() != Some(&(r as u32)) {
                        t.push(r as u32);
                    }
                }
            }
        }
        // The other ranks touching a node of element e.
        let others = |e: usize, me: usize| {
            let mut o: Vec<u32> = mesh.corners[e]
                .as_ref()
                .iter()
                .flat_map(|&n| touching[n as usize].iter().copied())
                .filter(|&q| q as usize != me)
                .collect();
            o.sort_unstable();
            o.dedup();
            o
        };
        // Per rank, its elements that another rank's nodes touch, by that rank.
        let mut border: Vec<Vec<Vec<u32>>> = vec![vec![Vec::new(); ranks]; ranks];
        for (r, range) in ranges.iter().enumerate() {
            for e in range.clone() {
                for q in others(e, r) {
                    border[r][q as usize].push(e as u32);
                }
            }
        }
        ranges
            .iter()
            .enumerate()
            .map(|(rank, elements)| {
                // Halo: every other rank's elements touching this rank's nodes.
                let mut halo: Vec<u32> = (0..ranks)
                    .filter(|&q| q != rank)
                    .flat_map(|q| border[q][rank].iter().copied())
                    .collect();
                halo.sort_unstable();
                let own = elements.len() as u32;
                let local_of_halo = |g: u32| own + halo.binary_search(&g).expect("halo") as u32;
                let neighbours = (0..ranks)
                    .filter(|&q| q != rank && !border[rank][q].is_empty())
                    .map(|q| Neighbour {
                        rank: q,
                        send: border[rank][q]
                            .iter()
                            .map(|&g| g - elements.start as u32)
                            .collect(),
                        receive: border[q][rank].iter().map(|&g| local_of_halo(g)).collect(),
                    })
                    .collect();
                let mut node_global: Vec<u32> = elements
                    .clone()
                    .chain(halo.iter().map(|&g| g as usize))
                    .flat_map(|e| mesh.corners[e].as_ref().iter().copied())
                    .collect();
                node_global.sort_unstable();
                node_global.dedup();
                let shared = node_global
                    .iter()
                    .enumerate()
                    .filter(|&(_, &g)| touching[g as usize].len() > 1)
                    .map(|(l, _)| l as u32)
                    .collect();
                debug_assert!(halo.iter().all(|&g| rank_of(g as usize) != rank));
                Partition {
                    rank,
                    ranks,
                    elements: elements.clone(),
                    halo,
                    node_global,
                    shared,
                    global_nodes: mesh.nodes(),
                    neighbours,
                    starts: starts.clone(),
                }
            })
            .collect()
    }

    /// This partition's rank, 0-based.
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// Number of partitions of the run.
    pub fn ranks(&self) -> usize {
        self.ranks
    }

    /// Whether this is the whole mesh (identity maps).
    pub fn is_whole(&self) -> bool {
        self.ranks == 1
    }

    /// The global elements owned.
    pub fn elements(&self) -> Range<usize> {
        self.elements.clone()
    }

    /// Number of owned elements (local elements `0..owned()`; the halo's follow).
    pub fn owned(&self) -> usize {
        self.elements.len()
    }

    /// The halo's global elements, increasing (local `owned()..`).
    pub fn halo(&self) -> &[u32] {
        &self.halo
    }

    /// The rank owning global element `global`.
    pub fn rank_of(&self, global: usize) -> usize {
        self.starts[1..].partition_point(|&s| s <= global)
    }

    /// The ranks this one exchanges element slots with.
    pub fn neighbours(&self) -> &[Neighbour] {
        &self.neighbours
    }

    /// Number of local nodes.
    pub fn nodes(&self) -> usize {
        self.node_global.len()
    }

    /// Global number of local element `local` (owned or halo).
    pub fn global_element(&self, local: usize) -> usize {
        match local.checked_sub(self.owned()) {
            None => self.elements.start + local,
            Some(h) => self.halo[h] as usize,
        }
    }

    /// Local number of global element `global`, if owned.
    pub fn local_element(&self, global: usize) -> Option<usize> {
        self.elements
            .contains(&global)
            .then(|| global - self.elements.start)
    }

    /// Local number of global element `global`, owned or in the halo.
    pub fn local_or_halo(&self, global: usize) -> Option<usize> {
        self.local_element(global).or_else(|| {
            self.halo
                .binary_search(&(global as u32))
                .ok()
                .map(|h| self.owned() + h)
        })
    }

    /// Global number of local node `local`.
    pub fn global_node(&self, local: usize) -> u32 {
        self.node_global[local]
    }

    /// Local number of global node `global`, if an owned or halo element touches it.
    pub fn local_node(&self, global: u32) -> Option<u32> {
        if self.is_whole() {
            return ((global as usize) < self.global_nodes).then_some(global);
        }
        self.node_global
            .binary_search(&global)
            .ok()
            .map(|l| l as u32)
    }

    /// Local nodes that other partitions' elements touch too (empty for the whole mesh).
    pub fn shared_nodes(&self) -> &[u32] {
        &self.shared
    }

    /// Local elements in global order (the order of every node's sum of element slots).
    pub fn elements_in_global_order(&self) -> Vec<u32> {
        let own = self.owned() as u32;
        let before = self
            .halo
            .partition_point(|&g| (g as usize) < self.elements.start) as u32;
        (own..own + before)
            .chain(0..own)
            .chain(own + before..own + self.halo.len() as u32)
            .collect()
    }

    /// The mesh this partition computes on: `global` itself for the whole mesh; otherwise its
    /// owned elements, then the halo's, on local nodes, neighbours beyond the halo marked
    /// [`REMOTE`].
    pub fn local_mesh<E: Element, R: Real>(&self, global: Mesh<E, R>) -> Mesh<E, R> {
        if self.is_whole() {
            return global;
        }
        let local = |g: u32| {
            self.local_node(g)
                .expect("local elements touch local nodes")
        };
        let els: Vec<usize> = self
            .elements
            .clone()
            .chain(self.halo.iter().map(|&g| g as usize))
            .collect();
        let mut node_of_model = vec![u32::MAX; global.node_of_model.len()];
        let model_node: Vec<u32> = self
            .node_global
            .iter()
            .enumerate()
            .map(|(l, &g)| {
                let m = global.model_node[g as usize];
                node_of_model[m as usize] = l as u32;
                m
            })
            .collect();
        Mesh {
            origin: global.origin,
            x: self
                .node_global
                .iter()
                .map(|&g| global.x[g as usize])
                .collect(),
            model_node,
            node_of_model,
            corners: els
                .iter()
                .map(|&e| {
                    let c = global.corners[e].as_ref();
                    E::nodes(|k| local(c[k]))
                })
                .collect(),
            map: els.iter().map(|&e| global.map[e]).collect(),
            grad: els.iter().map(|&e| global.grad[e]).collect(),
            volume: els.iter().map(|&e| global.volume[e]).collect(),
            min_altitude: els.iter().map(|&e| global.min_altitude[e]).collect(),
            neighbour: els
                .iter()
                .map(|&e| {
                    let f = global.neighbour[e].as_ref();
                    E::faces(|k| match f[k] {
                        u32::MAX => u32::MAX,
                        g => self.local_or_halo(g as usize).map_or(REMOTE, |l| l as u32),
                    })
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::mesh::TetMesh;
    use mpm_shared::{generate, ElementType};
    use proptest::prelude::*;

    fn mesh(n: usize) -> TetMesh<f64> {
        TetMesh::new(&generate::box_mesh([n, n, n], [1.0; 3], ElementType::Tet4)).unwrap()
    }

    #[test]
    fn one_process_owns_everything_with_identity_maps() {
        let m = mesh(3);
        let p = Partition::whole(&m);
        assert!(p.is_whole());
        assert_eq!(p.elements(), 0..m.elements());
        assert!(p.shared_nodes().is_empty());
        assert_eq!(p.local_node(5), Some(5));
        assert_eq!(p.local_node(m.nodes() as u32), None);
        let same = p.local_mesh(m.clone());
        assert_eq!(same.corners, m.corners);
        // One rank along the curve is the whole mesh too.
        let one = Partition::along_curve(&m, &vec![1; m.elements()], 1);
        assert_eq!(one, vec![p]);
    }

    proptest! {
        #[test]
        fn partitions_cover_the_mesh_once_and_agree_with_it(
            ranks in 2usize..6,
            weights in proptest::collection::vec(0u64..5, 162),
        ) {
            let m = mesh(3);
            prop_assert_eq!(m.elements(), 162);
            let parts = Partition::along_curve(&m, &weights, ranks);
            prop_assert_eq!(parts.len(), ranks);
            let mut next = 0;
            let mut touched = vec![0u32; m.nodes()];
            for p in &parts {
                prop_assert_eq!(p.elements().start, next);
                next = p.elements().end;
                for l in 0..p.nodes() {
                    let g = p.global_node(l);
                    prop_assert_eq!(p.local_node(g), Some(l as u32));
                    touched[g as usize] += 1;
                }
                let local = p.local_mesh(m.clone());
                prop_assert_eq!(p.elements().start % 64, 0);
                prop_assert_eq!(local.elements(), p.owned() + p.halo().len());
                for (le, c) in local.corners.iter().enumerate().take(p.owned()) {
                    let ge = p.global_element(le);
                    prop_assert_eq!(p.local_element(ge), Some(le));
                    for k in 0..4 {
                        // Same node, same geometry.
                        prop_assert_eq!(p.global_node(c[k] as usize), m.corners[ge][k]);
                        prop_assert_eq!(local.x[c[k] as usize], m.x[m.corners[ge][k] as usize]);
                        let n = local.neighbour[le][k];
                        let gn = m.neighbour[ge][k];
                        if gn == u32::MAX {
                            prop_assert_eq!(n, u32::MAX);
                        } else {
                            // A face neighbour touches the element's nodes: owned or in the halo.
                            prop_assert_eq!(p.global_element(n as usize), gn as usize);
                        }
                    }
                }
            }
            prop_assert_eq!(next, m.elements());
            // A node is shared exactly when the owned elements of more than one partition touch it.
            let mut touched = vec![0u32; m.nodes()];
            for p in &parts {
                let mut mine = vec![false; m.nodes()];
                for e in p.elements() {
                    for &n in &m.corners[e] {
                        mine[n as usize] = true;
                    }
                }
                for (t, &b) in touched.iter_mut().zip(&mine) {
                    *t += u32::from(b);
                }
            }
            for p in &parts {
                for l in 0..p.nodes() {
                    let g = p.global_node(l) as usize;
                    let shared = p.shared_nodes().binary_search(&(l as u32)).is_ok();
                    prop_assert_eq!(shared, touched[g] > 1);
                }
            }
        }
    }
}
