//! The step's energy terms at the nodes, after both remaps (docs/design.md §4.14): the external
//! work and the energy that damping and drag took out, each at the velocity the material
//! points actually had, and the external power and nodal kinetic energy of Anura3D's columns.
//!
//! Why after the remap: in MUSL a point's velocity changes by Δt Σ_k N_k a_k, so the points'
//! kinetic energy changes by exactly Δt Σ_k m_k a_k · ṽ_k, where ṽ_k = (P_k + P'_k) / 2 m_k is
//! the mean of the momentum mapped to node k before the step (P_k) and remapped after it (P'_k):
//! the mass-weighted mean of its points' mid-step velocities. Splitting m_k a_k into its forces
//! and taking each at ṽ_k gives the work and the dissipation that balance the points' own
//! kinetic energy. The nodes' own mid-step velocity v + a Δt/2 does not: a node that only the
//! tip of a point's shape function reaches (mass 1e-5 of its neighbours', when a point has
//! moved to the far side of its element) is accelerated a hundred thousand times harder than
//! the point, and a load on it would seem to do that much more work, which no point receives.

use crate::element::Element;
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;

/// Nodes per block, as in the grid update: each block's sums are formed in node order and the
/// blocks added in order, so the sums are the same for any thread count.
pub use crate::step::grid_update::NODE_BLOCK;

/// The nodal energy terms of one step (this process's nodes; kJ and kW).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NodalEnergy {
    /// External power at the remapped end-of-step velocities, Σ f_ext · v' (Anura3D's
    /// `external_work` column integrates it).
    pub power_end: f64,
    /// Kinetic energy of the nodes at the remapped velocities (both phases).
    pub kinetic: f64,
    /// Work of gravity and the loads over the step at ṽ (the energy balance's work term).
    pub work: f64,
    /// Energy taken out over the step by local damping and, in two-phase cases, the drag.
    pub dissipated: f64,
}

impl NodalEnergy {
    /// The step's terms from the mesh's sums of the per-node values that [`nodal_energy`]
    /// writes (power, kinetic energy, work rate, dissipation rate), for a step of `dt`.
    pub fn of_sums(t: [f64; 4], dt: f64) -> Self {
        NodalEnergy {
            power_end: t[0],
            kinetic: t[1],
            work: t[2] * dt,
            dissipated: t[3] * dt,
        }
    }
}

/// What the nodal energy pass reads besides the grid: the loads, as the grid update applied
/// them, and the fixities.
#[derive(Debug, Clone, Copy)]
pub struct Loads<'a, R: Real> {
    /// Nodal face loads at multiplier 1, and the multiplier of the step.
    pub traction: (&'a [V3<R>], R),
    /// Loads on the liquid at multiplier 1, and their multiplier (two-phase cases).
    pub liquid_traction: (&'a [V3<R>], R),
    /// Loads on the liquid act on the mixture too.
    pub liquid_load_on_mixture: bool,
    /// Fixed solid components.
    pub fixed: &'a [[bool; 3]],
    /// Fixed liquid components.
    pub liquid_fixed: &'a [[bool; 3]],
    /// Gravity of the step.
    pub gravity: V3<R>,
}

/// A block's liquid arrays, each sliced to the block's nodes (one length).
struct Liquid<'a, R: Real> {
    mass: &'a [R],
    mass_n: &'a [R],
    momentum: &'a [V3<R>],
    force: &'a [V3<R>],
    acc: &'a [V3<R>],
    vel: &'a [V3<R>],
    traction: &'a [V3<R>],
    fixed: &'a [[bool; 3]],
}

