//! The engine's state between steps for a checkpoint, and back; a new team of threads between
//! steps.

use crate::element::locate::NOTHING_FOUND;
use crate::element::Element;
use crate::parallel::reach::Reach;
use crate::parallel::team::Team;
use crate::real::Real;

use super::{Engine, PHASES};

impl<R: Real, E: Element> Engine<R, E> {
    /// The engine's state between steps that is not in the particle arrays and that later steps
    /// or outputs read, by name, for a checkpoint (f64 values as their bits). Every field is taken
    /// apart here, so a field added to the engine does not compile until it is placed in or out.
    pub fn checkpoint_scalars(&self) -> Vec<(&'static str, u64)> {
        let Engine {
            // Rebuilt from the case at set-up, or scratch that each step rewrites before reading.
            config: _,
            basis: _,
            reach: _,
            comm: _,
            partition: _,
            mesh: _,
            grid: _,
            fixed: _,
            traction: _,
            liquid_traction: _,
            laws: _,
            drop_lost: _,
            mixed: _,
            pore_weights: _,
            team: _,
            // How the threads spent their time: this run's, like the team.
            phase_load: _,
            layout: _,
            slots: _,
            sort_scratch: _,
            locate_outcome: _,
            fluids: _,
            liquid_fixed: _,
            smoothing: _,
            bulk: _,
            // Saved below: its counts (each step's solve starts from zero).
            semi_implicit,
            weight_ratio: _,
            gravity_by_material: _,
            input_element: _,
            input_node: _,
            guards: _,
            guard_slots: _,
            grid_scratch: _,
            energy_blocks: _,
            energy_values: _,
            owned_partials: _,
            initial_density: _,
            courant: _,
            energy_checked: _,
            stored_energy: _,
            first_touch: _,
            // Distributed runs take no checkpoints.
            balance: _,
            // Saved through the field list.
            particles: _,
            // Indices of points: they follow the points (by id) when restored.
            point_loads: _,
            // Saved below, by set.
            reactions,
            // Saved below: each constraint's own state (the moving mesh's nodes).
            constraints,
            // Its scratch; the step it set is `dt`.
            critical_step: _,
            // Rebuilt at set-up; its arrays are each step's scratch.
            structure: _,
            // Saved, the time step to check that the set-up matches.
            dt,
            time,
            steps,
            external_work,
            phase_seconds,
            lost,
            force_error,
            liquid_force_error,
            nodal_kinetic,
            strain_energy,
            dissipated,
            liquid_energy,
            liquid_initial,
            balance_work,
            step_kinetic,
            initial_kinetic,
        } = self;
        let mut out = vec![
            ("dt", dt.to_bits()),
            ("time", time.to_bits()),
            ("steps", *steps),
            ("external_work", external_work.to_bits()),
            ("lost", *lost),
            ("force_error", force_error.to_bits()),
            ("liquid_force_error", liquid_force_error.to_bits()),
            ("strain_energy", strain_energy.to_bits()),
            ("dissipated", dissipated.to_bits()),
            ("balance_work", balance_work.to_bits()),
            ("step_kinetic", step_kinetic.to_bits()),
            ("initial_kinetic", initial_kinetic.to_bits()),
            ("liquid_energy", liquid_energy.to_bits()),
            ("liquid_initial", liquid_initial.to_bits()),
            ("nodal_kinetic", nodal_kinetic.to_bits()),
        ];
        out.extend(
            PHASES
                .iter()
                .zip(phase_seconds)
                .map(|(&n, s)| (n, s.to_bits())),
        );
        reaction_scalars(reactions, &mut out);
        out.extend(semi_implicit.iter().flat_map(|s| s.counts.saved()));
        out.extend(
            constraints
                .saved()
                .into_iter()
                .map(|(name, x)| (name, x.to_bits())),
        );
        out
    }

    /// Carries on with `team` (between steps): the threads' ranges are laid out again for its
    /// thread count. The results do not change (they never depend on the threads); the
    /// points stay where the old team first touched them.
    pub fn rethread(&mut self, team: Team) {
        self.layout = self
            .layout
            .for_threads(&self.mesh, &self.particles, team.threads);
        self.slots = self.layout.new_slots();
        if let Some(b) = &self.basis {
            self.reach = Some(Reach::new(b, &self.mesh, &self.layout, team.threads));
        }
        self.locate_outcome = vec![NOTHING_FOUND; team.threads];
        self.team = team;
    }

