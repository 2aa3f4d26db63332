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
//! gradients with a diagonal preconditioner, matrix-free over the elements. For one material
//! the nodal rate δp / Δt is the explicit scheme's smoothed rate (`smooth_pressure`) at the
//! end-of-step velocities, so the two agree as Δt → 0; at a larger step the pressure is
//! backward Euler in time, unconditionally stable, while the effective stress stays explicit.
//!
//! Every sum runs over elements and nodes in their order on one thread, in f64: the result is
//! the same bits for any thread count.

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
    /// What the solves took so far.
    pub counts: SolveCounts,
}

impl SemiImplicit {
    /// The solve `case` asks for on a mesh of `elements` elements and `nodes` nodes (`None`
    /// under the explicit scheme).
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
            counts: SolveCounts::default(),
        }
    }

    /// The pressure increment of this step at each node (kPa), after [`SemiImplicit::correct`].
    pub fn increment(&self) -> &[f64] {
        &self.x
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
        self.node_coefficients(g, (fixed, liquid_fixed), dt);
        self.right_hand_side::<E, R>(g, (fixed, liquid_fixed), dt);
        self.preconditioner(dt);
        let (iterations, residual) = self.conjugate_gradients(dt);
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
    /// implicit-drag system without damping, its fixities kept) and the mixture's mobility γ.
    fn node_coefficients<R: Real>(
        &mut self,
        g: &Grid<R>,
        (fixed, liquid_fixed): (&[[bool; 3]], &[[bool; 3]]),
        dt: f64,
    ) {
        let gl = g.liquid.as_ref().expect("a two-phase case's nodes");
        let eps = g.empty_below.f64();
        for j in 0..g.mass.len() {
            let (ms, mw) = (g.mass[j].f64(), gl.mass[j].f64());
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
        }
    }

    /// b = Δt D q*, q* the mixture flux at the explicit end-of-step velocities.
    fn right_hand_side<E: Element, R: Real>(
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
                continue;
            }
            let n = gl.mass_n[j].f64() / mw;
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
        self.elements
            .divergence(&self.weights, &self.vector, &mut self.b);
        for b in &mut self.b {
            *b *= dt;
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
    /// relative residual reached.
    fn conjugate_gradients(&mut self, dt: f64) -> (usize, f64) {
        self.x.fill(0.0);
        let norm_b = dot(&self.b, &self.b).sqrt();
        if norm_b == 0.0 {
            return (0, 0.0);
        }
        self.r.copy_from_slice(&self.b);
        precondition(&self.precond, &self.r, &mut self.z);
        self.d.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        let limit = (ITERATIONS_PER_UNKNOWN * self.x.len()).max(MIN_ITERATIONS);
        for k in 1..=limit {
            self.apply(dt);
            let alpha = rz / dot(&self.d, &self.kd);
            for i in 0..self.x.len() {
                self.x[i] += alpha * self.d[i];
                self.r[i] -= alpha * self.kd[i];
            }
            let residual = dot(&self.r, &self.r).sqrt() / norm_b;
            if residual <= self.tolerance {
                return (k, residual);
            }
            precondition(&self.precond, &self.r, &mut self.z);
            let rz_next = dot(&self.r, &self.z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (d, &z) in self.d.iter_mut().zip(&self.z) {
                *d = z + beta * *d;
            }
        }
        (limit, dot(&self.r, &self.r).sqrt() / norm_b)
    }

    /// kd = K d = M_p d + Δt² D Γ Dᵀ d (0 at the nodes not solved for).
    fn apply(&mut self, dt: f64) {
        self.elements
            .transpose_divergence(&self.weights, &self.d, &mut self.vector);
        for (f, m) in self.vector.iter_mut().zip(&self.mobility) {
            for a in 0..3 {
                f[a] *= m[a];
            }
        }
        self.elements
            .divergence(&self.weights, &self.vector, &mut self.kd);
        for i in 0..self.kd.len() {
            self.kd[i] = if self.precond[i] > 0.0 {
                self.compress[i] * self.d[i] + dt * dt * self.kd[i]
            } else {
                0.0
            };
        }
    }

    /// The increments' nodal force f = −Dᵀ δp added to both phases' accelerations through
    /// their responses, and the liquid's nodal rate δp / Δt.
    fn apply_forces<E: Element, R: Real>(&mut self, g: &mut Grid<R>, dt: f64) {
        self.elements
            .transpose_divergence(&self.weights, &self.x, &mut self.vector);
        let gl = g.liquid.as_mut().expect("a two-phase case's nodes");
        for j in 0..g.acc.len() {
            for a in 0..E::DIM {
                let f = -self.vector[j][a];
                let [rs, rw] = self.response[j][a];
                g.acc[j][a] += R::of(rs * f);
                gl.acc[j][a] += R::of(rw * f);
            }
            gl.rate[j] = R::of(self.x[j] / dt);
        }
    }
}

/// The mesh's elements as the solve reads them, in f64 (linear elements: one gradient per
/// node), and those that hold saturated points this step.
#[derive(Debug, Clone)]
struct Elements {
    /// Per element, its nodes (the fourth repeats the first in a triangle, with weight and
    /// gradient 0).
    corners: Vec<[u32; 4]>,
    /// Per element, ∇N of each node.
    grad: Vec<[[f64; 3]; 4]>,
    /// The elements with saturated points this step, in order (capacity: every element).
    live: Vec<u32>,
}

impl Elements {
    fn of<E: Element, R: Real>(mesh: &Mesh<E, R>) -> Self {
        let n = mesh.elements();
        let mut corners = vec![[0u32; 4]; n];
        let mut grad = vec![[[0.0; 3]; 4]; n];
        for e in 0..n {
            let (c, g) = (mesh.corners[e].as_ref(), mesh.grad[e].as_ref());
            corners[e] = [0, 1, 2, 3].map(|k| c[k.min(c.len() - 1)]);
            for k in 0..c.len() {
                grad[e][k] = g[k].map(|v| v.f64());
            }
        }
        Elements {
            corners,
            grad,
            live: Vec::with_capacity(n),
        }
    }

    /// (D q)_i = Σ_e W_ei ∇·q over the live elements (linear elements: one divergence each),
    /// in element order.
    fn divergence(&self, weights: &[[f64; 4]], q: &[[f64; 3]], out: &mut [f64]) {
        out.fill(0.0);
        for &e in &self.live {
            let e = e as usize;
            let (c, g, w) = (&self.corners[e], &self.grad[e], &weights[e]);
            let mut div = 0.0;
            for j in 0..4 {
                let q = &q[c[j] as usize];
                div += g[j][0] * q[0] + g[j][1] * q[1] + g[j][2] * q[2];
            }
            for i in 0..4 {
                out[c[i] as usize] += w[i] * div;
            }
        }
    }

    /// (Dᵀ x)_j = Σ_e ∇N_j Σ_k W_ek x_k over the live elements, in element order.
    fn transpose_divergence(&self, weights: &[[f64; 4]], x: &[f64], out: &mut [[f64; 3]]) {
        out.fill([0.0; 3]);
        for &e in &self.live {
            let e = e as usize;
            let (c, g, w) = (&self.corners[e], &self.grad[e], &weights[e]);
            let s = w[0] * x[c[0] as usize]
                + w[1] * x[c[1] as usize]
                + w[2] * x[c[2] as usize]
                + w[3] * x[c[3] as usize];
            for j in 0..4 {
                let o = &mut out[c[j] as usize];
                for a in 0..3 {
                    o[a] += g[j][a] * s;
                }
            }
        }
    }
}

/// z = P r, P diagonal.
fn precondition(p: &[f64], r: &[f64], z: &mut [f64]) {
    for ((z, &p), &r) in z.iter_mut().zip(p).zip(r) {
        *z = p * r;
    }
}

/// Σ a_i b_i, in order.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
