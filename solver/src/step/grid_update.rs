//! Grid update: nodal accelerations with local damping and fixities (docs/design.md §4, step 2).

use crate::element::Element;
use crate::parallel::comm::Communicator;
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;

/// Nodes per block of the grid update: each block's force and energy sums are formed in node
/// order by one thread and the blocks added in order, so the sums are the same for any thread
/// count.
pub const NODE_BLOCK: usize = 1024;

/// The grid update's per-block results, preallocated for a mesh's nodes (a step allocates
/// nothing).
#[derive(Debug, Clone)]
pub struct GridScratch<R> {
    /// A value per block: each block's heaviest node (the empty-node threshold), then the
    /// largest nodal magnitude of [`crate::step::tail::cut_grid`].
    pub(crate) per_block: Vec<R>,
    done: Vec<()>,
    /// Per node, the terms of the force sums: |f_mix|, |f_ext| over the free solid components
    /// and the same for the liquid (0 at empty nodes). Summed by the layout's owned-node blocks
    /// ([`crate::parallel::gather::Layout::sum_owned`]), so that the sums are the same for any
    /// thread and rank count.
    pub node_sums: Vec<[f64; 4]>,
    /// Per node, the weights of a background grid's smoothed pore-pressure rates
    /// ([`crate::step::stress::smooth_rates`]; sized on first use).
    pub rate_weights: Vec<R>,
}

impl<R: Real> GridScratch<R> {
    /// Room for the blocks of `nodes` nodes.
    pub fn new(nodes: usize) -> Self {
        let blocks = nodes.div_ceil(NODE_BLOCK);
        GridScratch {
            per_block: vec![R::ZERO; blocks],
            done: vec![(); blocks],
            node_sums: vec![[0.0; 4]; nodes],
            rate_weights: Vec::new(),
        }
    }

    /// The mass below which a node counts as empty ([`MASS_EPS`] of the heaviest node of every
    /// process), on the team.
    fn empty_below(&mut self, team: &Team, comm: &dyn Communicator, mass: &[R]) -> R {
        team.for_blocks(mass.len(), NODE_BLOCK, &mut self.per_block, |r| {
            mass[r].iter().fold(R::ZERO, |a, &b| a.max(b))
        });
        let blocks = mass.len().div_ceil(NODE_BLOCK);
        let heaviest = self.per_block[..blocks]
            .iter()
            .fold(R::ZERO, |a, &b| a.max(b));
        // A rank's nodes shared with another hold part of their mass only, never more: the
        // largest over the ranks is the whole mesh's.
        R::of(comm.max(heaviest.f64())) * R::of(MASS_EPS)
    }

    /// The force sums from the per-node terms, (mixture, liquid), with `sum` adding a per-node
    /// array over the mesh ([`crate::parallel::gather::Layout::sum_owned`] and
    /// [`crate::parallel::gather::exact_total`]).
    pub fn totals(&self, sum: impl FnOnce(&[[f64; 4]]) -> [f64; 4]) -> (ForceSums, ForceSums) {
        let t = sum(&self.node_sums);
        (
            ForceSums {
                unbalanced: t[0],
                external: t[1],
            },
            ForceSums {
                unbalanced: t[2],
                external: t[3],
            },
        )
    }
}

/// Local damping of force `f` at a node moving with `v` (one component):
/// f - α |f| sign(v). At rest (v = 0) Anura3D's rule leaves the force undamped; the scenes'
/// rule damps it against the motion it is about to cause (sign of f), which is what Anura3D's
/// tiny first step amounts to for the first full step.
#[inline]
pub(crate) fn damp<R: Real>(rule: DampingRule, alpha: R, f: R, v: R) -> R {
    let s = if v != R::ZERO {
        v.sign()
    } else {
        match rule {
            DampingRule::Anura3d => return f,
            DampingRule::Phases => f.sign(),
        }
    };
    f - alpha * f.abs() * s
}