    /// Restores a checkpoint into an engine just set up for the same case: the scalars of
    /// [`Engine::checkpoint_scalars`] and the particle arrays; the point loads and prescribed
    /// points follow their points, and the threads' ranges the points' elements.
    pub fn restore(
        &mut self,
        saved: &crate::driver::checkpoint::Saved,
    ) -> Result<(), crate::driver::checkpoint::CheckpointError> {
        let expected = self.checkpoint_scalars();
        let names: Vec<&str> = saved.scalars.iter().map(|(n, _)| n.as_str()).collect();
        if names != expected.iter().map(|(n, _)| *n).collect::<Vec<_>>() {
            return Err(saved.corrupt(format!("engine state [{}]", names.join(", "))));
        }
        let v = |k: usize| saved.scalars[k].1;
        let f = |k: usize| f64::from_bits(v(k));
        if self.critical_step.is_some() {
            // Taken again after every step: the saved one is the next step's.
            self.dt = f(0);
        } else if v(0) != self.dt.to_bits() {
            return Err(saved.corrupt(format!(
                "time step {} s, the case now gives {} s",
                f(0),
                self.dt
            )));
        }
        // Old index (as placed) of each id, to carry point indices over.
        let placed = self.particles.id.clone();
        saved.load_particles(&mut self.particles)?;
        let top = placed.iter().copied().max().unwrap_or(0) as usize;
        let mut index_of = vec![u32::MAX; top + 1];
        for (i, &id) in placed.iter().enumerate() {
            index_of[id as usize] = i as u32;
        }
        let mut new_of_old = vec![u32::MAX; placed.len()];
        for (new, &id) in self.particles.id.iter().enumerate() {
            let old = index_of.get(id as usize).copied().unwrap_or(u32::MAX);
            if old == u32::MAX || new_of_old[old as usize] != u32::MAX {
                return Err(saved.corrupt(format!("point id {id} unknown or repeated")));
            }
            new_of_old[old as usize] = new as u32;
        }
        for load in &mut self.point_loads {
            load.0 = new_of_old[load.0 as usize];
        }
        self.constraints.follow(&new_of_old);
        let el = &self.particles.element;
        if el.iter().any(|&e| e as usize >= self.mesh.elements())
            || !el.windows(2).all(|w| w[0] <= w[1])
        {
            return Err(
                saved.corrupt("points not sorted by element, or an element beyond the mesh".into())
            );
        }
        // Every per-material table is indexed by it (a file re-signed after an edit passes
        // the checksum).
        let materials = self.laws.len();
        if let Some((i, &m)) = self
            .particles
            .material
            .iter()
            .enumerate()
            .find(|(_, &m)| m as usize >= materials)
        {
            return Err(saved.corrupt(format!(
                "material point {} of material {m}; the case has {materials}",
                self.particles.id[i]
            )));
        }
        self.layout.set_particle_elements(&self.particles.element);
        self.time = f(1);
        self.steps = v(2);
        self.external_work = f(3);
        self.lost = v(4);
        self.force_error = f(5);
        self.liquid_force_error = f(6);
        self.strain_energy = f(7);
        self.dissipated = f(8);
        self.balance_work = f(9);
        self.step_kinetic = f(10);
        self.initial_kinetic = f(11);
        self.liquid_energy = f(12);
        self.liquid_initial = f(13);
        self.nodal_kinetic = f(14);
        for (k, s) in self.phase_seconds.iter_mut().enumerate() {
            *s = f(15 + k);
        }
        let mut at = 15 + PHASES.len();
        for r in self.reactions.iter_mut() {
            r.travel = f(at);
            r.force = [1, 2, 3].map(|j| f(at + j));
            at += 4;
            if let Some(w) = &mut r.window {
                *w = ([0, 1, 2].map(|j| f(at + j)), f(at + 3));
                at += 4;
            }
        }
        if let Some(s) = &mut self.semi_implicit {
            s.counts =
                crate::step::semi_implicit::SolveCounts::restored([0, 1, 2, 3].map(|k| v(at + k)));
            at += 4;
        }
        let state: Vec<(&str, f64)> = (at..saved.scalars.len())
            .map(|k| (saved.scalars[k].0.as_str(), f(k)))
            .collect();
        if !self.constraints.restore(&mut self.mesh, &state) {
            let names: Vec<&str> = self.constraints.iter().map(|c| c.name()).collect();
            return Err(saved.corrupt(format!(
                "the state of the constraints ({})",
                names.join(", ")
            )));
        }
        Ok(())
    }
}

/// The reactions' checkpoint scalars, appended to `out`: each set's travel and last force, and
/// an averaged set's window.
fn reaction_scalars(reactions: &[crate::step::reaction::Reaction], out: &mut Vec<(&str, u64)>) {
    for r in reactions {
        out.push(("reaction_travel", r.travel.to_bits()));
        out.extend(
            ["reaction_fx", "reaction_fy", "reaction_fz"]
                .into_iter()
                .zip(r.force.map(f64::to_bits)),
        );
        if let Some((impulse, elapsed)) = r.window {
            out.extend(
                ["window_ix", "window_iy", "window_iz", "window_time"]
                    .into_iter()
                    .zip(impulse.iter().chain([&elapsed]).map(|v| v.to_bits())),
            );
        }
    }
}
