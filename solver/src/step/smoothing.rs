//! Anura3D's strain smoothing (`$$STRAIN_SMOOTHING 1`): the volumetric strain increments of the
//! solid and of the liquid are averaged from the elements to the nodes and back, material by
//! material, which removes the element-to-element (checkerboard) modes of linear tetrahedra.
//!
//! Per material m and step: each element e holding points of m has one volumetric strain
//! increment per phase, ε_e = Δt div v (linear tetrahedra); node i takes the volume-weighted
//! mean ε̄_i = Σ_e V_e ε_e / Σ_e V_e over those elements; every point of m in e then takes the
//! plain mean of its element's nodal values as its volumetric strain increment. The solid
//! keeps its deviatoric and shear increments (its normal increments, the two in-plane ones in
//! plane strain, are shifted equally);
//! the pore pressure takes Δp = (K_w / n) (n ε̄_w + (1 - n) ε̄_s).

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::parallel::gather::{node_slots, Slots};
use crate::parallel::team::Shared;
use crate::real::Real;
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::passes::Passes;

/// Materials summed in one pass over the slots: three values each (V ε_s, V ε_w, V).
const PER_PASS: usize = PASS_WIDTH / 3;

/// Values per node of one smoothing pass (three per material).
const PASS_WIDTH: usize = 12;

/// Nodal smoothed strains and the buffers of the smoothing, allocated once.
#[derive(Debug, Clone)]
pub struct StrainSmoothing<R: Real> {
    /// Column of each material index (`usize::MAX` for indices no element uses).
    column: Vec<usize>,
    /// Number of columns: materials smoothed separately.
    columns: usize,
    /// Per node and column (index `node * columns + column`): the smoothed volumetric strain
    /// increments of the solid and of the liquid.
    nodal: Vec<[R; 2]>,
}

impl<R: Real> StrainSmoothing<R> {
    /// Buffers for `nodes` nodes and the materials of `element_material` (0: empty element).
    pub fn new(nodes: usize, element_material: &[u32]) -> Self {
        let top = element_material.iter().copied().max().unwrap_or(0) as usize;
        let mut used = vec![false; top + 1];
        for &m in element_material {
            used[m as usize] = true;
        }
        // Columns in material order, so that they do not depend on the element order.
        let mut column = vec![usize::MAX; top + 1];
        let mut columns = 0;
        for m in 1..=top {
            if used[m] {
                column[m] = columns;
                columns += 1;
            }
        }
        StrainSmoothing {
            column,
            columns,
            nodal: vec![[R::ZERO; 2]; nodes * columns],
        }
    }

    /// Computes the nodal smoothed strain increments of this step from the nodal velocities of
    /// both phases (`g.vel`, and the liquid's when the case has one), over the elements
    /// holding points of `p`. With contact, `structure` gives the structure's own nodes and its
    /// material: that material's strain takes the structure's velocities (as Anura3D takes
    /// each material's body's displacements), the others the soil's `g`.
    pub fn compute<E: Element>(
        &mut self,
        passes: &Passes<'_, R, E>,
        slots: &mut Slots<R>,
        (p, g): (&Particles<R>, &Grid<R>),
        structure: Option<(&Grid<R>, u32)>,
        dt: R,
    ) {
        let (team, layout, mesh) = (passes.team, passes.layout, passes.mesh);
        let (column, columns) = (&self.column, self.columns);
        let wvel = g.liquid.as_ref().map(|l| &l.vel);
        // The structure's column and nodal velocities (no column: none).
        let (own, own_vel) = structure.map_or((usize::MAX, None), |(sg, m)| {
            (
                column.get(m as usize).copied().unwrap_or(usize::MAX),
                Some(&sg.vel),
            )
        });
        for lo in (0..columns).step_by(PER_PASS) {
            let hi = (lo + PER_PASS).min(columns);
            layout.scatter::<PASS_WIDTH, _>(team, slots, |e, points, four| {
                let mut present = [false; PER_PASS];
                for i in points {
                    let c = column[p.material[i] as usize];
                    if p.active[i] && (lo..hi).contains(&c) {
                        present[c - lo] = true;
                    }
                }
                if !present.contains(&true) {
                    return;
                }
                let grad = mesh.grad[e].as_ref();
                let (mut es, mut ew, mut es_own) = (R::ZERO, R::ZERO, R::ZERO);
                for k in 0..E::NODES {
                    let node = mesh.corners[e].as_ref()[k] as usize;
                    let v = g.vel[node];
                    for a in 0..3 {
                        es += v[a] * grad[k][a];
                    }
                    if let Some(w) = wvel {
                        for a in 0..3 {
                            ew += w[node][a] * grad[k][a];
                        }
                    }
                    if let Some(sv) = own_vel {
                        for a in 0..3 {
                            es_own += sv[node][a] * grad[k][a];
                        }
                    }
                }
                let ve = mesh.volume[e];
                let (es, ew, es_own) = (es * dt * ve, ew * dt * ve, es_own * dt * ve);
                for (j, _) in present.iter().enumerate().filter(|(_, &on)| on) {
                    // The structure is dry: its liquid term is 0.
                    let (s, w) = if lo + j == own {
                        (es_own, R::ZERO)
                    } else {
                        (es, ew)
                    };
                    for slot in node_slots::<E, R>(four, PASS_WIDTH) {
                        slot[3 * j] += s;
                        slot[3 * j + 1] += w;
                        slot[3 * j + 2] += ve;
                    }
                }
            });
            let nodal = Shared::new(&mut self.nodal);
            layout.gather::<PASS_WIDTH, _>(team, slots, |n, s| {
                // SAFETY: node n is this thread's only, and with it its columns.
                let out = unsafe { nodal.range(n * columns + lo..n * columns + hi) };
                for (j, o) in out.iter_mut().enumerate() {
                    let w = s[3 * j + 2];
                    *o = if w > R::ZERO {
                        [s[3 * j] / w, s[3 * j + 1] / w]
                    } else {
                        [R::ZERO; 2]
                    };
                }
            });
        }
    }

    /// The smoothed volumetric strain increments (solid, liquid) of material `m`'s points in
    /// element `e`: the plain mean of the element's nodal values.
    #[inline]
    pub fn element_mean<E: Element>(&self, mesh: &Mesh<E, R>, e: usize, m: u32) -> [R; 2] {
        let c = self.column[m as usize];
        // 1/4 for tetrahedra, exact in binary.
        let share = R::ONE / R::of(E::NODES as f64);
        let mut out = [R::ZERO; 2];
        for &node in mesh.corners[e].as_ref() {
            let v = self.nodal[node as usize * self.columns + c];
            out[0] += v[0] * share;
            out[1] += v[1] * share;
        }
        out
    }
}
