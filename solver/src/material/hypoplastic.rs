//! Hypoplastic sand (von Wolffersdorff 1996) with intergranular strain (Niemunis & Herle 1997;
//! Anura3D's `hypoplasticity`): a law without an elastic range, whose stress rate is nonlinear
//! in the strain rate D. Effective stresses T, tension positive as the code stores them;
//! T̂ = T / tr T, T̂* = T̂ − 1/3; ‖·‖ the Frobenius norm, A : B the full contraction.
//!
//! - The rate: T̊ = L : D + f_d N ‖D‖, with
//!   L = f_b f_e / (T̂ : T̂) (F² I + a² T̂ ⊗ T̂) and N = f_b f_e / (T̂ : T̂) a F (T̂ + T̂*);
//!   a = √3 (3 − sin φ_c) / (2√2 sin φ_c); F from the Lode angle and tan ψ = √3 ‖T̂*‖
//!   (Matsuoka–Nakai's critical surface).
//! - Bauer's compression law: e_i / e_i0 = e_c / e_c0 = e_d / e_d0 = exp(−(3p / h_s)^n);
//!   the barotropy f_b = (h_s / n) (e_i0 / e_c0)^β (1 + e_i) / e_i (3p / h_s)^(1 − n) /
//!   (3 + a² − √3 a ((e_i0 − e_d0) / (e_c0 − e_d0))^α); the pyknotropy f_e = (e_c / e)^β and
//!   f_d = ((e − e_d) / (e_c − e_d))^α (0 below e_d).
//! - The void ratio: ė = (1 + e) tr D.
//! - Intergranular strain δ (R > 0), ρ = ‖δ‖ / R, δ̂ = δ / ‖δ‖: on loading (δ̂ : D > 0)
//!   T̊ = [ρ^χ m_T + (1 − ρ^χ) m_R] L : D + ρ^χ (1 − m_T) (L : δ̂)(δ̂ : D) + ρ^χ f_d N (δ̂ : D)
//!   and δ̊ = D − ρ^β_r δ̂ (δ̂ : D); otherwise T̊ = [ρ^χ m_T + (1 − ρ^χ) m_R] L : D +
//!   ρ^χ (m_R − m_T) (L : δ̂)(δ̂ : D) and δ̊ = D. A reversal after a long monotonic path starts
//!   m_R times stiffer than the path's end; δ = 0 (a point's start by default) is the reversal.
//!
//! The update integrates the rate over the strain increment (the rate is homogeneous of
//! degree one in D: the increment's pseudo-time runs from 0 to 1) by the explicit Runge–Kutta
//! pair of orders 1 and 2 (Euler and Heun's modified Euler, Sloan's 1987 scheme for
//! elastoplastic laws; two rate evaluations a sub-step where the Runge–Kutta–Fehlberg pair of
//! orders 2 and 3 takes three, which made the law 1.5 times dearer) with error-controlled
//! sub-steps: the difference of the two orders, relative to the stress, R and the void ratio,
//! within `INTEGRATION_TOLERANCE`; the second-order result is taken. The
//! first sub-step is the whole increment, so the small increments of an explicit run take one
//! each. After each sub-step ‖δ‖ ≤ R and e_d(p) ≤ e ≤ e_i(p) are restored.
//!
//! Below `MINIMUM_PRESSURE` (and where the integration cannot continue: a stage outside the
//! compressive stresses where F is defined, or sub-steps below a millionth of the increment)
//! the point responds elastically with the model's isotropic small-strain stiffness at that
//! pressure, its deviator capped at the critical ratio M_c; a point pulled into tension falls
//! apart to the stress-free state, its intergranular strain forgotten.
//!
//! The point's state: e and δ (six values, co-rotated with the stress). e = 0 is "not set": the first update sets e = e0 and δ = ρ0 R along the initial
//! stress's direction (ρ0 = `IGS_INITIAL`: 1 for a soil whose initial stress was built by
//! monotonic compression). The time step takes the stiffest state the run can reach: the
//! densest (e_d) at `MAXIMUM_PRESSURE`, with the intergranular strain's m_R.

use std::f64::consts::SQRT_2;
use std::marker::PhantomData;

use crate::material::definition::{
    check_each, Bound, ConstitutiveLaw, LawDefinition, Parameter, ParameterError,
};
use crate::real::Real;

/// The hypoplastic law's parameters, checked by [`HypoplasticSpec::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HypoplasticSpec {
    /// The critical state friction angle φ_c (degrees).
    pub friction: f64,
    /// The granular hardness h_s (kPa).
    pub hardness: f64,
    /// Bauer's exponent n.
    pub exponent: f64,
    /// e_d0, the densest void ratio at zero pressure.
    pub e_d0: f64,
    /// e_c0, the critical void ratio at zero pressure.
    pub e_c0: f64,
    /// e_i0, the loosest void ratio at zero pressure.
    pub e_i0: f64,
    /// The pyknotropy exponent α (peak friction).
    pub alpha: f64,
    /// The pyknotropy exponent β (stiffness).
    pub beta: f64,
    /// The void ratio at the start.
    pub void_ratio: f64,
    /// The intergranular strain's elastic range R (0: without intergranular strain).
    pub igs_r: f64,
    /// m_R, the stiffness multiplier after a reversal of 180°.
    pub igs_mr: f64,
    /// m_T, the stiffness multiplier after a reversal of 90°.
    pub igs_mt: f64,
    /// β_r, the intergranular strain's evolution exponent.
    pub igs_beta_r: f64,
    /// χ, the interpolation exponent.
    pub igs_chi: f64,
    /// ρ0, the initial intergranular strain as a fraction of R, along the initial stress.
    pub igs_initial: f64,
    /// The integration's relative error tolerance per sub-step.
    pub tolerance: f64,
    /// Below this mean stress the response is elastic (kPa).
    pub minimum_pressure: f64,
    /// The largest mean stress the run reaches (kPa): the time step's stiffness.
    pub maximum_pressure: f64,
}

