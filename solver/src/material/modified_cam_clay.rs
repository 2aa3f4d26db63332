//! Modified Cam Clay (Roscoe & Burland 1968; Anura3D's `modified_cam_clay`): the critical-state
//! model of clay. Effective stresses, compression positive in the equations below (the code's
//! stresses are tension positive), p the mean stress and q = √(3 J2) the deviator:
//!
//! - yield surface, an ellipse through the origin and the preconsolidation pressure p_c:
//!   f = q² / M² + p (p − p_c) = 0; [`ConstitutiveLaw::yield_function`] gives it in kPa as
//!   p_eq − p_c, with p_eq = p + q² / (M² p);
//! - associated flow: dε_v^p = dλ (2p − p_c), dε_q^p = dλ 2q / M²;
//! - hardening with the plastic volumetric strain: dp_c / p_c = v dε_v^p / (λ − κ), v = 1 + e;
//! - pressure-dependent elasticity, the swelling line e = e_κ − κ ln p: the bulk modulus
//!   K = v max(p, p_min) / κ (integrated exactly within a step: p grows exponentially with the
//!   elastic volumetric strain, linearly below p_min so that a stress-free point has a
//!   stiffness), and the shear modulus either constant or G = 3 K (1 − 2ν) / (2 (1 + ν)).
//!
//! The return is backward Euler (closest point in the elastic metric): the deviator keeps the
//! trial's direction, and two equations in the plastic multiplier and the plastic volumetric
//! strain are solved by Newton's method in f64 whatever the run's precision. A strain increment
//! larger than a tenth of κ / v is cut into sub-steps, and a sub-step whose Newton iteration does
//! not converge is cut in halves again (up to 256 in all), so the update's accuracy does not
//! depend on the step the solver takes.
//!
//! The point's state is p_c and e. Both start at zero, which the first update reads as "not
//! set": it sets e = e0 and p_c from the stress the point has then (after K0 or a uniform
//! initial stress) as OCR p_eq, or the given p_c0 (at least p_eq), as Anura3D sets p_c at its
//! first step. OCR here is isotropic (Wood's R_p = p_c0 / p_eq0).
//!
//! The time step needs the stiffest state, which depends on the stress the run reaches: the
//! law's [`LawDefinition::elastic`] constants are those at `MAXIMUM_PRESSURE` (and e0).
//! A point in tension (p ≤ 0 after the elastic trial) goes to the apex, the stress-free state.

use std::marker::PhantomData;

use crate::material::definition::{
    check_each, Bound, ConstitutiveLaw, LawDefinition, Parameter, ParameterError,
};
use crate::material::linear_elastic::ELASTIC_PARAMETERS;
use crate::real::Real;

/// Modified Cam Clay's parameters, checked by [`ModifiedCamClaySpec::new`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModifiedCamClaySpec {
    /// Poisson's ratio ν (the shear modulus's ratio to K, unless `shear_modulus` is given).
    pub poisson: f64,
    /// A constant shear modulus G (kPa); 0: G from ν and the current bulk modulus.
    pub shear_modulus: f64,
    /// Slope λ of the normal compression line in e–ln p.
    pub lambda: f64,
    /// Slope κ of the swelling lines in e–ln p (less than λ).
    pub kappa: f64,
    /// Slope M of the critical state line in p–q.
    pub slope: f64,
    /// Void ratio e0 at the start; 0: from `ncl_intercept`.
    pub void_ratio: f64,
    /// N, the specific volume on the normal compression line at p = 1 kPa; 0: e0 given.
    pub ncl_intercept: f64,
    /// Isotropic over-consolidation ratio p_c0 / p_eq0 (1: normally consolidated).
    pub ocr: f64,
    /// The preconsolidation pressure p_c0 itself (kPa); 0: from `ocr`.
    pub preconsolidation: f64,
    /// The bulk modulus below this mean stress is that at it (kPa).
    pub minimum_pressure: f64,
    /// The largest mean effective stress the run reaches (kPa): the time step's stiffness.
    pub maximum_pressure: f64,
}

