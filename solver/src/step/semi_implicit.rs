//! The semi-implicit two-phase step (docs/design.md §4.4c): the pore pressure is solved for on
//! the nodes, implicitly, so that the step follows the skeleton's wave speed instead of the
//! undrained one (the water's compressibility, 10–30× faster in soils).
//!
//! The explicit grid update has given each node the accelerations a*_s, a*_w of the forces at
//! the start-of-step pore pressure p. This step then finds the nodal increments δp of the
//! pressure, interpolated to the points with their shape functions, whose forces make the
//! mixture's end-of-step flux satisfy the liquid's mass balance at the nodes:
//!
//!   M_p δp = Δt D q(δp),   q_j = (1 − n_j) v_j + n_j w_j,
//!   M_p,i = Σ_p V_p N_i(x_p) n_p / K_w,p,   (D q)_i = Σ_p V_p N_i(x_p) ∇·q(x_p),
//!
//! with v, w each phase's end-of-step nodal velocity (fixed components 0) and n_j the node's
//! porosity M̄_w / M_w. The increment pushes both the mixture and the liquid with the same nodal
//! force, f = −Dᵀ δp (−Σ_p V_p ∇N_j δp(x_p)), to which each node answers through the grid
//! update's implicit-drag 2×2 system (undamped, its fixities kept): Δa_s = r_s f, Δa_w = r_w f,
//! and so Δq = Δt γ f with γ = (1 − n) r_s + n r_w ≥ 0. Together:
//!
//!   (M_p + Δt² D Γ Dᵀ) δp = Δt D q*,
//!
//! symmetric and positive definite (M_p > 0 at every node with liquid), solved by conjugate
//! gradients with a diagonal preconditioner, matrix-free: one value per element, then a gather
//! per node over its elements. For one material
//! the nodal rate δp / Δt is the explicit scheme's smoothed rate (`smooth_pressure`) at the
//! end-of-step velocities, so the two agree as Δt → 0; at a larger step the pressure is
//! backward Euler in time, unconditionally stable, while the effective stress stays explicit.
//!
//! Every sum is in f64 and in a fixed order (a node's elements in element order, the dot
//! products per block of nodes and the blocks in order), whichever thread forms it: the result
//! is the same bits for any thread count.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::material::liquid::Fluid;
use crate::parallel::gather::Layout;
use crate::parallel::team::{Shared, Team};
use crate::real::Real;
use crate::state::grid::Grid;
use crate::state::particles::Particles;

/// The pressure solve's default relative tolerance: ‖K δp − b‖ ≤ tolerance ‖b‖.
pub const DEFAULT_TOLERANCE: f64 = 1e-8;

/// Conjugate-gradient iterations allowed per step, per unknown (at least [`MIN_ITERATIONS`]).
const ITERATIONS_PER_UNKNOWN: usize = 2;

/// The fewest iterations allowed per step.
const MIN_ITERATIONS: usize = 200;

/// Nodes (and live elements) per block of the solve's passes and sums.
const BLOCK: usize = 1024;

/// Live elements from which the solve's passes run on the thread team (below, one thread: a
/// team run costs more than such a pass).
const PARALLEL_FROM: usize = 4096;

/// The pressure solve did not reach its tolerance.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "the semi-implicit pressure solve stopped after {iterations} iterations at a relative \
     residual of {residual:.3e} (tolerance {tolerance:.1e})"
)]
pub struct NotConverged {
    /// Iterations run.
    pub iterations: usize,
    /// ‖K δp − b‖ / ‖b‖ reached.
    pub residual: f64,
    /// The tolerance asked for.
    pub tolerance: f64,
}

/// How many iterations the pressure solves took: the run's report.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveCounts {
    /// Steps solved.
    pub solves: u64,
    /// Iterations over every step.
    pub iterations: u64,
    /// The most iterations of one step.
    pub most: u32,
    /// The largest relative residual a step ended with.
    pub worst_residual: f64,
}

