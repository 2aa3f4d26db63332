//! The guard rails' sums of the stress pass: per block of
//! [`ELEMENT_BLOCK`](crate::parallel::gather::ELEMENT_BLOCK) elements, the
//! strain energy taken up, the energy the liquid's compression holds and the smallest volume
//! margin of its points ([`GuardSums`]), kept in registers for the block the pass is in
//! ([`Open`]) and added point by point in order ([`GuardTerms::add_point`]).

use crate::material::liquid::Fluid;
use crate::real::Real;

/// Per block of [`ELEMENT_BLOCK`](crate::parallel::gather::ELEMENT_BLOCK) elements, the guard
/// rails' sums over its active points after
/// the stress update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuardSums {
    /// Σ V0 (σ0 + σ1) : Δε, twice the strain energy taken up in the step (kJ; the energies are
    /// summed doubled and halved once, by the engine); NaN when a position or volume is not
    /// finite.
    pub strain: f64,
    /// Σ m |v|² (kJ), twice the kinetic energy with the step's new point velocities (written by
    /// grid to particle); for saturated points with the liquid's n ρw V_w |w|².
    pub kinetic: f64,
    /// Σ n V p² / K_w over saturated points (kJ): twice the energy the liquid's compression
    /// holds after the step; NaN when a pore pressure is not finite.
    pub liquid: f64,
    /// Smallest V ρ0 - r m of the points (t), r the guard's smallest volume ratio: ≤ 0 when a
    /// point's V / V0 has fallen to r.
    pub volume_margin: f64,
}

impl GuardSums {
    /// A block without points.
    pub const EMPTY: GuardSums = GuardSums {
        strain: 0.0,
        kinetic: 0.0,
        liquid: 0.0,
        volume_margin: f64::INFINITY,
    };
}

/// What [`super::update_stress_and_move`] needs to form the guard rails' sums.
pub struct Guard<'a, R: Real> {
    /// One slot per element.
    pub slots: &'a mut [GuardSums],
    /// Per material index, mass per initial volume of its points (ρ0, t/m³; 0 for none).
    pub initial_density: &'a [R],
    /// Per material index, its liquid (saturated materials).
    pub fluids: &'a [Option<Fluid<R>>],
    /// The smallest V / V0 allowed.
    pub min_volume_ratio: R,
}

/// The guard sums of the block the stress loop is in: the points' sums are added here, in
/// registers, and to the block's slot when the points pass to the next block (adding to the
/// slot point by point would chain every point's sum through memory). Points come sorted by
/// element, so blocks come in order; the slot's own strain and liquid terms start at 0 (grid to
/// particle began it), so the sums are those of adding in place, point by point.
pub(super) struct Open {
    /// The block.
    pub block: usize,
    strain: f64,
    liquid: f64,
    volume_margin: f64,
}

impl Open {
    /// No points of block `block` yet.
    pub fn new(block: usize) -> Self {
        Open {
            block,
            strain: 0.0,
            liquid: 0.0,
            volume_margin: f64::INFINITY,
        }
    }

    /// Adds these sums to the block's slot, `slots[0]`.
    pub fn close(&self, slots: &mut [GuardSums]) {
        let slot = &mut slots[0];
        slot.strain += self.strain;
        slot.liquid += self.liquid;
        slot.volume_margin = slot.volume_margin.min(self.volume_margin);
    }
}

/// What the guard's sums take of a point besides its values, per material: ρ0, the smallest
/// volume ratio and n / K_w (0 for a dry material).
#[derive(Clone, Copy)]
pub(super) struct GuardTerms<R: Real> {
    pub rho0: R,
    pub min_ratio: R,
    pub n_over_kw: R,
}

impl<R: Real> GuardTerms<R> {
    /// The terms of material `m`.
    #[inline(always)]
    pub fn of(m: u32, initial_density: &[R], fluids: &[Option<Fluid<R>>], min_ratio: R) -> Self {
        GuardTerms {
            rho0: initial_density[m as usize],
            min_ratio,
            n_over_kw: fluids[m as usize].as_ref().map_or(R::ZERO, |f| f.n_over_kw),
        }
    }

    /// Adds the points of four lanes (`on`: those whose point takes part) to `open`, point by
    /// point in order ([`GuardTerms::add_point`]).
    #[inline(always)]
    pub fn add_four(
        &self,
        open: &mut Open,
        on: [bool; 4],
        strain: [R; 4],
        v1: [R; 4],
        mass: [R; 4],
        pore: Option<[R; 4]>,
    ) {
        for q in 0..4 {
            if !on[q] {
                continue;
            }
            self.add_point(open, strain[q], v1[q], mass[q], pore.map(|p| p[q]));
        }
    }

    /// Adds one point to `open`: its strain-energy term `strain`, the liquid's energy of its
    /// new pore pressure `pore` (a saturated point's liquid holds n V p² / 2 K_w: the pore
    /// pressure's work on Δp = (K_w/n) Δε_mix; a non-finite pore pressure makes the sum NaN),
    /// and the volume check's margin V ρ0 - r m (V/V0 ≤ r is V ρ0 - r m ≤ 0, the mass being
    /// constant, m = ρ0 V0: no division per point). Twice the energies: the engine halves the
    /// sums (exactly, a power of two).
    #[inline(always)]
    pub fn add_point(&self, open: &mut Open, strain: R, v1: R, mass: R, pore: Option<R>) {
        let margin = v1 * self.rho0 - self.min_ratio * mass;
        open.strain += strain.f64();
        if let Some(p) = pore {
            open.liquid += (v1 * p * p * self.n_over_kw + R::ZERO * p).f64();
        }
        // A plain comparison (one instruction): NaN is caught by the strain sum.
        let m = margin.f64();
        if m < open.volume_margin {
            open.volume_margin = m;
        }
    }
}