/// Where and against which velocity local damping acts (`f ← f - α |f| sign(v)` per node and
/// component).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DampingRule {
    /// Anura3D's rule, for GOM input: a node whose velocity is exactly zero is not damped; in
    /// two-phase cases the liquid's force is damped against the liquid velocity, and the
    /// mixture's force in two parts, the solid part (effective stress, (1 - n) of the pore
    /// pressure, the solid's loads and weight) against the solid velocity and the liquid part
    /// (n times the liquid's force) against the liquid velocity.
    Anura3d,
    /// The rule of scenes: the mixture's force is damped in the same two parts, each against its
    /// own phase's start-of-step velocity (against the force where the node is at rest, which is
    /// what Anura3D's tiny first step amounts to), and the liquid's own force not at all: in
    /// seepage it is balanced by the drag, which dissipates already, and damping it would slow
    /// consolidation by (1 - α). Against Terzaghi this beats Anura3D's rule at every output of
    /// the default job's workshop set-up (docs/anura3d-fidelity.md).
    Phases,
}

/// Time integration of the Darcy drag Q (w - v) between liquid and solid (two-phase cases).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Drag {
    /// Per node, at the end-of-step velocities (a 2×2 solve per component): stable for any
    /// permeability, so the step is bounded by the waves alone.
    #[default]
    Implicit,
    /// At the start-of-step velocities, as Anura3D: the step must also resolve the drag's
    /// relaxation time k / (n g), which Mieremet's critical step does.
    Explicit,
}

/// Nodes lighter than this (relative to the heaviest) are treated as empty.
pub const MASS_EPS: f64 = 1e-12;

/// One phase's loads and conditions at the nodes for the grid update: the nodal face loads
/// at multiplier 1 (`traction`) and their multiplier (`scale`), the fixed components
/// (`fixed[n][a]`), and local damping (factor `alpha`, applied as `rule` says).
#[derive(Clone, Copy)]
pub struct NodeLoads<'a, R: Real> {
    /// Nodal face loads at multiplier 1.
    pub traction: &'a [V3<R>],
    /// Their multiplier.
    pub scale: R,
    /// Fixed components.
    pub fixed: &'a [[bool; 3]],
    /// Local damping factor α.
    pub alpha: R,
    /// Where and against which velocity local damping acts.
    pub rule: DampingRule,
    /// Mass scaling's factor f (1: none): the accelerations are the forces over f m.
    pub inertia: R,
}

/// a = (f_int + f_ext + traction) / (f m) (f the mass scaling, 1 without), with local damping f ← f - α |f| sign(v) per component
/// (at rest as `rule` says, see [`DampingRule`])
/// and zero acceleration in fixed directions, over the element's [`Element::DIM`] components (a
/// 2D section's z-acceleration is 0), `loads` giving the loads, fixities and damping.
///
/// Returns this process's sums for the out-of-balance force ratio of Anura3D's quasi-static
/// convergence check, |f_int + f_ext| / |f_ext| over the free components
/// ([`ForceSums::ratio`] once summed over every process, `comm`); the step's energy terms are
/// taken after the remap ([`crate::step::nodal_energy`]). The nodes are shared out on the team
/// in blocks of [`NODE_BLOCK`], and the sums formed per block (`scratch`): the same for any
/// thread count.
pub fn grid_update<E: Element, R: Real>(
    (team, comm): (&Team, &dyn Communicator),
    scratch: &mut GridScratch<R>,
    g: &mut Grid<R>,
    loads: &NodeLoads<'_, R>,
) {
    let NodeLoads {
        traction,
        scale,
        fixed,
        alpha,
        rule,
        inertia,
    } = *loads;
    let nodes = g.mass.len();
    let eps = scratch.empty_below(team, comm, &g.mass);
    g.empty_below = eps;
    let (mass, f_ext, f_int, momentum) = (&g.mass, &g.f_ext, &g.f_int, &g.momentum);
    let acc_out = Shared::new(&mut g.acc);
    let sums_out = Shared::new(&mut scratch.node_sums);
    team.for_blocks(nodes, NODE_BLOCK, &mut scratch.done, |r| {
        // SAFETY: the nodes of this block are this call's only.
        let (acc_out, sums) = unsafe { (acc_out.range(r.clone()), sums_out.range(r.clone())) };
        // Every array sliced to the block once (one length): the loop indexes without bounds
        // checks.
        let len = acc_out.len();
        let (mass, fixed, f_ext) = (
            &mass[r.clone()][..len],
            &fixed[r.clone()][..len],
            &f_ext[r.clone()][..len],
        );
        let (f_int, momentum, traction) = (
            &f_int[r.clone()][..len],
            &momentum[r.clone()][..len],
            &traction[r.clone()][..len],
        );
        for (n, (acc_n, sum)) in acc_out.iter_mut().zip(&mut sums[..len]).enumerate() {
            let m = mass[n];
            // (Times 1 is the mass's own bits: no scaling, no change.)
            let scaled = m * inertia;
            // Components past the element's dimension stay 0 (a section's z: no force there).
            *acc_n = [R::ZERO; 3];
            if m <= eps {
                *sum = [0.0; 4];
                continue;
            }
            let (mut out2, mut ext2) = (0.0, 0.0);
            for a in 0..E::DIM {
                if fixed[n][a] {
                    continue;
                }
                let ext = f_ext[n][a] + scale * traction[n][a];
                let f = f_int[n][a] + ext;
                out2 += f.f64() * f.f64();
                ext2 += ext.f64() * ext.f64();
                acc_n[a] = damp(rule, alpha, f, momentum[n][a]) / scaled;
            }
            *sum = [out2.sqrt(), ext2.sqrt(), 0.0, 0.0];
        }
    });
}

