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

use crate::material::definition::{ConstitutiveLaw, LawDefinition, Parameter, ParameterError};
use crate::material::linear_elastic::{LinearElastic, LinearElasticSpec, ELASTIC_PARAMETERS};
use crate::material::mohr_coulomb::Surface;
use crate::material::strength::{check_strength, DILATANCY, FRICTION, NON_NEGATIVE};
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

impl<R: Real> ConstitutiveLaw<R> for StrainSofteningMohrCoulomb<R> {
    #[inline(always)]
    fn update(&self, stress: &mut [R; 6], de: &[R; 6], state: &mut [R]) {
        StrainSofteningMohrCoulomb::update(self, stress, de, state);
    }

    fn yield_function(&self, stress: &[R; 6], state: &[R]) -> Option<R> {
        // The surface `update` returns to from this state: the peak one built at set-up
        // until the point yields.
        match state.first() {
            Some(&eq) if eq != R::ZERO => {
                Some(surface::<R>(&self.strength(eq.f64())).yield_at(stress))
            }
            _ => Some(self.peak_surface.yield_at(stress)),
        }
    }
}

/// Strain-softening Mohr–Coulomb's parameters (kPa, angles in degrees), checked by
/// [`StrainSofteningMohrCoulombSpec::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainSofteningMohrCoulombSpec {
    /// Young's modulus (kPa).
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Peak strength.
    pub peak: Strength,
    /// Residual strength.
    pub residual: Strength,
    /// Shape factor η.
    pub shape_factor: f64,
}

const PARAMETERS: [Parameter; 9] = [
    ELASTIC_PARAMETERS[0],
    ELASTIC_PARAMETERS[1],
    Parameter::new("PEAK_COHESION", "kPa", "peak cohesion c_p")
        .range(NON_NEGATIVE.0, NON_NEGATIVE.1),
    Parameter::new("RESIDUAL_COHESION", "kPa", "residual cohesion c_r")
        .range(NON_NEGATIVE.0, NON_NEGATIVE.1),
    Parameter::new("PEAK_FRICTION_ANGLE", "degrees", "peak friction angle φ_p")
        .range(FRICTION.0, FRICTION.1),
    Parameter::new(
        "RESIDUAL_FRICTION_ANGLE",
        "degrees",
        "residual friction angle φ_r",
    )
    .range(FRICTION.0, FRICTION.1),
    Parameter::new(
        "PEAK_DILATANCY_ANGLE",
        "degrees",
        "peak dilatancy angle ψ_p, at most φ_p",
    )
    .range(DILATANCY.0, DILATANCY.1),
    Parameter::new(
        "RESIDUAL_DILATANCY_ANGLE",
        "degrees",
        "residual dilatancy angle ψ_r, at most φ_r",
    )
    .range(DILATANCY.0, DILATANCY.1),
    Parameter::new(
        "SHAPE_FACTOR",
        "",
        "shape factor η of the softening exp(-η ε_eq^p)",
    )
    .range(NON_NEGATIVE.0, NON_NEGATIVE.1),
];

impl StrainSofteningMohrCoulombSpec {
    /// Checked: the elastic constants as [`LinearElasticSpec::new`], peak and residual
    /// strengths each as in [`crate::material::mohr_coulomb::MohrCoulombSpec::new`], η ≥ 0.
    pub fn new(
        young: f64,
        poisson: f64,
        peak: Strength,
        residual: Strength,
        shape_factor: f64,
    ) -> Result<Self, ParameterError> {
        LinearElasticSpec::new(young, poisson)?;
        check_strength("peak ", peak.friction, peak.dilatancy, peak.cohesion)?;
        check_strength(
            "residual ",
            residual.friction,
            residual.dilatancy,
            residual.cohesion,
        )?;
        if !(shape_factor >= 0.0 && shape_factor.is_finite()) {
            return Err(ParameterError(format!(
                "shape factor must be non-negative, got {shape_factor}"
            )));
        }
        Ok(StrainSofteningMohrCoulombSpec {
            young,
            poisson,
            peak,
            residual,
            shape_factor,
        })
    }
}

impl LawDefinition for StrainSofteningMohrCoulombSpec {
    const NAME: &'static str = "strain_softening_mohr_coulomb";
    const PARAMETERS: &'static [Parameter] = &PARAMETERS;
    type Law<R: Real> = StrainSofteningMohrCoulomb<R>;

    fn read(get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, ParameterError> {
        let need = |k| Self::need(get, k);
        // Read peak, then residual (not the keys' order): the first key missing is named.
        let (young, poisson) = (need("YOUNG_MODULUS")?, need("POISSON_RATIO")?);
        let peak = Strength {
            cohesion: need("PEAK_COHESION")?,
            friction: need("PEAK_FRICTION_ANGLE")?,
            dilatancy: need("PEAK_DILATANCY_ANGLE")?,
        };
        let residual = Strength {
            cohesion: need("RESIDUAL_COHESION")?,
            friction: need("RESIDUAL_FRICTION_ANGLE")?,
            dilatancy: need("RESIDUAL_DILATANCY_ANGLE")?,
        };
        Self::new(young, poisson, peak, residual, need("SHAPE_FACTOR")?)
    }

    fn values(&self) -> Vec<f64> {
        let (p, r) = (self.peak, self.residual);
        vec![
            self.young,
            self.poisson,
            p.cohesion,
            r.cohesion,
            p.friction,
            r.friction,
            p.dilatancy,
            r.dilatancy,
            self.shape_factor,
        ]
    }

    fn elastic(&self) -> (f64, f64) {
        (self.young, self.poisson)
    }

    fn state_len(&self) -> usize {
        1
    }

    fn build<R: Real>(&self) -> StrainSofteningMohrCoulomb<R> {
        StrainSofteningMohrCoulomb::new(
            self.young,
            self.poisson,
            self.peak,
            self.residual,
            self.shape_factor,
        )
    }

    fn examples() -> Vec<Self> {
        let strength = |cohesion, friction, dilatancy| Strength {
            cohesion,
            friction,
            dilatancy,
        };
        let law = |peak, residual, shape_factor| StrainSofteningMohrCoulombSpec {
            young: 1e4,
            poisson: 0.3,
            peak,
            residual,
            shape_factor,
        };
        vec![
            law(strength(20.0, 35.0, 5.0), strength(2.0, 25.0, 0.0), 50.0),
            // Softening to no cohesion at all; and none (η = 0).
            law(strength(5.0, 30.0, 10.0), strength(0.0, 20.0, 0.0), 200.0),
            law(strength(10.0, 30.0, 0.0), strength(1.0, 20.0, 0.0), 0.0),
        ]
    }
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
