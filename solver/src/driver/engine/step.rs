//! One explicit MUSL time step through its named phases (docs/design.md §4.1):
//!
//! 1. [`Phase::MapToGrid`]: the points' mass, momentum and forces to the nodes of their body;
//! 2. [`Phase::GridUpdate`]: the nodes' accelerations, and the force sums of the convergence
//!    check;
//! 3. [`Phase::Constraints`]: the constraints' hooks after the grid update (walls, prescribed
//!    velocities, contact, ...), and the reactions' travel;
//! 4. [`Phase::Remap`]: the points take the nodes' accelerations, their momentum is mapped back,
//!    and the constraints' hooks after the re-mapping set the nodal velocities;
//! 5. [`Phase::Stress`]: strain increments, pore pressures and stresses at the points, which
//!    move (and, where nothing between this pass and the next bears on it, find their element
//!    as they move);
//! 6. [`Phase::Energy`]: the step's energy terms at the nodes, the clock, the guard rails;
//! 7. [`Phase::Relocate`]: the constraints' hooks after the move (the moving mesh), the points'
//!    elements and their order, and the next critical step where it follows the points.
//!
//! Each phase is a method that takes the step's [`Moment`] (clock and load multipliers), and
//! each is timed by [`Engine::timed`] into one of the run's reported phases
//! ([`PHASES`](super::PHASES)).

use std::iter::once;
use std::time::Instant;

use crate::element::locate::NOTHING_FOUND;
use crate::element::Element;
use crate::parallel::gather::exact_total;
use crate::real::{Real, V3};
use crate::step::constraint::{Constraints, Hook};
use crate::step::grid_update::ForceSums;
use crate::step::moment::Moment;
use crate::step::moving_mesh::Inverted;
use crate::step::nodal_energy::NodalEnergy;
use crate::step::passes::Passes;
use crate::step::stress::Guard;
use crate::step::tail::{self, Nodal};
use crate::step::{grid_to_particle, grid_update, nodal_energy, particle_to_grid, stress};

use super::{Engine, StepError};

/// The phases of a step, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Particle to grid.
    MapToGrid,
    /// The nodes' accelerations.
    GridUpdate,
    /// The constraints after the grid update.
    Constraints,
    /// Grid to particle, and the constraints after it.
    Remap,
    /// Strains, pore pressures, stresses, the points' move.
    Stress,
    /// The step's energy terms and the guard rails.
    Energy,
    /// The mesh's move and the points' elements.
    Relocate,
}

impl Phase {
    /// The phase of the run's report ([`PHASES`](super::PHASES)) this phase's time is counted in: the
    /// constraints with the re-mapping, the energy with the stress pass (as before they were
    /// phases of their own, so that the reports compare across versions).
    pub fn reported(self) -> usize {
        match self {
            Phase::MapToGrid => 0,
            Phase::GridUpdate => 1,
            Phase::Constraints | Phase::Remap => 2,
            Phase::Stress | Phase::Energy => 3,
            Phase::Relocate => 4,
        }
    }
}

impl<R: Real, E: Element> Engine<R, E> {
    /// One explicit MUSL step of length `dt`; `snap_to` sets the clock exactly when the step
    /// ends on an output time (so times print as given, not as sums of steps).
    pub fn step(&mut self, dt: f64, snap_to: Option<f64>) -> Result<(), StepError> {
        // Team runs between steps (energies, output) are not the step's.
        self.team.take_load();
        let at = self.moment(dt);
        self.timed(Phase::MapToGrid, |e| e.map_to_grid(&at));
        let forces = self.timed(Phase::GridUpdate, |e| e.update_grid(&at))?;
        self.timed(Phase::Constraints, |e| e.constrain(&at));
        self.timed(Phase::Remap, |e| e.remap(&at));
        let located = self.timed(Phase::Stress, |e| e.update_stress(&at));
        self.timed(Phase::Energy, |e| e.account_energy(&at, &forces, snap_to))?;
        self.timed(Phase::Relocate, |e| e.relocate(&at, located))
    }