const POSITIVE: (Bound, Bound) = (Bound::Open(0.0), Bound::Open(f64::INFINITY));

const PARAMETERS: [Parameter; 11] = [
    ELASTIC_PARAMETERS[1],
    Parameter::new(
        "SHEAR_MODULUS",
        "kPa",
        "a constant shear modulus G; 0: G = 3K(1 − 2ν)/(2(1 + ν)) from the current bulk modulus",
    )
    .range(Bound::Closed(0.0), Bound::Open(f64::INFINITY))
    .with_default(0.0),
    Parameter::new(
        "LAMBDA",
        "",
        "slope λ of the normal compression line in e–ln p'",
    )
    .range(POSITIVE.0, POSITIVE.1),
    Parameter::new(
        "KAPPA",
        "",
        "slope κ of the swelling lines in e–ln p', less than λ",
    )
    .range(POSITIVE.0, POSITIVE.1),
    Parameter::new(
        "CRITICAL_STATE_SLOPE",
        "",
        "slope M of the critical state line in p'–q",
    )
    .range(Bound::Open(0.0), Bound::Open(3.0)),
    Parameter::new(
        "INITIAL_VOID_RATIO",
        "",
        "void ratio e0 at the start, the same at every point; 0: from NCL_INTERCEPT",
    )
    .range(Bound::Closed(0.0), Bound::Open(f64::INFINITY))
    .with_default(0.0),
    Parameter::new(
        "NCL_INTERCEPT",
        "",
        "N, the specific volume 1 + e on the normal compression line at p' = 1 kPa: each point's e0 from its stress and p'c0 (v = N − λ ln p'c0 + κ ln(p'c0/p'eq0)); 0: e0 given",
    )
    .range(Bound::Closed(0.0), Bound::Open(f64::INFINITY))
    .with_default(0.0),
    Parameter::new(
        "OCR",
        "",
        "isotropic over-consolidation ratio p'c0 / p'eq0 of the initial stress",
    )
    .range(Bound::Closed(1.0), Bound::Open(f64::INFINITY))
    .with_default(1.0),
    Parameter::new(
        "PRECONSOLIDATION_PRESSURE",
        "kPa",
        "the preconsolidation pressure p'c0 itself (at least p'eq0); 0: from OCR",
    )
    .range(Bound::Closed(0.0), Bound::Open(f64::INFINITY))
    .with_default(0.0),
    Parameter::new(
        "MINIMUM_PRESSURE",
        "kPa",
        "below this p' the bulk modulus stays that at it (a stress-free point's stiffness)",
    )
    .range(POSITIVE.0, POSITIVE.1)
    .with_default(1.0),
    Parameter::new(
        "MAXIMUM_PRESSURE",
        "kPa",
        "the largest p' the run reaches: the time step takes the stiffness there",
    )
    .range(POSITIVE.0, POSITIVE.1),
];