const POSITIVE: Bound = Bound::Open(0.0);
const UNBOUNDED: Bound = Bound::Open(f64::INFINITY);

const PARAMETERS: [Parameter; 18] = [
    Parameter::new(
        "CRITICAL_FRICTION_ANGLE",
        "degrees",
        "the critical state friction angle φc",
    )
    .range(POSITIVE, Bound::Open(90.0)),
    Parameter::new(
        "GRANULAR_HARDNESS",
        "kPa",
        "the granular hardness hs of Bauer's compression law",
    )
    .range(POSITIVE, UNBOUNDED),
    Parameter::new("EXPONENT_N", "", "Bauer's exponent n").range(POSITIVE, Bound::Closed(1.0)),
    Parameter::new(
        "MINIMUM_VOID_RATIO",
        "",
        "ed0, the densest void ratio at zero pressure",
    )
    .range(POSITIVE, UNBOUNDED),
    Parameter::new(
        "CRITICAL_VOID_RATIO",
        "",
        "ec0, the critical void ratio at zero pressure (between ed0 and ei0)",
    )
    .range(POSITIVE, UNBOUNDED),
    Parameter::new(
        "MAXIMUM_VOID_RATIO",
        "",
        "ei0, the loosest void ratio at zero pressure",
    )
    .range(POSITIVE, UNBOUNDED),
    Parameter::new(
        "EXPONENT_ALPHA",
        "",
        "the pyknotropy exponent α (the peak friction's dependence on density)",
    )
    .range(Bound::Closed(0.0), UNBOUNDED),
    Parameter::new(
        "EXPONENT_BETA",
        "",
        "the pyknotropy exponent β (the stiffness's dependence on density)",
    )
    .range(Bound::Closed(0.0), UNBOUNDED),
    Parameter::new(
        "INITIAL_VOID_RATIO",
        "",
        "the void ratio e0 at the start, the same at every point",
    )
    .range(POSITIVE, UNBOUNDED),
    Parameter::new(
        "IGS_R",
        "",
        "the intergranular strain's elastic range R; 0: without intergranular strain",
    )
    .range(Bound::Closed(0.0), Bound::Open(0.1))
    .with_default(0.0),
    Parameter::new(
        "IGS_MR",
        "",
        "mR, the stiffness multiplier after a full reversal (at least 1)",
    )
    .range(Bound::Closed(1.0), UNBOUNDED)
    .with_default(5.0),
    Parameter::new(
        "IGS_MT",
        "",
        "mT, the stiffness multiplier after a reversal of 90° (1 to mR)",
    )
    .range(Bound::Closed(1.0), UNBOUNDED)
    .with_default(2.0),
    Parameter::new(
        "IGS_BETA_R",
        "",
        "βr, the intergranular strain's evolution exponent",
    )
    .range(POSITIVE, UNBOUNDED)
    .with_default(0.5),
    Parameter::new("IGS_CHI", "", "χ, the stiffness interpolation's exponent")
        .range(POSITIVE, UNBOUNDED)
        .with_default(6.0),
    Parameter::new(
        "IGS_INITIAL",
        "",
        "ρ0, the initial intergranular strain as a fraction of R along the initial stress (1: mobilised by the compression that built it; 0: none, the state after a reversal)",
    )
    .range(Bound::Closed(0.0), Bound::Closed(1.0))
    .with_default(0.0),
    Parameter::new(
        "INTEGRATION_TOLERANCE",
        "",
        "the sub-steps' relative error tolerance",
    )
    .range(Bound::Closed(1e-9), Bound::Closed(0.1))
    .with_default(1e-4),
    Parameter::new(
        "MINIMUM_PRESSURE",
        "kPa",
        "below this p' a point responds elastically with the stiffness at it",
    )
    .range(POSITIVE, UNBOUNDED)
    .with_default(1.0),
    Parameter::new(
        "MAXIMUM_PRESSURE",
        "kPa",
        "the largest p' the run reaches: the time step takes the stiffness there",
    )
    .range(POSITIVE, UNBOUNDED),
];

