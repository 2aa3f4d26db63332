//! The constitutive-law interface: what a material's law is (its parameters as given, chosen by
//! name as Anura3D's `MATERIAL_MODEL_SOLID` names it), and the law ready to compute in the run's
//! precision. Laws are an enum with static dispatch, so the stress kernel's inner loop has no
//! indirect call; a law with state (plasticity's hardening, back stress) declares how many values
//! it keeps per point and gets that slice of the particles' state slab at each update.

use crate::material::linear_elastic::LinearElastic;
use crate::real::Real;

/// A material's law and its parameters (kPa), as the input gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LawSpec {
    /// Isotropic linear elasticity.
    LinearElastic {
        /// Young's modulus (kPa).
        young: f64,
        /// Poisson's ratio.
        poisson: f64,
    },
}

/// Why a law cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LawError {
    /// No law has this name.
    #[error("no constitutive law is called {name:?} (known: {known})", name = .0, known = KNOWN.join(", "))]
    Unknown(String),
    /// A parameter is out of range.
    #[error("{0}")]
    Parameter(String),
}

/// Names of the laws, as Anura3D's `MATERIAL_MODEL_SOLID` spells them.
pub const KNOWN: [&str; 1] = ["linear_elasticity"];

impl LawSpec {
    /// Linear elasticity, checked: E > 0, -1 < ν < 0.5.
    pub fn linear_elastic(young: f64, poisson: f64) -> Result<Self, LawError> {
        if !(young > 0.0) {
            return Err(LawError::Parameter(format!(
                "Young's modulus must be positive, got {young}"
            )));
        }
        if !(poisson > -1.0 && poisson < 0.5) {
            return Err(LawError::Parameter(format!(
                "Poisson's ratio must be in (-1, 0.5), got {poisson}"
            )));
        }
        Ok(LawSpec::LinearElastic { young, poisson })
    }

    /// The law called `name` with the parameters `get(key)` finds (Anura3D's keys:
    /// `YOUNG_MODULUS`, `POISSON_RATIO`): the factory by name.
    pub fn by_name(name: &str, get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, LawError> {
        match name {
            "linear_elasticity" => {
                let need = |k: &str| {
                    get(k).ok_or_else(|| LawError::Parameter(format!("{name} needs {k}")))
                };
                Self::linear_elastic(need("YOUNG_MODULUS")?, need("POISSON_RATIO")?)
            }
            other => Err(LawError::Unknown(other.to_string())),
        }
    }

    /// The name of the law.
    pub fn name(&self) -> &'static str {
        match self {
            LawSpec::LinearElastic { .. } => "linear_elasticity",
        }
    }

    /// The stiffness that bounds the time step: the constrained (P-wave) modulus of the law's
    /// stiffest state (kPa); the critical step is Δx / sqrt(this / ρ).
    pub fn constrained_modulus(&self) -> f64 {
        match *self {
            LawSpec::LinearElastic { young, poisson } => {
                LinearElastic::<f64>::oedometric(young, poisson)
            }
        }
    }

    /// State values the law keeps per material point.
    pub fn state_len(&self) -> usize {
        match self {
            LawSpec::LinearElastic { .. } => 0,
        }
    }

    /// The law in precision `R`.
    pub fn build<R: Real>(&self) -> Law<R> {
        match *self {
            LawSpec::LinearElastic { young, poisson } => {
                Law::LinearElastic(LinearElastic::new(young, poisson))
            }
        }
    }
}

/// A law ready to compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law<R: Real> {
    /// Isotropic linear elasticity (no state).
    LinearElastic(LinearElastic<R>),
    /// No material (empty elements' index): the stress does not change.
    Void,
}

impl<R: Real> Law<R> {
    /// Adds the stress increment of the strain increment `de` (xx yy zz xy yz zx, tensor shear
    /// components) to `stress`, updating the point's `state` (its [`LawSpec::state_len`]
    /// values).
    #[inline]
    pub fn update(&self, stress: &mut [R; 6], de: &[R; 6], _state: &mut [R]) {
        match self {
            Law::LinearElastic(l) => l.update(stress, de),
            Law::Void => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_factory_builds_by_name_and_refuses_what_it_does_not_know() {
        let params = |k: &str| match k {
            "YOUNG_MODULUS" => Some(1000.0),
            "POISSON_RATIO" => Some(0.3),
            _ => None,
        };
        let law = LawSpec::by_name("linear_elasticity", &params).unwrap();
        assert_eq!(law.state_len(), 0);
        assert!((law.constrained_modulus() - 1346.153846153846).abs() < 1e-9);
        let e = LawSpec::by_name("mohr_coulomb", &params).unwrap_err();
        assert!(e.to_string().contains("linear_elasticity"), "{e}");
        let e = LawSpec::by_name("linear_elasticity", &|_| None).unwrap_err();
        assert!(e.to_string().contains("YOUNG_MODULUS"), "{e}");
        assert!(LawSpec::linear_elastic(1000.0, 0.5).is_err());
    }

    #[test]
    fn linear_elastic_law_adds_the_elastic_increment() {
        let law = LawSpec::linear_elastic(1000.0, 0.3).unwrap().build::<f64>();
        let mut s = [0.0; 6];
        law.update(&mut s, &[0.0, -1e-3, 0.0, 0.0, 0.0, 0.0], &mut []);
        assert!((s[1] + 1.346153846153846).abs() < 1e-12);
        let mut v = [1.0; 6];
        Law::<f64>::Void.update(&mut v, &[1.0; 6], &mut []);
        assert_eq!(v, [1.0; 6]);
    }
}