impl ModifiedCamClaySpec {
    /// Checked: each value in its range ([`LawDefinition::PARAMETERS`]), κ < λ, exactly one of
    /// e0 and N, N above 1 + λ ln p_max (a positive void ratio on the normal compression line
    /// up to p_max), not both an OCR above 1 and a p_c0, and p_min < p_max.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        poisson: f64,
        shear_modulus: f64,
        lambda: f64,
        kappa: f64,
        slope: f64,
        void_ratio: f64,
        ncl_intercept: f64,
        ocr: f64,
        preconsolidation: f64,
        minimum_pressure: f64,
        maximum_pressure: f64,
    ) -> Result<Self, ParameterError> {
        let spec = ModifiedCamClaySpec {
            poisson,
            shear_modulus,
            lambda,
            kappa,
            slope,
            void_ratio,
            ncl_intercept,
            ocr,
            preconsolidation,
            minimum_pressure,
            maximum_pressure,
        };
        check_each(&PARAMETERS, &spec.values())?;
        if kappa >= lambda {
            return Err(ParameterError(format!(
                "KAPPA must be less than LAMBDA ({lambda}), got {kappa}"
            )));
        }
        if (void_ratio > 0.0) == (ncl_intercept > 0.0) {
            return Err(ParameterError(format!(
                "give INITIAL_VOID_RATIO ({void_ratio}) or NCL_INTERCEPT ({ncl_intercept}): exactly one of them, not 0"
            )));
        }
        let lowest = 1.0 + lambda * maximum_pressure.ln();
        if ncl_intercept > 0.0 && ncl_intercept <= lowest {
            return Err(ParameterError(format!(
                "NCL_INTERCEPT ({ncl_intercept}) must exceed 1 + λ ln MAXIMUM_PRESSURE ({lowest}): the void ratio on the normal compression line at p'max"
            )));
        }
        if ocr > 1.0 && preconsolidation > 0.0 {
            return Err(ParameterError(format!(
                "give OCR ({ocr}) or PRECONSOLIDATION_PRESSURE ({preconsolidation}), not both"
            )));
        }
        if minimum_pressure >= maximum_pressure {
            return Err(ParameterError(format!(
                "MINIMUM_PRESSURE ({minimum_pressure}) must be less than MAXIMUM_PRESSURE ({maximum_pressure})"
            )));
        }
        Ok(spec)
    }
}

impl LawDefinition for ModifiedCamClaySpec {
    const NAME: &'static str = "modified_cam_clay";
    const PARAMETERS: &'static [Parameter] = &PARAMETERS;
    type Law<R: Real> = ModifiedCamClay<R>;

    fn read(get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, ParameterError> {
        let [nu, g, lambda, kappa, m, e0, big_n, ocr, pc, pmin, pmax] =
            PARAMETERS.map(|p| Self::need(get, p.key));
        Self::new(
            nu?, g?, lambda?, kappa?, m?, e0?, big_n?, ocr?, pc?, pmin?, pmax?,
        )
    }

    fn values(&self) -> Vec<f64> {
        vec![
            self.poisson,
            self.shear_modulus,
            self.lambda,
            self.kappa,
            self.slope,
            self.void_ratio,
            self.ncl_intercept,
            self.ocr,
            self.preconsolidation,
            self.minimum_pressure,
            self.maximum_pressure,
        ]
    }

    /// E and ν at `MAXIMUM_PRESSURE` and e0: K = (1 + e0) p_max / κ with the shear modulus
    /// (with N instead of e0, v = N: no point is looser than that at p ≥ 1 kPa on the normal
    /// compression line, and an over-consolidated one only by κ ln OCR).
    fn elastic(&self) -> (f64, f64) {
        let law = self.build::<f64>();
        let v = if self.void_ratio > 0.0 {
            1.0 + self.void_ratio
        } else {
            self.ncl_intercept
        };
        let k = law.c.bulk(self.maximum_pressure, v);
        let g = law.c.shear(k);
        let young = 9.0 * k * g / (3.0 * k + g);
        (young, (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g)))
    }

    fn state_len(&self) -> usize {
        2
    }

    fn build<R: Real>(&self) -> ModifiedCamClay<R> {
        ModifiedCamClay {
            c: Constants {
                shear_ratio: 3.0 * (1.0 - 2.0 * self.poisson) / (2.0 * (1.0 + self.poisson)),
                shear_modulus: self.shear_modulus,
                lambda: self.lambda,
                kappa: self.kappa,
                slope2: self.slope * self.slope,
                void_ratio: self.void_ratio,
                ncl_intercept: self.ncl_intercept,
                ocr: self.ocr,
                preconsolidation: self.preconsolidation,
                minimum_pressure: self.minimum_pressure,
            },
            precision: PhantomData,
        }
    }