/// Norms of the out-of-balance and the external force over the free components, Anura3D's
/// (its `Norm`): the sum over the nodes of each node's Euclidean norm.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ForceSums {
    /// Σ_nodes |f_int + f_ext|.
    pub unbalanced: f64,
    /// Σ_nodes |f_ext|.
    pub external: f64,
}

impl ForceSums {
    /// |out-of-balance| / |external| (0 without external force).
    pub fn ratio(self) -> f64 {
        if self.external > 0.0 {
            self.unbalanced / self.external
        } else {
            0.0
        }
    }
}

/// The loads and conditions of the two-phase grid update: the mixture's ([`NodeLoads`], its
/// damping the update's), the liquid's face loads and fixities, the drag's integration, whether
/// loads on the liquid act on the mixture too, the step's gravity and the step.
#[derive(Clone, Copy)]
pub struct TwoPhaseLoads<'a, R: Real> {
    /// The mixture's loads, fixities and damping.
    pub mixture: NodeLoads<'a, R>,
    /// Nodal face loads on the liquid at multiplier 1.
    pub liquid_traction: &'a [V3<R>],
    /// Their multiplier.
    pub liquid_scale: R,
    /// The liquid's fixed components.
    pub liquid_fixed: &'a [[bool; 3]],
    /// How the drag is integrated.
    pub drag: Drag,
    /// Whether loads on the liquid act on the mixture too.
    pub liquid_load_on_mixture: bool,
    /// The acceleration of gravity this step.
    pub gravity: V3<R>,
    /// The step.
    pub dt: R,
}

