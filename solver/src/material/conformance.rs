//! The conformance suite every constitutive law passes, generic over [`LawDefinition`] so that a
//! law written outside the crate runs it too ([`check_law`] for each of its
//! [`LawDefinition::examples`], [`check`] for one parameter set). It checks
//!
//! - the parameters: read back by name from [`LawDefinition::parameters`] they give the same
//!   law, each inside its own range, a missing key refused with its name, and every value out
//!   of a parameter's range on its own ([`crate::material::definition::Parameter::low`],
//!   `high`, and NaN) refused;
//! - the elastic limit: a small increment from a stress well inside the yield surface adds the
//!   elastic stiffness's increment (for a law with a pressure-dependent elasticity,
//!   [`ConstitutiveLaw::elastic_tangent`], the tangent's, to second order); a law without an
//!   elastic range ([`ConstitutiveLaw::stress_rate`], hypoplasticity) adds its rate's increment
//!   instead, to second order, and its rate is homogeneous of degree one (rate independence);
//! - consistency: after an increment whose elastic trial lies beyond the surface, the stress
//!   lies on it or inside (within round-off scaled to the stress), for the state the update
//!   started from (explicit updates, as strain softening) or the one it ends with;
//! - objectivity: for random rotations Q, update(Q σ Qᵀ, Q Δε Qᵀ) = Q update(σ, Δε) Qᵀ to
//!   round-off, with the same state (the state's tensors, [`ConstitutiveLaw::state_tensors`],
//!   rotated; the other values are invariants);
//! - precision: each path run in f32 follows the f64 one within f32's round-off;
//! - the checkpoint: a path run in two halves, the stress and state written and read back in
//!   between through the particles' own encoding ([`Particles::put_point`],
//!   [`Particles::push_encoded`]), ends with the bits of the path run in one go.
//!
//! The paths are random (a fixed seed: the same numbers on every machine) strain increments
//! from a hydrostatic compression of E / 1000 (the law's Young's modulus), of 10⁻⁵ to 3·10⁻³
//! each, so a law's examples should have strengths of the order of E / 1000 to yield on them.
//! The stress checks run in both precisions; what they allow is round-off ([`Tolerances`],
//! in units of the precision's ε), which a law with an iterative return may widen
//! ([`check_with`]).

use proptest::prelude::Rng;
use proptest::test_runner::{RngAlgorithm, TestRng};

use crate::material::definition::{Bound, ConstitutiveLaw, LawDefinition};
use crate::real::Real;
use crate::state::particles::Particles;

/// The checks of the suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Check {
    /// Parameters read back, ranges, missing keys.
    Parameters,
    /// Values out of range refused.
    Refusal,
    /// The elastic response inside the yield surface.
    Elastic,
    /// Stresses on or inside the yield surface after plastic increments.
    Consistency,
    /// Updates commute with rotations.
    Objectivity,
    /// f32 against f64.
    Precision,
    /// A path through the checkpoint's encoding and back.
    Checkpoint,
}

/// A check a law failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{law} with {parameters}: {check:?} check failed: {what}")]
pub struct Failure {
    /// Which check.
    pub check: Check,
    /// The law's name.
    pub law: &'static str,
    /// Its parameters, as (key, value) pairs in words.
    pub parameters: String,
    /// What went wrong.
    pub what: String,
}

/// Paths per check.
const PATHS: usize = 12;
/// Steps per path.
const STEPS: usize = 16;

/// Strain increments' sizes, path by path in turn.
const STRAIN_STEPS: [f64; 4] = [1e-5, 1e-4, 1e-3, 3e-3];

/// What the checks allow, relative to the stresses' size (the state values': their size
/// plus 10⁻³, as for strains), as multiples of the precision's ε unless said otherwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// The elastic response.
    pub elastic: f64,
    /// The yield function after a plastic increment (an iterative return would need its own
    /// convergence tolerance here).
    pub surface: f64,
    /// The rotated update against the update rotated.
    pub rotation: f64,
    /// f32 against f64, per step taken (relative, not in ε).
    pub f32_per_step: f64,
}

