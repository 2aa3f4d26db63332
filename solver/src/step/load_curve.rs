//! Load multipliers over time (gravity, tractions, liquid loads, prescribed velocities): a
//! step, a ramp, Anura3D's stairs, a table of (time, multiplier) pairs, and hammer blows.

use std::sync::Arc;

/// How a load grows with time.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadCurve {
    /// Full value from the first step.
    Step,
    /// Linear from 0 at t = 0 to 1 at t = `over`, then 1.
    Ramp {
        /// Seconds to full load.
        over: f64,
    },
    /// Anura3D's `step` multiplier over several load steps: constant within each, load step k
    /// of `steps` (the times in ((k - 1) T, k T], T = `load_step`) at
    /// from + (k / steps)(to - from).
    Stairs {
        /// The first number of the CPS line.
        from: f64,
        /// The second, reached in the last load step.
        to: f64,
        /// Duration of a load step (s).
        load_step: f64,
        /// Number of load steps.
        steps: u32,
    },
    /// Linear between (time, multiplier) pairs of increasing time; the first multiplier
    /// before the first time, the last after the last.
    Table(Arc<[(f64, f64)]>),
    /// Anura3D's multiplier file (`.PVF`): linear between (time, multiplier) rows as
    /// [`LoadCurve::Table`], but 0 after the last time (the motion stops), with a rate of 0
    /// there ([`LoadCurve::stopped`]).
    File(Arc<[(f64, f64)]>),
    /// Hammer blows (see [`Blow`]), each normalised by its peak Z v₀, one every `interval`
    /// seconds from t = `first`, `count` of them; 0 before the first and after the last one's
    /// interval.
    Blows {
        /// One blow's force over Z v₀.
        blow: Blow,
        /// The time of the first blow (s).
        first: f64,
        /// Seconds between blows.
        interval: f64,
        /// Number of blows.
        count: u32,
    },
}

/// The force of a ram of mass m striking a pile of impedance Z at v₀, over Z v₀: without a
/// cushion F = Z v₀ exp(−Z t / m) (the pile head takes the ram's momentum as a dashpot would);
/// through a cushion of stiffness k the cushion's compression s obeys
/// m s̈ + (k m / Z) ṡ + k s = 0 with s(0) = 0, ṡ(0) = v₀, F = k s, and the blow ends when the
/// cushion has come back to its length (it cannot pull).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blow {
    /// Z / m (1/s).
    pub decay: f64,
    /// The cushion's k / m (1/s²), if there is one.
    pub cushion: Option<f64>,
}

impl Blow {
    /// A blow of a ram of `ram_mass` (t) at `velocity` (m/s) on a pile of `impedance` (kN·s/m),
    /// through a cushion of `cushion` (kN/m) if given.
    pub fn new(ram_mass: f64, impedance: f64, cushion: Option<f64>) -> Self {
        Blow {
            decay: impedance / ram_mass,
            cushion: cushion.map(|k| k / ram_mass),
        }
    }

    /// F(t) / (Z v₀), t seconds after impact.
    pub fn at(&self, t: f64) -> f64 {
        if t < 0.0 {
            return 0.0;
        }
        let Some(w2) = self.cushion else {
            return (-self.decay * t).exp();
        };
        // s̈ + 2 ζ ω s̈ + ω² s = 0 with ω² = k/m and 2 ζ ω = k / Z = ω² / decay; F/(Z v₀) =
        // (k / Z) s / v₀ = 2 ζ ω s / v₀.
        let w = w2.sqrt();
        let two_zeta_w = w2 / self.decay;
        let h = 0.5 * two_zeta_w;
        let s = if h < w {
            let wd = (w2 - h * h).sqrt();
            if t >= std::f64::consts::PI / wd {
                return 0.0;
            }
            (-h * t).exp() * (wd * t).sin() / wd
        } else if h > w {
            let r = (h * h - w2).sqrt();
            ((-(h - r) * t).exp() - (-(h + r) * t).exp()) / (2.0 * r)
        } else {
            t * (-h * t).exp()
        };
        two_zeta_w * s
    }
}

impl LoadCurve {
    /// A ramp over `over` seconds, or a step when `over` is 0.
    pub fn ramp(over: f64) -> Self {
        if over > 0.0 {
            LoadCurve::Ramp { over }
        } else {
            LoadCurve::Step
        }
    }