impl SolveCounts {
    /// The counts as a checkpoint's named values (the residual as its bits).
    pub fn saved(&self) -> [(&'static str, u64); 4] {
        [
            ("pressure_solves", self.solves),
            ("pressure_iterations", self.iterations),
            ("pressure_most", self.most as u64),
            ("pressure_worst_residual", self.worst_residual.to_bits()),
        ]
    }

    /// The counts of [`SolveCounts::saved`]'s values.
    pub fn restored(v: [u64; 4]) -> Self {
        SolveCounts {
            solves: v[0],
            iterations: v[1],
            most: v[2] as u32,
            worst_residual: f64::from_bits(v[3]),
        }
    }
}

/// The semi-implicit pressure solve of a run: its settings, the per-element weights, the
/// per-node coefficients and the solver's vectors, all sized at set-up (a step allocates
/// nothing).
#[derive(Debug, Clone)]
pub struct SemiImplicit {
    /// Relative tolerance of the solve.
    pub tolerance: f64,
    /// The mesh's elements as the solve reads them.
    elements: Elements,
    /// Per element, Σ V N_k over its saturated active points (node k of the element).
    weights: Vec<[f64; 4]>,
    /// Per element, Σ V N_k n / K_w over the same points.
    element_compress: Vec<[f64; 4]>,
    /// Per node, M_p = Σ V N n / K_w.
    compress: Vec<f64>,
    /// Per node and component, the solid's and the liquid's acceleration per unit force.
    response: Vec<[[f64; 2]; 3]>,
    /// Per node and component, γ = (1 − n) r_s + n r_w.
    mobility: Vec<[f64; 3]>,
    /// Per node, the mixture flux at the explicit end-of-step velocities, then the force Dᵀ x.
    vector: Vec<[f64; 3]>,
    /// The diagonal preconditioner's inverse.
    precond: Vec<f64>,
    /// The solution δp, the right-hand side, the residual, the preconditioned residual, the
    /// search direction and its image.
    x: Vec<f64>,
    b: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    d: Vec<f64>,
    kd: Vec<f64>,
    /// Per block of nodes, the passes' partial sums.
    per_block: Vec<[f64; 2]>,
    /// What the solves took so far.
    pub counts: SolveCounts,
}

impl SemiImplicit {
    /// The solve `case` asks for on `mesh` (`None` under the explicit scheme).
    pub fn of<E: Element, R: Real>(
        case: &crate::input::case::Case,
        mesh: &Mesh<E, R>,
    ) -> Option<Self> {
        match case.numerics.scheme {
            crate::input::case::Scheme::SemiImplicit { tolerance } => {
                Some(Self::new(mesh, tolerance))
            }
            crate::input::case::Scheme::Explicit => None,
        }
    }

    /// The solve on `mesh`, to `tolerance`.
    pub fn new<E: Element, R: Real>(mesh: &Mesh<E, R>, tolerance: f64) -> Self {
        let (elements, nodes) = (mesh.elements(), mesh.nodes());
        let zeros = vec![0.0; nodes];
        SemiImplicit {
            tolerance,
            elements: Elements::of(mesh),
            weights: vec![[0.0; 4]; elements],
            element_compress: vec![[0.0; 4]; elements],
            compress: zeros.clone(),
            response: vec![[[0.0; 2]; 3]; nodes],
            mobility: vec![[0.0; 3]; nodes],
            vector: vec![[0.0; 3]; nodes],
            precond: zeros.clone(),
            x: zeros.clone(),
            b: zeros.clone(),
            r: zeros.clone(),
            z: zeros.clone(),
            d: zeros.clone(),
            kd: zeros,
            per_block: vec![[0.0; 2]; nodes.div_ceil(BLOCK)],
            counts: SolveCounts::default(),
        }
    }