/// Two-phase grid update (docs/design.md §4). With the mixture force F (total-stress internal force,
/// mixture weight, loads), the liquid force F_w (pore-pressure gradient, liquid weight, loads on
/// the liquid), the lumped masses M_s, M_w, M̄_w and drag Q, per node and component:
///
///   M_w a_w = F_w - Q (w - v),   M_s a_s = F - M̄_w a_w,
///
/// with the drag at the start-of-step velocities ([`Drag::Explicit`], as Anura3D) or at the
/// end-of-step ones, w + a_w Δt and v + a_s Δt ([`Drag::Implicit`]: a 2×2 solve that never
/// limits the step). Local damping follows `rule` ([`DampingRule`]): Anura3D's damps F_w
/// against w and splits the mixture force into its solid part F - n F_w, damped against v, and
/// its liquid part n F_w, damped against the liquid velocity already updated with its explicit
/// acceleration, w + a_w Δt (n: the node's porosity M̄_w / M_w); the scenes' rule damps the
/// same two parts against the start-of-step v and w and leaves F_w alone. Fixed components of a phase have zero
/// acceleration (a fixed solid takes the reaction; a fixed liquid is an impermeable face) and,
/// as in Anura3D, zero velocity in the explicit drag and the damping. Loads on the liquid
/// (`liquid_traction` × `liquid_scale`) act on the liquid and, with `liquid_load_on_mixture`,
/// as part of the total traction, on the mixture too (Anura3D applies them to the liquid
/// alone). Nodes without liquid mass follow the dry update. As [`grid_update`], over the
/// element's [`Element::DIM`] components. Returns the out-of-balance
/// force ratios of the mixture, as [`grid_update`], and of the liquid: |F_w + Q (v - w)| /
/// |M_w g + loads + Q (v - w)| over the free liquid components (start-of-step velocities, as
/// Anura3D's convergence check; 0 without external force). `gravity` is the acceleration of
/// this step. The step's energy terms are taken after the remap
/// ([`crate::step::nodal_energy`]).
pub fn grid_update_two_phase<E: Element, R: Real>(
    (team, comm): (&Team, &dyn Communicator),
    scratch: &mut GridScratch<R>,
    g: &mut Grid<R>,
    loads: &TwoPhaseLoads<'_, R>,
) {
    // Mass scaling is refused with a liquid at set-up (`SetupError::MassScaling`).
    debug_assert!(
        loads.mixture.inertia == R::ONE,
        "mass scaling with a liquid"
    );
    let nodes = g.mass.len();
    let eps = scratch.empty_below(team, comm, &g.mass);
    g.empty_below = eps;
    let gl = g.liquid.as_mut().expect("liquid arrays");
    let (acc_s, acc_w) = (Shared::new(&mut g.acc), Shared::new(&mut gl.acc));
    let sums_out = Shared::new(&mut scratch.node_sums);
    let arrays = TwoPhaseNodes {
        mass: &g.mass,
        f_ext: &g.f_ext,
        f_int: &g.f_int,
        momentum: &g.momentum,
        l_mass: &gl.mass,
        l_mass_n: &gl.mass_n,
        l_drag: &gl.drag,
        l_momentum: &gl.momentum,
        l_force: &gl.force,
    };
    team.for_blocks(nodes, NODE_BLOCK, &mut scratch.done, |r| {
        // SAFETY: the nodes of this block are this call's only.
        let (acc_s, acc_w, sums) = unsafe {
            (
                acc_s.range(r.clone()),
                acc_w.range(r.clone()),
                sums_out.range(r.clone()),
            )
        };
        // Every array sliced to the block once (one length): the loop indexes without bounds
        // checks.
        let len = acc_s.len();
        let (acc_w, sums) = (&mut acc_w[..len], &mut sums[..len]);
        let block = arrays.block(r.clone(), len);
        let (traction, liquid_traction, fixed, liquid_fixed) = (
            &loads.mixture.traction[r.clone()][..len],
            &loads.liquid_traction[r.clone()][..len],
            &loads.mixture.fixed[r.clone()][..len],
            &loads.liquid_fixed[r.clone()][..len],
        );
        for (n, ((acc_s, acc_w), sum)) in acc_s.iter_mut().zip(acc_w).zip(sums).enumerate() {
            // Components past the element's dimension stay 0 (a section's z: no force there).
            *acc_s = [R::ZERO; 3];
            *acc_w = [R::ZERO; 3];
            if block.mass[n] <= eps {
                *sum = [0.0; 4];
                continue;
            }
            let wet = block.l_mass[n] > eps;
            let mut norms = [0.0; 4];
            for a in 0..E::DIM {
                let lt = loads.liquid_scale * liquid_traction[n][a];
                let scaled = loads.mixture.scale * traction[n][a];
                let ext = if loads.liquid_load_on_mixture {
                    block.f_ext[n][a] + scaled + lt
                } else {
                    block.f_ext[n][a] + scaled
                };
                let f_mix = block.f_int[n][a] + ext;
                if !fixed[n][a] {
                    norms[0] += f_mix.f64() * f_mix.f64();
                    norms[1] += ext.f64() * ext.f64();
                }
                let c = Component {
                    ms: block.mass[n],
                    mw: block.l_mass[n],
                    mwn: block.l_mass_n[n],
                    q: block.l_drag[n],
                    p_s: block.momentum[n][a],
                    p_w: block.l_momentum[n][a],
                    f_mix,
                    f_w: block.l_force[n][a] + lt,
                    fixed: fixed[n][a],
                    liquid_fixed: liquid_fixed[n][a],
                    weight_w: block.l_mass[n] * loads.gravity[a] + lt,
                };
                (acc_s[a], acc_w[a]) = if wet {
                    c.accelerations(loads, &mut norms)
                } else if c.fixed {
                    (R::ZERO, R::ZERO)
                } else {
                    let m = &loads.mixture;
                    (damp(m.rule, m.alpha, f_mix, c.p_s) / c.ms, R::ZERO)
                };
            }
            *sum = norms.map(f64::sqrt);
        }
    });
}