/// The energy terms of the step per node, on the team, into `values` (one per node:
/// [`NodalEnergy::of_sums`]'s power, kinetic energy, work rate and dissipation rate; `done`:
/// preallocated, one per [`NODE_BLOCK`] nodes). Call after the remap of both phases (`g.vel`
/// and the liquid's `vel` hold the remapped velocities, `g.momentum` and `g.acc` those of the
/// step). Over the element's [`Element::DIM`] components: a 2D section's z-terms are zeros.
pub fn nodal_energy<E: Element, R: Real>(
    team: &Team,
    values: &mut [[f64; 4]],
    done: &mut [()],
    g: &Grid<R>,
    loads: &Loads<'_, R>,
) {
    let nodes = g.mass.len();
    let eps = g.empty_below;
    let half = R::of(0.5);
    let (traction, scale) = loads.traction;
    let (liquid_traction, liquid_scale) = loads.liquid_traction;
    let out = Shared::new(values);
    team.for_blocks(nodes, NODE_BLOCK, done, |r| {
        // SAFETY: the nodes of this block are this call's only.
        let out = unsafe { out.range(r.clone()) };
        // The solid's arrays sliced to the block once (one length): the loop indexes them
        // without bounds checks.
        let len = out.len();
        let (mass, f_ext, f_int, vel) = (
            &g.mass[r.clone()][..len],
            &g.f_ext[r.clone()][..len],
            &g.f_int[r.clone()][..len],
            &g.vel[r.clone()][..len],
        );
        let (momentum, acc, traction, fixed) = (
            &g.momentum[r.clone()][..len],
            &g.acc[r.clone()][..len],
            &traction[r.clone()][..len],
            &loads.fixed[r.clone()][..len],
        );
        // The liquid's likewise (two-phase cases).
        let liquid = g.liquid.as_ref().map(|l| Liquid {
            mass: &l.mass[r.clone()][..len],
            mass_n: &l.mass_n[r.clone()][..len],
            momentum: &l.momentum[r.clone()][..len],
            force: &l.force[r.clone()][..len],
            acc: &l.acc[r.clone()][..len],
            vel: &l.vel[r.clone()][..len],
            traction: &liquid_traction[r.clone()][..len],
            fixed: &loads.liquid_fixed[r.clone()][..len],
        });
        for (i, value) in out.iter_mut().enumerate() {
            let mut s = NodalEnergy::default();
            let ms = mass[i];
            // The end-of-step power of gravity and the solid's loads, and the nodal kinetic
            // energy (every node). Only the element's dimensions: a section's nodes have no
            // z-force or z-velocity, whose terms would add zeros.
            for a in 0..E::DIM {
                let ext = f_ext[i][a] + scale * traction[i][a];
                s.power_end += (ext * vel[i][a]).f64();
                s.kinetic += 0.5 * (ms * vel[i][a] * vel[i][a]).f64();
                if let Some(l) = &liquid {
                    s.kinetic += 0.5 * (l.mass_n[i] * l.vel[i][a] * l.vel[i][a]).f64();
                }
            }
            if ms <= eps {
                *value = [s.power_end, s.kinetic, 0.0, 0.0];
                continue;
            }
            let wet = liquid.as_ref().filter(|l| l.mass[i] > eps);
            for a in 0..E::DIM {
                if fixed[i][a] && wet.is_none() {
                    continue;
                }
                // Loads on the liquid (two-phase cases only: a dry run has none).
                let lt = if let Some(l) = &liquid {
                    liquid_scale * l.traction[i][a]
                } else {
                    R::ZERO
                };
                let ext = if liquid.is_some() && loads.liquid_load_on_mixture {
                    f_ext[i][a] + scale * traction[i][a] + lt
                } else {
                    f_ext[i][a] + scale * traction[i][a]
                };
                let f_mix = f_int[i][a] + ext;
                // The points' mean velocity over the step at this node (0 where fixed).
                let v = if fixed[i][a] {
                    R::ZERO
                } else {
                    half * (momentum[i][a] / ms + vel[i][a])
                };
                let a_s = acc[i][a];
                let Some(l) = wet else {
                    // A dry node: its force less what moved it is what damping took.
                    s.work += (ext * v).f64();
                    s.dissipated += ((f_mix - ms * a_s) * v).f64();
                    continue;
                };
                let mw = l.mass[i];
                let mut power = (f_mix * v).f64();
                let mut external = (ext * v).f64();
                let mut kinetic = (ms * a_s * v).f64();
                if !l.fixed[i][a] {
                    // The liquid's relative motion: its force and its weight and loads do work
                    // on n (w̃ - ṽ) (the liquid's equation put into the mixture's).
                    let w = half * (l.momentum[i][a] / mw + l.vel[i][a]);
                    let porosity = l.mass_n[i] / mw;
                    let relative = porosity * (w - v);
                    let f_w = l.force[i][a] + lt;
                    power += (f_w * relative).f64();
                    external += ((mw * loads.gravity[a] + lt) * relative).f64();
                    kinetic += (l.mass_n[i] * l.acc[i][a] * w).f64();
                }
                s.work += external;
                s.dissipated += power - kinetic;
            }
            *value = [s.power_end, s.kinetic, s.work, s.dissipated];
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;
    use crate::state::grid::LiquidNodes;
    use crate::step::grid_update::{
        grid_update_two_phase, DampingRule, Drag, GridScratch, NodeLoads, TwoPhaseLoads,
    };

    /// One saturated node moving along x and y, its liquid faster than its solid, with loads
    /// on both phases and the liquid's weight.
    fn node(drag: f64) -> Grid<f64> {
        let mut g = Grid::new(1);
        let mut l = LiquidNodes::new(1);
        g.mass[0] = 2.0;
        g.momentum[0] = [0.2, -0.1, 0.0];
        g.f_int[0] = [-3.0, 1.5, 0.25];
        g.f_ext[0] = [0.5, -4.0, 0.0];
        l.mass[0] = 1.0;
        l.mass_n[0] = 0.4;
        l.drag[0] = drag;
        l.momentum[0] = [0.5, 0.3, -0.2];
        l.force[0] = [1.0, -2.0, 0.5];
        g.liquid = Some(l);
        g
    }

    /// The grid update of one node, its velocities then remapped as from one point (the
    /// nodal update carried over exactly), and the step's energy terms.
    fn energies(g: &mut Grid<f64>, alpha: f64, drag: Drag, fixed: [bool; 3]) -> NodalEnergy {
        let gravity = [0.0, -9.81, 0.0];
        let dt = 1e-3;
        let team = Team::new(1, crate::parallel::team::Pin::None).unwrap();
        let (traction, liquid_traction) = ([[0.1, 0.2, 0.0]], [[0.0, -0.3, 0.0]]);
        let loads = TwoPhaseLoads {
            mixture: NodeLoads {
                traction: &traction,
                scale: 1.0,
                fixed: &[[false; 3]],
                alpha,
                rule: DampingRule::Phases,
                inertia: 1.0,
            },
            liquid_traction: &liquid_traction,
            liquid_scale: 1.0,
            liquid_fixed: &[fixed],
            drag,
            liquid_load_on_mixture: true,
            gravity,
            dt,
        };
        let single = crate::parallel::comm::SingleProcess;
        grid_update_two_phase::<Tet4, _>((&team, &single), &mut GridScratch::new(1), g, &loads);
        for a in 0..3 {
            g.vel[0][a] = g.momentum[0][a] / g.mass[0] + g.acc[0][a] * dt;
            let l = g.liquid.as_mut().unwrap();
            l.vel[0][a] = if fixed[a] {
                0.0
            } else {
                l.momentum[0][a] / l.mass[0] + l.acc[0][a] * dt
            };
        }
        let loads = Loads {
            traction: (&traction, 1.0),
            liquid_traction: (&liquid_traction, 1.0),
            liquid_load_on_mixture: true,
            fixed: &[[false; 3]],
            liquid_fixed: &[fixed],
            gravity,
        };
        energy_of(&team, g, &loads, dt)
    }

    /// The pass's terms summed over the nodes in node order.
    fn energy_of(team: &Team, g: &Grid<f64>, loads: &Loads<'_, f64>, dt: f64) -> NodalEnergy {
        let mut values = vec![[0.0; 4]; g.mass.len()];
        nodal_energy::<Tet4, _>(team, &mut values, &mut [(); 1], g, loads);
        let mut t = [0.0; 4];
        for v in &values {
            for c in 0..4 {
                t[c] += v[c];
            }
        }
        NodalEnergy::of_sums(t, dt)
    }

    #[test]
    fn without_drag_or_damping_the_two_phase_update_dissipates_nothing() {
        // The kinetic energy's change is then exactly the forces' power: what the update
        // reports as dissipated is round-off, whatever the loads (the power's split is right).
        for drag in [Drag::Implicit, Drag::Explicit] {
            let s = energies(&mut node(0.0), 0.0, drag, [false; 3]);
            assert!(s.dissipated.abs() < 1e-15, "{drag:?}: {}", s.dissipated);
            assert!(s.work.abs() > 1e-4);
        }
    }

    #[test]
    fn drag_and_damping_dissipate_and_an_impermeable_face_drops_the_liquid_term() {
        for drag in [Drag::Implicit, Drag::Explicit] {
            let d = energies(&mut node(50.0), 0.0, drag, [false; 3]).dissipated;
            assert!(d > 0.0, "{drag:?}: {d}");
            let d = energies(&mut node(0.0), 0.5, drag, [false; 3]).dissipated;
            assert!(d > 0.0, "{drag:?}: {d}");
        }
        // A fixed liquid: the solid alone, undamped and without drag, dissipates nothing.
        let s = energies(&mut node(50.0), 0.0, Drag::Implicit, [true; 3]);
        assert!(s.dissipated.abs() < 1e-15, "{}", s.dissipated);
    }

    #[test]
    fn a_nearly_empty_loaded_node_does_not_seem_to_take_the_loads_work() {
        // Two nodes of one point: the far node has 1e-5 of the point's mass and carries a
        // load. The point's velocity change, Δt Σ N a, takes the load as on the whole point;
        // so does the work at the remapped velocities, while the far node's own mid-step
        // velocity would count the load's work 1e5 times over.
        let team = Team::new(1, crate::parallel::team::Pin::None).unwrap();
        let (m, v0, dt, load) = (1.0, 0.01, 1e-3, 2.0);
        let shares = [1.0 - 1e-5, 1e-5];
        let mut g = Grid::new(2);
        for k in 0..2 {
            g.mass[k] = m * shares[k];
            g.momentum[k] = [0.0, m * shares[k] * v0, 0.0];
        }
        let traction = [[0.0; 3], [0.0, load, 0.0]];
        let loads = NodeLoads {
            traction: &traction,
            scale: 1.0,
            fixed: &[[false; 3]; 2],
            alpha: 0.0,
            rule: DampingRule::Phases,
            inertia: 1.0,
        };
        let single = crate::parallel::comm::SingleProcess;
        crate::step::grid_update::grid_update::<Tet4, _>(
            (&team, &single),
            &mut GridScratch::new(2),
            &mut g,
            &loads,
        );
        // The point: v += Δt Σ N a; the remap gives every node the point's new velocity.
        let dv: f64 = (0..2).map(|k| shares[k] * g.acc[k][1] * dt).sum();
        let v1 = v0 + dv;
        for k in 0..2 {
            g.vel[k] = [0.0, v1, 0.0];
        }
        let loads = Loads {
            traction: (&traction, 1.0),
            liquid_traction: (&traction, 0.0),
            liquid_load_on_mixture: false,
            fixed: &[[false; 3]; 2],
            liquid_fixed: &[[false; 3]; 2],
            gravity: [0.0; 3],
        };
        let e = energy_of(&team, &g, &loads, dt);
        let kinetic = 0.5 * m * (v1 * v1 - v0 * v0);
        assert!(
            (e.work - kinetic).abs() < 1e-12 * kinetic.abs().max(1e-9),
            "{e:?}"
        );
        assert!(e.dissipated.abs() < 1e-15, "{e:?}");
        // The far node's own mid-step velocity would have counted this much.
        let mid = load * (v0 + 0.5 * g.acc[1][1] * dt) * dt;
        assert!(mid > 1e3 * e.work);
    }
}
