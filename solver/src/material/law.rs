//! The constitutive laws' registry: what a material's law is (its parameters as given, chosen
//! by name as Anura3D's `MATERIAL_MODEL_SOLID` names it, [`LawSpec`]), and the law ready to
//! compute in the run's precision ([`Law`]). Each law is one file of `material/` implementing
//! [`LawDefinition`] and [`ConstitutiveLaw`]; the one list in the `laws!` invocation below
//! makes both enums, [`KNOWN`], [`keys`] and the dispatch from it, so adding a law is its file
//! (and `pub mod` in `material/mod.rs`) plus one line there. Laws are an enum with static
//! dispatch, so the stress kernel's inner loop has no indirect call; a law with state
//! (plasticity's hardening, back stress) declares how many values it keeps per point and gets
//! that slice of the particles' state slab at each update.

use crate::material::definition::{
    keys_of, ConstitutiveLaw, LawDefinition, Parameter, ParameterError,
};
use crate::material::hypoplastic::HypoplasticSpec;
use crate::material::linear_elastic::{LinearElastic, LinearElasticSpec};
use crate::material::modified_cam_clay::ModifiedCamClaySpec;
use crate::material::mohr_coulomb::MohrCoulombSpec;
use crate::material::strain_softening_mohr_coulomb::{StrainSofteningMohrCoulombSpec, Strength};
use crate::real::Real;

/// Something done for each registered law's definition ([`for_each_law`]).
pub trait LawVisitor {
    /// One law of the registry.
    fn visit<D: LawDefinition>(&mut self)
    where
        LawSpec: From<D>;
}