impl Default for Tolerances {
    /// Round-off of an explicit update: the laws of this crate stay below a tenth of these.
    fn default() -> Self {
        Tolerances {
            elastic: 16.0,
            surface: 1e3,
            rotation: 256.0,
            f32_per_step: 4e-6,
        }
    }
}

/// The floor of a state value's size, for its tolerances.
const STATE_FLOOR: f64 = 1e-3;

/// Runs the suite on each of the law's [`LawDefinition::examples`].
pub fn check_law<D: LawDefinition>() -> Result<(), Failure> {
    let examples = D::examples();
    if examples.is_empty() {
        return Err(Failure {
            check: Check::Parameters,
            law: D::NAME,
            parameters: String::new(),
            what: "the law gives no examples to check".into(),
        });
    }
    examples.iter().try_for_each(check)
}

/// Runs the suite on the law with the parameters `spec`, with the default [`Tolerances`].
pub fn check<D: LawDefinition>(spec: &D) -> Result<(), Failure> {
    check_with(spec, &Tolerances::default())
}

/// Runs the suite on the law with the parameters `spec`, allowing `tolerances`.
pub fn check_with<D: LawDefinition>(spec: &D, tolerances: &Tolerances) -> Result<(), Failure> {
    let suite = Suite::new(spec, *tolerances);
    suite.parameters()?;
    suite.refusals()?;
    suite.elastic::<f64>()?;
    suite.elastic::<f32>()?;
    suite.consistency::<f64>()?;
    suite.consistency::<f32>()?;
    suite.objectivity::<f64>()?;
    suite.objectivity::<f32>()?;
    suite.precision()?;
    suite.checkpoint::<f64>()?;
    suite.checkpoint::<f32>()
}

/// A random strain path: the start stress and the increments.
struct Path {
    start: [f64; 6],
    steps: Vec<[f64; 6]>,
}

/// One law's parameters and what the checks share.
struct Suite<'a, D: LawDefinition> {
    spec: &'a D,
    tolerances: Tolerances,
    /// The stresses' scale E / 1000 (kPa).
    scale: f64,
    /// Lamé's λ and the shear modulus G of the elastic part (kPa).
    lambda: f64,
    shear: f64,
    paths: Vec<Path>,
}