    /// Runs `f` as `phase`: its wall time and its thread team's load go to the phase's
    /// reported counters.
    fn timed<T>(&mut self, phase: Phase, f: impl FnOnce(&mut Self) -> T) -> T {
        let start = Instant::now();
        let out = f(self);
        let k = phase.reported();
        self.phase_seconds[k] += start.elapsed().as_secs_f64();
        self.phase_load[k] += self.team.take_load();
        out
    }

    /// The clock and the load multipliers of a step of `dt` from now; each material's gravity
    /// (its weight ratio applied) for the step.
    fn moment(&mut self, dt: f64) -> Moment<R> {
        let c = &self.config;
        let end = self.time + dt;
        let gm = c.gravity_curve.at(end);
        for (gv, &ratio) in self.gravity_by_material.iter_mut().zip(&self.weight_ratio) {
            *gv = c.gravity.map(|g| R::of(g * gm * ratio));
        }
        Moment {
            time: self.time,
            dt,
            gravity: c.gravity.map(|g| R::of(g * gm)),
            traction: R::of(c.traction_curve.at(end)),
            liquid: R::of(c.liquid_curve.at(end)),
            damping: R::of(c.damping),
            damping_rule: c.damping_rule,
            drag: c.drag,
        }
    }

    /// The constraints and what their hooks act on, borrowed apart.
    fn hook<'a>(&'a mut self, at: &'a Moment<R>) -> (&'a mut Constraints<R, E>, Hook<'a, R, E>) {
        let (structure, structure_traction): (_, &[V3<R>]) = match self.structure.as_mut() {
            Some(s) => (Some(&mut s.grid), &s.traction),
            None => (None, &[]),
        };
        let hook = Hook {
            at,
            mesh: &mut self.mesh,
            layout: &self.layout,
            particles: &mut self.particles,
            soil: &mut self.grid,
            structure,
            fixed: &self.fixed,
            liquid_fixed: &self.liquid_fixed,
            traction: &self.traction,
            structure_traction,
            reactions: &mut self.reactions,
        };
        (&mut self.constraints, hook)
    }

    /// Particle to grid: each body to its own nodes (one pass of every point without a second
    /// body), the liquid with the soil; then the loads carried by points.
    fn map_to_grid(&mut self, at: &Moment<R>) {
        let soil = self.structure.as_ref().map(|s| s.soil());
        let structure = self.structure.as_mut().map(|s| (&mut s.grid, Some(s.body)));
        // The liquid goes with the soil's pass (the structure is dry).
        let mut liquid = Some(particle_to_grid::LiquidLoads {
            fluids: &self.fluids,
            gravity: at.gravity,
        });
        let passes = Passes::new(&self.team, &self.layout, &self.mesh, &*self.comm);
        for (grid, body) in once((&mut self.grid, soil)).chain(structure) {
            let to = particle_to_grid::MapToGrid {
                particles: &self.particles,
                gravity: &self.gravity_by_material,
                grid,
                body,
                mixed: self.mixed.as_mut(),
                liquid: liquid.take(),
                // (Asked of the liquid's pass only, the first.)
                pore_weights: self.pore_weights.as_mut(),
            };
            match (&self.basis, &self.reach) {
                (Some(b), Some(r)) => particle_to_grid::particle_to_grid(
                    &passes.with_basis(b, r),
                    &mut self.slots,
                    to,
                ),
                _ => particle_to_grid::particle_to_grid(&passes, &mut self.slots, to),
            }
        }
        particle_to_grid::add_point_loads(
            &self.mesh,
            &self.particles,
            &self.point_loads,
            at.traction,
            &mut self.grid,
        );
    }

    /// The grid update of each body (the mixture and liquid together in two-phase cases), the
    /// accelerations' precursor cut, and the force sums of the convergence check (over both
    /// bodies with contact), kept as the step's force errors and returned. Under the
    /// semi-implicit scheme the pressure solve then corrects the accelerations (an error where
    /// it does not converge).
    fn update_grid(&mut self, at: &Moment<R>) -> Result<ForceSums, StepError> {
        let c = &self.config;
        let dt = R::of(at.dt);
        if self.grid.liquid.is_some() {
            let loads = grid_update::TwoPhaseLoads {
                mixture: grid_update::NodeLoads {
                    traction: &self.traction,
                    scale: at.traction,
                    fixed: &self.fixed,
                    alpha: at.damping,
                    rule: at.damping_rule,
                    inertia: R::of(c.mass_scaling),
                },
                liquid_traction: &self.liquid_traction,
                liquid_scale: at.liquid,
                liquid_fixed: &self.liquid_fixed,
                drag: c.drag,
                liquid_load_on_mixture: c.liquid_load_on_mixture,
                gravity: at.gravity,
                dt,
            };
            let (team, comm) = (&self.team, &*self.comm);
            grid_update::grid_update_two_phase::<E, R>(
                (team, comm),
                &mut self.grid_scratch,
                &mut self.grid,
                &loads,
            );
            if let Some(semi) = &mut self.semi_implicit {
                semi.correct(
                    (&self.team, &self.layout),
                    &self.mesh,
                    &self.particles,
                    &self.fluids,
                    &mut self.grid,
                    (&self.fixed, &self.liquid_fixed),
                    at.dt,
                )?;
            }
            let (team, comm) = (&self.team, &*self.comm);
            tail::cut_grid(
                team,
                comm,
                &mut self.grid_scratch,
                &mut self.grid,
                Nodal::Acceleration,
            );
        }
        // The dry soil's, then the structure's (dry), each with its own face loads.
        let soil = self.grid.liquid.is_none().then_some((
            &mut self.grid_scratch,
            &mut self.grid,
            &self.traction[..],
        ));
        let structure = self
            .structure
            .as_mut()
            .map(|s| (&mut s.scratch, &mut s.grid, &s.traction[..]));
        for (scratch, grid, traction) in soil.into_iter().chain(structure) {
            let loads = grid_update::NodeLoads {
                traction,
                scale: at.traction,
                fixed: &self.fixed,
                alpha: at.damping,
                rule: at.damping_rule,
                inertia: R::of(c.mass_scaling),
            };
            let (team, comm) = (&self.team, &*self.comm);
            grid_update::grid_update::<E, R>((team, comm), scratch, grid, &loads);
            tail::cut_grid(&self.team, &*self.comm, scratch, grid, Nodal::Acceleration);
        }
        if let Some(s) = &mut self.structure {
            s.force_sums(
                &self.team,
                (&self.grid, &self.traction, at.traction),
                &self.fixed,
                &mut self.grid_scratch.node_sums,
            );
        }
        let (forces, liquid_forces) = {
            let (layout, team, comm) = (&self.layout, &self.team, &*self.comm);
            let partials = &mut self.owned_partials;
            self.grid_scratch.totals(|values| {
                layout.sum_owned(team, values, partials);
                exact_total(comm, &partials[..layout.owned_blocks()])
            })
        };
        self.force_error = forces.ratio();
        self.liquid_force_error = liquid_forces.ratio();
        Ok(forces)
    }

    /// The constraints' hooks after the grid update, in their order; then every prescribed set
    /// travels the step.
    fn constrain(&mut self, at: &Moment<R>) {
        let (constraints, mut cx) = self.hook(at);
        constraints.after_grid_update(&mut cx);
        for r in &mut self.reactions {
            r.advance(at.end(), at.dt);
        }
    }

    /// Grid to particle for each body (the liquid with the soil), the re-mapped velocities'
    /// precursor cut, and the constraints' hooks after the re-mapping.
    fn remap(&mut self, at: &Moment<R>) {
        let soil = self.structure.as_ref().map(|s| s.soil());
        let structure = self.structure.as_mut().map(|s| (&mut s.grid, Some(s.body)));
        let passes = Passes::new(&self.team, &self.layout, &self.mesh, &*self.comm);
        for (k, (grid, body)) in once((&mut self.grid, soil)).chain(structure).enumerate() {
            let remap = grid_to_particle::Remap {
                particles: &mut self.particles,
                grid,
                fixed: &self.fixed,
                dt: R::of(at.dt),
                pic: R::of(self.config.pic_blend),
                guard: self.guards.enabled.then_some(&mut self.guard_slots[..]),
                body,
                begin: k == 0,
                // The liquid goes with the soil's pass (the structure is dry).
                liquid: (k == 0).then_some(grid_to_particle::LiquidRemap {
                    fluids: &self.fluids,
                    fixed: &self.liquid_fixed,
                }),
            };
            match (&self.basis, &self.reach) {
                (Some(b), Some(r)) => grid_to_particle::grid_to_particle(
                    &passes.with_basis(b, r),
                    &mut self.slots,
                    remap,
                ),
                _ => grid_to_particle::grid_to_particle(&passes, &mut self.slots, remap),
            }
        }
        // Each body's re-mapped velocities, their precursor cut before the constraints set
        // theirs.
        let structure = self
            .structure
            .as_mut()
            .map(|s| (&mut s.scratch, &mut s.grid));
        for (scratch, grid) in once((&mut self.grid_scratch, &mut self.grid)).chain(structure) {
            tail::cut_grid(&self.team, &*self.comm, scratch, grid, Nodal::Velocity);
        }
        let (constraints, mut cx) = self.hook(at);
        constraints.after_remap(&mut cx);
    }

    /// Strain smoothing where asked, the pore pressures, and each body's stress pass, which
    /// moves its points; returns whether the points were located as they moved.
    fn update_stress(&mut self, at: &Moment<R>) -> bool {
        let dt = R::of(at.dt);
        let c = &self.config;
        let passes = Passes::new(&self.team, &self.layout, &self.mesh, &*self.comm);
        if let Some(sm) = &mut self.smoothing {
            let structure = self
                .structure
                .as_ref()
                .map(|s| (&s.grid, s.body.structure_material));
            let pg = (&self.particles, &self.grid);
            sm.compute(&passes, &mut self.slots, pg, structure, dt);
        }
        let pressure = stress::PorePressure {
            particles: &mut self.particles,
            grid: &mut self.grid,
            fluids: &self.fluids,
            smooth: c.smooth_pressure,
            smoothing: self.smoothing.as_ref(),
            weights: self.pore_weights.as_mut(),
            dt,
        };
        // On a grid the rate is smoothed through its nodes here, or each saturated point takes
        // its own in the stress pass.
        let rate_pending = match &self.basis {
            // The pressure solve left its rates at the nodes.
            None if self.semi_implicit.is_some() => true,
            None => stress::update_pore_pressure(&passes, &mut self.slots, pressure),
            Some(b) if c.smooth_pressure && self.grid.liquid.is_some() => {
                let (grid, fluids) = (&mut self.grid, &self.fluids);
                let w = &mut self.grid_scratch.rate_weights;
                let reach = self.reach.as_ref().expect("a grid's reach");
                stress::smooth_rates((b, reach, &passes), &self.particles, grid, fluids, w);
                true
            }
            Some(_) => false,
        };
        let located = self.locates_in_stress_pass();
        if located {
            self.locate_outcome.fill(NOTHING_FOUND);
        }
        // Each body's points strain and move with its own nodes' velocities.
        let soil = self.structure.as_ref().map(|s| s.soil());
        let structure = self.structure.as_ref().map(|s| (&s.grid, Some(s.body)));
        // The smoothed pore-pressure rates reach the points in the stress pass.
        let pore_rate = self
            .grid
            .liquid
            .as_ref()
            .filter(|_| rate_pending)
            .map(|gl| stress::PoreRate {
                nodal: &gl.rate,
                fluids: &self.fluids,
            });
        for (k, (grid, body)) in once((&self.grid, soil)).chain(structure).enumerate() {
            let update = stress::StressUpdate {
                particles: &mut self.particles,
                grid,
                laws: &self.laws,
                objective: c.objective_stress,
                hoop_in_volume: c.hoop_in_volume,
                smoothing: self.smoothing.as_ref(),
                dt,
                guard: self.guards.enabled.then_some(Guard {
                    slots: &mut self.guard_slots,
                    initial_density: &self.initial_density,
                    fluids: &self.fluids,
                    min_volume_ratio: R::of(self.guards.min_volume_ratio),
                }),
                body,
                pore_rate: pore_rate.filter(|_| k == 0),
                located: (located && k == 0).then_some(&mut self.locate_outcome[..]),
                background: self.basis.as_ref(),
                point_rates: self
                    .basis
                    .as_ref()
                    .filter(|_| k == 0 && self.grid.liquid.is_some() && !rate_pending)
                    .map(|_| &self.fluids[..]),
                bulk: self.bulk.as_ref(),
            };
            stress::update_stress_and_move(&passes, update);
        }
        if let Some(m) = &self.mixed {
            m.after_stress(&self.team, &self.layout, &mut self.particles);
        }
        located
    }

    /// The step's energy terms at the nodes, with the re-mapped velocities: Anura3D's external
    /// power and nodal kinetic energy, and the guards' work and dissipation (with contact the
    /// structure's nodes add their power, work and dissipation; Anura3D's nodal kinetic energy,
    /// its convergence check, is the soil's alone). Then the clock, and the guard rails.
    fn account_energy(
        &mut self,
        at: &Moment<R>,
        forces: &ForceSums,
        snap_to: Option<f64>,
    ) -> Result<(), StepError> {
        let dt = at.dt;
        let loads = nodal_energy::Loads {
            traction: (&self.traction, at.traction),
            liquid_traction: (&self.liquid_traction, at.liquid),
            liquid_load_on_mixture: self.config.liquid_load_on_mixture,
            fixed: &self.fixed,
            liquid_fixed: &self.liquid_fixed,
            gravity: at.gravity,
        };
        let mut energy = NodalEnergy::default();
        // Each body with its own face loads.
        let grids = once((&self.grid, &self.traction[..]))
            .chain(self.structure.as_ref().map(|s| (&s.grid, &s.traction[..])));
        for (k, (grid, traction)) in grids.enumerate() {
            let loads = nodal_energy::Loads {
                traction: (traction, at.traction),
                ..loads
            };
            nodal_energy::nodal_energy::<E, R>(
                &self.team,
                &mut self.energy_values,
                &mut self.energy_blocks,
                grid,
                &loads,
            );
            self.layout
                .sum_owned(&self.team, &self.energy_values, &mut self.owned_partials);
            let partials = &self.owned_partials[..self.layout.owned_blocks()];
            let body = NodalEnergy::of_sums(exact_total(&*self.comm, partials), dt);
            energy = if k == 0 {
                body
            } else {
                NodalEnergy {
                    power_end: energy.power_end + body.power_end,
                    kinetic: energy.kinetic,
                    work: energy.work + body.work,
                    dissipated: energy.dissipated + body.dissipated,
                }
            };
        }
        let w = energy.power_end;
        self.nodal_kinetic = energy.kinetic;
        self.external_work += w * dt;
        self.steps += 1;
        self.time += dt;
        if let Some(t) = snap_to {
            self.time = t;
        }
        if self.guards.enabled {
            self.check_step(dt, w, forces, &energy)?;
        }
        Ok(())
    }

    /// The constraints' hooks after the move (the mesh moves before the points are located in
    /// it), the points' elements (`located`: already found in the stress pass), the mixed
    /// rule's averages over the new elements, and the next step where it follows the points.
    fn relocate(&mut self, at: &Moment<R>, located: bool) -> Result<(), StepError> {
        let (constraints, mut cx) = self.hook(at);
        if let Err(e) = constraints.after_move(&mut cx) {
            return Err(Inverted {
                element: self.input_element[e] + 1,
                step: self.steps,
                time: self.time,
            }
            .into());
        }
        if located {
            self.settle_located(at.dt)?;
        } else {
            self.locate(at.dt)?;
        }
        if let Some(m) = &self.mixed {
            m.after_locate(&self.team, &self.layout, &mut self.particles);
        }
        if let Some(cs) = &mut self.critical_step {
            let (crossing, element) =
                cs.shortest_crossing(&self.team, &self.layout, &self.mesh, &self.particles);
            let shortest = self.comm.min(crossing);
            // With no point left in the mesh the last step stands.
            if shortest.is_finite() {
                self.dt = crate::step::time_step::step_of(self.courant.0, shortest);
                if crossing == shortest {
                    self.courant.1 = element as usize;
                }
            }
        }
        Ok(())
    }
}
