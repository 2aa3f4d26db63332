//! The energies of the run and the guard rails that stop a diverging one (docs/design.md §4.14),
//! and Anura3D's quasi-static convergence test.

use crate::element::Element;
use crate::material::liquid::Fluid;
use crate::parallel::gather::exact_total;
use crate::real::Real;
use crate::step::{grid_update, nodal_energy};

use super::{Check, Divergence, Engine, StepError, BALANCE_FROM_STEP, BLOW_UP_FLOOR};

impl<R: Real, E: Element> Engine<R, E> {
    /// The guard rails after a step: sums the per-block slots in block order (so the result
    /// does not depend on the threads), updates the energy terms and checks them. `w`:
    /// the external power summed over the nodes this step; `forces`: the grid update's sums;
    /// `energy`: the step's nodal energy terms (this process's).
    pub(super) fn check_step(
        &mut self,
        dt: f64,
        w: f64,
        forces: &grid_update::ForceSums,
        energy: &nodal_energy::NodalEnergy,
    ) -> Result<(), StepError> {
        // The owned blocks' sums of every rank, exact; the smallest margin.
        let mut margin = f64::INFINITY;
        for (p, s) in self
            .owned_partials
            .iter_mut()
            .zip(&self.guard_slots[..self.layout.owned_blocks()])
        {
            *p = [s.strain, s.kinetic, s.liquid, 0.0];
            margin = margin.min(s.volume_margin);
        }
        let [strain, kinetic, liquid, _] = exact_total(
            &*self.comm,
            &self.owned_partials[..self.layout.owned_blocks()],
        );
        let margin = self.comm.min(margin);
        // The slots hold twice each energy (see `GuardSums`).
        let (strain, kinetic, liquid) = (0.5 * strain, 0.5 * kinetic, 0.5 * liquid);
        let previous = self.step_kinetic;
        self.strain_energy += strain;
        self.liquid_energy = liquid;
        self.step_kinetic = kinetic;
        let (work, dissipated) = (energy.work, energy.dissipated);
        self.dissipated += dissipated;
        self.balance_work += work;
        let nodal = w * dt + work + dissipated + forces.unbalanced;
        let fail = |check| Err(StepError::Diverged(Box::new(self.diagnose(check))));
        // A non-finite stress, velocity, position, volume or pore pressure makes the energies'
        // sums NaN or infinite (the passes fold the last three in); nodal values the nodal
        // sums.
        if !(strain + kinetic + liquid).is_finite() || !nodal.is_finite() {
            return fail(Check::NonFinite);
        }
        if margin <= 0.0 {
            return fail(Check::Volume);
        }
        // Both energy checks compare energies: over the first steps they are near zero and
        // their ratios are start-up and round-off (Anura3D's first step lasts 1e-15 s).
        if self.energy_checked.0 && self.steps > BALANCE_FROM_STEP {
            let released = (-self.internal_energy()).max(0.0);
            // A body that starts in equilibrium under initial stresses or pore pressures has a
            // budget of round-off (no work, nothing released), which its round-off kinetic
            // energy can outgrow (f32, an undrained column): a thousandth of the energy those
            // hold is the floor; a real blow-up passes it within a few steps.
            let floor = BLOW_UP_FLOOR * (self.stored_energy + self.liquid_initial);
            let budget = self.initial_kinetic + self.balance_work.max(0.0) + released + floor;
            if kinetic > self.guards.blow_up_factor * budget && kinetic > previous {
                return fail(Check::BlowUp);
            }
        }
        if self.energy_checked.1 && self.steps > BALANCE_FROM_STEP {
            if let Some(tol) = self.guards.energy_tolerance {
                if self.balance_error() > tol {
                    return fail(Check::EnergyBalance);
                }
            }
        }
        Ok(())
    }