    /// Solves for this step's nodal pressure increments and corrects the nodes' accelerations
    /// (left by the two-phase grid update at the start-of-step pressure) with their forces; the
    /// liquid's nodal `rate` becomes δp / Δt, for the stress pass to interpolate to the points.
    /// `fixed` and `liquid_fixed` are each phase's fixed components.
    #[allow(clippy::too_many_arguments)]
    pub fn correct<E: Element, R: Real>(
        &mut self,
        (team, layout): (&Team, &Layout<R, E>),
        mesh: &Mesh<E, R>,
        p: &Particles<R>,
        fluids: &[Option<Fluid<R>>],
        g: &mut Grid<R>,
        (fixed, liquid_fixed): (&[[bool; 3]], &[[bool; 3]]),
        dt: f64,
    ) -> Result<(), NotConverged> {
        self.element_weights(team, layout, mesh, p, fluids);
        self.node_terms::<E, R>(g, (fixed, liquid_fixed), dt);
        self.preconditioner(dt);
        let (iterations, residual) = self.conjugate_gradients(team, dt);
        let c = &mut self.counts;
        c.solves += 1;
        c.iterations += iterations as u64;
        c.most = c.most.max(iterations as u32);
        c.worst_residual = c.worst_residual.max(residual);
        if residual > self.tolerance {
            return Err(NotConverged {
                iterations,
                residual,
                tolerance: self.tolerance,
            });
        }
        self.apply_forces::<E, R>(g, dt);
        Ok(())
    }

    /// Per element, Σ V N_k over its saturated active points, and per node M_p: each element's
    /// points on the thread that holds the element, in point order.
    fn element_weights<E: Element, R: Real>(
        &mut self,
        team: &Team,
        layout: &Layout<R, E>,
        mesh: &Mesh<E, R>,
        p: &Particles<R>,
        fluids: &[Option<Fluid<R>>],
    ) {
        {
            let (w_out, c_out) = (
                Shared::new(&mut self.weights),
                Shared::new(&mut self.element_compress),
            );
            team.run(|t| {
                for e in layout.element_range(t) {
                    let (mut w, mut c) = ([0.0; 4], [0.0; 4]);
                    for i in layout.particles_of(e) {
                        let Some(f) = (p.active[i])
                            .then(|| fluids[p.material[i] as usize].as_ref())
                            .flatten()
                        else {
                            continue;
                        };
                        let n = mesh.shape(e, &p.x[i]);
                        let (v, nk) = (p.volume[i].f64(), f.n_over_kw.f64());
                        for (k, &nv) in n.as_ref().iter().enumerate() {
                            w[k] += v * nv.f64();
                            c[k] += v * nv.f64() * nk;
                        }
                    }
                    // SAFETY: element e is this thread's only.
                    unsafe {
                        w_out.write(e, w);
                        c_out.write(e, c);
                    }
                }
            });
        }
        self.compress.fill(0.0);
        self.elements.live.clear();
        // An element that is not live keeps the value 0 through the step's passes.
        self.elements.value.fill(0.0);
        self.elements.take_weights(&self.weights);
        for (e, (c, w)) in self.element_compress.iter().zip(&self.weights).enumerate() {
            if w.iter().all(|&w| w == 0.0) {
                continue;
            }
            // (Within its capacity, the mesh's element count: no allocation.)
            self.elements.live.push(e as u32);
            for (k, &node) in mesh.corners[e].as_ref().iter().enumerate() {
                self.compress[node as usize] += c[k];
            }
        }
    }

