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
use crate::parallel::team::balanced_ranges;
use crate::real::Real;

/// Neighbour marker of a face whose element belongs to another process.
pub const REMOTE: u32 = u32::MAX - 1;

/// The elements and nodes of one process (rank) of a run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Partition {
    rank: usize,
    ranks: usize,
    /// Global elements owned, contiguous along the curve.
    elements: Range<usize>,
    /// Global node of each local node, increasing (local order follows the global order).
    node_global: Vec<u32>,
    /// Local nodes that elements of other processes touch too, increasing.
    shared: Vec<u32>,
    /// Number of global nodes.
    global_nodes: usize,
}

impl Partition {
    /// The one partition of a single-process run: every element and node, identity maps.
    pub fn whole<E: Element, R: Real>(mesh: &Mesh<E, R>) -> Self {
        Partition {
            rank: 0,
            ranks: 1,
            elements: 0..mesh.elements(),
            node_global: (0..mesh.nodes() as u32).collect(),
            shared: Vec::new(),
            global_nodes: mesh.nodes(),
        }
    }

    /// `ranks` partitions of `mesh` along its element order, balanced by `weight[e]` (for
    /// instance each element's material points), as the threads of one process are.
    pub fn along_curve<E: Element, R: Real>(
        mesh: &Mesh<E, R>,
        weight: &[u64],
        ranks: usize,
    ) -> Vec<Partition> {
        assert_eq!(weight.len(), mesh.elements(), "one weight per element");
        let ranges = balanced_ranges(weight.iter().copied(), ranks);
        let ranks = ranges.len();
        // Which ranks touch each node: the first and the last suffice to know if it is shared.
        let mut first = vec![u32::MAX; mesh.nodes()];
        let mut last = vec![0u32; mesh.nodes()];
        for (r, range) in ranges.iter().enumerate() {
            for c in &mesh.corners[range.clone()] {
                for &n in c.as_ref() {
                    let n = n as usize;
                    first[n] = first[n].min(r as u32);
                    last[n] = last[n].max(r as u32);
                }
            }
        }
        ranges
            .into_iter()
            .enumerate()
            .map(|(rank, elements)| {
                let mut node_global: Vec<u32> = mesh.corners[elements.clone()]
                    .iter()
                    .flat_map(|c| c.as_ref().iter().copied())
                    .collect();
                node_global.sort_unstable();
                node_global.dedup();
                let shared = node_global
                    .iter()
                    .enumerate()
                    .filter(|&(_, &g)| first[g as usize] != last[g as usize])
                    .map(|(l, _)| l as u32)
                    .collect();
                Partition {
                    rank,
                    ranks,
                    elements,
                    node_global,
                    shared,
                    global_nodes: mesh.nodes(),
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

    /// Number of local nodes.
    pub fn nodes(&self) -> usize {
        self.node_global.len()
    }

    /// Global number of local element `local`.
    pub fn global_element(&self, local: usize) -> usize {
        self.elements.start + local
    }

    /// Local number of global element `global`, if owned.
    pub fn local_element(&self, global: usize) -> Option<usize> {
        self.elements
            .contains(&global)
            .then(|| global - self.elements.start)
    }

    /// Global number of local node `local`.
    pub fn global_node(&self, local: usize) -> u32 {
        self.node_global[local]
    }

    /// Local number of global node `global`, if an owned element touches it.
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

    /// The mesh this partition computes on: `global` itself for the whole mesh; otherwise its
    /// owned elements on local nodes, neighbours across the cut marked [`REMOTE`].
    pub fn local_mesh<E: Element, R: Real>(&self, global: Mesh<E, R>) -> Mesh<E, R> {
        if self.is_whole() {
            return global;
        }
        let local = |g: u32| {
            self.local_node(g)
                .expect("owned elements touch local nodes")
        };
        let el = self.elements.clone();
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
            corners: global.corners[el.clone()]
                .iter()
                .map(|c| {
                    let c = c.as_ref();
                    E::nodes(|k| local(c[k]))
                })
                .collect(),
            map: global.map[el.clone()].to_vec(),
            grad: global.grad[el.clone()].to_vec(),
            volume: global.volume[el.clone()].to_vec(),
            min_altitude: global.min_altitude[el.clone()].to_vec(),
            neighbour: global.neighbour[el]
                .iter()
                .map(|f| {
                    let f = f.as_ref();
                    E::faces(|k| match f[k] {
                        u32::MAX => u32::MAX,
                        g => self.local_element(g as usize).map_or(REMOTE, |l| l as u32),
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
                prop_assert_eq!(local.elements(), p.elements().len());
                for (le, c) in local.corners.iter().enumerate() {
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
                        } else if p.elements().contains(&(gn as usize)) {
                            prop_assert_eq!(p.global_element(n as usize), gn as usize);
                        } else {
                            prop_assert_eq!(n, REMOTE);
                        }
                    }
                }
            }
            prop_assert_eq!(next, m.elements());
            // A node is shared exactly when more than one partition touches it.
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
