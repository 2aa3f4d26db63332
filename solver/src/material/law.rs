//! The constitutive-law interface: what a material's law is (its parameters as given, chosen by
//! name as Anura3D's `MATERIAL_MODEL_SOLID` names it), and the law ready to compute in the run's
//! precision. Laws are an enum with static dispatch, so the stress kernel's inner loop has no
//! indirect call; a law with state (plasticity's hardening, back stress) declares how many values
//! it keeps per point and gets that slice of the particles' state slab at each update.

use crate::material::linear_elastic::LinearElastic;
use crate::material::mohr_coulomb::{apex, MohrCoulomb};
use crate::material::strain_softening_mohr_coulomb::{StrainSofteningMohrCoulomb, Strength};
use crate::real::Real;

/// A material's law and its parameters (kPa, angles in degrees), as the input gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LawSpec {
    /// Isotropic linear elasticity.
    LinearElastic {
        /// Young's modulus (kPa).
        young: f64,
        /// Poisson's ratio.
        poisson: f64,
    },
    /// Mohr–Coulomb with tension cut-off ([`crate::material::mohr_coulomb`]).
    MohrCoulomb {
        /// Young's modulus (kPa).
        young: f64,
        /// Poisson's ratio.
        poisson: f64,
        /// Friction angle φ (degrees).
        friction_angle: f64,
        /// Cohesion c (kPa).
        cohesion: f64,
        /// Dilatancy angle ψ (degrees).
        dilatancy_angle: f64,
        /// Tensile strength σt (kPa).
        tensile_strength: f64,
    },
    /// Mohr–Coulomb with exponential strain softening
    /// ([`crate::material::strain_softening_mohr_coulomb`]).
    StrainSofteningMohrCoulomb {
        /// Young's modulus (kPa).
        young: f64,
        /// Poisson's ratio.
        poisson: f64,
        /// Peak strength.
        peak: Strength,
        /// Residual strength.
        residual: Strength,
        /// Shape factor η.
        shape_factor: f64,
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
pub const KNOWN: [&str; 3] = [
    "linear_elasticity",
    "mohr_coulomb",
    "strain_softening_mohr_coulomb",
];

/// The parameter keys of the law `name` (Anura3D's, in the order Anura3D reads them); `None`
/// for an unknown law.
pub fn keys(name: &str) -> Option<&'static [&'static str]> {
    Some(match name {
        "linear_elasticity" => &["YOUNG_MODULUS", "POISSON_RATIO"],
        "mohr_coulomb" => &[
            "YOUNG_MODULUS",
            "POISSON_RATIO",
            "FRICTION_ANGLE",
            "COHESION",
            "DILATANCY_ANGLE",
            "TENSILE_STRENGTH",
        ],
        "strain_softening_mohr_coulomb" => &[
            "YOUNG_MODULUS",
            "POISSON_RATIO",
            "PEAK_COHESION",
            "RESIDUAL_COHESION",
            "PEAK_FRICTION_ANGLE",
            "RESIDUAL_FRICTION_ANGLE",
            "PEAK_DILATANCY_ANGLE",
            "RESIDUAL_DILATANCY_ANGLE",
            "SHAPE_FACTOR",
        ],
        _ => return None,
    })
}

fn parameter(message: String) -> LawError {
    LawError::Parameter(message)
}

/// Checks a friction angle, a dilatancy angle no larger and a cohesion (`what`: "peak ",
/// "residual " or "").
fn check_strength(
    what: &str,
    friction: f64,
    dilatancy: f64,
    cohesion: f64,
) -> Result<(), LawError> {
    if !(0.0..90.0).contains(&friction) {
        return Err(parameter(format!(
            "{what}friction angle must be in [0, 90) degrees, got {friction}"
        )));
    }
    if !(dilatancy >= 0.0 && dilatancy <= friction) {
        return Err(parameter(format!(
            "{what}dilatancy angle must be in [0, {what}friction angle {friction}] degrees, got {dilatancy}"
        )));
    }
    if !(cohesion >= 0.0 && cohesion.is_finite()) {
        return Err(parameter(format!(
            "{what}cohesion must be non-negative, got {cohesion}"
        )));
    }
    Ok(())
}