    /// Per node and component, each phase's acceleration per unit force (the grid update's
    /// implicit-drag system without damping, its fixities kept) and the mixture's mobility γ;
    /// then b = Δt D q*, q* the mixture flux at the explicit end-of-step velocities.
    fn node_terms<E: Element, R: Real>(
        &mut self,
        g: &Grid<R>,
        (fixed, liquid_fixed): (&[[bool; 3]], &[[bool; 3]]),
        dt: f64,
    ) {
        let gl = g.liquid.as_ref().expect("a two-phase case's nodes");
        let eps = g.empty_below.f64();
        for j in 0..g.mass.len() {
            let (ms, mw) = (g.mass[j].f64(), gl.mass[j].f64());
            self.vector[j] = [0.0; 3];
            if ms <= eps || mw <= 0.0 {
                self.response[j] = [[0.0; 2]; 3];
                self.mobility[j] = [0.0; 3];
                continue;
            }
            let (mwn, qdt) = (gl.mass_n[j].f64(), gl.drag[j].f64() * dt);
            let n = mwn / mw;
            for a in 0..3 {
                let rs_rw = match (fixed[j][a], liquid_fixed[j][a]) {
                    (true, true) => [0.0, 0.0],
                    (true, false) => [0.0, 1.0 / (mw + qdt)],
                    (false, true) => [1.0 / ms, 0.0],
                    (false, false) => {
                        let rw = (1.0 + qdt / ms) / (mw + qdt * (1.0 + mwn / ms));
                        [(1.0 - mwn * rw) / ms, rw]
                    }
                };
                self.response[j][a] = rs_rw;
                self.mobility[j][a] = (1.0 - n) * rs_rw[0] + n * rs_rw[1];
            }
            for a in 0..E::DIM {
                let v = if fixed[j][a] {
                    0.0
                } else {
                    g.momentum[j][a].f64() / ms + g.acc[j][a].f64() * dt
                };
                let w = if liquid_fixed[j][a] {
                    0.0
                } else {
                    gl.momentum[j][a].f64() / mw + gl.acc[j][a].f64() * dt
                };
                self.vector[j][a] = (1.0 - n) * v + n * w;
            }
        }
        self.elements.element_divergences(None, &self.vector);
        for i in 0..self.b.len() {
            self.b[i] = dt * self.elements.gather_weighted(i);
        }
    }

    /// The inverse of an approximate diagonal of K: M_p plus each element's own share of
    /// Δt² D Γ Dᵀ (the shares of two elements meeting at a node are left out); 0 at a node
    /// without liquid, which is not solved for.
    fn preconditioner(&mut self, dt: f64) {
        self.precond.copy_from_slice(&self.compress);
        let el = &self.elements;
        for &e in &el.live {
            let e = e as usize;
            let (c, g, w) = (&el.corners[e], &el.grad[e], &self.weights[e]);
            for i in 0..4 {
                let mut s = 0.0;
                for j in 0..4 {
                    let m = &self.mobility[c[j] as usize];
                    for a in 0..3 {
                        let v = w[i] * g[j][a];
                        s += m[a] * v * v;
                    }
                }
                self.precond[c[i] as usize] += dt * dt * s;
            }
        }
        for (d, &m) in self.precond.iter_mut().zip(&self.compress) {
            *d = if m > 0.0 { 1.0 / *d } else { 0.0 };
        }
    }

    /// Preconditioned conjugate gradients on K δp = b from δp = 0: the iterations and the
    /// relative residual reached. Each pass runs on the team where there are at least
    /// [`PARALLEL_FROM`] live elements, else on this thread: the same sums either way (each
    /// element's value, each node's gather in element order, the products summed per block of
    /// [`BLOCK`] nodes and the blocks in order), so the same bits.
    fn conjugate_gradients(&mut self, team: &Team, dt: f64) -> (usize, f64) {
        let on = (self.elements.live.len() >= PARALLEL_FROM && team.threads > 1).then_some(team);
        let n = self.x.len();
        self.x.fill(0.0);
        let norm_b = self.sum(on, |i, s| s.b[i] * s.b[i]).sqrt();
        if norm_b == 0.0 {
            return (0, 0.0);
        }
        self.r.copy_from_slice(&self.b);
        for i in 0..n {
            self.z[i] = self.precond[i] * self.r[i];
        }
        self.d.copy_from_slice(&self.z);
        let mut rz = self.sum(on, |i, s| s.r[i] * s.z[i]);
        let limit = (ITERATIONS_PER_UNKNOWN * n).max(MIN_ITERATIONS);
        for k in 1..=limit {
            let dkd = self.apply(on, dt);
            let alpha = rz / dkd;
            let [rr, rz_next] = self.step_vectors(on, alpha);
            let residual = rr.sqrt() / norm_b;
            if residual <= self.tolerance {
                return (k, residual);
            }
            let beta = rz_next / rz;
            rz = rz_next;
            let (d, z) = (Shared::new(&mut self.d), &self.z);
            blocks(on, n, &mut self.per_block, |r| {
                // SAFETY: block r is this call's only.
                let d = unsafe { d.range(r.clone()) };
                for (d, &z) in d.iter_mut().zip(&z[r]) {
                    *d = z + beta * *d;
                }
                [0.0; 2]
            });
        }
        let rr = self.sum(on, |i, s| s.r[i] * s.r[i]);
        (limit, rr.sqrt() / norm_b)
    }