    fn examples() -> Vec<Self> {
        let law = |shear_modulus, ocr, preconsolidation| ModifiedCamClaySpec {
            poisson: 0.3,
            shear_modulus,
            lambda: 0.2,
            kappa: 0.04,
            slope: 1.0,
            void_ratio: 1.2,
            ncl_intercept: 0.0,
            ocr,
            preconsolidation,
            minimum_pressure: 1.0,
            maximum_pressure: 2000.0,
        };
        // The suite starts near p = 130 kPa (E / 1000 at p_max): lightly over-consolidated
        // (wet side), normally consolidated with a constant G, heavily over-consolidated
        // (dry side, softening).
        // The last with N instead of e0.
        let from_n = ModifiedCamClaySpec {
            void_ratio: 0.0,
            ncl_intercept: 3.3,
            ..law(0.0, 1.2, 0.0)
        };
        vec![
            law(0.0, 1.5, 0.0),
            law(3000.0, 1.0, 0.0),
            law(0.0, 1.0, 700.0),
            from_n,
        ]
    }
}

/// Modified Cam Clay in precision `R` (its arithmetic is f64 whatever `R` is).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModifiedCamClay<R: Real> {
    c: Constants,
    precision: PhantomData<R>,
}

/// The constants the update uses.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Constants {
    /// G / K from ν: 3 (1 − 2ν) / (2 (1 + ν)).
    shear_ratio: f64,
    /// A constant G (kPa), or 0.
    shear_modulus: f64,
    lambda: f64,
    kappa: f64,
    /// M².
    slope2: f64,
    void_ratio: f64,
    ncl_intercept: f64,
    ocr: f64,
    preconsolidation: f64,
    minimum_pressure: f64,
}

/// Sub-steps at most in one update.
const MOST_SUBSTEPS: u32 = 256;
/// A sub-step's strain at most, as a fraction of κ / v.
const SUBSTEP_STRAIN: f64 = 0.1;
/// Newton iterations at most in one return.
const NEWTON_ITERATIONS: usize = 60;

/// A point's stress as the update works with it: the mean stress p (compression positive) and
/// the deviator (tension positive, tensor shear components).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Stress {
    p: f64,
    dev: [f64; 6],
}

impl Stress {
    /// The stress-free apex of the yield surface.
    const APEX: Stress = Stress {
        p: 0.0,
        dev: [0.0; 6],
    };

    /// Of a stress, tension positive (xx yy zz xy yz zx).
    fn of(s: &[f64; 6]) -> Self {
        let p = -(s[0] + s[1] + s[2]) / 3.0;
        Stress {
            p,
            dev: std::array::from_fn(|c| if c < 3 { s[c] + p } else { s[c] }),
        }
    }

    /// The stress, tension positive.
    fn tensor(&self) -> [f64; 6] {
        std::array::from_fn(|c| {
            if c < 3 {
                self.dev[c] - self.p
            } else {
                self.dev[c]
            }
        })
    }

    /// q = √(3/2 s:s).
    fn q(&self) -> f64 {
        equivalent(&self.dev, 1.5)
    }
}

/// √(factor d:d) of a deviator (its shear components counted twice).
fn equivalent(d: &[f64; 6], factor: f64) -> f64 {
    let n: f64 = d[..3].iter().map(|x| x * x).sum();
    let t: f64 = d[3..].iter().map(|x| x * x).sum();
    (factor * (n + 2.0 * t)).sqrt()
}

impl Constants {
    /// The bulk modulus at mean stress `p` and specific volume `v` (kPa).
    fn bulk(&self, p: f64, v: f64) -> f64 {
        v * p.max(self.minimum_pressure) / self.kappa
    }

    /// The shear modulus with bulk modulus `k` (kPa).
    fn shear(&self, k: f64) -> f64 {
        if self.shear_modulus > 0.0 {
            self.shear_modulus
        } else {
            self.shear_ratio * k
        }
    }

