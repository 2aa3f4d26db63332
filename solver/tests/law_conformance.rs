//! A law written outside the crate, through the public interface alone, passes the conformance
//! suite (`mpm_solve::material::conformance`): von Mises perfect plasticity with a radial
//! return. Two broken versions of it are caught, each by the check it breaks: one that caps
//! the shear components one by one (which ignores rotation), one that returns only half way to
//! the surface; and two definitions whose parameters are read wrong are caught too.

use mpm_solve::material::conformance::{check, check_law, Check};
use mpm_solve::material::definition::{
    Bound, ConstitutiveLaw, LawDefinition, Parameter, ParameterError,
};
use mpm_solve::real::Real;

/// How the toy returns a trial beyond its surface.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Return {
    /// Radially, onto von Mises' cylinder (right).
    Radial,
    /// Each shear component cut to the strength on its own (not objective).
    PerComponent,
    /// Radially, but only half way (not consistent).
    HalfWay,
}

/// The toy's parameters: elasticity and the yield stress σy (kPa).
#[derive(Debug, Clone, Copy, PartialEq)]
struct VonMisesSpec {
    young: f64,
    poisson: f64,
    yield_stress: f64,
}

/// The toy in precision `R`, with the return `how` (fixed per definition type below).
#[derive(Debug, Clone, Copy, PartialEq)]
struct VonMises<R: Real> {
    lambda: R,
    shear: R,
    yield_stress: R,
    how: Return,
}

const PARAMETERS: &[Parameter] = &[
    Parameter::new("YOUNG_MODULUS", "kPa", "Young's modulus E")
        .range(Bound::Open(0.0), Bound::Open(f64::INFINITY)),
    Parameter::new("POISSON_RATIO", "", "Poisson's ratio ν")
        .range(Bound::Open(-1.0), Bound::Open(0.5)),
    Parameter::new("YIELD_STRESS", "kPa", "uniaxial yield stress σy")
        .range(Bound::Open(0.0), Bound::Open(f64::INFINITY)),
];

/// The toy's parameters read and checked, for any of the three definitions.
fn read(name: &str, get: &dyn Fn(&str) -> Option<f64>) -> Result<VonMisesSpec, ParameterError> {
    let [young, poisson, yield_stress] = [0, 1, 2].map(|i| {
        get(PARAMETERS[i].key)
            .ok_or_else(|| ParameterError(format!("{name} needs {}", PARAMETERS[i].key)))
    });
    let spec = VonMisesSpec {
        young: young?,
        poisson: poisson?,
        yield_stress: yield_stress?,
    };
    for (p, v) in PARAMETERS
        .iter()
        .zip([spec.young, spec.poisson, spec.yield_stress])
    {
        if !(p.admits(v) && v.is_finite()) {
            return Err(ParameterError(format!("{} out of range: {v}", p.key)));
        }
    }
    Ok(spec)
}

impl VonMisesSpec {
    /// The toy in precision `R`, returning `how`.
    fn build<R: Real>(&self, how: Return) -> VonMises<R> {
        let (e, nu) = (self.young, self.poisson);
        VonMises {
            lambda: R::of(e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))),
            shear: R::of(e / (2.0 * (1.0 + nu))),
            yield_stress: R::of(self.yield_stress),
            how,
        }
    }

    fn examples() -> Vec<Self> {
        vec![
            VonMisesSpec {
                young: 1e4,
                poisson: 0.3,
                yield_stress: 10.0,
            },
            VonMisesSpec {
                young: 5e4,
                poisson: 0.2,
                yield_stress: 30.0,
            },
        ]
    }
}

/// The mean stress, the deviator and von Mises' equivalent stress sqrt(3 J2).
fn invariants<R: Real>(s: &[R; 6]) -> (R, [R; 6], R) {
    let p = (s[0] + s[1] + s[2]) * R::of(1.0 / 3.0);
    let d: [R; 6] = std::array::from_fn(|c| if c < 3 { s[c] - p } else { s[c] });
    let j2 = R::of(0.5) * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        + d[3] * d[3]
        + d[4] * d[4]
        + d[5] * d[5];
    (p, d, (R::of(3.0) * j2).sqrt())
}