    /// Σ_i f(i) over the nodes, per block of [`BLOCK`] nodes, the blocks added in order.
    fn sum(&mut self, on: Option<&Team>, f: impl Fn(usize, &Self) -> f64 + Sync) -> f64 {
        let mut partial = std::mem::take(&mut self.per_block);
        let this = &*self;
        blocks(on, this.x.len(), &mut partial, |r| {
            [r.map(|i| f(i, this)).sum(), 0.0]
        });
        let blocks = this.x.len().div_ceil(BLOCK);
        let total = partial[..blocks].iter().map(|p| p[0]).sum();
        self.per_block = partial;
        total
    }

    /// x ← x + α d, r ← r − α K d, z = P r: returns (r·r, r·z).
    fn step_vectors(&mut self, on: Option<&Team>, alpha: f64) -> [f64; 2] {
        let n = self.x.len();
        let (x, r, z) = (
            Shared::new(&mut self.x),
            Shared::new(&mut self.r),
            Shared::new(&mut self.z),
        );
        let (d, kd, p) = (&self.d, &self.kd, &self.precond);
        blocks(on, n, &mut self.per_block, |b| {
            // SAFETY: block b is this call's only.
            let (x, r, z) = unsafe { (x.range(b.clone()), r.range(b.clone()), z.range(b.clone())) };
            let (mut rr, mut rz) = (0.0, 0.0);
            for (k, i) in b.enumerate() {
                x[k] += alpha * d[i];
                r[k] -= alpha * kd[i];
                z[k] = p[i] * r[k];
                rr += r[k] * r[k];
                rz += r[k] * z[k];
            }
            [rr, rz]
        });
        let blocks = n.div_ceil(BLOCK);
        self.per_block[..blocks]
            .iter()
            .fold([0.0; 2], |a, p| [a[0] + p[0], a[1] + p[1]])
    }

    /// kd = K d = M_p d + Δt² D Γ Dᵀ d (0 at the nodes not solved for); returns d · kd.
    fn apply(&mut self, on: Option<&Team>, dt: f64) -> f64 {
        let el = &mut self.elements;
        el.element_sums(on, &self.weights, &self.d);
        let (q, mobility) = (Shared::new(&mut self.vector), &self.mobility);
        let el = &self.elements;
        blocks(on, self.x.len(), &mut self.per_block, |r| {
            // SAFETY: block r is this call's only.
            let q = unsafe { q.range(r.clone()) };
            for (k, j) in r.enumerate() {
                let g = el.gather_gradient(j);
                q[k] = [0, 1, 2].map(|a| mobility[j][a] * g[a]);
            }
            [0.0; 2]
        });
        let el = &mut self.elements;
        el.element_divergences(on, &self.vector);
        let kd = Shared::new(&mut self.kd);
        let (el, d, m, p) = (&self.elements, &self.d, &self.compress, &self.precond);
        blocks(on, self.x.len(), &mut self.per_block, |r| {
            // SAFETY: block r is this call's only.
            let kd = unsafe { kd.range(r.clone()) };
            let mut dkd = 0.0;
            for (k, i) in r.enumerate() {
                kd[k] = if p[i] > 0.0 {
                    m[i] * d[i] + dt * dt * el.gather_weighted(i)
                } else {
                    0.0
                };
                dkd += d[i] * kd[k];
            }
            [dkd, 0.0]
        });
        let blocks = self.x.len().div_ceil(BLOCK);
        self.per_block[..blocks].iter().map(|p| p[0]).sum()
    }