    /// The mean stress after the elastic volumetric strain `ev` (compression positive) from
    /// `p`, at specific volume `v`: dp = K(p) dε exactly.
    fn elastic_p(&self, p: f64, ev: f64, v: f64) -> f64 {
        let pm = self.minimum_pressure;
        let k = self.kappa / v;
        if p >= pm {
            let x = p * (ev / k).exp();
            if x >= pm {
                return x;
            }
        }
        // Through p_min: the strain coordinate of p measured from p_min.
        let from = if p >= pm {
            k * (p / pm).ln()
        } else {
            k * (p - pm) / pm
        };
        let to = from + ev;
        if to >= 0.0 {
            pm * (to / k).exp()
        } else {
            pm + pm * to / k
        }
    }

    /// p_c and e of a point whose state is not set yet, at stress `s`.
    fn initial(&self, s: &Stress) -> (f64, f64) {
        let p = s.p.max(self.minimum_pressure);
        let q = s.q();
        let equivalent = p + q * q / (self.slope2 * p);
        let pc = if self.preconsolidation > 0.0 {
            self.preconsolidation.max(equivalent)
        } else {
            self.ocr * equivalent
        };
        let e = if self.void_ratio > 0.0 {
            self.void_ratio
        } else {
            // On the normal compression line at p_c, then back along the swelling line to p.
            self.ncl_intercept - self.lambda * pc.ln() + self.kappa * (pc / p).ln() - 1.0
        };
        (pc, e)
    }

    /// The update of `s`, `pc` and `v` by the strain increment's volumetric part `ev`
    /// (compression positive) and deviator `dd`, in sub-steps.
    fn update(&self, s: &mut Stress, pc: &mut f64, v: &mut f64, ev: f64, dd: &[f64; 6]) {
        let size = ev.abs().max(equivalent(dd, 2.0 / 3.0));
        let wanted = (size * *v / (SUBSTEP_STRAIN * self.kappa)).ceil();
        let mut n = if wanted >= 1.0 {
            (wanted.min(MOST_SUBSTEPS as f64)) as u32
        } else {
            1
        };
        loop {
            if let Some(done) = self.substeps(*s, *pc, *v, ev, dd, n) {
                (*s, *pc, *v) = done;
                return;
            }
            if n >= MOST_SUBSTEPS {
                break;
            }
            n = (2 * n).min(MOST_SUBSTEPS);
        }
        // No return converged even in the finest sub-steps: the elastic trial of the whole
        // increment, brought onto the surface at its own p (kept for robustness; the
        // conformance suite's paths and the element tests never come here).
        self.elastic_trial(s, v, ev, dd);
        if s.p > 0.0 {
            let p = s.p.min(*pc);
            let q = (self.slope2 * p * (*pc - p)).max(0.0).sqrt();
            let q_trial = s.q();
            let scale = if q_trial > q { q / q_trial } else { 1.0 };
            s.p = p;
            s.dev = s.dev.map(|x| x * scale);
        } else {
            *s = Stress::APEX;
        }
    }

    /// The increment in `n` equal sub-steps from (`s`, `pc`, `v`); `None` if a return fails.
    fn substeps(
        &self,
        mut s: Stress,
        mut pc: f64,
        mut v: f64,
        ev: f64,
        dd: &[f64; 6],
        n: u32,
    ) -> Option<(Stress, f64, f64)> {
        let f = 1.0 / n as f64;
        let (ev, dd) = (ev * f, dd.map(|x| x * f));
        for _ in 0..n {
            self.substep(&mut s, &mut pc, &mut v, ev, &dd)?;
        }
        Some((s, pc, v))
    }

    /// The elastic trial of (`ev`, `dd`) from `s` at specific volume `v`, then `v` updated.
    fn elastic_trial(&self, s: &mut Stress, v: &mut f64, ev: f64, dd: &[f64; 6]) -> f64 {
        let g2 = 2.0 * self.shear(self.bulk(s.p, *v));
        let shear = g2 / 2.0;
        s.p = self.elastic_p(s.p, ev, *v);
        s.dev = std::array::from_fn(|c| s.dev[c] + g2 * dd[c]);
        *v *= (-ev).exp();
        shear
    }