impl HypoplasticSpec {
    /// Checked: each value in its range ([`LawDefinition::PARAMETERS`]), e_d0 < e_c0 < e_i0,
    /// a positive denominator of f_b, m_T ≤ m_R, p_min < p_max, and an e0 the model admits at
    /// some pressure up to p_max: e_d(p_max) ≤ e0 ≤ e_i0 (each point's own start is checked
    /// against its pressure, [`LawDefinition::check_start`]).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        [friction, hardness, exponent, e_d0, e_c0, e_i0, alpha, beta]: [f64; 8],
        void_ratio: f64,
        [igs_r, igs_mr, igs_mt, igs_beta_r, igs_chi, igs_initial]: [f64; 6],
        tolerance: f64,
        minimum_pressure: f64,
        maximum_pressure: f64,
    ) -> Result<Self, ParameterError> {
        let spec = HypoplasticSpec {
            friction,
            hardness,
            exponent,
            e_d0,
            e_c0,
            e_i0,
            alpha,
            beta,
            void_ratio,
            igs_r,
            igs_mr,
            igs_mt,
            igs_beta_r,
            igs_chi,
            igs_initial,
            tolerance,
            minimum_pressure,
            maximum_pressure,
        };
        check_each(&PARAMETERS, &spec.values())?;
        let refuse = |m: String| Err(ParameterError(m));
        if !(e_d0 < e_c0 && e_c0 < e_i0) {
            return refuse(format!(
                "the void ratios must grow from MINIMUM_VOID_RATIO ({e_d0}) to CRITICAL_VOID_RATIO ({e_c0}) to MAXIMUM_VOID_RATIO ({e_i0})"
            ));
        }
        let c = Constants::of(&spec);
        if !(c.fb > 0.0) {
            return refuse(format!(
                "3 + a² − √3 a ((ei0 − ed0)/(ec0 − ed0))^α must be positive (the barotropy factor fb's denominator): lower EXPONENT_ALPHA ({alpha}) or bring the void ratios closer"
            ));
        }
        if igs_mt > igs_mr {
            return refuse(format!(
                "IGS_MT ({igs_mt}) must not exceed IGS_MR ({igs_mr})"
            ));
        }
        if minimum_pressure >= maximum_pressure {
            return refuse(format!(
                "MINIMUM_PRESSURE ({minimum_pressure}) must be less than MAXIMUM_PRESSURE ({maximum_pressure})"
            ));
        }
        let densest = c.bauer(3.0 * maximum_pressure) * e_d0;
        if void_ratio < densest || void_ratio > e_i0 {
            return refuse(format!(
                "INITIAL_VOID_RATIO ({void_ratio}) lies outside the model's bounds at any pressure up to MAXIMUM_PRESSURE: from ed = {densest:.4} (the densest at {maximum_pressure} kPa) to ei0 = {e_i0} (the loosest at zero pressure)"
            ));
        }
        Ok(spec)
    }
}

impl LawDefinition for HypoplasticSpec {
    const NAME: &'static str = "hypoplasticity";
    const PARAMETERS: &'static [Parameter] = &PARAMETERS;
    type Law<R: Real> = Hypoplastic<R>;

    fn read(get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, ParameterError> {
        let v = PARAMETERS.map(|p| Self::need(get, p.key));
        let mut values = [0.0; 18];
        for (to, from) in values.iter_mut().zip(v) {
            *to = from?;
        }
        let [a, b, c, d, e, f, g, h, e0, r, mr, mt, br, chi, rho, tol, pmin, pmax] = values;
        Self::new(
            [a, b, c, d, e, f, g, h],
            e0,
            [r, mr, mt, br, chi, rho],
            tol,
            pmin,
            pmax,
        )
    }

    fn values(&self) -> Vec<f64> {
        vec![
            self.friction,
            self.hardness,
            self.exponent,
            self.e_d0,
            self.e_c0,
            self.e_i0,
            self.alpha,
            self.beta,
            self.void_ratio,
            self.igs_r,
            self.igs_mr,
            self.igs_mt,
            self.igs_beta_r,
            self.igs_chi,
            self.igs_initial,
            self.tolerance,
            self.minimum_pressure,
            self.maximum_pressure,
        ]
    }

    /// E and ν of an isotropic stiffness whose constrained modulus bounds the law's at
    /// `MAXIMUM_PRESSURE` (the densest state, e_d, where f_e is largest; m_R times L, plus
    /// N's largest share, f_d at e_i), with L's ratio of shear to constrained modulus.
    fn elastic(&self) -> (f64, f64) {
        let c = Constants::of(self);
        let (lambda, shear) = c.stiffest(3.0 * self.maximum_pressure);
        let young = shear * (3.0 * lambda + 2.0 * shear) / (lambda + shear);
        (young, lambda / (2.0 * (lambda + shear)))
    }

    fn state_len(&self) -> usize {
        STATE_LEN
    }

    fn build<R: Real>(&self) -> Hypoplastic<R> {
        Hypoplastic {
            c: Constants::of(self),
            precision: PhantomData,
        }
    }

    /// e0 between e_d and e_i at the point's pressure.
    fn check_start(&self, stress: &[f64; 6]) -> Result<(), ParameterError> {
        let c = Constants::of(self);
        let ps = -(stress[0] + stress[1] + stress[2]);
        let x = c.bauer(ps.max(0.0));
        let (ed, ei) = (self.e_d0 * x, self.e_i0 * x);
        let e = self.void_ratio;
        if e < ed || e > ei {
            return Err(ParameterError(format!(
                "its void ratio {e} lies outside the hypoplastic bounds at p' = {:.4} kPa: from ed = {ed:.4} to ei = {ei:.4}",
                ps / 3.0
            )));
        }
        Ok(())
    }

    fn examples() -> Vec<Self> {
        // Hochstetten sand (Herle & Gudehus 1999; the intergranular strain's usual constants).
        let sand = |void_ratio, igs_r, igs_initial| HypoplasticSpec {
            friction: 33.0,
            hardness: 1.0e6,
            exponent: 0.25,
            e_d0: 0.55,
            e_c0: 0.95,
            e_i0: 1.05,
            alpha: 0.25,
            beta: 1.5,
            void_ratio,
            igs_r,
            igs_mr: 5.0,
            igs_mt: 2.0,
            igs_beta_r: 0.5,
            igs_chi: 6.0,
            igs_initial,
            tolerance: 1e-4,
            minimum_pressure: 1.0,
            maximum_pressure: 2000.0,
        };
        // Dense and loose without intergranular strain; medium with it, from none and from a
        // mobilised one. (The suite's paths start near 390 kPa without and 1850 kPa with the
        // intergranular strain, where e_i is 0.87 and 0.80.)
        vec![
            sand(0.60, 0.0, 0.0),
            sand(0.82, 0.0, 0.0),
            sand(0.70, 1e-4, 0.0),
            sand(0.70, 1e-4, 1.0),
        ]
    }
}

/// State values per point: e, δ (six).
const STATE_LEN: usize = 7;
/// Where δ starts among the state values.
const DELTA: usize = 1;
/// Sub-steps at most in one increment, accepted and rejected.
const MOST_SUBSTEPS: u32 = 1000;
/// The smallest sub-step, as a fraction of the increment.
const SMALLEST_SUBSTEP: f64 = 1e-6;

/// The hypoplastic law in precision `R` (its arithmetic is f64 whatever `R` is).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hypoplastic<R: Real> {
    c: Constants,
    precision: PhantomData<R>,
}