    /// Multiplier at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match *self {
            LoadCurve::Table(ref rows) => table_at(rows, t, false),
            LoadCurve::File(ref rows) => match rows.last() {
                Some(&(last, _)) if t > last => 0.0,
                _ => table_at(rows, t, true),
            },
            LoadCurve::Blows {
                blow,
                first,
                interval,
                count,
            } => {
                let t = t - first;
                let k = (t / interval).floor();
                if k < 0.0 || k >= f64::from(count) {
                    0.0
                } else if k == 0.0 {
                    // (One blow has an infinite interval: 0 × ∞ is not 0.)
                    blow.at(t)
                } else {
                    blow.at(t - k * interval)
                }
            }
            LoadCurve::Step => 1.0,
            LoadCurve::Ramp { over } => (t / over).min(1.0),
            LoadCurve::Stairs {
                from,
                to,
                load_step,
                steps,
            } => {
                // A step that ends a load step ends at its time up to round-off (the clock is
                // a sum of steps): it still belongs to that load step.
                let k = (t / load_step - 1e-9).ceil().clamp(1.0, f64::from(steps));
                from + k / f64::from(steps) * (to - from)
            }
        }
    }
}

impl LoadCurve {
    /// Whether a step ending at `end` is past an Anura3D file's last time, where Anura3D stops
    /// the motion without decelerating it (the multiplier's rate is then 0).
    pub fn stopped(&self, end: f64) -> bool {
        matches!(self, LoadCurve::File(rows) if rows.last().is_some_and(|&(last, _)| end > last))
    }
}

/// One `time multiplier` row of a curve file (a scene's CSV, Anura3D's `.PVF`): two numbers
/// separated by commas or white space, Fortran's `d` exponents taken; `None` otherwise. With
/// `strict` a third field is refused (a scene's CSV), else ignored (Fortran's list-directed
/// read of two values).
pub fn parse_row(line: &str, strict: bool) -> Option<(f64, f64)> {
    let mut fields = line
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|f| !f.is_empty());
    let mut number = || fields.next()?.replace(['d', 'D'], "e").parse::<f64>().ok();
    let row = (number()?, number()?);
    (!strict || fields.next().is_none()).then_some(row)
}