    /// One sub-step: the elastic trial, and the return where it lies beyond the surface.
    fn substep(
        &self,
        s: &mut Stress,
        pc: &mut f64,
        v: &mut f64,
        ev: f64,
        dd: &[f64; 6],
    ) -> Option<()> {
        let (p0, v0) = (s.p, *v);
        let mut trial = *s;
        let shear = self.elastic_trial(&mut trial, v, ev, dd);
        if trial.p <= 0.0 {
            // Tension: a soil without cohesion falls apart, to the stress-free apex.
            *s = Stress::APEX;
            return Some(());
        }
        let q_trial = trial.q();
        if q_trial * q_trial / self.slope2 + trial.p * (trial.p - *pc) <= 0.0 {
            *s = trial;
            return Some(());
        }
        let (p, q, pc_new) = self.return_map(p0, v0, ev, q_trial, shear, *pc)?;
        let scale = if q_trial > 0.0 { q / q_trial } else { 0.0 };
        *s = Stress {
            p,
            dev: trial.dev.map(|x| x * scale),
        };
        *pc = pc_new;
        Some(())
    }

    /// Backward Euler's return from the trial (`q_trial`; p from `p0` by `ev` at `v`), with
    /// shear modulus `shear` and preconsolidation `pc0`: Newton's method on the plastic
    /// volumetric strain x and the multiplier dλ,
    ///   x − dλ (2p − p_c) = 0,  (q² / M² + p (p − p_c)) / p_c0² = 0,
    /// with p(x) the elastic p of ev − x, p_c(x) = p_c0 exp(v x / (λ − κ)) and
    /// q(dλ) = q_trial / (1 + 6 G dλ / M²). (p, q, p_c) when it converges.
    fn return_map(
        &self,
        p0: f64,
        v: f64,
        ev: f64,
        q_trial: f64,
        shear: f64,
        pc0: f64,
    ) -> Option<(f64, f64, f64)> {
        let hardening = v / (self.lambda - self.kappa);
        let g = 6.0 * shear / self.slope2;
        let scale = 1.0 / (pc0 * pc0);
        let (mut x, mut dl) = (0.0f64, 0.0f64);
        for _ in 0..NEWTON_ITERATIONS {
            let p = self.elastic_p(p0, ev - x, v);
            let pc = pc0 * (hardening * x).exp();
            let q = q_trial / (1.0 + g * dl);
            if !(p > 0.0 && pc.is_finite() && q.is_finite()) {
                return None;
            }
            let r1 = x - dl * (2.0 * p - pc);
            let r2 = (q * q / self.slope2 + p * (p - pc)) * scale;
            if r1.abs() <= 1e-15 * (1.0 + ev.abs()) && r2.abs() <= 1e-14 {
                return Some((p, q, pc));
            }
            let p_x = -self.bulk(p, v);
            let pc_x = pc * hardening;
            let q_l = -q * g / (1.0 + g * dl);
            let j11 = 1.0 - dl * (2.0 * p_x - pc_x);
            let j12 = -(2.0 * p - pc);
            let j21 = ((2.0 * p - pc) * p_x - p * pc_x) * scale;
            let j22 = 2.0 * q * q_l / self.slope2 * scale;
            let det = j11 * j22 - j12 * j21;
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            x += (-r1 * j22 + r2 * j12) / det;
            dl += (-r2 * j11 + r1 * j21) / det;
            if dl < 0.0 {
                dl = 0.0;
            }
        }
        None
    }

    /// The yield function p_eq − p_c (kPa) at `s` for preconsolidation `pc`; in tension,
    /// q / M − p, zero only at the apex.
    fn yield_at(&self, s: &Stress, pc: f64) -> f64 {
        let q = s.q();
        if s.p > 0.0 {
            s.p + q * q / (self.slope2 * s.p) - pc
        } else {
            q / self.slope2.sqrt() - s.p
        }
    }
}

