//! Element tests: one material point of any registered law driven along a laboratory path,
//! strain or stress controlled per component, as a triaxial cell or an oedometer drives a
//! sample. The axial direction is y (the solver's vertical); compression is positive in what
//! the tests record (p, q, strains), as soil mechanics writes it.
//!
//! - [`undrained_triaxial`]: isochoric axial compression (ε_xx = ε_zz = −ε_yy / 2), the
//!   effective stress path of a saturated sample whose water is incompressible.
//! - [`drained_triaxial`]: axial compression at constant cell pressure (σ_xx = σ_zz fixed),
//!   the lateral strain found each step by the secant method on the law's own response.
//! - [`oedometer`]: axial strain alone (no lateral strain), loading and unloading.
//! - [`cyclic_undrained`]: isochoric axial strain reversed each time the deviator reaches
//!   ±q_ampl (stress-controlled cyclic triaxial), until the sample liquefies.

use crate::material::law::{Law, LawSpec};

/// One recorded state of an element test (compression positive; strains from the start).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// Axial strain ε_a.
    pub axial: f64,
    /// Volumetric strain ε_v.
    pub volumetric: f64,
    /// Mean effective stress p' (kPa).
    pub p: f64,
    /// Deviator q = σ_a − σ_r (kPa; negative in extension).
    pub q: f64,
    /// The axial stress σ_a (kPa).
    pub axial_stress: f64,
    /// The law's state values after the step.
    pub state: [f64; 4],
}

/// A sample: its law, stress (tension positive, xx yy zz xy yz zx) and state.
#[derive(Debug, Clone)]
pub struct Sample {
    law: Law<f64>,
    stress: [f64; 6],
    state: Vec<f64>,
    axial: f64,
    volumetric: f64,
}

impl Sample {
    /// A sample of `law` at the isotropic-or-not effective `stress` (compression positive
    /// principal values: radial, axial), its state not set.
    pub fn new(law: &LawSpec, radial: f64, axial: f64) -> Self {
        Sample {
            law: law.build(),
            stress: [-radial, -axial, -radial, 0.0, 0.0, 0.0],
            state: vec![0.0; law.state_len()],
            axial: 0.0,
            volumetric: 0.0,
        }
    }

    /// The current record.
    pub fn record(&self) -> Record {
        let s = &self.stress;
        let mut state = [0.0; 4];
        for (to, from) in state.iter_mut().zip(&self.state) {
            *to = *from;
        }
        Record {
            axial: self.axial,
            volumetric: self.volumetric,
            p: -(s[0] + s[1] + s[2]) / 3.0,
            q: (s[0] + s[2]) / 2.0 - s[1],
            axial_stress: -s[1],
            state,
        }
    }

    /// The stress after the strain increment (radial, axial; compression positive) from the
    /// current state, without taking it.
    fn trial(&self, radial: f64, axial: f64) -> ([f64; 6], Vec<f64>) {
        let (mut s, mut state) = (self.stress, self.state.clone());
        self.law.update(
            &mut s,
            &[-radial, -axial, -radial, 0.0, 0.0, 0.0],
            &mut state,
        );
        (s, state)
    }

    /// Takes the strain increment (radial, axial; compression positive).
    pub fn strain(&mut self, radial: f64, axial: f64) {
        let (s, state) = self.trial(radial, axial);
        self.take(s, state, radial, axial);
    }

    fn take(&mut self, s: [f64; 6], state: Vec<f64>, radial: f64, axial: f64) {
        self.stress = s;
        self.state = state;
        self.axial += axial;
        self.volumetric += axial + 2.0 * radial;
    }

    /// Takes the axial strain increment `axial` with the radial stress held: the radial
    /// strain by the secant method (its first slope from a probe), to a thousandth of a Pa.
    /// `None` when it does not converge in 50 iterations.
    pub fn strain_at_radial_stress(&mut self, axial: f64) -> Option<()> {
        let target = self.stress[0];
        let mut radial = -axial / 2.0;
        let (s, _) = self.trial(radial + 1e-7, axial);
        let mut last = (radial + 1e-7, s[0] - target);
        for _ in 0..50 {
            let (s, state) = self.trial(radial, axial);
            let r = s[0] - target;
            if r.abs() <= 1e-6 {
                self.take(s, state, radial, axial);
                return Some(());
            }
            let slope = (r - last.1) / (radial - last.0);
            if !(slope.is_finite() && slope != 0.0) {
                return None;
            }
            last = (radial, r);
            radial -= r / slope;
        }
        None
    }
}

