//! The deterministic parallel sum of a basis whose points reach past their element's corners
//! (the background grid's splines, [`crate::basis`]): owner computes.
//!
//! Each thread owns a contiguous range of nodes (in the mesh's order, the space-filling
//! curve's, so a range is a compact region) and visits, in increasing element order, every
//! element whose points may touch one of its nodes ([`Basis::reach`]); it adds each such
//! point's share into its own nodes only. Every node's sum is then taken over its points in
//! the global point order, from zero, whatever the thread count: the same bits as one thread
//! summing point after point, with no slots, locks or atomics. The price is the halo: the
//! points within a stencil's reach of a range's border are visited by both threads beside it
//! (a few cells' layer; [`Reach::halo_share`]).
//!
//! The elements each thread visits depend on the mesh, the basis and the node ranges only, not
//! on where the points are: they are found once, when the case is set up (or its team
//! replaced), and the step allocates nothing.

use std::ops::Range;

use crate::basis::{Basis, Stencil};
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::parallel::gather::Layout;
use crate::parallel::team::balanced_ranges;
use crate::real::{Real, V3};

/// Who sums which nodes, and which elements each must visit to do so.
#[derive(Debug, Clone)]
pub struct Reach {
    /// Each thread's nodes: contiguous, disjoint, in order, covering the mesh's nodes.
    nodes: Vec<Range<usize>>,
    /// Each thread's elements, as increasing, disjoint runs: those with a node of the
    /// thread's within reach.
    runs: Vec<Vec<Range<usize>>>,
    /// Elements visited by all threads together, over the mesh's.
    visits: f64,
}

impl Reach {
    /// The node ranges of `threads` threads on `mesh`, balanced by the points of `layout`
    /// (each element's counted on its first corner), and the elements each thread visits
    /// under `basis`.
    pub fn new<E, R, B>(basis: &B, mesh: &Mesh<E, R>, layout: &Layout<R, E>, threads: usize) -> Self
    where
        E: Element,
        R: Real,
        B: Basis<E, R>,
    {
        let threads = threads.max(1);
        let mut weight = vec![0u64; mesh.x.len()];
        for e in 0..mesh.elements() {
            weight[mesh.corners[e].as_ref()[0] as usize] += layout.particles_of(e).len() as u64;
        }
        let nodes = balanced_ranges(weight.iter().copied(), threads);
        let mut owner = vec![0u32; mesh.x.len()];
        for (t, r) in nodes.iter().enumerate() {
            owner[r.clone()].fill(t as u32);
        }
        let mut runs: Vec<Vec<Range<usize>>> = vec![Vec::new(); threads];
        let mut reach = Vec::new();
        for e in 0..mesh.elements() {
            basis.reach(mesh, e, &mut reach);
            for &n in &reach {
                let mine = &mut runs[owner[n as usize] as usize];
                match mine.last_mut() {
                    Some(last) if last.end > e => {}
                    Some(last) if last.end == e => last.end = e + 1,
                    _ => mine.push(e..e + 1),
                }
            }
        }
        let visited: usize = runs.iter().flatten().map(|r| r.len()).sum();
        let visits = visited as f64 / mesh.elements().max(1) as f64;
        Reach {
            nodes,
            runs,
            visits,
        }
    }

    /// Threads the ranges are cut for.
    pub fn threads(&self) -> usize {
        self.nodes.len()
    }

    /// Thread `t`'s nodes.
    pub fn nodes(&self, t: usize) -> Range<usize> {
        self.nodes[t].clone()
    }

    /// Thread `t`'s elements, in increasing order.
    pub fn elements(&self, t: usize) -> impl Iterator<Item = usize> + '_ {
        self.runs[t].iter().flat_map(|r| r.clone())
    }

    /// Calls `f(e, i, stencil)`, in point order, for each point `i` that `takes_part` of the
    /// elements `e` thread `t` visits whose stencil under `basis` (at `x[i]`) touches one of
    /// the thread's nodes: the points whose shares the thread sums.
    pub fn visit<E, R, B>(
        &self,
        t: usize,
        (basis, mesh, layout): (&B, &Mesh<E, R>, &Layout<R, E>),
        (x, takes_part): (&[V3<R>], impl Fn(usize) -> bool),
        mut f: impl FnMut(usize, usize, &Stencil<R>),
    ) where
        E: Element,
        R: Real,
        B: Basis<E, R>,
    {
        let own = self.nodes(t);
        let mut stencil = Stencil::default();
        for e in self.elements(t) {
            for i in layout.particles_of(e) {
                if !takes_part(i) {
                    continue;
                }
                basis.stencil(mesh, e, &x[i], &mut stencil);
                if stencil.nodes().iter().any(|&n| own.contains(&(n as usize))) {
                    f(e, i, &stencil);
                }
            }
        }
    }

    /// The share of element visits beyond one per element: what the halo costs.
    pub fn halo_share(&self) -> f64 {
        (self.visits - 1.0).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::grid::{Cartesian, GridSpec};
    use crate::basis::spline::Shape;
    use crate::element::tet4::Tet4;
    use crate::state::particles::Particles;
    use mpm_shared::{generate, ElementType};

    /// Every node a point can touch is owned by exactly one thread, and that thread visits the
    /// point's element: points all over each element of a grid, every basis, 1 to 5 threads.
    #[test]
    fn every_node_a_point_touches_is_summed_by_a_thread_that_visits_its_element() {
        let model = generate::box_mesh([4, 3, 5], [1.0, 0.75, 1.25], ElementType::Tet4);
        let mesh = Mesh::<Tet4, f64>::new(&model).unwrap();
        let element: Vec<u32> = (0..mesh.elements() as u32).collect();
        let p = Particles::<f64>::at_rest(element);
        let layout = Layout::new(&mesh, &p, 1);
        let mut rng = crate::test_rng::uniform(5);
        for shape in [Shape::Linear, Shape::Gimp { a: 0.25 }, Shape::Bspline2] {
            let spec = GridSpec {
                origin: [0.0; 3],
                cell: [0.25; 3],
                cells: [4, 3, 5],
                dim: 3,
                shape,
                points_per_axis: None,
            };
            let basis = Cartesian::new(spec, &mesh).unwrap();
            for threads in 1..=5 {
                let reach = Reach::new(&basis, &mesh, &layout, threads);
                let mut seen = 0;
                for t in 0..threads {
                    assert_eq!(reach.nodes(t).start, seen);
                    seen = reach.nodes(t).end;
                    let elements: Vec<usize> = reach.elements(t).collect();
                    assert!(elements.windows(2).all(|w| w[0] < w[1]));
                }
                assert_eq!(seen, mesh.x.len());
                let mut st = Stencil::<f64>::default();
                for e in 0..mesh.elements() {
                    let c = mesh.corners[e];
                    for _ in 0..8 {
                        let w: [f64; 4] = std::array::from_fn(|_| rng() + 0.501);
                        let total: f64 = w.iter().sum();
                        let x = std::array::from_fn(|a| {
                            (0..4)
                                .map(|k| w[k] / total * mesh.x[c[k] as usize][a])
                                .sum()
                        });
                        basis.stencil(&mesh, e, &x, &mut st);
                        for &n in st.nodes() {
                            let t = (0..threads)
                                .find(|&t| reach.nodes(t).contains(&(n as usize)))
                                .unwrap();
                            assert!(
                                reach.elements(t).any(|v| v == e),
                                "{shape:?}, {threads} threads: node {n} of element {e}"
                            );
                        }
                    }
                }
                if threads == 1 {
                    assert_eq!(reach.halo_share(), 0.0);
                }
            }
        }
    }
}