impl<R: Real> ModifiedCamClay<R> {
    /// The point's p_c and e from its `state`, set from `s` if not set yet.
    fn state_at(&self, s: &Stress, state: &[R]) -> (f64, f64) {
        let (pc, e) = (state[0].f64(), state[1].f64());
        if pc > 0.0 {
            (pc, e)
        } else {
            self.c.initial(s)
        }
    }
}

impl<R: Real> ConstitutiveLaw<R> for ModifiedCamClay<R> {
    fn update(&self, stress: &mut [R; 6], de: &[R; 6], state: &mut [R]) {
        let mut s = Stress::of(&stress.map(R::f64));
        let (mut pc, e) = self.state_at(&s, state);
        let mut v = 1.0 + e;
        let de = de.map(R::f64);
        let ev = -(de[0] + de[1] + de[2]);
        let dd: [f64; 6] = std::array::from_fn(|c| if c < 3 { de[c] + ev / 3.0 } else { de[c] });
        self.c.update(&mut s, &mut pc, &mut v, ev, &dd);
        *stress = s.tensor().map(R::of);
        state[0] = R::of(pc);
        // e + Δv rather than v − 1: a step without strain keeps e's bits.
        state[1] = R::of(e + (v - (1.0 + e)));
    }

    fn yield_function(&self, stress: &[R; 6], state: &[R]) -> Option<R> {
        let s = Stress::of(&stress.map(R::f64));
        let (pc, _) = self.state_at(&s, state);
        Some(R::of(self.c.yield_at(&s, pc)))
    }