    /// The increments' nodal force f = −Dᵀ δp added to both phases' accelerations through
    /// their responses, and the liquid's nodal rate δp / Δt.
    fn apply_forces<E: Element, R: Real>(&mut self, g: &mut Grid<R>, dt: f64) {
        self.elements.element_sums(None, &self.weights, &self.x);
        let gl = g.liquid.as_mut().expect("a two-phase case's nodes");
        for j in 0..g.acc.len() {
            let force = self.elements.gather_gradient(j);
            for a in 0..E::DIM {
                let f = -force[a];
                let [rs, rw] = self.response[j][a];
                g.acc[j][a] += R::of(rs * f);
                gl.acc[j][a] += R::of(rw * f);
            }
            gl.rate[j] = R::of(self.x[j] / dt);
        }
    }
}

/// The mesh's elements as the solve reads them, in f64 (linear elements: one gradient per
/// node), those that hold saturated points this step, and each node's elements. Both operators
/// form one value per element, then gather each node's from its elements in element order:
/// no scattered additions, so the nodes can be shared out among threads.
#[derive(Debug, Clone)]
struct Elements {
    /// Per element, its nodes (the fourth repeats the first in a triangle, with weight and
    /// gradient 0).
    corners: Vec<[u32; 4]>,
    /// Per element, ∇N of each node.
    grad: Vec<[[f64; 3]; 4]>,
    /// The elements with saturated points this step, in order (capacity: every element).
    live: Vec<u32>,
    /// Where each node's entries of `incident` start (nodes + 1).
    node_start: Vec<u32>,
    /// Per node, 4 e + k for each element e it is corner k of, in element order.
    incident: Vec<u32>,
    /// Per entry of `incident`, its element.
    inc_element: Vec<u32>,
    /// Per entry of `incident`, ∇N_k of its element (the gathers read it in a row).
    inc_grad: Vec<[f64; 3]>,
    /// Per entry of `incident`, this step's W_ek.
    inc_weight: Vec<f64>,
    /// Per element, the operator's value (0 for an element that is not live).
    value: Vec<f64>,
    /// Per block of live elements, nothing: the element passes' result slots.
    done: Vec<[f64; 2]>,
}

impl Elements {
    fn of<E: Element, R: Real>(mesh: &Mesh<E, R>) -> Self {
        let (n, nodes) = (mesh.elements(), mesh.nodes());
        let mut corners = vec![[0u32; 4]; n];
        let mut grad = vec![[[0.0; 3]; 4]; n];
        let mut start = vec![0u32; nodes + 1];
        for e in 0..n {
            let (c, g) = (mesh.corners[e].as_ref(), mesh.grad[e].as_ref());
            corners[e] = [0, 1, 2, 3].map(|k| c[k.min(c.len() - 1)]);
            for k in 0..c.len() {
                grad[e][k] = g[k].map(|v| v.f64());
                start[c[k] as usize + 1] += 1;
            }
        }
        for i in 0..nodes {
            start[i + 1] += start[i];
        }
        let mut incident = vec![0u32; start[nodes] as usize];
        let mut next = start.clone();
        for e in 0..n {
            for (k, &c) in mesh.corners[e].as_ref().iter().enumerate() {
                incident[next[c as usize] as usize] = (4 * e + k) as u32;
                next[c as usize] += 1;
            }
        }
        let inc_element = incident.iter().map(|&ek| ek / 4).collect();
        let inc_grad = incident
            .iter()
            .map(|&ek| grad[ek as usize / 4][ek as usize % 4])
            .collect();
        let inc_weight = vec![0.0; incident.len()];
        Elements {
            corners,
            grad,
            live: Vec::with_capacity(n),
            node_start: start,
            incident,
            inc_element,
            inc_grad,
            inc_weight,
            value: vec![0.0; n],
            done: vec![[0.0; 2]; n.div_ceil(BLOCK)],
        }
    }