/// Generates, from the list of registered laws (`Variant => its LawDefinition`, each with its
/// doc comment), the two enums the solver dispatches on and the functions that go by name.
macro_rules! laws {
    ($($(#[$doc:meta])* $variant:ident => $spec:ty,)+) => {
        /// A material's law and its parameters (kPa, angles in degrees), as the input gives
        /// them: one variant per registered law, holding its [`LawDefinition`].
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum LawSpec {
            $($(#[$doc])* $variant($spec),)+
        }

        /// A law ready to compute: one variant per registered law, holding its
        /// [`LawDefinition::Law`].
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum Law<R: Real> {
            $($(#[$doc])* $variant(<$spec as LawDefinition>::Law<R>),)+
            /// No material (empty elements' index): the stress does not change.
            Void,
        }

        /// Names of the laws, as Anura3D's `MATERIAL_MODEL_SOLID` spells them.
        pub const KNOWN: [&str; [$(stringify!($variant)),+].len()] =
            [$(<$spec as LawDefinition>::NAME),+];

        /// The parameter keys of the law `name` (Anura3D's, in the order Anura3D reads
        /// them); `None` for an unknown law.
        pub fn keys(name: &str) -> Option<&'static [&'static str]> {
            $(if name == <$spec as LawDefinition>::NAME {
                const KEYS: [&str; <$spec as LawDefinition>::PARAMETERS.len()] =
                    keys_of(<$spec as LawDefinition>::PARAMETERS);
                return Some(&KEYS);
            })+
            None
        }

        /// The parameters of the law `name` ([`LawDefinition::PARAMETERS`]: keys, units,
        /// ranges, defaults); `None` for an unknown law.
        pub fn parameter_list(name: &str) -> Option<&'static [Parameter]> {
            $(if name == <$spec as LawDefinition>::NAME {
                return Some(<$spec as LawDefinition>::PARAMETERS);
            })+
            None
        }

        /// Hands every registered law's definition to `visitor`, in [`KNOWN`]'s order.
        pub fn for_each_law(visitor: &mut impl LawVisitor) {
            $(visitor.visit::<$spec>();)+
        }

        $(impl From<$spec> for LawSpec {
            fn from(spec: $spec) -> Self {
                LawSpec::$variant(spec)
            }
        })+

        impl LawSpec {
            /// The law called `name` with the parameters `get(key)` finds (Anura3D's keys,
            /// see [`keys`]; angles in degrees): the factory by name.
            pub fn by_name(
                name: &str,
                get: &dyn Fn(&str) -> Option<f64>,
            ) -> Result<Self, LawError> {
                $(if name == <$spec as LawDefinition>::NAME {
                    return Ok(LawSpec::$variant(<$spec as LawDefinition>::read(get)?));
                })+
                Err(LawError::Unknown(name.to_string()))
            }

            /// The parameters as (Anura3D key, value), in [`keys`]' order: what
            /// [`LawSpec::by_name`] reads back.
            pub fn parameters(&self) -> Vec<(&'static str, f64)> {
                match self {
                    $(LawSpec::$variant(spec) => spec.parameters(),)+
                }
            }

            /// The name of the law.
            pub fn name(&self) -> &'static str {
                match self {
                    $(LawSpec::$variant(_) => <$spec as LawDefinition>::NAME,)+
                }
            }

            /// Young's modulus and Poisson's ratio of the elastic part.
            pub fn elastic(&self) -> (f64, f64) {
                match self {
                    $(LawSpec::$variant(spec) => spec.elastic(),)+
                }
            }

            /// State values the law keeps per material point: none for the elastic and the
            /// perfectly plastic laws, ε_eq^p for strain softening.
            pub fn state_len(&self) -> usize {
                match self {
                    $(LawSpec::$variant(spec) => spec.state_len(),)+
                }
            }

            /// Whether a point may start at `stress` ([`LawDefinition::check_start`]).
            pub fn check_start(&self, stress: &[f64; 6]) -> Result<(), LawError> {
                match self {
                    $(LawSpec::$variant(spec) => Ok(spec.check_start(stress)?),)+
                }
            }

            /// The law in precision `R`.
            pub fn build<R: Real>(&self) -> Law<R> {
                match self {
                    $(LawSpec::$variant(spec) => Law::$variant(spec.build()),)+
                }
            }
        }

        impl<R: Real> Law<R> {
            /// Adds the stress increment of the strain increment `de` (xx yy zz xy yz zx,
            /// tensor shear components) to `stress`, updating the point's `state` (its
            /// [`LawSpec::state_len`] values). Always inlined: the stress loop's call would
            /// otherwise stay a call (the plastic laws make the match large), which costs
            /// linear elasticity, the cheapest law, about a third of its update.
            #[inline(always)]
            pub fn update(&self, stress: &mut [R; 6], de: &[R; 6], state: &mut [R]) {
                match self {
                    $(Law::$variant(law) => ConstitutiveLaw::update(law, stress, de, state),)+
                    Law::Void => {}
                }
            }

            /// The law's yield function ([`ConstitutiveLaw::yield_function`]); `None` for an
            /// elastic law and for no material.
            pub fn yield_function(&self, stress: &[R; 6], state: &[R]) -> Option<R> {
                match self {
                    $(Law::$variant(law) => law.yield_function(stress, state),)+
                    Law::Void => None,
                }
            }

            /// Where the law's tensor state values start ([`ConstitutiveLaw::state_tensors`]):
            /// the stress pass co-rotates them with the stress.
            pub fn state_tensors(&self) -> &'static [usize] {
                match self {
                    $(Law::$variant(law) => law.state_tensors(),)+
                    Law::Void => &[],
                }
            }
        }
    };
}

laws! {
    /// Isotropic linear elasticity ([`crate::material::linear_elastic`]).
    LinearElastic => LinearElasticSpec,
    /// Mohr–Coulomb with tension cut-off ([`crate::material::mohr_coulomb`]).
    MohrCoulomb => MohrCoulombSpec,
    /// Mohr–Coulomb with exponential strain softening
    /// ([`crate::material::strain_softening_mohr_coulomb`]).
    StrainSofteningMohrCoulomb => StrainSofteningMohrCoulombSpec,
    /// Modified Cam Clay ([`crate::material::modified_cam_clay`]).
    ModifiedCamClay => ModifiedCamClaySpec,
    /// Hypoplastic sand with intergranular strain ([`crate::material::hypoplastic`]).
    Hypoplasticity => HypoplasticSpec,
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

impl From<ParameterError> for LawError {
    fn from(e: ParameterError) -> Self {
        LawError::Parameter(e.0)
    }
}

impl LawSpec {
    /// Linear elasticity, checked: E > 0, -1 < ν < 0.5 ([`LinearElasticSpec::new`]).
    pub fn linear_elastic(young: f64, poisson: f64) -> Result<Self, LawError> {
        Ok(LinearElasticSpec::new(young, poisson)?.into())
    }

    /// Mohr–Coulomb, checked as [`MohrCoulombSpec::new`] does.
    pub fn mohr_coulomb(
        young: f64,
        poisson: f64,
        friction_angle: f64,
        cohesion: f64,
        dilatancy_angle: f64,
        tensile_strength: f64,
    ) -> Result<Self, LawError> {
        Ok(MohrCoulombSpec::new(
            young,
            poisson,
            friction_angle,
            cohesion,
            dilatancy_angle,
            tensile_strength,
        )?
        .into())
    }

    /// Strain-softening Mohr–Coulomb, checked as [`StrainSofteningMohrCoulombSpec::new`] does.
    pub fn strain_softening_mohr_coulomb(
        young: f64,
        poisson: f64,
        peak: Strength,
        residual: Strength,
        shape_factor: f64,
    ) -> Result<Self, LawError> {
        Ok(
            StrainSofteningMohrCoulombSpec::new(young, poisson, peak, residual, shape_factor)?
                .into(),
        )
    }

    /// The stiffness that bounds the time step: the constrained (P-wave) modulus of the law's
    /// stiffest state (kPa); the critical step is Δx / sqrt(this / ρ). For the plastic laws,
    /// that of their elastic part.
    pub fn constrained_modulus(&self) -> f64 {
        let (young, poisson) = self.elastic();
        LinearElastic::<f64>::oedometric(young, poisson)
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
        let LawSpec::StrainSofteningMohrCoulomb(StrainSofteningMohrCoulombSpec {
            peak,
            residual,
            shape_factor,
            ..
        }) = law
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

    /// Runs the conformance suite on a registered law, and checks that the registry's
    /// dispatch is the law's own: its name, keys, parameters back by name, state length, and
    /// the bits of its updates through [`Law::update`].
    struct Conforms(Vec<&'static str>);

    impl LawVisitor for Conforms {
        fn visit<D: LawDefinition>(&mut self)
        where
            LawSpec: From<D>,
        {
            crate::material::conformance::check_law::<D>().unwrap_or_else(|e| panic!("{e}"));
            self.0.push(D::NAME);
            let keys: Vec<_> = D::PARAMETERS.iter().map(|p| p.key).collect();
            assert_eq!(super::keys(D::NAME), Some(&keys[..]));
            for spec in D::examples() {
                let law = LawSpec::from(spec);
                assert_eq!(law.name(), D::NAME);
                assert_eq!(law.parameters(), spec.parameters());
                assert_eq!(law.elastic(), spec.elastic());
                assert_eq!(law.state_len(), spec.state_len());
                let get = |k: &str| spec.parameters().iter().find(|p| p.0 == k).map(|p| p.1);
                assert_eq!(LawSpec::by_name(D::NAME, &get), Ok(law));
                let (own, registered) = (spec.build::<f64>(), law.build::<f64>());
                let mut rng = crate::test_rng::uniform(7);
                let mut a = ([-10.0; 6], vec![0.0; spec.state_len()]);
                let mut b = a.clone();
                for _ in 0..50 {
                    let de: [f64; 6] = std::array::from_fn(|_| rng() * 2e-3);
                    own.update(&mut a.0, &de, &mut a.1);
                    registered.update(&mut b.0, &de, &mut b.1);
                    assert_eq!(a.0.map(f64::to_bits), b.0.map(f64::to_bits));
                    assert_eq!(a.1, b.1);
                    assert_eq!(
                        registered.yield_function(&b.0, &b.1),
                        own.yield_function(&a.0, &a.1)
                    );
                }
            }
        }
    }

    #[test]
    fn the_gom_reader_takes_every_key_of_every_law() {
        for name in KNOWN {
            for k in keys(name).unwrap() {
                assert!(mpm_shared::model::is_material_key(k), "{name}: {k}");
            }
        }
    }

    #[test]
    fn every_registered_law_passes_the_conformance_suite() {
        let mut seen = Conforms(Vec::new());
        for_each_law(&mut seen);
        assert_eq!(seen.0, KNOWN);
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