/// The nodal arrays the two-phase grid update reads: the solid's mass, external and internal
/// force and momentum, the liquid's two masses, drag, momentum and force.
#[derive(Clone, Copy)]
struct TwoPhaseNodes<'a, R: Real> {
    mass: &'a [R],
    f_ext: &'a [V3<R>],
    f_int: &'a [V3<R>],
    momentum: &'a [V3<R>],
    l_mass: &'a [R],
    l_mass_n: &'a [R],
    l_drag: &'a [R],
    l_momentum: &'a [V3<R>],
    l_force: &'a [V3<R>],
}

impl<'a, R: Real> TwoPhaseNodes<'a, R> {
    /// Every array sliced to the nodes `r`, `len` of them (one length: indexed without bounds
    /// checks).
    #[inline(always)]
    fn block(&self, r: std::ops::Range<usize>, len: usize) -> Self {
        TwoPhaseNodes {
            mass: &self.mass[r.clone()][..len],
            f_ext: &self.f_ext[r.clone()][..len],
            f_int: &self.f_int[r.clone()][..len],
            momentum: &self.momentum[r.clone()][..len],
            l_mass: &self.l_mass[r.clone()][..len],
            l_mass_n: &self.l_mass_n[r.clone()][..len],
            l_drag: &self.l_drag[r.clone()][..len],
            l_momentum: &self.l_momentum[r.clone()][..len],
            l_force: &self.l_force[r][..len],
        }
    }
}

/// One component of a node holding liquid: the masses M_s, M_w, M̄_w and drag Q, both phases'
/// momenta, the mixture force and the liquid force (loads included), the fixities, and the
/// liquid's weight with its loads (the external force of its convergence check).
struct Component<R: Real> {
    ms: R,
    mw: R,
    mwn: R,
    q: R,
    p_s: R,
    p_w: R,
    f_mix: R,
    f_w: R,
    fixed: bool,
    liquid_fixed: bool,
    weight_w: R,
}

