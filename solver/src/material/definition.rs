//! What a constitutive law is to the rest of the program: [`LawDefinition`], the law as the
//! input gives it (its name, its parameters, their checks, how many state values it keeps per
//! point), and [`ConstitutiveLaw`], the law built in the run's precision that updates a point's
//! stress. Each law is one file of `material/` implementing both, registered by one line in
//! [`crate::material::law`], which generates the enums the solver dispatches on; the
//! conformance suite ([`crate::material::conformance`]) checks any implementation, inside the
//! crate or out.

use std::fmt::Debug;

use crate::real::Real;

/// Why a law's parameters are refused: the message the input's error shows.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ParameterError(pub String);

/// One end of a parameter's range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The value itself is refused (±∞ for no bound where infinity is refused too).
    Open(f64),
    /// The value itself is accepted (±∞ where infinity is accepted).
    Closed(f64),
}

/// One parameter of a law, for the readers, the generated documentation and the conformance
/// suite's refusals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameter {
    /// Anura3D's key (`FRICTION_ANGLE`); scenes write it in lower case.
    pub key: &'static str,
    /// Its unit ("kPa", "degrees"; "" for a number).
    pub unit: &'static str,
    /// What it is, in one line.
    pub meaning: &'static str,
    /// The lower end of its range on its own (other parameters may narrow it further).
    pub low: Bound,
    /// The upper end of its range on its own.
    pub high: Bound,
    /// The value a scene may leave out (`None`: it must be given); Anura3D's files give all.
    pub default: Option<f64>,
}

impl Parameter {
    /// A parameter accepting any finite value, required (narrow it with [`Parameter::range`]).
    pub const fn new(key: &'static str, unit: &'static str, meaning: &'static str) -> Self {
        Parameter {
            key,
            unit,
            meaning,
            low: Bound::Open(f64::NEG_INFINITY),
            high: Bound::Open(f64::INFINITY),
            default: None,
        }
    }

    /// The same with the range from `low` to `high`.
    pub const fn range(mut self, low: Bound, high: Bound) -> Self {
        self.low = low;
        self.high = high;
        self
    }

    /// The same with a default value for scenes.
    pub const fn with_default(mut self, value: f64) -> Self {
        self.default = Some(value);
        self
    }

    /// The range in words: "(0, ∞)", "[1, ∞)".
    pub fn range_words(&self) -> String {
        let end = |x: f64| {
            if x.is_infinite() {
                "∞".to_string()
            } else {
                x.to_string()
            }
        };
        let low = match self.low {
            Bound::Open(x) => format!("({}", end(x)),
            Bound::Closed(x) => format!("[{}", end(x)),
        };
        let high = match self.high {
            Bound::Open(x) => format!("{})", end(x)),
            Bound::Closed(x) => format!("{}]", end(x)),
        };
        format!("{low}, {high}")
    }

    /// Whether `value` lies in the range on its own ([`Parameter::low`], [`Parameter::high`]).
    pub fn admits(&self, value: f64) -> bool {
        let above = match self.low {
            Bound::Open(l) => value > l,
            Bound::Closed(l) => value >= l,
        };
        let below = match self.high {
            Bound::Open(h) => value < h,
            Bound::Closed(h) => value <= h,
        };
        above && below
    }
}

/// Each of `values` inside its parameter's own range ([`Parameter::admits`]), or the refusal
/// naming the first that is not: its key, meaning, range and value.
pub fn check_each(parameters: &[Parameter], values: &[f64]) -> Result<(), ParameterError> {
    for (p, &v) in parameters.iter().zip(values) {
        if !p.admits(v) {
            return Err(ParameterError(format!(
                "{} ({}) must be in {}, got {v}",
                p.key,
                p.meaning,
                p.range_words()
            )));
        }
    }
    Ok(())
}

/// The keys of `parameters`, in their order, as an array (for `law::keys`' constant slices).
pub const fn keys_of<const N: usize>(parameters: &[Parameter]) -> [&'static str; N] {
    let mut keys = [""; N];
    let mut i = 0;
    while i < N {
        keys[i] = parameters[i].key;
        i += 1;
    }
    keys
}