/// The constants the rate uses.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Constants {
    a: f64,
    /// a².
    a2: f64,
    hardness: f64,
    exponent: f64,
    e_d0: f64,
    e_c0: f64,
    e_i0: f64,
    alpha: f64,
    beta: f64,
    /// (h_s / n)(e_i0 / e_c0)^β / (3 + a² − √3 a ((e_i0 − e_d0)/(e_c0 − e_d0))^α).
    fb: f64,
    /// M_c = 6 sin φ_c / (3 − sin φ_c).
    critical_ratio: f64,
    /// The powers n, α, β, χ and β_r.
    pow_n: Power,
    pow_alpha: Power,
    pow_beta: Power,
    pow_chi: Power,
    pow_beta_r: Power,
    void_ratio: f64,
    /// R (0: no intergranular strain), m_R, m_T, β_r, χ, ρ0.
    r: f64,
    mr: f64,
    mt: f64,
    beta_r: f64,
    chi: f64,
    rho0: f64,
    tolerance: f64,
    minimum_pressure: f64,
}

/// A point's state as the integration carries it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Point {
    /// The stress, tension positive (xx yy zz xy yz zx).
    t: [f64; 6],
    /// The intergranular strain.
    delta: [f64; 6],
    /// The void ratio.
    e: f64,
}

impl Point {
    /// `self + h · rate`.
    fn plus(&self, h: f64, rate: &Point) -> Point {
        Point {
            t: std::array::from_fn(|c| self.t[c] + h * rate.t[c]),
            delta: std::array::from_fn(|c| self.delta[c] + h * rate.delta[c]),
            e: self.e + h * rate.e,
        }
    }

    /// The combination Σ w_k y_k.
    fn combine(parts: &[(f64, &Point)]) -> Point {
        let mut out = Point {
            t: [0.0; 6],
            delta: [0.0; 6],
            e: 0.0,
        };
        for (w, y) in parts {
            for c in 0..6 {
                out.t[c] += w * y.t[c];
                out.delta[c] += w * y.delta[c];
            }
            out.e += w * y.e;
        }
        out
    }
}

/// x^e for a fixed exponent e: by multiplications and square roots where e is a multiple of
/// ¼ up to 16 (the published parameter sets' n = 0.25, α = 0.25, β = 1.5, χ = 6, β_r = 0.5:
/// a sixth of the general power's cost), exp(e ln x) otherwise.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Power {
    /// e = k / 4.
    Quarters(u32),
    /// Any other e.
    General(f64),
}

impl Power {
    fn of(e: f64) -> Self {
        let k = 4.0 * e;
        if k.fract() == 0.0 && (0.0..=64.0).contains(&k) {
            Power::Quarters(k as u32)
        } else {
            Power::General(e)
        }
    }

    /// x^e for x > 0.
    #[inline]
    fn of_positive(self, x: f64) -> f64 {
        match self {
            Power::Quarters(k) => {
                let whole = powi(x, k / 4);
                match k % 4 {
                    0 => whole,
                    2 => whole * x.sqrt(),
                    r => {
                        let q = x.sqrt().sqrt();
                        whole * if r == 1 { q } else { q * q * q }
                    }
                }
            }
            Power::General(e) => (e * x.ln()).exp(),
        }
    }
}

/// x^k by squaring.
#[inline]
fn powi(mut x: f64, mut k: u32) -> f64 {
    let mut out = 1.0;
    while k > 0 {
        if k & 1 == 1 {
            out *= x;
        }
        x *= x;
        k >>= 1;
    }
    out
}

