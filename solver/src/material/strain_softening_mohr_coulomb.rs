//! Mohr–Coulomb with exponential strain softening (Anura3D's `strain_softening_mohr_coulomb`
//! keys): cohesion, friction angle and dilatancy angle go from their peak to their residual
//! values as plastic strain accumulates,
//!
//! x = x_r + (x_p - x_r) · exp(-η ε_eq^p)   for x = c, φ, ψ (angles in degrees),
//!
//! with the shape factor η and the accumulated equivalent plastic deviatoric strain
//! ε_eq^p = Σ sqrt(2/3 · Δe^p : Δe^p), summed over the steps, where Δe^p is the deviatoric part
//! of the step's plastic strain increment Δε^p = D⁻¹ (σ_trial - σ_returned) (tensor strains).
//! ε_eq^p is the one state value per point.
//!
//! The update is explicit: the step's return uses the strengths of the ε_eq^p the point starts
//! the step with; ε_eq^p then grows by the step's increment, and the next step sees the
//! softened surface. The surface is the pyramid of [`crate::material::mohr_coulomb`] without a
//! tension cut-off (Anura3D reads no tensile strength for this law).
//!
//! Anura3D 2025 reads these keys (in this order: YOUNG_MODULUS, POISSON_RATIO, PEAK_COHESION,
//! RESIDUAL_COHESION, PEAK_FRICTION_ANGLE, RESIDUAL_FRICTION_ANGLE, PEAK_DILATANCY_ANGLE,
//! RESIDUAL_DILATANCY_ANGLE, SHAPE_FACTOR) but assigns this law no stress routine (its pointer
//! is commented out): the oracle cannot run a case that uses it, so this law has no Anura3D
//! reference (its source holds no softening formula either; the one above is this solver's).

use crate::material::linear_elastic::LinearElastic;
use crate::material::mohr_coulomb::Surface;
use crate::real::Real;

/// Peak or residual strength parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Strength {
    /// Cohesion c (kPa).
    pub cohesion: f64,
    /// Friction angle φ (degrees).
    pub friction: f64,
    /// Dilatancy angle ψ (degrees).
    pub dilatancy: f64,
}

/// Strain-softening Mohr–Coulomb, one state value per point (ε_eq^p).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainSofteningMohrCoulomb<R: Real> {
    /// The elastic part.
    pub elastic: LinearElastic<R>,
    /// Peak strength (at ε_eq^p = 0).
    pub peak: Strength,
    /// Residual strength (as ε_eq^p → ∞).
    pub residual: Strength,
    /// Shape factor η.
    pub shape: f64,
    /// The surface at peak strength, built once: points that have not yielded use it.
    peak_surface: Surface<R>,
}

impl<R: Real> StrainSofteningMohrCoulomb<R> {
    /// From E (kPa), ν, peak and residual strengths and η; checked by
    /// [`crate::material::law::LawSpec`].
    pub fn new(young: f64, poisson: f64, peak: Strength, residual: Strength, shape: f64) -> Self {
        StrainSofteningMohrCoulomb {
            elastic: LinearElastic::new(young, poisson),
            peak,
            residual,
            shape,
            peak_surface: surface(&peak),
        }
    }

    /// The strength at accumulated equivalent plastic strain `eq`.
    pub fn strength(&self, eq: f64) -> Strength {
        let w = (-self.shape * eq).exp();
        let mix = |p: f64, r: f64| r + (p - r) * w;
        Strength {
            cohesion: mix(self.peak.cohesion, self.residual.cohesion),
            friction: mix(self.peak.friction, self.residual.friction),
            dilatancy: mix(self.peak.dilatancy, self.residual.dilatancy),
        }
    }

    /// Adds the stress increment of `de` (xx yy zz xy yz zx, tensor shear components) to `s`
    /// and the step's equivalent plastic strain to `state[0]` (ε_eq^p).
    #[inline]
    pub fn update(&self, s: &mut [R; 6], de: &[R; 6], state: &mut [R]) {
        self.elastic.update(s, de);
        let eq = state.first().copied().unwrap_or(R::ZERO);
        let correction = if eq == R::ZERO {
            self.peak_surface.return_map(&self.elastic, s)
        } else {
            surface::<R>(&self.strength(eq.f64())).return_map(&self.elastic, s)
        };
        let (Some(d), Some(eq)) = (correction, state.first_mut()) else {
            return;
        };
        // Deviatoric plastic strain: dev(Δσ) / 2G (D⁻¹ on a deviator).
        let mean = (d[0] + d[1] + d[2]) * R::of(1.0 / 3.0);
        let g2 = self.elastic.shear + self.elastic.shear;
        let e = [(d[0] - mean) / g2, (d[1] - mean) / g2, (d[2] - mean) / g2];
        *eq += (R::of(2.0 / 3.0) * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2])).sqrt();
    }
}

/// The pyramid without cut-off for strength `s`.
fn surface<R: Real>(s: &Strength) -> Surface<R> {
    Surface::new(s.friction, s.cohesion, s.dilatancy, f64::INFINITY)
}