/// A constitutive law as the input gives it: implemented by the law's parameter type, which
/// is one variant of [`crate::material::law::LawSpec`] once the law is registered.
pub trait LawDefinition: Debug + Clone + Copy + PartialEq + Send + Sync + 'static {
    /// The law's name, as Anura3D's `MATERIAL_MODEL_SOLID` spells it.
    const NAME: &'static str;
    /// Its parameters, in the order Anura3D reads them (and [`LawDefinition::values`] gives).
    const PARAMETERS: &'static [Parameter];
    /// The law ready to compute in precision `R`.
    type Law<R: Real>: ConstitutiveLaw<R>;

    /// The parameters `get(key)` finds, checked: a missing key is refused as
    /// [`LawDefinition::need`] words it, a value out of range with the law's own message.
    fn read(get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, ParameterError>;

    /// The parameter values, in [`LawDefinition::PARAMETERS`]' order.
    fn values(&self) -> Vec<f64>;

    /// Young's modulus (kPa) and Poisson's ratio of the elastic part (of the stiffest state):
    /// the time step's bound and the conformance suite's elastic stiffness.
    fn elastic(&self) -> (f64, f64);

    /// State values the law keeps per material point (the length of `state` in
    /// [`ConstitutiveLaw::update`]); they start at zero.
    fn state_len(&self) -> usize;

    /// The law in precision `R`.
    fn build<R: Real>(&self) -> Self::Law<R>;

    /// Whether a point may start at `stress` (tension positive, kPa): the refusal says why
    /// not (a void ratio outside the model's bounds at that pressure). Every start is
    /// admitted by default.
    fn check_start(&self, _stress: &[f64; 6]) -> Result<(), ParameterError> {
        Ok(())
    }

    /// Parameter sets that exercise the law (each of its branches), for the conformance suite.
    fn examples() -> Vec<Self>;

    /// The parameters as (key, value), in [`LawDefinition::PARAMETERS`]' order: what
    /// [`LawDefinition::read`] reads back.
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        Self::PARAMETERS
            .iter()
            .map(|p| p.key)
            .zip(self.values())
            .collect()
    }

    /// The value of `key` that `get` finds, or the refusal "NAME needs KEY".
    fn need(get: &dyn Fn(&str) -> Option<f64>, key: &str) -> Result<f64, ParameterError> {
        get(key).ok_or_else(|| ParameterError(format!("{} needs {key}", Self::NAME)))
    }
}

/// A constitutive law in the run's precision: the stress update of one material point.
pub trait ConstitutiveLaw<R: Real>: Debug + Clone + Copy + PartialEq + Send + Sync {
    /// Adds the stress increment of the strain increment `de` (xx yy zz xy yz zx, tensor shear
    /// components; stresses tension positive, kPa) to `stress`, updating the point's `state`
    /// (its [`LawDefinition::state_len`] values).
    fn update(&self, stress: &mut [R; 6], de: &[R; 6], state: &mut [R]);

    /// The yield function at `stress` for the point's `state` (kPa): negative inside the
    /// elastic domain, zero on the surface an update returns to, positive beyond; the largest
    /// of them where the surface has several (a cut-off). `None` for a law without one.
    fn yield_function(&self, stress: &[R; 6], state: &[R]) -> Option<R>;

    /// The bulk and shear moduli (kPa) of the elastic response at `stress` and `state`, for a
    /// law whose elasticity depends on them (pressure-dependent, as Cam Clay's); `None`
    /// (the default): the constant ones of [`LawDefinition::elastic`].
    fn elastic_tangent(&self, _stress: &[R; 6], _state: &[R]) -> Option<(f64, f64)> {
        None
    }

    /// The stress rate for the strain rate `d` at `stress` and `state`, for a law without an
    /// elastic range (hypoplasticity's T̊ = M(σ, state, d) : d, nonlinear in `d`); `None` (the
    /// default): the law has an elastic range or is elastic. The conformance suite checks the
    /// update of a small increment against it.
    fn stress_rate(&self, _stress: &[R; 6], _state: &[R], _d: &[f64; 6]) -> Option<[f64; 6]> {
        None
    }

    /// Where symmetric tensors (six values, xx yy zz xy yz zx, tensor shear components) start
    /// among the point's state values, for the state values that turn with the material
    /// (hypoplasticity's intergranular strain); the others are invariants. The stress pass
    /// co-rotates these with the stress (Jaumann), and the conformance suite rotates them.
    fn state_tensors(&self) -> &'static [usize] {
        &[]
    }
}