/// A : B of two symmetric tensors (xx yy zz xy yz zx, tensor shear components).
fn dot(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + 2.0 * (a[3] * b[3] + a[4] * b[4] + a[5] * b[5])
}

/// The Frobenius norm.
fn norm(a: &[f64; 6]) -> f64 {
    dot(a, a).sqrt()
}

/// The determinant of a symmetric tensor.
fn det(a: &[f64; 6]) -> f64 {
    a[0] * (a[1] * a[2] - a[4] * a[4]) - a[3] * (a[3] * a[2] - a[4] * a[5])
        + a[5] * (a[3] * a[4] - a[1] * a[5])
}

impl Constants {
    fn of(s: &HypoplasticSpec) -> Self {
        let sin = s.friction.to_radians().sin();
        let a = 3f64.sqrt() * (3.0 - sin) / (2.0 * 2f64.sqrt() * sin);
        let ratio = ((s.e_i0 - s.e_d0) / (s.e_c0 - s.e_d0)).powf(s.alpha);
        let denominator = 3.0 + a * a - 3f64.sqrt() * a * ratio;
        Constants {
            a,
            a2: a * a,
            hardness: s.hardness,
            exponent: s.exponent,
            e_d0: s.e_d0,
            e_c0: s.e_c0,
            e_i0: s.e_i0,
            alpha: s.alpha,
            beta: s.beta,
            fb: s.hardness / s.exponent * (s.e_i0 / s.e_c0).powf(s.beta) / denominator,
            critical_ratio: 6.0 * sin / (3.0 - sin),
            pow_n: Power::of(s.exponent),
            pow_alpha: Power::of(s.alpha),
            pow_beta: Power::of(s.beta),
            pow_chi: Power::of(s.igs_chi),
            pow_beta_r: Power::of(s.igs_beta_r),
            void_ratio: s.void_ratio,
            r: s.igs_r,
            mr: s.igs_mr,
            mt: s.igs_mt,
            beta_r: s.igs_beta_r,
            chi: s.igs_chi,
            rho0: s.igs_initial,
            tolerance: s.tolerance,
            minimum_pressure: s.minimum_pressure,
        }
    }

    /// Bauer's factor exp(−(p_s / h_s)^n) at p_s = −tr T = 3p (> 0).
    fn bauer(&self, ps: f64) -> f64 {
        if ps <= 0.0 {
            return 1.0;
        }
        (-self.pow_n.of_positive(ps / self.hardness)).exp()
    }

    /// f_b f_e at p_s = 3p and void ratio `e`, with e_d, e_c there: (f_b f_e, e_d, e_c).
    fn factors(&self, ps: f64, e: f64) -> (f64, f64, f64) {
        let ratio = ps / self.hardness;
        let x = self.pow_n.of_positive(ratio);
        let bauer = (-x).exp();
        let (ei, ec, ed) = (self.e_i0 * bauer, self.e_c0 * bauer, self.e_d0 * bauer);
        // (p_s / h_s)^(1 − n) = (p_s / h_s) / x.
        let fb = self.fb * (1.0 + ei) / ei * ratio / x;
        (fb * self.pow_beta.of_positive(ec / e), ed, ec)
    }

    /// Lamé's λ and G of an isotropic stiffness bounding the law's stiffest response at
    /// p_s = 3p (see [`LawDefinition::elastic`]).
    fn stiffest(&self, ps: f64) -> (f64, f64) {
        let bauer = self.bauer(ps);
        let (fbfe, _, _) = self.factors(ps, self.e_d0 * bauer);
        let m = if self.r > 0.0 { self.mr } else { 1.0 };
        let fd = ((self.e_i0 - self.e_d0) / (self.e_c0 - self.e_d0)).powf(self.alpha);
        // L's shear 2G = 3 f_b f_e, its constrained modulus f_b f_e (3 + a²/3), N's axial
        // share a f_b f_e f_d.
        let shear = 1.5 * fbfe * m;
        let constrained = m * fbfe * (3.0 + self.a2 / 3.0) + self.a * fbfe * fd;
        (constrained - 2.0 * shear, shear)
    }

