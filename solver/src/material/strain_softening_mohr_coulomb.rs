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
//! is commented out): the oracle built from that source stops with a segmentation fault in the
//! first step of a case that uses it (checked on a column of `testdata/mc_column.toml`'s mesh).
//! This law therefore has no Anura3D reference, and its source holds no softening formula either:
//! the one above is this solver's.

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::principal::principal;

    const PEAK: Strength = Strength {
        cohesion: 20.0,
        friction: 35.0,
        dilatancy: 5.0,
    };
    const RESIDUAL: Strength = Strength {
        cohesion: 2.0,
        friction: 25.0,
        dilatancy: 0.0,
    };

    #[test]
    fn strength_goes_from_peak_to_residual_by_the_formula() {
        let l = StrainSofteningMohrCoulomb::<f64>::new(1e4, 0.3, PEAK, RESIDUAL, 50.0);
        assert_eq!(l.strength(0.0), PEAK);
        let s = l.strength(0.01);
        let w = (-0.5f64).exp();
        assert!((s.cohesion - (2.0 + 18.0 * w)).abs() < 1e-12);
        assert!((s.friction - (25.0 + 10.0 * w)).abs() < 1e-12);
        assert!((s.dilatancy - 5.0 * w).abs() < 1e-12);
        let r = l.strength(10.0);
        assert!((r.cohesion - 2.0).abs() < 1e-12 && (r.friction - 25.0).abs() < 1e-12);
        // η = 0: no softening.
        let hard = StrainSofteningMohrCoulomb::<f64>::new(1e4, 0.3, PEAK, RESIDUAL, 0.0);
        assert_eq!(hard.strength(1.0), PEAK);
    }

    /// D⁻¹ σ with tensor shear strains (E, ν).
    fn compliance(e: f64, nu: f64, s: &[f64; 6]) -> [f64; 6] {
        let tr = s[0] + s[1] + s[2];
        let g2 = e / (1.0 + nu);
        let n = |x: f64| ((1.0 + nu) * x - nu * tr) / e;
        [n(s[0]), n(s[1]), n(s[2]), s[3] / g2, s[4] / g2, s[5] / g2]
    }

    #[test]
    fn shearing_softens_to_residual_and_counts_the_equivalent_plastic_strain() {
        let (e, nu) = (1e4, 0.3);
        let l = StrainSofteningMohrCoulomb::<f64>::new(e, nu, PEAK, RESIDUAL, 50.0);
        let mut s = [-100.0, -100.0, -100.0, 0.0, 0.0, 0.0];
        let mut state = [0.0];
        let mut sum = 0.0;
        let mut largest_shear: f64 = 0.0;
        // Simple shear in xy with the normal strains held.
        let de = [0.0, 0.0, 0.0, 1e-4, 0.0, 0.0];
        for _ in 0..4000 {
            let (s0, eq0) = (s, state[0]);
            l.update(&mut s, &de, &mut state);
            // The test's own ε_eq^p: the plastic strain from the stress change, its deviator,
            // sqrt(2/3 e:e) with the shear components counted twice.
            let ds: [f64; 6] = core::array::from_fn(|i| s[i] - s0[i]);
            let ee = compliance(e, nu, &ds);
            let ep: [f64; 6] = core::array::from_fn(|i| de[i] - ee[i]);
            let m = (ep[0] + ep[1] + ep[2]) / 3.0;
            let dev = [ep[0] - m, ep[1] - m, ep[2] - m];
            let ee2 = dev.iter().map(|x| x * x).sum::<f64>()
                + 2.0 * (ep[3] * ep[3] + ep[4] * ep[4] + ep[5] * ep[5]);
            sum += (2.0 / 3.0 * ee2).sqrt();
            assert!(
                (state[0] - sum).abs() < 1e-10 * sum.max(1e-6),
                "ε_eq^p {} against {sum}",
                state[0]
            );
            // On the surface of the strength the step started with (explicit update).
            if state[0] > eq0 {
                let st = l.strength(eq0);
                let p = principal(&s);
                let sf = Surface::<f64>::new(st.friction, st.cohesion, st.dilatancy, f64::INFINITY);
                let f = sf.yield_value(p.values[0], p.values[2]);
                assert!(f.abs() < 1e-9, "F = {f}");
            }
            largest_shear = largest_shear.max(s[3]);
        }
        assert!(state[0] > 0.4, "ε_eq^p = {}", state[0]);
        // At the end the strength is residual: the shear stress has dropped from its peak to
        // the residual one at the final mean stress.
        let r = l.strength(state[0]);
        assert!((r.friction - 25.0).abs() < 1e-6 && (r.cohesion - 2.0).abs() < 1e-6);
        let p = principal(&s);
        let sf = Surface::<f64>::new(25.0, 2.0, 0.0, f64::INFINITY);
        assert!(sf.yield_value(p.values[0], p.values[2]).abs() < 1e-4);
        assert!(
            s[3] < 0.9 * largest_shear,
            "{} against peak {largest_shear}",
            s[3]
        );
    }

    #[test]
    fn a_missing_state_slot_does_not_panic() {
        let l = StrainSofteningMohrCoulomb::<f32>::new(1e4, 0.3, PEAK, RESIDUAL, 50.0);
        let mut s = [-10.0f32, -10.0, -10.0, 0.0, 0.0, 0.0];
        l.update(&mut s, &[0.0, 0.0, 0.0, 1e-2, 0.0, 0.0], &mut []);
        assert!(s.iter().all(|x| x.is_finite()));
    }
}