    fn elastic_tangent(&self, stress: &[R; 6], state: &[R]) -> Option<(f64, f64)> {
        let s = Stress::of(&stress.map(R::f64));
        let (_, e) = self.state_at(&s, state);
        let k = self.c.bulk(s.p, 1.0 + e);
        Some((k, self.c.shear(k)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clay(ocr: f64) -> ModifiedCamClaySpec {
        ModifiedCamClaySpec::new(0.3, 0.0, 0.2, 0.04, 1.0, 1.2, 0.0, ocr, 0.0, 1.0, 2000.0).unwrap()
    }

    #[test]
    fn parameters_are_checked_together() {
        let e = |r: Result<ModifiedCamClaySpec, ParameterError>| r.unwrap_err().0;
        assert!(e(ModifiedCamClaySpec::new(
            0.3, 0.0, 0.2, 0.2, 1.0, 1.2, 0.0, 1.0, 0.0, 1.0, 2000.0
        ))
        .contains("KAPPA must be less than LAMBDA"));
        assert!(e(ModifiedCamClaySpec::new(
            0.3, 0.0, 0.2, 0.04, 1.0, 1.2, 0.0, 2.0, 300.0, 1.0, 2000.0
        ))
        .contains("not both"));
        assert!(e(ModifiedCamClaySpec::new(
            0.3, 0.0, 0.2, 0.04, 1.0, 1.2, 0.0, 1.0, 0.0, 3000.0, 2000.0
        ))
        .contains("MINIMUM_PRESSURE"));
        let m = e(ModifiedCamClaySpec::new(
            0.3, 0.0, 0.2, 0.04, 3.5, 1.2, 0.0, 1.0, 0.0, 1.0, 2000.0,
        ));
        assert!(
            m.contains("CRITICAL_STATE_SLOPE") && m.contains("(0, 3)"),
            "{m}"
        );
    }

    #[test]
    fn the_time_step_stiffness_is_that_at_the_maximum_pressure() {
        let (young, poisson) = clay(1.0).elastic();
        let k = 2.2 * 2000.0 / 0.04;
        assert!((young / (3.0 * (1.0 - 2.0 * poisson)) / k - 1.0).abs() < 1e-12);
        assert!((poisson - 0.3).abs() < 1e-12);
    }

    #[test]
    fn the_first_update_sets_the_state_from_the_stress() {
        let law = clay(2.0).build::<f64>();
        let mut s = [-100.0, -100.0, -100.0, 0.0, 0.0, 0.0];
        let mut state = [0.0, 0.0];
        law.update(&mut s, &[0.0; 6], &mut state);
        assert_eq!(state, [200.0, 1.2]);
        assert!(s
            .iter()
            .zip([-100.0, -100.0, -100.0, 0.0, 0.0, 0.0])
            .all(|(a, b)| (a - b).abs() < 1e-12));
        // Stress-free: p_c from p_min.
        let (mut s, mut state) = ([0.0; 6], [0.0, 0.0]);
        law.update(&mut s, &[-1e-4, 0.0, 0.0, 0.0, 0.0, 0.0], &mut state);
        assert_eq!(state[0], 2.0);
        assert!(s[0] < 0.0);
    }

    #[test]
    fn isotropic_compression_follows_the_normal_compression_line() {
        // Normally consolidated, compressed isotropically: p_c = p, and
        // Δe = −λ ln(p1 / p0) along the NCL (v taken as ln-strain: v = v0 exp(−ε_v)).
        let law = clay(1.0).build::<f64>();
        let mut s = [-100.0, -100.0, -100.0, 0.0, 0.0, 0.0];
        let mut state = [0.0, 0.0];
        for _ in 0..1000 {
            law.update(&mut s, &[-1e-4, -1e-4, -1e-4, 0.0, 0.0, 0.0], &mut state);
        }
        let p = -s[0];
        assert!((state[0] - p).abs() < 1e-9 * p, "{state:?} {p}");
        // dv/v = −dε_v and v dε_v = λ dp/p on the NCL: ln v changes by −0.3 in all, so
        // ∫ λ dp/(p v) = 0.3, i.e. λ ln(p1/p0) = ∫ v dε_v.
        let v1 = 2.2 * (-0.3f64).exp();
        assert!((state[1] + 1.0 - v1).abs() < 1e-12);
        let want = 2.2 * (1.0 - (-0.3f64).exp()) / 0.2;
        assert!(
            ((p / 100.0).ln() - want).abs() < 1e-3,
            "{} {want}",
            (p / 100.0).ln()
        );
    }

    #[test]
    fn with_n_each_point_starts_on_its_swelling_line() {
        let spec = ModifiedCamClaySpec {
            void_ratio: 0.0,
            ncl_intercept: 3.0,
            ..clay(2.0)
        };
        let law = spec.build::<f64>();
        for p in [10.0, 100.0] {
            let mut s = [-p, -p, -p, 0.0, 0.0, 0.0];
            let mut state = [0.0, 0.0];
            law.update(&mut s, &[0.0; 6], &mut state);
            let want = 3.0 - 0.2 * (2.0 * p).ln() + 0.04 * 2f64.ln() - 1.0;
            assert!((state[1] - want).abs() < 1e-12, "{state:?} {want}");
        }
        let e = |e0: f64, n: f64| {
            ModifiedCamClaySpec {
                void_ratio: e0,
                ncl_intercept: n,
                ..clay(1.0)
            }
            .elastic()
        };
        assert_eq!(e(0.0, 2.2), e(1.2, 0.0));
        let refuse = |e0, n| {
            ModifiedCamClaySpec::new(0.3, 0.0, 0.2, 0.04, 1.0, e0, n, 1.0, 0.0, 1.0, 2000.0)
                .unwrap_err()
                .0
        };
        assert!(refuse(1.2, 3.0).contains("exactly one"));
        assert!(refuse(0.0, 0.0).contains("exactly one"));
        assert!(refuse(0.0, 2.5).contains("must exceed 1 + λ ln MAXIMUM_PRESSURE"));
    }

    #[test]
    fn tension_goes_to_the_apex() {
        let law = clay(1.0).build::<f64>();
        let mut s = [-10.0, -10.0, -10.0, 0.0, 0.0, 0.0];
        let mut state = [0.0, 0.0];
        law.update(&mut s, &[0.5, 0.5, 0.5, 0.0, 0.0, 0.0], &mut state);
        assert_eq!(s, [0.0; 6]);
        assert_eq!(law.yield_function(&s, &state), Some(0.0));
    }
}