    /// The rate of the point's stress, intergranular strain and void ratio for the strain
    /// rate `d`, with Bauer's factor at the point; `None` outside the compressive stresses
    /// where the rate is defined.
    fn rate_at(&self, y: &Point, d: &[f64; 6]) -> Option<(Point, f64)> {
        let t = &y.t;
        let tr = t[0] + t[1] + t[2];
        if !(tr < 0.0) {
            return None;
        }
        let inv = 1.0 / tr;
        let th: [f64; 6] = t.map(|x| x * inv);
        let third = 1.0 / 3.0;
        let dev: [f64; 6] = std::array::from_fn(|c| if c < 3 { th[c] - third } else { th[c] });
        let thth = dot(&th, &th);
        let dev2 = dot(&dev, &dev);
        let t2 = 3.0 * dev2;
        let tan_psi = t2.sqrt();
        // tan ψ cos 3θ, with cos 3θ = −√6 tr(T̂*³) / ‖T̂*‖³ and tr(A³) = 3 det A for a
        // deviator: −9√2 det T̂* / ‖T̂*‖² (cos 3θ kept in [−1, 1]).
        let tan_cos = if dev2 > 1e-24 {
            (-9.0 * SQRT_2 * det(&dev) / dev2).clamp(-tan_psi, tan_psi)
        } else {
            -tan_psi
        };
        let denominator = 2.0 + SQRT_2 * tan_cos;
        if !(denominator > 1e-10) {
            return None;
        }
        let radicand = t2 / 8.0 + (2.0 - t2) / denominator;
        if !(radicand >= 0.0) {
            return None;
        }
        let f = radicand.sqrt() - tan_psi / (2.0 * SQRT_2);
        let (fbfe, ed, ec) = self.factors(-tr, y.e);
        let bauer = ed / self.e_d0;
        let fd = if y.e > ed {
            self.pow_alpha.of_positive((y.e - ed) / (ec - ed))
        } else {
            0.0
        };
        let c = fbfe / thth;
        let (cf2, ca2) = (c * f * f, c * self.a2);
        // L : X = c (F² X + a² T̂ (T̂ : X)); f_d N = c a F f_d (T̂ + T̂*).
        let l = |x: &[f64; 6]| -> [f64; 6] {
            let s = ca2 * dot(&th, x);
            std::array::from_fn(|k| cf2 * x[k] + s * th[k])
        };
        let n = c * self.a * f * fd;
        let nd: [f64; 6] = std::array::from_fn(|k| n * (th[k] + dev[k]));
        let ld = l(d);
        let e = (1.0 + y.e) * (d[0] + d[1] + d[2]);
        if self.r <= 0.0 {
            let size = norm(d);
            return Some((
                Point {
                    t: std::array::from_fn(|k| ld[k] + nd[k] * size),
                    delta: [0.0; 6],
                    e,
                },
                bauer,
            ));
        }
        let size = norm(&y.delta);
        if size == 0.0 {
            // ρ = 0: a reversal's stiffness, δ̊ = D.
            return Some((
                Point {
                    t: ld.map(|x| self.mr * x),
                    delta: *d,
                    e,
                },
                bauer,
            ));
        }
        let rho = (size / self.r).min(1.0);
        let hat: [f64; 6] = y.delta.map(|x| x * (1.0 / size));
        let along = dot(&hat, d);
        let rc = self.pow_chi.of_positive(rho);
        let mix = rc * self.mt + (1.0 - rc) * self.mr;
        let lh = l(&hat);
        if along > 0.0 {
            let rb = self.pow_beta_r.of_positive(rho);
            let w = rc * (1.0 - self.mt) * along;
            let wn = rc * along;
            Some((
                Point {
                    t: std::array::from_fn(|k| mix * ld[k] + w * lh[k] + wn * nd[k]),
                    delta: std::array::from_fn(|k| d[k] - rb * along * hat[k]),
                    e,
                },
                bauer,
            ))
        } else {
            let w = rc * (self.mr - self.mt) * along;
            Some((
                Point {
                    t: std::array::from_fn(|k| mix * ld[k] + w * lh[k]),
                    delta: *d,
                    e,
                },
                bauer,
            ))
        }
    }

    /// The point's state after its first update's setting: e0 and δ = ρ0 R along the stress.
    fn initial(&self, t: &[f64; 6]) -> Point {
        let size = norm(t);
        let delta = if self.r > 0.0 && size > 0.0 {
            t.map(|x| self.rho0 * self.r * x / size)
        } else {
            [0.0; 6]
        };
        Point {
            t: *t,
            delta,
            e: self.void_ratio,
        }
    }

    /// Integrates the increment `d` from `y`, the whole increment as the first sub-step.
    /// Where the integration cannot continue, the rest goes elastically
    /// ([`Constants::elastic`]).
    fn integrate(&self, y: &mut Point, d: &[f64; 6]) {
        if norm(d) == 0.0 {
            return;
        }
        if -(y.t[0] + y.t[1] + y.t[2]) < 3.0 * self.minimum_pressure {
            self.elastic(y, d);
            return;
        }
        let mut h = 1.0f64;
        let mut done = 0.0;
        for _ in 0..MOST_SUBSTEPS {
            h = h.min(1.0 - done);
            // The next sub-step's factor for a local error growing as h²: 0.9 √(TOL / error),
            // from the squares.
            let tol2 = self.tolerance * self.tolerance;
            let factor = |error2: f64| 0.9 * (tol2 / error2).sqrt().sqrt();
            match self.heun(y, d, h) {
                Some((next, error2, bauer)) if error2 <= tol2 => {
                    *y = next;
                    self.restore_bounds(y, bauer);
                    done += h;
                    if done >= 1.0 - 1e-12 {
                        return;
                    }
                    // (At most four times longer: roots only where they may say less.)
                    h *= if error2 * 400.0 <= tol2 {
                        4.0
                    } else {
                        factor(error2).clamp(0.25, 4.0)
                    };
                }
                Some((_, error2, _)) => h *= factor(error2).clamp(0.1, 0.5),
                None => h *= 0.25,
            }
            if h < SMALLEST_SUBSTEP {
                break;
            }
        }
        // The rest of the increment, elastically (the stress left the region where the rate
        // is defined, or the sub-steps would not end).
        let rest = (1.0 - done).max(0.0);
        self.elastic(y, &d.map(|x| x * rest));
    }