    /// Node `i`'s entries of `incident`.
    #[inline]
    fn entries(&self, i: usize) -> std::ops::Range<usize> {
        self.node_start[i] as usize..self.node_start[i + 1] as usize
    }

    /// Each entry's W_ek of this step's `weights`.
    fn take_weights(&mut self, weights: &[[f64; 4]]) {
        for (w, &ek) in self.inc_weight.iter_mut().zip(&self.incident) {
            *w = weights[ek as usize / 4][ek as usize % 4];
        }
    }

    /// Each live element's value Σ_k W_ek x_k (the element's share of Dᵀ x).
    fn element_sums(&mut self, on: Option<&Team>, weights: &[[f64; 4]], x: &[f64]) {
        let (value, live, corners) = (Shared::new(&mut self.value), &self.live, &self.corners);
        blocks(on, live.len(), &mut self.done, |r| {
            for &e in &live[r] {
                let (e, c, w) = (e as usize, &corners[e as usize], &weights[e as usize]);
                let s = w[0] * x[c[0] as usize]
                    + w[1] * x[c[1] as usize]
                    + w[2] * x[c[2] as usize]
                    + w[3] * x[c[3] as usize];
                // SAFETY: the live elements are distinct, each in one block.
                unsafe { value.write(e, s) };
            }
            [0.0; 2]
        });
    }

    /// Each live element's divergence of the nodal field q, Σ_j ∇N_j · q_j.
    fn element_divergences(&mut self, on: Option<&Team>, q: &[[f64; 3]]) {
        let (value, live) = (Shared::new(&mut self.value), &self.live);
        let (corners, grad) = (&self.corners, &self.grad);
        blocks(on, live.len(), &mut self.done, |r| {
            for &e in &live[r] {
                let (c, g) = (&corners[e as usize], &grad[e as usize]);
                let mut div = 0.0;
                for j in 0..4 {
                    let q = &q[c[j] as usize];
                    div += g[j][0] * q[0] + g[j][1] * q[1] + g[j][2] * q[2];
                }
                // SAFETY: the live elements are distinct, each in one block.
                unsafe { value.write(e as usize, div) };
            }
            [0.0; 2]
        });
    }

    /// (Dᵀ x)_j = Σ_e ∇N_j s_e over node j's elements, s_e from [`Elements::element_sums`].
    #[inline]
    fn gather_gradient(&self, j: usize) -> [f64; 3] {
        let r = self.entries(j);
        let mut sum = [0.0; 3];
        for (g, &e) in self.inc_grad[r.clone()].iter().zip(&self.inc_element[r]) {
            let s = self.value[e as usize];
            sum[0] += g[0] * s;
            sum[1] += g[1] * s;
            sum[2] += g[2] * s;
        }
        sum
    }

    /// (D q)_i = Σ_e W_ei div_e over node i's elements, div_e from
    /// [`Elements::element_divergences`].
    #[inline]
    fn gather_weighted(&self, i: usize) -> f64 {
        let r = self.entries(i);
        let mut sum = 0.0;
        for (w, &e) in self.inc_weight[r.clone()].iter().zip(&self.inc_element[r]) {
            sum += w * self.value[e as usize];
        }
        sum
    }
}

/// `f` over the blocks of [`BLOCK`] of `0..n`, its results into `out`: on the team where `on`
/// names it, else in order on this thread. Each block's result is the same either way.
fn blocks<F: Fn(std::ops::Range<usize>) -> [f64; 2] + Sync>(
    on: Option<&Team>,
    n: usize,
    out: &mut [[f64; 2]],
    f: F,
) {
    match on {
        Some(team) => team.for_blocks(n, BLOCK, out, f),
        None => {
            for (b, o) in out.iter_mut().enumerate().take(n.div_ceil(BLOCK)) {
                *o = f(b * BLOCK..((b + 1) * BLOCK).min(n));
            }
        }
    }
}