impl<R: Real> ConstitutiveLaw<R> for VonMises<R> {
    fn update(&self, s: &mut [R; 6], de: &[R; 6], _: &mut [R]) {
        let tr = self.lambda * (de[0] + de[1] + de[2]);
        let g2 = self.shear + self.shear;
        for c in 0..6 {
            s[c] += g2 * de[c] + if c < 3 { tr } else { R::ZERO };
        }
        let (p, d, q) = invariants(s);
        if self.how == Return::PerComponent {
            for x in &mut s[3..] {
                *x = x.max(-self.yield_stress).min(self.yield_stress);
            }
            return;
        }
        if q <= self.yield_stress {
            return;
        }
        let mut k = self.yield_stress / q;
        if self.how == Return::HalfWay {
            k = R::of(0.5) * (k + R::ONE);
        }
        for c in 0..6 {
            s[c] = d[c] * k + if c < 3 { p } else { R::ZERO };
        }
    }

    fn yield_function(&self, s: &[R; 6], _: &[R]) -> Option<R> {
        Some(match self.how {
            Return::PerComponent => s[3].abs().max(s[4].abs()).max(s[5].abs()) - self.yield_stress,
            _ => invariants(s).2 - self.yield_stress,
        })
    }
}

/// The parameters as `get` gives them, unchecked.
fn read_unchecked(
    name: &str,
    get: &dyn Fn(&str) -> Option<f64>,
) -> Result<VonMisesSpec, ParameterError> {
    let need = |k: &str| get(k).ok_or_else(|| ParameterError(format!("{name} needs {k}")));
    Ok(VonMisesSpec {
        young: need("YOUNG_MODULUS")?,
        poisson: need("POISSON_RATIO")?,
        yield_stress: need("YIELD_STRESS")?,
    })
}

/// The parameters, checked, with the yield stress read one higher than given.
fn read_shifted(
    name: &str,
    get: &dyn Fn(&str) -> Option<f64>,
) -> Result<VonMisesSpec, ParameterError> {
    read(name, get).map(|s| VonMisesSpec {
        yield_stress: s.yield_stress + 1.0,
        ..s
    })
}

/// Implements [`LawDefinition`] for a newtype of [`VonMisesSpec`] read by `$read` whose law
/// returns `$how`.
macro_rules! toy {
    ($name:ident, $key:literal, $how:expr, $read:ident) => {
        #[derive(Debug, Clone, Copy, PartialEq)]
        struct $name(VonMisesSpec);

        impl LawDefinition for $name {
            const NAME: &'static str = $key;
            const PARAMETERS: &'static [Parameter] = PARAMETERS;
            type Law<R: Real> = VonMises<R>;

            fn read(get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, ParameterError> {
                $read($key, get).map($name)
            }

            fn values(&self) -> Vec<f64> {
                vec![self.0.young, self.0.poisson, self.0.yield_stress]
            }

            fn elastic(&self) -> (f64, f64) {
                (self.0.young, self.0.poisson)
            }

            fn state_len(&self) -> usize {
                0
            }

            fn build<R: Real>(&self) -> VonMises<R> {
                self.0.build($how)
            }

            fn examples() -> Vec<Self> {
                VonMisesSpec::examples().into_iter().map($name).collect()
            }
        }
    };
}

toy!(VonMisesLaw, "von_mises", Return::Radial, read);
toy!(ShearCaps, "shear_caps", Return::PerComponent, read);
toy!(HalfWay, "half_way_von_mises", Return::HalfWay, read);
toy!(Lax, "lax_von_mises", Return::Radial, read_unchecked);
toy!(Shifted, "shifted_von_mises", Return::Radial, read_shifted);

#[test]
fn a_law_written_outside_the_crate_passes_the_suite() {
    check_law::<VonMisesLaw>().unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn a_law_that_ignores_rotation_fails_the_objectivity_check() {
    let e = check_law::<ShearCaps>().unwrap_err();
    assert_eq!(e.check, Check::Objectivity, "{e}");
    assert!(
        e.to_string()
            .starts_with("shear_caps with YOUNG_MODULUS = 10000"),
        "{e}"
    );
}

#[test]
fn a_return_that_stops_short_fails_the_consistency_check() {
    let e = check_law::<HalfWay>().unwrap_err();
    assert_eq!(e.check, Check::Consistency, "{e}");
}

#[test]
fn a_reader_that_takes_values_out_of_range_fails_the_refusal_check() {
    let e = check_law::<Lax>().unwrap_err();
    assert_eq!(e.check, Check::Refusal, "{e}");
    assert!(e.what.contains("YOUNG_MODULUS = NaN is accepted"), "{e}");
}

#[test]
fn parameters_that_do_not_read_back_fail_the_parameters_check() {
    let e = check(&Shifted::examples()[0]).unwrap_err();
    assert_eq!(e.check, Check::Parameters, "{e}");
}