impl LawSpec {
    /// Linear elasticity, checked: E > 0, -1 < ν < 0.5.
    pub fn linear_elastic(young: f64, poisson: f64) -> Result<Self, LawError> {
        if !(young > 0.0 && young.is_finite()) {
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

    /// Mohr–Coulomb, checked: the elastic constants as [`LawSpec::linear_elastic`], φ in
    /// [0°, 90°), 0 ≤ ψ ≤ φ, c ≥ 0, σt ≥ 0 and, for φ > 0, σt no more than the pyramid's apex
    /// c cos φ / sin φ (Anura3D's Mohr–Coulomb routine takes a larger σt as given, where its
    /// cut-off cannot act as one; its older stress routine capped σt at the apex).
    pub fn mohr_coulomb(
        young: f64,
        poisson: f64,
        friction_angle: f64,
        cohesion: f64,
        dilatancy_angle: f64,
        tensile_strength: f64,
    ) -> Result<Self, LawError> {
        Self::linear_elastic(young, poisson)?;
        check_strength("", friction_angle, dilatancy_angle, cohesion)?;
        let top = apex(friction_angle, cohesion);
        // A little room for an apex written out in decimals.
        if !(tensile_strength >= 0.0 && tensile_strength <= top * (1.0 + 1e-9)) {
            return Err(parameter(format!(
                "tensile strength must be in [0, {top}] kPa (the apex c cos φ / sin φ), got {tensile_strength}"
            )));
        }
        Ok(LawSpec::MohrCoulomb {
            young,
            poisson,
            friction_angle,
            cohesion,
            dilatancy_angle,
            tensile_strength,
        })
    }

    /// Strain-softening Mohr–Coulomb, checked: the elastic constants as
    /// [`LawSpec::linear_elastic`], peak and residual strengths each as in
    /// [`LawSpec::mohr_coulomb`], η ≥ 0.
    pub fn strain_softening_mohr_coulomb(
        young: f64,
        poisson: f64,
        peak: Strength,
        residual: Strength,
        shape_factor: f64,
    ) -> Result<Self, LawError> {
        Self::linear_elastic(young, poisson)?;
        check_strength("peak ", peak.friction, peak.dilatancy, peak.cohesion)?;
        check_strength(
            "residual ",
            residual.friction,
            residual.dilatancy,
            residual.cohesion,
        )?;
        if !(shape_factor >= 0.0 && shape_factor.is_finite()) {
            return Err(parameter(format!(
                "shape factor must be non-negative, got {shape_factor}"
            )));
        }
        Ok(LawSpec::StrainSofteningMohrCoulomb {
            young,
            poisson,
            peak,
            residual,
            shape_factor,
        })
    }

    /// The law called `name` with the parameters `get(key)` finds (Anura3D's keys, see
    /// [`keys`]; angles in degrees): the factory by name.
    pub fn by_name(name: &str, get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, LawError> {
        let need = |k: &str| get(k).ok_or_else(|| parameter(format!("{name} needs {k}")));
        match name {
            "linear_elasticity" => {
                Self::linear_elastic(need("YOUNG_MODULUS")?, need("POISSON_RATIO")?)
            }
            "mohr_coulomb" => Self::mohr_coulomb(
                need("YOUNG_MODULUS")?,
                need("POISSON_RATIO")?,
                need("FRICTION_ANGLE")?,
                need("COHESION")?,
                need("DILATANCY_ANGLE")?,
                need("TENSILE_STRENGTH")?,
            ),
            "strain_softening_mohr_coulomb" => {
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
                Self::strain_softening_mohr_coulomb(
                    young,
                    poisson,
                    peak,
                    residual,
                    need("SHAPE_FACTOR")?,
                )
            }
            other => Err(LawError::Unknown(other.to_string())),
        }
    }

    /// The parameters as (Anura3D key, value), in [`keys`]' order: what
    /// [`LawSpec::by_name`] reads back.
    pub fn parameters(&self) -> Vec<(&'static str, f64)> {
        let values = match *self {
            LawSpec::LinearElastic { young, poisson } => vec![young, poisson],
            LawSpec::MohrCoulomb {
                young,
                poisson,
                friction_angle,
                cohesion,
                dilatancy_angle,
                tensile_strength,
            } => vec![
                young,
                poisson,
                friction_angle,
                cohesion,
                dilatancy_angle,
                tensile_strength,
            ],
            LawSpec::StrainSofteningMohrCoulomb {
                young,
                poisson,
                peak,
                residual,
                shape_factor,
            } => vec![
                young,
                poisson,
                peak.cohesion,
                residual.cohesion,
                peak.friction,
                residual.friction,
                peak.dilatancy,
                residual.dilatancy,
                shape_factor,
            ],
        };
        keys(self.name())
            .unwrap_or(&[])
            .iter()
            .copied()
            .zip(values)
            .collect()
    }

    /// The name of the law.
    pub fn name(&self) -> &'static str {
        match self {
            LawSpec::LinearElastic { .. } => "linear_elasticity",
            LawSpec::MohrCoulomb { .. } => "mohr_coulomb",
            LawSpec::StrainSofteningMohrCoulomb { .. } => "strain_softening_mohr_coulomb",
        }
    }

    /// Young's modulus and Poisson's ratio of the elastic part.
    pub fn elastic(&self) -> (f64, f64) {
        match *self {
            LawSpec::LinearElastic { young, poisson }
            | LawSpec::MohrCoulomb { young, poisson, .. }
            | LawSpec::StrainSofteningMohrCoulomb { young, poisson, .. } => (young, poisson),
        }
    }

    /// The stiffness that bounds the time step: the constrained (P-wave) modulus of the law's
    /// stiffest state (kPa); the critical step is Δx / sqrt(this / ρ). For the plastic laws,
    /// that of their elastic part.
    pub fn constrained_modulus(&self) -> f64 {
        let (young, poisson) = self.elastic();
        LinearElastic::<f64>::oedometric(young, poisson)
    }

    /// State values the law keeps per material point: none for the elastic and the perfectly
    /// plastic laws, ε_eq^p for strain softening.
    pub fn state_len(&self) -> usize {
        match self {
            LawSpec::LinearElastic { .. } | LawSpec::MohrCoulomb { .. } => 0,
            LawSpec::StrainSofteningMohrCoulomb { .. } => 1,
        }
    }

    /// The law in precision `R`.
    pub fn build<R: Real>(&self) -> Law<R> {
        match *self {
            LawSpec::LinearElastic { young, poisson } => {
                Law::LinearElastic(LinearElastic::new(young, poisson))
            }
            LawSpec::MohrCoulomb {
                young,
                poisson,
                friction_angle,
                cohesion,
                dilatancy_angle,
                tensile_strength,
            } => Law::MohrCoulomb(MohrCoulomb::new(
                young,
                poisson,
                friction_angle,
                cohesion,
                dilatancy_angle,
                tensile_strength,
            )),
            LawSpec::StrainSofteningMohrCoulomb {
                young,
                poisson,
                peak,
                residual,
                shape_factor,
            } => Law::StrainSofteningMohrCoulomb(StrainSofteningMohrCoulomb::new(
                young,
                poisson,
                peak,
                residual,
                shape_factor,
            )),
        }
    }
}

/// A law ready to compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law<R: Real> {
    /// Isotropic linear elasticity (no state).
    LinearElastic(LinearElastic<R>),
    /// Mohr–Coulomb with tension cut-off (no state).
    MohrCoulomb(MohrCoulomb<R>),
    /// Strain-softening Mohr–Coulomb (state: ε_eq^p).
    StrainSofteningMohrCoulomb(StrainSofteningMohrCoulomb<R>),
    /// No material (empty elements' index): the stress does not change.
    Void,
}

impl<R: Real> Law<R> {
    /// Adds the stress increment of the strain increment `de` (xx yy zz xy yz zx, tensor shear
    /// components) to `stress`, updating the point's `state` (its [`LawSpec::state_len`]
    /// values). Always inlined: the stress loop's call would otherwise stay a call (the
    /// plastic laws make the match large), which costs linear elasticity, the cheapest law,
    /// about a third of its update.
    #[inline(always)]
    pub fn update(&self, stress: &mut [R; 6], de: &[R; 6], state: &mut [R]) {
        match self {
            Law::LinearElastic(l) => l.update(stress, de),
            Law::MohrCoulomb(l) => l.update(stress, de),
            Law::StrainSofteningMohrCoulomb(l) => l.update(stress, de, state),
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
        let e = LawSpec::by_name("hardening_soil", &params).unwrap_err();
        assert!(
            e.to_string().contains("linear_elasticity, mohr_coulomb"),
            "{e}"
        );
        let e = LawSpec::by_name("mohr_coulomb", &params).unwrap_err();
        assert_eq!(e.to_string(), "mohr_coulomb needs FRICTION_ANGLE");
        let e = LawSpec::by_name("linear_elasticity", &|_| None).unwrap_err();
        assert!(e.to_string().contains("YOUNG_MODULUS"), "{e}");
        assert!(LawSpec::linear_elastic(1000.0, 0.5).is_err());
    }

    /// The Mohr–Coulomb keys with `key` set to `value` (c = 10, φ = 30: apex 10 √3).
    fn mc(key: &str, value: f64) -> Result<LawSpec, LawError> {
        let owned = key.to_string();
        LawSpec::by_name("mohr_coulomb", &move |k| {
            if k == owned {
                return Some(value);
            }
            Some(match k {
                "YOUNG_MODULUS" => 1e4,
                "POISSON_RATIO" => 0.3,
                "FRICTION_ANGLE" => 30.0,
                "COHESION" => 10.0,
                "DILATANCY_ANGLE" => 5.0,
                "TENSILE_STRENGTH" => 1.0,
                _ => return None,
            })
        })
    }

    #[test]
    fn mohr_coulomb_parameters_are_read_and_checked() {
        let law = mc("", 0.0).unwrap();
        assert_eq!(law.name(), "mohr_coulomb");
        assert_eq!(law.state_len(), 0);
        assert!((law.constrained_modulus() - 13461.538461538461).abs() < 1e-8);
        let back: Vec<_> = law.parameters();
        assert_eq!(
            back,
            vec![
                ("YOUNG_MODULUS", 1e4),
                ("POISSON_RATIO", 0.3),
                ("FRICTION_ANGLE", 30.0),
                ("COHESION", 10.0),
                ("DILATANCY_ANGLE", 5.0),
                ("TENSILE_STRENGTH", 1.0),
            ]
        );
        assert_eq!(
            LawSpec::by_name("mohr_coulomb", &|k| back
                .iter()
                .find(|p| p.0 == k)
                .map(|p| p.1)),
            Ok(law)
        );
        for (key, value, says) in [
            ("FRICTION_ANGLE", 90.0, "friction angle must be in [0, 90)"),
            ("FRICTION_ANGLE", -1.0, "friction angle must be in [0, 90)"),
            (
                "DILATANCY_ANGLE",
                31.0,
                "dilatancy angle must be in [0, friction angle 30]",
            ),
            ("DILATANCY_ANGLE", -1.0, "dilatancy angle"),
            ("COHESION", -1.0, "cohesion must be non-negative"),
            (
                "TENSILE_STRENGTH",
                -1.0,
                "tensile strength must be in [0, 17.32",
            ),
            (
                "TENSILE_STRENGTH",
                17.4,
                "tensile strength must be in [0, 17.32",
            ),
            ("YOUNG_MODULUS", 0.0, "Young's modulus"),
            ("POISSON_RATIO", 0.5, "Poisson's ratio"),
            ("COHESION", f64::NAN, "cohesion"),
        ] {
            let e = mc(key, value).unwrap_err().to_string();
            assert!(e.contains(says), "{key} = {value}: {e}");
        }
        // σt at the apex, as written with a few digits, and any σt for φ = 0.
        assert!(mc("TENSILE_STRENGTH", 10.0 * 3f64.sqrt()).is_ok());
        assert!(LawSpec::mohr_coulomb(1e4, 0.3, 0.0, 10.0, 0.0, 1e3).is_ok());
        // ψ = φ (associated) is accepted.
        assert!(mc("DILATANCY_ANGLE", 30.0).is_ok());
    }

    #[test]
    fn strain_softening_parameters_are_read_and_checked() {
        let keys = keys("strain_softening_mohr_coulomb").unwrap();
        let values = [1e4, 0.3, 20.0, 2.0, 35.0, 25.0, 5.0, 0.0, 50.0];
        let get = |k: &str| keys.iter().position(|&x| x == k).map(|i| values[i]);
        let law = LawSpec::by_name("strain_softening_mohr_coulomb", &get).unwrap();
        assert_eq!(law.state_len(), 1);
        let LawSpec::StrainSofteningMohrCoulomb {
            peak,
            residual,
            shape_factor,
            ..
        } = law
        else {
            panic!("{law:?}");
        };
        assert_eq!(
            (peak.cohesion, peak.friction, peak.dilatancy),
            (20.0, 35.0, 5.0)
        );
        assert_eq!(
            (residual.cohesion, residual.friction, residual.dilatancy),
            (2.0, 25.0, 0.0)
        );
        assert_eq!(shape_factor, 50.0);
        assert_eq!(
            law.parameters(),
            keys.iter().copied().zip(values).collect::<Vec<_>>()
        );
        for (i, value, says) in [
            (8, -1.0, "shape factor must be non-negative"),
            (5, 90.0, "residual friction angle must be in [0, 90)"),
            (
                6,
                36.0,
                "peak dilatancy angle must be in [0, peak friction angle 35]",
            ),
            (3, -2.0, "residual cohesion must be non-negative"),
        ] {
            let mut v = values;
            v[i] = value;
            let get = |k: &str| keys.iter().position(|&x| x == k).map(|i| v[i]);
            let e = LawSpec::by_name("strain_softening_mohr_coulomb", &get).unwrap_err();
            assert!(e.to_string().contains(says), "{e}");
        }
        let e = LawSpec::by_name("strain_softening_mohr_coulomb", &|k| {
            (k != "SHAPE_FACTOR").then_some(1.0)
        })
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "strain_softening_mohr_coulomb needs SHAPE_FACTOR"
        );
    }