impl<'a, D: LawDefinition> Suite<'a, D> {
    /// The suite for `spec`, its paths drawn.
    fn new(spec: &'a D, tolerances: Tolerances) -> Self {
        let (young, poisson) = spec.elastic();
        let scale = young * 1e-3;
        let mut rng = Random::new(1);
        let paths = (0..PATHS)
            .map(|p| {
                let size = STRAIN_STEPS[p % STRAIN_STEPS.len()];
                // Half the paths compress as they shear (soil's usual loading), half not.
                let squeeze = if p % 2 == 0 { 0.2 * size } else { 0.0 };
                let start = std::array::from_fn(|c| {
                    let hydrostatic = if c < 3 { -scale } else { 0.0 };
                    hydrostatic + 0.2 * scale * rng.uniform()
                });
                let steps = (0..STEPS)
                    .map(|_| {
                        std::array::from_fn(|c| {
                            size * rng.uniform() - if c < 3 { squeeze } else { 0.0 }
                        })
                    })
                    .collect();
                Path { start, steps }
            })
            .collect();
        Suite {
            spec,
            tolerances,
            scale,
            lambda: young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)),
            shear: young / (2.0 * (1.0 + poisson)),
            paths,
        }
    }

    /// The failure of `check`, saying `what`.
    fn fail(&self, check: Check, what: String) -> Failure {
        let parameters = self
            .spec
            .parameters()
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect::<Vec<_>>()
            .join(", ");
        Failure {
            check,
            law: D::NAME,
            parameters,
            what,
        }
    }

    /// The elastic stress increment of the strain increment `de` (f64).
    fn stiffness(&self, de: &[f64; 6]) -> [f64; 6] {
        stiffness(self.lambda, self.shear, de)
    }

    /// The stress and state after each step of `path` in precision `R` (the start first).
    fn run<R: Real>(&self, law: &D::Law<R>, path: &Path) -> Vec<([R; 6], Vec<R>)> {
        let mut at = (path.start.map(R::of), vec![R::ZERO; self.spec.state_len()]);
        let mut out = vec![at.clone()];
        for de in &path.steps {
            law.update(&mut at.0, &de.map(R::of), &mut at.1);
            out.push(at.clone());
        }
        out
    }

    /// Read back by name, in range, a missing key named.
    fn parameters(&self) -> Result<(), Failure> {
        let fail = |what| Err(self.fail(Check::Parameters, what));
        let given = self.spec.parameters();
        if given.len() != D::PARAMETERS.len() {
            return fail(format!(
                "{} values for {} parameters",
                given.len(),
                D::PARAMETERS.len()
            ));
        }
        for (i, p) in D::PARAMETERS.iter().enumerate() {
            if D::PARAMETERS[..i].iter().any(|q| q.key == p.key) {
                return fail(format!("{} is listed twice", p.key));
            }
            if !p.admits(given[i].1) || p.default.is_some_and(|d| !p.admits(d)) {
                return fail(format!(
                    "{} = {} is out of its own range",
                    p.key, given[i].1
                ));
            }
        }
        let lookup = |k: &str| given.iter().find(|g| g.0 == k).map(|g| g.1);
        match D::read(&lookup) {
            Ok(back) if back == *self.spec => {}
            other => return fail(format!("its parameters read back as {other:?}")),
        }
        for p in D::PARAMETERS {
            match D::read(&|k| if k == p.key { None } else { lookup(k) }) {
                Err(e) if e.0.contains(p.key) => {}
                other => return fail(format!("without {} it reads {other:?}", p.key)),
            }
        }
        Ok(())
    }

    /// Each parameter's values beyond its own range, and NaN, refused.
    fn refusals(&self) -> Result<(), Failure> {
        let given = self.spec.parameters();
        for p in D::PARAMETERS {
            // Just beyond a closed end; an open end itself (infinity too).
            let beyond = |b: Bound, down: f64| match b {
                Bound::Open(x) => Some(x),
                Bound::Closed(x) if x.is_finite() => Some(x + down * 1e-6 * x.abs().max(1.0)),
                Bound::Closed(_) => None,
            };
            let values = [Some(f64::NAN), beyond(p.low, -1.0), beyond(p.high, 1.0)];
            for value in values.into_iter().flatten() {
                let get = |k: &str| {
                    if k == p.key {
                        return Some(value);
                    }
                    given.iter().find(|g| g.0 == k).map(|g| g.1)
                };
                if let Ok(spec) = D::read(&get) {
                    return Err(self.fail(
                        Check::Refusal,
                        format!("{} = {value} is accepted: {spec:?}", p.key),
                    ));
                }
            }
        }
        Ok(())
    }

    /// A small increment from each state well inside the surface along the paths: the elastic
    /// stiffness's increment.
    fn elastic<R: Real>(&self) -> Result<(), Failure> {
        let law = self.spec.build::<R>();
        let mut rng = Random::new(2);
        let mut checked = 0;
        for path in &self.paths {
            for (s, state) in self.run(&law, path) {
                // How far inside: the surface's distance where there is one.
                let room = match law.yield_function(&s, &state) {
                    None => self.scale,
                    Some(f) if f.f64() < -1e-3 * self.scale => -f.f64(),
                    Some(_) => continue,
                };
                let dir: [f64; 6] = std::array::from_fn(|_| rng.uniform());
                let size = norm(&self.stiffness(&dir));
                if law.stress_rate(&s, &state, &dir).is_some() {
                    self.incremental(&law, (&s, &state), dir.map(|x| x * room / size))?;
                    checked += 1;
                    continue;
                }
                // A pressure-dependent elasticity: its tangent, on an increment a thousand
                // times smaller, with the curvature's second order allowed (4 |Δσ|² / |σ|
                // bounds it for K ∝ p: a few thousandths of the increment).
                let tangent = law.elastic_tangent(&s, &state);
                let fraction = if tangent.is_some() { 2.5e-4 } else { 0.25 };
                let de = dir.map(|x| R::of(x * fraction * room / size));
                let (increment, curvature) = match tangent {
                    None => (self.stiffness(&de.map(R::f64)), 0.0),
                    Some((bulk, shear)) => {
                        let d = stiffness(bulk - 2.0 * shear / 3.0, shear, &de.map(R::f64));
                        let n = norm(&d);
                        (d, 4.0 * n * n / norm(&s.map(R::f64)).max(f64::MIN_POSITIVE))
                    }
                };
                let want = add(&s.map(R::f64), &increment);
                if law
                    .yield_function(&want.map(R::of), &state)
                    .is_some_and(|f| f > R::ZERO)
                {
                    continue;
                }
                let mut got = s;
                law.update(&mut got, &de, &mut state.clone());
                let tolerance =
                    self.tolerances.elastic * R::EPSILON * (norm(&want) + room) + curvature;
                let off = distance(&got.map(R::f64), &want);
                if off > tolerance {
                    return Err(self.fail(
                        Check::Elastic,
                        format!("in {}, from {s:?} by {de:?}: {got:?}, not the elastic {want:?} ({off:e} off)", R::NAME),
                    ));
                }
                checked += 1;
            }
        }
        if checked == 0 {
            return Err(self.fail(
                Check::Elastic,
                "no stress of the paths lay well inside the yield surface".into(),
            ));
        }
        Ok(())
    }

    /// A law without an elastic range ([`ConstitutiveLaw::stress_rate`]) at stress `s` and
    /// `state`, for increments along `de` (of the stress scale's size): a small increment adds
    /// the rate's stress increment to second order (the difference falls at least three times
    /// in one of three halvings, down to round-off), and the rate is homogeneous of degree
    /// one (the law is rate-independent).
    fn incremental<R: Real>(
        &self,
        law: &D::Law<R>,
        (s, state): (&[R; 6], &[R]),
        de: [f64; 6],
    ) -> Result<(), Failure> {
        let s64 = s.map(R::f64);
        let round_off = self.tolerances.elastic * R::EPSILON * (norm(&s64) + self.scale);
        // The change of stress by `de`, and its difference from the rate's increment.
        let off_rate = |de: &[R; 6]| {
            let rate = law
                .stress_rate(s, state, &de.map(R::f64))
                .expect("the law has a rate");
            let mut got = *s;
            law.update(&mut got, de, &mut state.to_vec());
            let change: [f64; 6] = std::array::from_fn(|c| got[c].f64() - s64[c]);
            (change, rate, distance(&change, &rate))
        };
        let de = de.map(|x| R::of(x * 1e-3));
        let (once, rate, _) = off_rate(&de);
        // Halved three times: second order in one halving at least (a switch of branch, as
        // the intergranular strain's loading to unloading, may lie inside another).
        let offs: Vec<f64> = (0..4)
            .map(|j| off_rate(&de.map(|x| x * R::of(0.5f64.powi(j)))).2)
            .collect();
        if !offs.windows(2).any(|w| w[1] <= w[0] / 3.0 + round_off) {
            return Err(self.fail(
                Check::Elastic,
                format!("in {}, from {s:?} (state {state:?}) by {de:?}: a change of {once:?}, not the rate's {rate:?} to second order ({offs:?} off for the increment halved 0 to 3 times)", R::NAME),
            ));
        }
        let rate2 = law
            .stress_rate(s, state, &de.map(|x| 2.0 * x.f64()))
            .expect("the law has a rate");
        if distance(&rate2, &rate.map(|x| 2.0 * x)) > round_off {
            return Err(self.fail(
                Check::Elastic,
                format!("in {}, from {s:?} (state {state:?}): the rate of {de:?} is {rate:?}, of twice that {rate2:?}, not twice the first", R::NAME),
            ));
        }
        Ok(())
    }

    /// Each increment along the paths whose elastic trial lies beyond the surface ends on it
    /// (or inside).
    fn consistency<R: Real>(&self) -> Result<(), Failure> {
        let law = self.spec.build::<R>();
        let mut plastic = 0;
        for path in &self.paths {
            let states = self.run(&law, path);
            for (n, de) in path.steps.iter().enumerate() {
                let ((s0, state0), (s1, state1)) = (&states[n], &states[n + 1]);
                let de = de.map(R::of);
                let trial = add(&s0.map(R::f64), &self.stiffness(&de.map(R::f64)));
                let Some(f) = law.yield_function(&trial.map(R::of), state0) else {
                    return Ok(());
                };
                let tolerance = self.tolerances.surface * R::EPSILON * norm(&trial).max(self.scale);
                if f.f64() <= tolerance {
                    continue;
                }
                plastic += 1;
                let f0 = law.yield_function(s1, state0).map_or(0.0, R::f64);
                let f1 = law.yield_function(s1, state1).map_or(0.0, R::f64);
                if f0.min(f1) > tolerance {
                    return Err(self.fail(
                        Check::Consistency,
                        format!("in {}, {s0:?} by {de:?} went to {s1:?}, outside the surface (F = {f0:e} for the state before, {f1:e} after; tolerance {tolerance:e})", R::NAME),
                    ));
                }
            }
        }
        if plastic == 0 {
            return Err(self.fail(
                Check::Consistency,
                "no increment of the paths reached the yield surface".into(),
            ));
        }
        Ok(())
    }

    /// Each increment along the paths, rotated with its stress, gives the rotated update.
    fn objectivity<R: Real>(&self) -> Result<(), Failure> {
        let law = self.spec.build::<R>();
        let mut rng = Random::new(3);
        for path in &self.paths {
            let states = self.run(&law, path);
            for (n, de) in path.steps.iter().enumerate() {
                let ((s0, state0), (s1, state1)) = (&states[n], &states[n + 1]);
                let q = rng.rotation();
                let de = de.map(R::of).map(R::f64);
                let mut s = rotate(&q, &s0.map(R::f64)).map(R::of);
                let tensors = law.state_tensors();
                let mut state = rotate_state(&q, state0, tensors);
                law.update(&mut s, &rotate(&q, &de).map(R::of), &mut state);
                let want = rotate(&q, &s1.map(R::f64));
                let state1 = &rotate_state(&q, state1, tensors);
                let size = norm(&s0.map(R::f64)) + norm(&self.stiffness(&de));
                let ulps = self.tolerances.rotation * R::EPSILON;
                let off = distance(&s.map(R::f64), &want);
                let state_off = state
                    .iter()
                    .zip(state1)
                    .any(|(a, b)| (a.f64() - b.f64()).abs() > ulps * (b.f64().abs() + STATE_FLOOR));
                let tolerance = ulps * size;
                if off > tolerance || state_off {
                    return Err(self.fail(
                        Check::Objectivity,
                        format!("in {}, {s0:?} by {de:?} (state {state0:?}) gives {s1:?} (state {state1:?}), rotated by {q:?} it gives {s:?} (state {state:?}), not {want:?} ({off:e} off)", R::NAME),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Each path in f32 follows the path in f64.
    fn precision(&self) -> Result<(), Failure> {
        let (single, double) = (self.spec.build::<f32>(), self.spec.build::<f64>());
        for path in &self.paths {
            let (a, b) = (self.run(&single, path), self.run(&double, path));
            let mut size = self.scale;
            for (n, ((s32, state32), (s64, state64))) in a.iter().zip(&b).enumerate() {
                size = size.max(norm(s64));
                let relative = self.tolerances.f32_per_step * (n + 1) as f64;
                let off = distance(&s32.map(f64::from), s64);
                let state_off = state32
                    .iter()
                    .zip(state64)
                    .any(|(x, y)| (f64::from(*x) - y).abs() > relative * (y.abs() + STATE_FLOOR));
                let tolerance = relative * size;
                if off > tolerance || state_off {
                    return Err(self.fail(
                        Check::Precision,
                        format!("after {n} steps of {:?}: {s32:?} (state {state32:?}) in f32, {s64:?} (state {state64:?}) in f64 ({off:e} apart)", path.steps),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Each path run in two halves through the particles' encoding ends with the same bits.
    fn checkpoint<R: Real>(&self) -> Result<(), Failure> {
        let law = self.spec.build::<R>();
        for path in &self.paths {
            let whole = self.run(&law, path);
            let half = STEPS / 2;
            let (mut s, mut state) = whole[half].clone();
            (s, state) = through_checkpoint(s, state);
            for de in &path.steps[half..] {
                law.update(&mut s, &de.map(R::of), &mut state);
            }
            let bits = |s: &[R; 6], state: &[R]| {
                let mut out = Vec::new();
                s.iter().chain(state).for_each(|x| x.put_bits(&mut out));
                out
            };
            let (want, want_state) = &whole[STEPS];
            if bits(&s, &state) != bits(want, want_state) {
                return Err(self.fail(
                    Check::Checkpoint,
                    format!("in {}, resumed half way the path ends at {s:?} (state {state:?}), in one go at {want:?} (state {want_state:?})", R::NAME),
                ));
            }
        }
        Ok(())
    }
}

/// The stress and state written as one material point's fields and read back as the
/// checkpoint and the exchange between ranks do ([`Particles::put_point`],
/// [`Particles::push_encoded`]).
fn through_checkpoint<R: Real>(stress: [R; 6], state: Vec<R>) -> ([R; 6], Vec<R>) {
    let state_len = state.len();
    let point = Particles {
        x: vec![[R::ZERO; 3]],
        u: vec![[R::ZERO; 3]],
        v: vec![[R::ZERO; 3]],
        mass: vec![R::ONE],
        volume: vec![R::ONE],
        stress: vec![stress],
        element: vec![0],
        material: vec![1],
        id: vec![1],
        active: vec![true],
        state,
        state_len,
        liquid: None,
        bulk: None,
    };
    let mut bytes = Vec::new();
    point.put_point(0, &mut bytes);
    let mut back = Particles::<R> {
        state_len,
        ..Default::default()
    };
    back.push_encoded(&bytes);
    (back.stress[0], back.state)
}

/// The deterministic generator of the paths and rotations.
struct Random(TestRng);

impl Random {
    /// The generator of seed `seed`.
    fn new(seed: u8) -> Self {
        Random(TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]))
    }

    /// A number uniform in [-0.5, 0.5).
    fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    /// A rotation matrix, from a random unit quaternion.
    fn rotation(&mut self) -> [[f64; 3]; 3] {
        let q: [f64; 4] = std::array::from_fn(|_| self.uniform());
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-3);
        let [w, x, y, z] = q.map(|c| c / n);
        [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ]
    }
}

/// Q s Qᵀ for a symmetric tensor s (xx yy zz xy yz zx).
fn rotate(q: &[[f64; 3]; 3], s: &[f64; 6]) -> [f64; 6] {
    let m = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    let r = |i: usize, j: usize| -> f64 {
        (0..3)
            .map(|k| (0..3).map(|l| q[i][k] * m[k][l] * q[j][l]).sum::<f64>())
            .sum()
    };
    [r(0, 0), r(1, 1), r(2, 2), r(0, 1), r(1, 2), r(2, 0)]
}

/// The stress increment of the strain increment `de` for Lamé's `lambda` and shear modulus
/// `shear`.
fn stiffness(lambda: f64, shear: f64, de: &[f64; 6]) -> [f64; 6] {
    let tr = lambda * (de[0] + de[1] + de[2]);
    let g2 = 2.0 * shear;
    std::array::from_fn(|c| if c < 3 { tr + g2 * de[c] } else { g2 * de[c] })
}

/// The state values with the tensors starting at `tensors` rotated by `q`.
fn rotate_state<R: Real>(q: &[[f64; 3]; 3], state: &[R], tensors: &[usize]) -> Vec<R> {
    let mut out = state.to_vec();
    for &at in tensors {
        let t: [f64; 6] = std::array::from_fn(|c| state[at + c].f64());
        for (c, v) in rotate(q, &t).into_iter().enumerate() {
            out[at + c] = R::of(v);
        }
    }
    out
}

/// The sum of two tensors.
fn add(a: &[f64; 6], b: &[f64; 6]) -> [f64; 6] {
    std::array::from_fn(|c| a[c] + b[c])
}

/// The Frobenius norm of a symmetric tensor (its shear components counted twice).
fn norm(s: &[f64; 6]) -> f64 {
    let n: f64 = s[..3].iter().map(|x| x * x).sum();
    let t: f64 = s[3..].iter().map(|x| x * x).sum();
    (n + 2.0 * t).sqrt()
}

/// The Frobenius norm of the difference of two tensors.
fn distance(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    norm(&std::array::from_fn(|c| a[c] - b[c]))
}