    /// |kinetic + internal + dissipated - work - initial kinetic| over the largest of those
    /// terms (0 while all are 0), with the kinetic energy of the last step. Under mass scaling
    /// by f the loads' work goes into the scaled inertia: the kinetic terms count f times.
    pub fn balance_error(&self) -> f64 {
        let f = self.config.mass_scaling;
        crate::driver::guard::balance_error(
            f * self.step_kinetic,
            self.internal_energy(),
            self.dissipated,
            self.balance_work,
            f * self.initial_kinetic,
            self.stored_energy + self.liquid_initial,
        )
    }

    /// Energy taken up by the material since the start (kJ): the skeleton's strain energy and
    /// the change of what the liquid's compression holds.
    pub fn internal_energy(&self) -> f64 {
        self.strain_energy + (self.liquid_energy - self.liquid_initial)
    }

    /// What tripped, where: the point, element or node and the value, and the likely cause.
    pub(super) fn diagnose(&self, check: Check) -> Divergence {
        crate::driver::guard::diagnose(
            check,
            &crate::driver::guard::View {
                particles: &self.particles,
                grid: &self.grid,
                input_element: &self.input_element,
                input_node: &self.input_node,
                initial_density: &self.initial_density,
                courant: self.courant.0,
                critical_element: self.input_element[self.courant.1] + 1,
                step: self.steps,
                time: self.time,
                kinetic: self.step_kinetic,
                balance_error: self.balance_error(),
                tolerance: self.guards.energy_tolerance,
            },
        )
    }

    /// Anura3D's quasi-static convergence test: out-of-balance forces of the mixture and of the
    /// liquid and the nodes' kinetic energy (per unit of external work) within the tolerances.
    pub fn converged(&self, qs: &crate::input::case::QuasiStatic) -> bool {
        let (force_tolerance, energy_tolerance) = (qs.force_tolerance, qs.energy_tolerance);
        let kinetic = if self.external_work != 0.0 {
            (self.nodal_kinetic / self.external_work).abs()
        } else {
            0.0
        };
        self.force_error <= force_tolerance
            && self.liquid_force_error <= qs.liquid_force_tolerance
            && kinetic <= energy_tolerance
    }

    /// The liquid's kinetic energy Σ n ρw V_w |w|² / 2 and the energy its compression holds,
    /// Σ n V p² / 2 K_w, over the active saturated points (kJ; as the guard rails' sums).
    pub(super) fn liquid_energies(&self) -> (f64, f64) {
        let p = &self.particles;
        let Some(l) = &p.liquid else {
            return (0.0, 0.0);
        };
        let sum = |part: &(dyn Fn(usize, &Fluid<R>) -> f64 + Sync)| {
            self.comm.sum(self.team.sum_blocks(p.len(), |r| {
                r.filter(|&i| p.active[i])
                    .filter_map(|i| self.fluids[p.material[i] as usize].map(|f| part(i, &f)))
                    .sum()
            }))
        };
        let kinetic = sum(&|i, f| {
            let vw = l.volume0.as_ref().map_or(p.volume[i], |v0| v0[i]);
            let ww: R = l.w[i].iter().map(|&w| w * w).fold(R::ZERO, |a, b| a + b);
            0.5 * (f.n * f.rho_w * vw * ww).f64()
        });
        let stored = sum(&|i, f| 0.5 * (p.volume[i] * l.p[i] * l.p[i] / f.kw_over_n).f64());
        (kinetic, stored)
    }

    /// Kinetic energy of the active points, with their liquid's in two-phase cases (kJ).
    pub fn total_kinetic_energy(&self) -> f64 {
        self.kinetic_energy() + self.liquid_energies().0
    }

    /// Kinetic energy of the active points (kJ; the solid's), summed in fixed blocks of points.
    pub fn kinetic_energy(&self) -> f64 {
        let p = &self.particles;
        self.comm.sum(self.team.sum_blocks(p.len(), |r| {
            r.filter(|&i| p.active[i])
                .map(|i| {
                    0.5 * p.mass[i].f64() * p.v[i].iter().map(|v| v.f64() * v.f64()).sum::<f64>()
                })
                .sum()
        }))
    }
}