impl<R: Real> Component<R> {
    /// The solid's and the liquid's accelerations ([`grid_update_two_phase`]), the liquid's
    /// convergence terms added to `norms[2..4]` (squared).
    #[inline(always)]
    fn accelerations(&self, loads: &TwoPhaseLoads<'_, R>, norms: &mut [f64; 4]) -> (R, R) {
        let (rule, alpha, dt) = (loads.mixture.rule, loads.mixture.alpha, loads.dt);
        let Component {
            ms,
            mw,
            mwn,
            q,
            f_w,
            ..
        } = *self;
        // Start-of-step velocities of the fixity-masked phases (Anura3D's nodal velocities).
        let v = if self.fixed { R::ZERO } else { self.p_s / ms };
        let w = if self.liquid_fixed {
            R::ZERO
        } else {
            self.p_w / mw
        };
        if !self.liquid_fixed {
            let qvw = q * (v - w);
            let (out, ext) = (f_w + qvw, self.weight_w + qvw);
            norms[2] += out.f64() * out.f64();
            norms[3] += ext.f64() * ext.f64();
        }
        let fw = match rule {
            DampingRule::Phases => f_w,
            DampingRule::Anura3d => damp(rule, alpha, f_w, w),
        };
        // The liquid's acceleration with the drag at the start-of-step velocities.
        let a_w_explicit = if self.liquid_fixed {
            R::ZERO
        } else {
            (fw + q * (v - w)) / mw
        };
        let f_wn = mwn / mw * f_w;
        let fs = match rule {
            DampingRule::Phases => {
                damp(rule, alpha, self.f_mix - f_wn, self.p_s) + damp(rule, alpha, f_wn, self.p_w)
            }
            DampingRule::Anura3d => {
                // Anura3D damps the liquid part of the mixture's force against the liquid
                // velocity it has just updated (with the explicit drag), the solid part against
                // the start-of-step solid velocity.
                let w_end = match loads.drag {
                    Drag::Explicit => w + a_w_explicit * dt,
                    Drag::Implicit => w,
                };
                damp(rule, alpha, self.f_mix - f_wn, v) + damp(rule, alpha, f_wn, w_end)
            }
        };
        match loads.drag {
            Drag::Implicit => {
                // Relative velocity w - v at the start of the step.
                let dv = self.p_w / mw - self.p_s / ms;
                let qdt = q * dt;
                match (self.fixed, self.liquid_fixed) {
                    (true, true) => (R::ZERO, R::ZERO),
                    (true, false) => (R::ZERO, (fw - q * dv) / (mw + qdt)),
                    (false, true) => (fs / ms, R::ZERO),
                    (false, false) => {
                        let a_w = (fw - q * dv + qdt * fs / ms) / (mw + qdt * (R::ONE + mwn / ms));
                        ((fs - mwn * a_w) / ms, a_w)
                    }
                }
            }
            Drag::Explicit => {
                let a_s = if self.fixed {
                    R::ZERO
                } else {
                    (fs - mwn * a_w_explicit) / ms
                };
                (a_s, a_w_explicit)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;
    use crate::parallel::comm::SingleProcess;
    use crate::state::grid::LiquidNodes;

    /// A grid of `n` nodes with pseudo-random masses (some empty), momenta, forces and
    /// fixities, saturated.
    fn random_grid(n: usize) -> (Grid<f64>, Vec<[bool; 3]>, Vec<[f64; 3]>) {
        let mut next = crate::test_rng::uniform(0x9e37_79b9_7f4a_7c15);
        let mut g = Grid::new(n);
        let mut l = LiquidNodes::new(n);
        let mut fixed = vec![[false; 3]; n];
        let mut traction = vec![[0.0; 3]; n];
        for i in 0..n {
            g.mass[i] = if i % 17 == 0 { 0.0 } else { 1.0 + next() };
            l.mass[i] = 0.5 + next() * 0.5;
            l.mass_n[i] = 0.4 * l.mass[i];
            l.drag[i] = 10.0 + next();
            for a in 0..3 {
                g.momentum[i][a] = next();
                g.f_int[i][a] = next();
                g.f_ext[i][a] = next();
                l.momentum[i][a] = next();
                l.force[i][a] = next();
                traction[i][a] = next();
                fixed[i][a] = next() > 0.4;
            }
        }
        g.liquid = Some(l);
        (g, fixed, traction)
    }

    /// The grid update of the tests (two-phase where `g` has a liquid, dry otherwise): loads at
    /// multipliers 0.7 (and 0.3 on the liquid, acting on the mixture too), damping 0.05,
    /// gravity 9.81 down y, Δt 1 ms; the liquid fixed where the solid is.
    fn update<E: Element>(
        team: &Team,
        scratch: &mut GridScratch<f64>,
        g: &mut Grid<f64>,
        (fixed, traction): (&[[bool; 3]], &[[f64; 3]]),
        rule: DampingRule,
        drag: Drag,
    ) {
        let mixture = NodeLoads {
            traction,
            scale: 0.7,
            fixed,
            alpha: 0.05,
            rule,
            inertia: 1.0,
        };
        if g.liquid.is_some() {
            let loads = TwoPhaseLoads {
                mixture,
                liquid_traction: traction,
                liquid_scale: 0.3,
                liquid_fixed: fixed,
                drag,
                liquid_load_on_mixture: true,
                gravity: [0.0, -9.81, 0.0],
                dt: 1e-3,
            };
            grid_update_two_phase::<E, _>((team, &SingleProcess), scratch, g, &loads);
        } else {
            grid_update::<E, _>((team, &SingleProcess), scratch, g, &mixture);
        }
    }

    #[test]
    fn the_grid_update_is_the_same_for_any_thread_count() {
        // Several blocks of nodes, the last one short: accelerations and every sum bit for bit.
        let n = 3 * NODE_BLOCK + 77;
        let run = |threads: usize| {
            let team = Team::new(threads, crate::parallel::team::Pin::None).unwrap();
            let mut scratch = GridScratch::new(n);
            let (mut g, fixed, traction) = random_grid(n);
            let loads = (&fixed[..], &traction[..]);
            update::<Tet4>(
                &team,
                &mut scratch,
                &mut g,
                loads,
                DampingRule::Phases,
                Drag::Implicit,
            );
            let two = scratch.node_sums.clone();
            let (mut d, _, _) = random_grid(n);
            d.liquid = None;
            update::<Tet4>(
                &team,
                &mut scratch,
                &mut d,
                loads,
                DampingRule::Anura3d,
                Drag::Implicit,
            );
            let dry = scratch.node_sums.clone();
            let acc = |g: &Grid<f64>| {
                let mut v: Vec<u64> = g.acc.iter().flatten().map(|x| x.to_bits()).collect();
                if let Some(l) = &g.liquid {
                    v.extend(l.acc.iter().flatten().map(|x| x.to_bits()));
                }
                v
            };
            (two, dry, acc(&g), acc(&d))
        };
        let one = run(1);
        assert!(one.0.iter().any(|s| s[0] > 0.0) && one.1.iter().any(|s| s[1] > 0.0));
        for threads in [2, 3] {
            assert_eq!(run(threads), one, "{threads} threads");
        }
    }

    #[test]
    fn a_section_updates_as_the_3d_grid_with_zero_z_data() {
        // The 2D updates take the in-plane components only: on a grid whose z-data are zero
        // (a section's), accelerations, force sums and nodal energy terms are the 3D update's,
        // bit for bit, in both phases, under both damping rules and both drags.
        use crate::element::tri3::Tri3;
        use crate::step::nodal_energy::{nodal_energy, Loads};
        let n = 2 * NODE_BLOCK + 5;
        let team = Team::new(2, crate::parallel::team::Pin::None).unwrap();
        let flat = || {
            let (mut g, mut fixed, mut traction) = random_grid(n);
            for i in 0..n {
                g.momentum[i][2] = 0.0;
                g.f_int[i][2] = 0.0;
                g.f_ext[i][2] = 0.0;
                let l = g.liquid.as_mut().unwrap();
                l.momentum[i][2] = 0.0;
                l.force[i][2] = 0.0;
                traction[i][2] = 0.0;
                // Some sections fix z, some leave it free.
                fixed[i][2] = i % 2 == 0;
            }
            (g, fixed, traction)
        };
        fn energy(
            team: &Team,
            g: &mut Grid<f64>,
            fixed: &[[bool; 3]],
            traction: &[[f64; 3]],
            plane: bool,
        ) -> Vec<[f64; 4]> {
            let n = g.mass.len();
            // Remapped velocities as the nodal update gives them.
            for i in 0..n {
                for a in 0..3 {
                    g.vel[i][a] = if g.mass[i] > 0.0 {
                        g.momentum[i][a] / g.mass[i] + g.acc[i][a] * 1e-3
                    } else {
                        0.0
                    };
                    if let Some(l) = g.liquid.as_mut() {
                        l.vel[i][a] = l.momentum[i][a] / l.mass[i] + l.acc[i][a] * 1e-3;
                    }
                }
            }
            let loads = Loads {
                traction: (traction, 0.7),
                liquid_traction: (traction, 0.3),
                liquid_load_on_mixture: true,
                fixed,
                liquid_fixed: fixed,
                gravity: [0.0, -9.81, 0.0],
            };
            let mut values = vec![[0.0; 4]; n];
            let mut done = vec![(); n.div_ceil(NODE_BLOCK)];
            if plane {
                nodal_energy::<Tri3, _>(team, &mut values, &mut done, g, &loads);
            } else {
                nodal_energy::<Tet4, _>(team, &mut values, &mut done, g, &loads);
            }
            values
        }
        let bits = |g: &Grid<f64>, sums: &[[f64; 4]], energies: &[[f64; 4]]| {
            let mut v: Vec<u64> = g.acc.iter().flatten().map(|x| x.to_bits()).collect();
            if let Some(l) = &g.liquid {
                v.extend(l.acc.iter().flatten().map(|x| x.to_bits()));
            }
            v.extend(sums.iter().flatten().map(|x| x.to_bits()));
            v.extend(energies.iter().flatten().map(|x| x.to_bits()));
            v
        };
        for (rule, drag) in [
            (DampingRule::Phases, Drag::Implicit),
            (DampingRule::Anura3d, Drag::Explicit),
        ] {
            let run = |plane: bool, wet: bool| {
                let (mut g, fixed, traction) = flat();
                if !wet {
                    g.liquid = None;
                }
                let mut scratch = GridScratch::new(n);
                let loads = (&fixed[..], &traction[..]);
                if plane {
                    update::<Tri3>(&team, &mut scratch, &mut g, loads, rule, drag);
                } else {
                    update::<Tet4>(&team, &mut scratch, &mut g, loads, rule, drag);
                }
                let energies = energy(&team, &mut g, &fixed, &traction, plane);
                assert!(g.acc.iter().all(|a| a[2].to_bits() == 0));
                bits(&g, &scratch.node_sums, &energies)
            };
            for wet in [false, true] {
                let plane = run(true, wet);
                assert!(plane.iter().any(|&b| b != 0));
                assert_eq!(plane, run(false, wet), "{rule:?} {drag:?} wet {wet}");
            }
        }
    }
}