    /// One sub-step `h` of the increment `d` by the explicit Runge–Kutta pair of orders 1 and
    /// 2 (Euler and Heun's modified Euler, as Sloan 1987 integrates elastoplastic laws): the
    /// second-order state, the square of the relative error estimate (half the difference of
    /// the two stages' rates) and Bauer's factor at the sub-step's start; `None` where a stage
    /// leaves the rate's domain.
    fn heun(&self, y: &Point, d: &[f64; 6], h: f64) -> Option<(Point, f64, f64)> {
        let (k1, bauer) = self.rate_at(y, d)?;
        let (k2, _) = self.rate_at(&y.plus(h, &k1), d)?;
        let second = Point::combine(&[(1.0, y), (0.5 * h, &k1), (0.5 * h, &k2)]);
        // Second order minus first order (y + h k1).
        let gap = Point::combine(&[(0.5 * h, &k2), (-0.5 * h, &k1)]);
        // The squares: no roots where the error is small.
        let stress = dot(&gap.t, &gap.t) / dot(&second.t, &second.t).max(f64::MIN_POSITIVE);
        let igs = if self.r > 0.0 {
            dot(&gap.delta, &gap.delta) / (self.r * self.r)
        } else {
            0.0
        };
        let void = gap.e * gap.e / (second.e * second.e);
        let error2 = stress + igs + void;
        if !error2.is_finite() {
            return None;
        }
        Some((second, error2, bauer))
    }

    /// ‖δ‖ ≤ R and e_d ≤ e ≤ e_i for Bauer's factor `bauer` (the sub-step's start's: a
    /// bound to stay within, not a state to follow).
    fn restore_bounds(&self, y: &mut Point, bauer: f64) {
        if self.r > 0.0 {
            let size = norm(&y.delta);
            if size > self.r {
                let s = self.r / size;
                y.delta = y.delta.map(|x| x * s);
            }
        }
        y.e = y.e.clamp(self.e_d0 * bauer, self.e_i0 * bauer);
    }

    /// Lamé's λ and 2G of the isotropic small-strain stiffness at p_min and void ratio `e`
    /// (m_R L with intergranular strain, L without; e no denser than e_d there).
    fn low_stiffness(&self, e: f64) -> (f64, f64) {
        let ps = 3.0 * self.minimum_pressure;
        let e = e.max(self.e_d0 * self.bauer(ps));
        let (fbfe, _, _) = self.factors(ps, e);
        let m = if self.r > 0.0 { self.mr } else { 1.0 };
        (m * fbfe * self.a2 / 3.0, m * 3.0 * fbfe)
    }

    /// The elastic response below the minimum pressure: the isotropic small-strain stiffness
    /// at p_min (m_R L with intergranular strain, L without), the deviator capped at M_c p;
    /// in tension the stress-free state, the intergranular strain forgotten.
    fn elastic(&self, y: &mut Point, d: &[f64; 6]) {
        let (lambda, g2) = self.low_stiffness(y.e);
        let tr_d = d[0] + d[1] + d[2];
        for c in 0..6 {
            y.t[c] += g2 * d[c] + if c < 3 { lambda * tr_d } else { 0.0 };
        }
        y.e += (1.0 + y.e) * tr_d;
        let p = -(y.t[0] + y.t[1] + y.t[2]) / 3.0;
        if p <= 0.0 {
            y.t = [0.0; 6];
            y.delta = [0.0; 6];
            return;
        }
        let dev: [f64; 6] = std::array::from_fn(|c| if c < 3 { y.t[c] + p } else { y.t[c] });
        let q = (1.5 * dot(&dev, &dev)).sqrt();
        let cap = self.critical_ratio * p;
        if q > cap {
            let s = cap / q;
            y.t = std::array::from_fn(|c| dev[c] * s - if c < 3 { p } else { 0.0 });
        }
        self.restore_bounds(y, self.bauer(3.0 * p));
    }
}

impl<R: Real> Hypoplastic<R> {
    /// The point's state from its stress and state values (set if not set yet).
    fn point(&self, stress: &[R; 6], state: &[R]) -> Point {
        let t = stress.map(R::f64);
        if state[0].f64() > 0.0 {
            let delta = std::array::from_fn(|c| state[DELTA + c].f64());
            Point {
                t,
                delta,
                e: state[0].f64(),
            }
        } else {
            self.c.initial(&t)
        }
    }
}

impl<R: Real> ConstitutiveLaw<R> for Hypoplastic<R> {
    fn update(&self, stress: &mut [R; 6], de: &[R; 6], state: &mut [R]) {
        let mut y = self.point(stress, state);
        let e0 = y.e;
        self.c.integrate(&mut y, &de.map(R::f64));
        *stress = y.t.map(R::of);
        // e0 + Δe rather than e: a step without strain keeps e's bits.
        state[0] = R::of(e0 + (y.e - e0));
        for c in 0..6 {
            state[DELTA + c] = R::of(y.delta[c]);
        }
    }

    fn yield_function(&self, _stress: &[R; 6], _state: &[R]) -> Option<R> {
        None
    }