/// An isochoric (undrained) triaxial compression of `steps` axial increments `step`.
pub fn undrained_triaxial(sample: &mut Sample, step: f64, steps: usize) -> Vec<Record> {
    let mut out = vec![sample.record()];
    for _ in 0..steps {
        sample.strain(-step / 2.0, step);
        out.push(sample.record());
    }
    out
}

/// A drained triaxial compression of `steps` axial increments `step` at the sample's radial
/// stress; it stops early where the lateral strain cannot be found (the sample has failed).
pub fn drained_triaxial(sample: &mut Sample, step: f64, steps: usize) -> Vec<Record> {
    let mut out = vec![sample.record()];
    for _ in 0..steps {
        if sample.strain_at_radial_stress(step).is_none() {
            break;
        }
        out.push(sample.record());
    }
    out
}

/// An oedometer test: the axial strain increments of `path` in turn (positive: loading),
/// each cut into increments no larger than `step`.
pub fn oedometer(sample: &mut Sample, path: &[f64], step: f64) -> Vec<Record> {
    let mut out = vec![sample.record()];
    for &leg in path {
        let n = (leg.abs() / step).ceil().max(1.0) as usize;
        for _ in 0..n {
            sample.strain(0.0, leg / n as f64);
            out.push(sample.record());
        }
    }
    out
}

/// A cyclic undrained test's outcome.
#[derive(Debug, Clone)]
pub struct Cyclic {
    /// Every step's record.
    pub records: Vec<Record>,
    /// The cycles the sample took to liquefy, in half cycles (compression, then extension:
    /// 0.5 is the first compression), or `None` if it did not within the cycles run.
    pub liquefied_at: Option<f64>,
    /// p' at the end of each full cycle (kPa).
    pub p_after_cycle: Vec<f64>,
}

/// A stress-controlled cyclic undrained triaxial test: isochoric axial strain increments of
/// `step`, compression first, reversed each time q reaches ±`amplitude`, for up to `cycles`
/// cycles. The sample has liquefied when p' falls below 5 % of its start, or a half cycle's
/// axial strain exceeds 5 % (it cannot reach the amplitude any more).
pub fn cyclic_undrained(sample: &mut Sample, amplitude: f64, step: f64, cycles: usize) -> Cyclic {
    let p0 = sample.record().p;
    let mut out = Cyclic {
        records: vec![sample.record()],
        liquefied_at: None,
        p_after_cycle: Vec::new(),
    };
    for half in 0..2 * cycles {
        let sign = if half % 2 == 0 { 1.0 } else { -1.0 };
        let start = sample.axial;
        loop {
            sample.strain(-sign * step / 2.0, sign * step);
            let r = sample.record();
            out.records.push(r);
            if r.p < 0.05 * p0 || (r.axial - start).abs() > 0.05 {
                out.liquefied_at = Some((half + 1) as f64 / 2.0);
                return out;
            }
            if sign * r.q >= amplitude {
                break;
            }
        }
        if half % 2 == 1 {
            out.p_after_cycle.push(sample.record().p);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_elastic_sample_follows_hookes_law() {
        let law = LawSpec::linear_elastic(1e4, 0.25).unwrap();
        let mut s = Sample::new(&law, 100.0, 100.0);
        let r = drained_triaxial(&mut s, 1e-4, 10);
        let last = r.last().unwrap();
        // Drained: Δq = E ε_a, ε_v = (1 − 2ν) ε_a.
        assert!((last.q - 1e4 * 1e-3).abs() < 1e-6, "{last:?}");
        assert!((last.volumetric - 0.5e-3).abs() < 1e-9, "{last:?}");
        let mut s = Sample::new(&law, 100.0, 100.0);
        let r = undrained_triaxial(&mut s, 1e-4, 10);
        // Undrained: p constant, q = 3 G ε_a.
        let last = r.last().unwrap();
        assert!((last.p - 100.0).abs() < 1e-9 && (last.q - 3.0 * 4e3 * 1e-3).abs() < 1e-6);
        let mut s = Sample::new(&law, 100.0, 100.0);
        let r = oedometer(&mut s, &[1e-3, -1e-3], 1e-4);
        assert_eq!(r.len(), 21);
        assert!((r[10].axial_stress - 100.0 - 1.2e4 * 1e-3).abs() < 1e-6);
        assert!((r[20].axial_stress - 100.0).abs() < 1e-9);
    }
}