    #[test]
    fn laws_dispatch_by_kind() {
        let mc = LawSpec::mohr_coulomb(1e4, 0.3, 30.0, 0.0, 0.0, 0.0)
            .unwrap()
            .build::<f64>();
        // Pure shear beyond the cohesionless pyramid: returned, unlike the elastic law.
        let mut s = [-10.0, -10.0, -10.0, 0.0, 0.0, 0.0];
        mc.update(&mut s, &[0.0, 0.0, 0.0, 1e-2, 0.0, 0.0], &mut []);
        assert!(s[3] > 0.0 && s[3] < 10.0, "{s:?}");
        let ss = LawSpec::by_name("strain_softening_mohr_coulomb", &|k| {
            Some(match k {
                "YOUNG_MODULUS" => 1e4,
                "POISSON_RATIO" => 0.3,
                k if k.contains("FRICTION") => 30.0,
                "SHAPE_FACTOR" => 10.0,
                _ => 0.0,
            })
        })
        .unwrap()
        .build::<f64>();
        let (mut s, mut state) = ([-10.0, -10.0, -10.0, 0.0, 0.0, 0.0], [0.0]);
        ss.update(&mut s, &[0.0, 0.0, 0.0, 1e-2, 0.0, 0.0], &mut state);
        assert!(state[0] > 0.0 && s[3] < 10.0);
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