    fn stress_rate(&self, stress: &[R; 6], state: &[R], d: &[f64; 6]) -> Option<[f64; 6]> {
        let y = self.point(stress, state);
        if -(y.t[0] + y.t[1] + y.t[2]) < 3.0 * self.c.minimum_pressure {
            let (lambda, g2) = self.c.low_stiffness(y.e);
            let tr = d[0] + d[1] + d[2];
            return Some(std::array::from_fn(|c| {
                g2 * d[c] + if c < 3 { lambda * tr } else { 0.0 }
            }));
        }
        self.c.rate_at(&y, d).map(|r| r.0.t)
    }

    fn state_tensors(&self) -> &'static [usize] {
        &[DELTA]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hochstetten sand (Herle & Gudehus 1999) with the usual intergranular strain constants
    /// (`igs_r` 1e-4 or 0), e0 `e0`, tolerance `tol`.
    pub(crate) fn hochstetten(e0: f64, igs_r: f64, tol: f64) -> HypoplasticSpec {
        HypoplasticSpec::new(
            [33.0, 1.0e6, 0.25, 0.55, 0.95, 1.05, 0.25, 1.5],
            e0,
            [igs_r, 5.0, 2.0, 0.5, 6.0, 0.0],
            tol,
            1.0,
            5000.0,
        )
        .unwrap()
    }

    /// The isotropic strain increment `ev / 3` in each direction.
    fn isotropic(ev: f64) -> [f64; 6] {
        [ev / 3.0, ev / 3.0, ev / 3.0, 0.0, 0.0, 0.0]
    }

    #[test]
    fn powers_by_quarters_agree_with_the_general_power() {
        for e in [0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.25, 6.0, 0.13, 1.05, 5.5] {
            let p = Power::of(e);
            assert_eq!(matches!(p, Power::Quarters(_)), (4.0 * e).fract() == 0.0);
            for x in [1e-6, 0.3, 1.0, 2.7, 1e3] {
                let (got, want) = (p.of_positive(x), x.powf(e));
                assert!((got / want - 1.0).abs() < 1e-14, "{x}^{e}: {got} {want}");
            }
        }
    }

    #[test]
    fn isotropic_compression_from_the_loosest_state_stays_on_it() {
        // e_i(p) solves the isotropic compression: from e = e_i(p0), e = e_i(p), and with
        // (1 + e) = (1 + e0) exp(ε_v) the pressure follows from the strain alone.
        let p0 = 10.0;
        let c = Constants::of(&hochstetten(0.9, 0.0, 1e-6));
        let e0 = 1.05 * c.bauer(3.0 * p0);
        let law = HypoplasticSpec {
            void_ratio: e0,
            ..hochstetten(0.9, 0.0, 1e-6)
        }
        .build::<f64>();
        let mut s = [-p0, -p0, -p0, 0.0, 0.0, 0.0];
        let mut state = [0.0; STATE_LEN];
        let (step, steps) = (-1e-3, 60);
        for _ in 0..steps {
            law.update(&mut s, &isotropic(step), &mut state);
        }
        let e = (1.0 + e0) * (step * steps as f64).exp() - 1.0;
        let want = 1e6 / 3.0 * (-(e / 1.05).ln()).powf(4.0);
        let p = -s[0];
        assert!(p > 500.0, "{p}");
        assert!(
            (p / want - 1.0).abs() < 1e-6,
            "p {p}, from the strain {want}"
        );
        assert!((state[0] / e - 1.0).abs() < 1e-9, "{} {e}", state[0]);
    }

    /// The OpenSees manual's worked example of the soilmodels.com UMAT (Hochstetten sand with
    /// intergranular strain, e0 0.70, isotropic 100 kPa, δ0 = 0): 50 oedometric increments
    /// of −1e-4, then one of +1e-4. (σ_axial, loading stiffness of the last increment, the
    /// first unloading stiffness), kPa.
    fn opensees_example(tol: f64) -> (f64, f64, f64) {
        let law = HypoplasticSpec {
            maximum_pressure: 1000.0,
            ..hochstetten(0.70, 1e-4, tol)
        }
        .build::<f64>();
        let mut s = [-100.0, -100.0, -100.0, 0.0, 0.0, 0.0];
        let mut state = [0.0; STATE_LEN];
        let mut before = s[0];
        for _ in 0..50 {
            before = s[0];
            law.update(&mut s, &[-1e-4, 0.0, 0.0, 0.0, 0.0, 0.0], &mut state);
        }
        let loading = (s[0] - before) / -1e-4;
        let top = s[0];
        law.update(&mut s, &[1e-4, 0.0, 0.0, 0.0, 0.0, 0.0], &mut state);
        (-top, loading, (s[0] - top) / 1e-4)
    }

    #[test]
    fn the_opensees_worked_example_is_reproduced() {
        for tol in [1e-3, 1e-4, 1e-5, 1e-6] {
            let (sigma, loading, unloading) = opensees_example(tol);
            println!("tol {tol:e}: σ {sigma:.2} kPa, loading {loading:.0} kPa, unloading {unloading:.0} kPa");
        }
        let (sigma, loading, unloading) = opensees_example(1e-5);
        // The UMAT's published outputs, as printed: 294.3, 29080, 316559 kPa.
        assert!((sigma / 294.3 - 1.0).abs() < 5e-4, "{sigma}");
        assert!((loading / 29080.0 - 1.0).abs() < 5e-4, "{loading}");
        assert!((unloading / 316559.0 - 1.0).abs() < 5e-4, "{unloading}");
    }
}