/// The piecewise-linear multiplier of `rows` (increasing times) at `t`; with `anura3d`, in
/// Anura3D's order of operations (its `.PVF` multipliers), else in that of a ramp (a table
/// [[0, 0], [T, 1]] is a ramp over T to the bit).
fn table_at(rows: &[(f64, f64)], t: f64, anura3d: bool) -> f64 {
    let i = rows.partition_point(|&(ti, _)| ti <= t);
    match (rows.get(i.wrapping_sub(1)), rows.get(i)) {
        (Some(&(t0, m0)), Some(&(t1, m1))) if anura3d => m0 + (m1 - m0) / (t1 - t0) * (t - t0),
        (Some(&(t0, m0)), Some(&(t1, m1))) => m0 + (m1 - m0) * (t - t0) / (t1 - t0),
        (Some(&(_, m)), None) | (None, Some(&(_, m))) => m,
        (None, None) => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stairs_hold_each_load_steps_value() {
        let c = LoadCurve::Stairs {
            from: 0.0,
            to: 1.0,
            load_step: 0.05,
            steps: 4,
        };
        assert_eq!(c.at(1e-15), 0.25);
        assert_eq!(c.at(0.05), 0.25);
        assert_eq!(c.at(0.05 * (1.0 + 1e-15)), 0.25);
        assert_eq!(c.at(0.0500001), 0.5);
        assert_eq!(c.at(0.2), 1.0);
        assert_eq!(c.at(0.3), 1.0);
        let down = LoadCurve::Stairs {
            from: 10.0,
            to: 2.0,
            load_step: 1.0,
            steps: 2,
        };
        assert_eq!(down.at(0.5), 6.0);
        assert_eq!(down.at(1.5), 2.0);
    }

    #[test]
    fn an_anura3d_file_stops_after_its_last_time() {
        let c = LoadCurve::File(vec![(0.0, 0.0), (1.0, 2.0)].into());
        assert_eq!(c.at(0.5), 1.0);
        assert_eq!(c.at(1.0), 2.0);
        assert_eq!(c.at(1.0 + 1e-12), 0.0);
        assert!(!c.stopped(0.75) && c.stopped(1.25));
    }

    #[test]
    fn a_table_interpolates_and_holds_its_ends() {
        let c = LoadCurve::Table(vec![(0.0, 0.0), (1.0, 2.0), (3.0, -2.0)].into());
        assert_eq!(c.at(-1.0), 0.0);
        assert_eq!(c.at(0.5), 1.0);
        assert_eq!(c.at(1.0), 2.0);
        assert_eq!(c.at(2.0), 0.0);
        assert_eq!(c.at(9.0), -2.0);
        let late = LoadCurve::Table(vec![(1.0, 5.0)].into());
        assert_eq!((late.at(0.0), late.at(2.0)), (5.0, 5.0));
    }

    #[test]
    fn blows_decay_as_the_ram_gives_its_momentum_and_repeat() {
        // Z / m = 100 /s: e^-1 after 10 ms; a blow every 0.5 s, two of them.
        let c = LoadCurve::Blows {
            blow: Blow::new(2.0, 200.0, None),
            first: 0.0,
            interval: 0.5,
            count: 2,
        };
        assert_eq!(c.at(0.0), 1.0);
        assert!((c.at(0.01) - (-1.0f64).exp()).abs() < 1e-15);
        assert!((c.at(0.51) - (-1.0f64).exp()).abs() < 1e-12);
        assert_eq!(c.at(1.0), 0.0);
        let once = LoadCurve::Blows {
            blow: Blow::new(2.0, 200.0, None),
            first: 0.0,
            interval: f64::INFINITY,
            count: 1,
        };
        assert!((once.at(0.01) - (-1.0f64).exp()).abs() < 1e-15);
        // The impulse of one blow is the ram's momentum: ∫ F dt = Z v0 · m / Z = m v0.
        let dt = 1e-6;
        let impulse: f64 = (0..400_000).map(|i| c.at((i as f64 + 0.5) * dt) * dt).sum();
        assert!((impulse - 2.0 / 200.0).abs() < 1e-7, "{impulse}");
    }

    #[test]
    fn blows_start_at_the_first_blows_time() {
        let c = LoadCurve::Blows {
            blow: Blow::new(2.0, 200.0, None),
            first: 0.25,
            interval: 0.5,
            count: 2,
        };
        assert_eq!(c.at(0.2), 0.0, "before the first blow");
        assert_eq!(c.at(0.25), 1.0);
        assert_eq!(c.at(0.75), 1.0, "the second blow");
        assert!((c.at(0.26) - (-1.0f64).exp()).abs() < 1e-15);
        assert_eq!(c.at(1.25), 0.0, "after the last one's interval");
    }

    #[test]
    fn a_cushion_blow_follows_the_ram_cushion_pile_equations() {
        // m = 2 t, Z = 200 kN·s/m, v0 = 1: integrate m ẍ = −k s, Z ẏ = k s, s = x − y, with
        // RK4 and compare F = k s over Z v0, under-, critically (k = 4 Z² / m) and over-damped.
        let (m, z) = (2.0, 200.0);
        for k in [1e3, 1e4, 2e4, 8e4, 1e5, 1e6] {
            let b = Blow::new(m, z, Some(k));
            assert_eq!(b.at(0.0), 0.0);
            let rate = |s: f64, ds: f64| (ds, -k * s / m - k * ds / z);
            let (mut s, mut ds, dt) = (0.0, 1.0, 1e-6);
            for i in 1..=100_000 {
                let (a1, b1) = rate(s, ds);
                let (a2, b2) = rate(s + 0.5 * dt * a1, ds + 0.5 * dt * b1);
                let (a3, b3) = rate(s + 0.5 * dt * a2, ds + 0.5 * dt * b2);
                let (a4, b4) = rate(s + dt * a3, ds + dt * b3);
                s += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
                ds += dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
                if s < 0.0 {
                    assert_eq!(b.at(i as f64 * dt + 1e-9), 0.0, "k {k}: the blow ends");
                    break;
                }
                let want = k * s / z;
                let got = b.at(i as f64 * dt);
                assert!(
                    (got - want).abs() < 1e-9 * (1.0 + want),
                    "k {k}, t {}: {got} vs {want}",
                    i as f64 * dt
                );
            }
        }
        // A very stiff cushion is the bare blow.
        let stiff = Blow::new(m, z, Some(1e12));
        assert!((stiff.at(0.01) - (-1.0f64).exp()).abs() < 1e-3);
    }
}
