//! Mohr–Coulomb elasto-plasticity with a tension cut-off, as Anura3D's `mohr_coulomb`
//! (A3DMohrCoulombStandard): linear elasticity, the Mohr–Coulomb pyramid with a non-associated
//! flow rule (dilatancy angle ψ) and an associated Rankine cut-off at the tensile strength σt.
//!
//! Stresses are tension positive; principal stresses σ1 ≤ σ2 ≤ σ3 (σ1 the most compressive).
//! With sin φ capped at 0.999 and the cohesion term c cos φ (cos φ of the uncapped angle), as
//! Anura3D has them, the yield functions are
//!
//! - F = (σ3 - σ1)/2 + (σ3 + σ1)/2 · sin φ - c cos φ (the pyramid's face in the sorted sextant;
//!   its two edges add the same function of (σ1, σ2), the triaxial compression edge σ2 = σ3,
//!   and of (σ2, σ3), the triaxial extension edge σ1 = σ2),
//! - Ft = σ3 - σt (and σ2 - σt, σ1 - σt on the cut-off's edge and apex),
//!
//! with the plastic potentials G = (σ3 - σ1)/2 + (σ3 + σ1)/2 · sin ψ for the pyramid and Ft
//! itself for the cut-off. The return is explicit and exact (one step, no iteration): the
//! elastic trial σB is returned along D ∂G/∂σ in principal space onto the face, an edge, the
//! line where face and cut-off meet, the cut-off's edge, or a corner (the pyramid's apex, or
//! one of the cut-off's corners), whichever satisfies the consistency conditions (multipliers
//! Δλ ≥ 0, every yield function ≤ 0 after the return), in the manner of Clausen, Damkilde and
//! Andersen's return algorithms for multiple yield planes. The returned principal stresses are
//! put back on the trial's principal directions (the return is coaxial).
//!
//! The face and the two edges use Anura3D's formulas (the same multipliers; only round-off can
//! differ). Where the trial lies beyond the cut-off this return can differ from Anura3D's,
//! whose region tests send a few trials to a corner the consistency conditions do not give.
//!
//! Cost: an elastic trial is recognised from its invariants (mean stress and J2, a bound that
//! holds for every Lode angle), without the eigen decomposition, in most elastic states; only
//! trials near or beyond the surface are decomposed.

use crate::material::linear_elastic::LinearElastic;
use crate::material::principal::{principal, rebuild};
use crate::real::Real;

/// Anura3D's largest sin φ: above it the yield function uses this value (φ ≈ 87.4°).
pub const SIN_PHI_CAP: f64 = 0.999;

/// The yield surface and flow rule in the run's precision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface<R: Real> {
    /// sin φ, capped at [`SIN_PHI_CAP`].
    pub sin_phi: R,
    /// sin ψ.
    pub sin_psi: R,
    /// c cos φ (kPa), cos φ of the uncapped angle.
    pub cohesion: R,
    /// σt (kPa).
    pub tension: R,
    /// Whether the cut-off cuts the pyramid (σt below its apex c cos φ / sin φ); without it the
    /// pyramid's apex is the corner.
    pub cut_off: bool,
    /// 1 + sin²φ / 3: F ≤ p sin φ + sqrt(J2 · this) - c cos φ for every Lode angle.
    bound: R,
}

/// The pyramid's apex c cos φ / sin φ (kPa) with Anura3D's capped sin φ; +∞ for φ = 0.
pub fn apex(friction_deg: f64, cohesion: f64) -> f64 {
    let s = friction_deg.to_radians().sin();
    let sc = s.min(SIN_PHI_CAP);
    if sc > 0.0 {
        cohesion * (1.0 - s * s).sqrt() / sc
    } else {
        f64::INFINITY
    }
}

/// The planes the return can make active, as yield gradient a, flow gradient D b and a·σ at
/// yield. 0: the face F(σ1, σ3); 1: F(σ1, σ2) (with 0: σ2 = σ3, the compression edge);
/// 2: F(σ2, σ3) (with 0: σ1 = σ2, the extension edge); 3, 4, 5: σ3, σ2, σ1 at σt.
struct Planes<R: Real> {
    a: [[R; 3]; 6],
    db: [[R; 3]; 6],
    k: [R; 6],
}

/// Active sets tried in turn without the cut-off: face, extension edge, compression edge, apex.
const PYRAMID: [&[usize]; 4] = [&[0], &[0, 2], &[0, 1], &[0, 1, 2]];

/// Active sets tried in turn with the cut-off: faces, edges, the face–cut-off line, the corners
/// (σa, σa, σt), (σa, σt, σt) (four planes meet there: each triple spans part of its cone) and
/// (σt, σt, σt).
const WITH_CUT_OFF: [&[usize]; 12] = [
    &[0],
    &[3],
    &[0, 2],
    &[0, 1],
    &[0, 3],
    &[3, 4],
    &[0, 2, 3],
    &[0, 1, 3],
    &[0, 1, 4],
    &[0, 3, 4],
    &[1, 3, 4],
    &[3, 4, 5],
];

#[inline]
fn dot<R: Real>(a: &[R; 3], b: &[R; 3]) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl<R: Real> Surface<R> {
    /// From φ and ψ in degrees, c and σt in kPa (Anura3D's definitions: sin φ capped, c cos φ).
    pub fn new(friction_deg: f64, cohesion: f64, dilatancy_deg: f64, tension: f64) -> Self {
        let s = friction_deg.to_radians().sin();
        let sc = s.min(SIN_PHI_CAP);
        Surface {
            sin_phi: R::of(sc),
            sin_psi: R::of(dilatancy_deg.to_radians().sin()),
            cohesion: R::of(cohesion * (1.0 - s * s).sqrt()),
            tension: R::of(tension),
            cut_off: tension < apex(friction_deg, cohesion),
            bound: R::of(1.0 + sc * sc / 3.0),
        }
    }

    /// F for the smallest and largest principal stress.
    #[inline]
    pub fn yield_value(&self, lo: R, hi: R) -> R {
        let half = R::of(0.5);
        half * (hi - lo) + half * (hi + lo) * self.sin_phi - self.cohesion
    }

    /// Whether `s` is inside both surfaces by a bound from its invariants alone (false means
    /// "look closer", not "outside").
    #[inline]
    fn surely_inside(&self, s: &[R; 6]) -> bool {
        let p = (s[0] + s[1] + s[2]) * R::of(1.0 / 3.0);
        let (d0, d1, d2) = (s[0] - p, s[1] - p, s[2] - p);
        let j2 = R::of(0.5) * (d0 * d0 + d1 * d1 + d2 * d2)
            + s[3] * s[3]
            + s[4] * s[4]
            + s[5] * s[5];
        // Largest (σ3 - σ1)/2 - σ2' sin φ / 2 over the Lode angle: sqrt(J2 (1 + sin²φ/3)).
        let r = self.cohesion - p * self.sin_phi;
        let pyramid = r >= R::ZERO && j2 * self.bound <= r * r;
        if !self.cut_off {
            return pyramid;
        }
        // Largest principal deviator: 2 sqrt(J2 / 3).
        let t = self.tension - p;
        pyramid && t >= R::ZERO && j2 * R::of(4.0 / 3.0) <= t * t
    }

    /// Returns the trial stress `s` to the surface. `None` when the trial is elastic (then `s`
    /// is untouched); otherwise the principal stress correction σB - σC (in the trial's sorted
    /// principal axes) that was taken off, which D⁻¹ turns into the plastic strain increment.
    #[inline]
    pub fn return_map(&self, el: &LinearElastic<R>, s: &mut [R; 6]) -> Option<[R; 3]> {
        if self.surely_inside(s) {
            return None;
        }
        self.return_decomposed(el, s)
    }

    /// The part of [`Surface::return_map`] that needs the principal stresses.
    fn return_decomposed(&self, el: &LinearElastic<R>, s: &mut [R; 6]) -> Option<[R; 3]> {
        let p = principal(s);
        let sig = p.values;
        let mut scale = sig[0].abs().max(sig[2].abs()).max(self.cohesion);
        if self.cut_off {
            scale = scale.max(self.tension.abs());
        }
        // Inside to round-off: a returned stress, decomposed again, stays as it is.
        let tol = R::of(16.0 * R::EPSILON) * scale;
        let inside_tension = !self.cut_off || sig[2] - self.tension <= tol;
        if self.yield_value(sig[0], sig[2]) <= tol && inside_tension {
            return None;
        }
        let back = self.principal_return(el, &sig, scale);
        *s = rebuild(&back, &p.vectors);
        Some([sig[0] - back[0], sig[1] - back[1], sig[2] - back[2]])
    }

    fn planes(&self, el: &LinearElastic<R>) -> Planes<R> {
        let half = R::of(0.5);
        let (z, one) = (R::ZERO, R::ONE);
        let (mf, pf) = (half * (one - self.sin_phi), half * (one + self.sin_phi));
        let (mg, pg) = (half * (one - self.sin_psi), half * (one + self.sin_psi));
        let a = [
            [-mf, z, pf],
            [-mf, pf, z],
            [z, -mf, pf],
            [z, z, one],
            [z, one, z],
            [one, z, z],
        ];
        let b = [
            [-mg, z, pg],
            [-mg, pg, z],
            [z, -mg, pg],
            [z, z, one],
            [z, one, z],
            [one, z, z],
        ];
        let g2 = el.shear + el.shear;
        let db = b.map(|b| {
            let l = el.lambda * (b[0] + b[1] + b[2]);
            [l + g2 * b[0], l + g2 * b[1], l + g2 * b[2]]
        });
        let (c, t) = (self.cohesion, self.tension);
        Planes {
            a,
            db,
            k: [c, c, c, t, t, t],
        }
    }

    /// The returned principal stresses of the sorted trial `sig` (outside the surface).
    fn principal_return(&self, el: &LinearElastic<R>, sig: &[R; 3], scale: R) -> [R; 3] {
        let planes = self.planes(el);
        let f = core::array::from_fn::<R, 6, _>(|j| dot(&planes.a[j], sig) - planes.k[j]);
        let tol = R::of(64.0 * R::EPSILON) * scale;
        let sets: &[&[usize]] = if self.cut_off {
            &WITH_CUT_OFF
        } else {
            &PYRAMID
        };
        // The first consistent candidate wins; failing all (round-off at a region boundary),
        // the least inconsistent one.
        let mut best: Option<([R; 3], R)> = None;
        for set in sets {
            let Some((back, violation)) = self.candidate(el, &planes, &f, sig, set) else {
                continue;
            };
            if violation <= tol {
                return back;
            }
            if best.map_or(true, |(_, v)| violation < v) {
                best = Some((back, violation));
            }
        }
        best.map_or(*sig, |(b, _)| b)
    }

    /// The return with the planes `set` active: the stress, and how far it is from consistent
    /// (a negative multiplier as 2G Δλ, a yield function above 0), in kPa. `None` when the
    /// planes' system is singular (φ = 0 makes the apex's three planes dependent).
    fn candidate(
        &self,
        el: &LinearElastic<R>,
        planes: &Planes<R>,
        f: &[R; 6],
        sig: &[R; 3],
        set: &[usize],
    ) -> Option<([R; 3], R)> {
        let m = |j: usize, l: usize| dot(&planes.a[set[j]], &planes.db[set[l]]);
        let rhs = |j: usize| f[set[j]];
        let mut dl = [R::ZERO; 3];
        let tiny = R::of(R::EPSILON) * el.shear;
        match set.len() {
            1 => {
                let d = m(0, 0);
                if !(d.abs() > tiny) {
                    return None;
                }
                dl[0] = rhs(0) / d;
            }
            2 => {
                let (a, b, c, d) = (m(0, 0), m(0, 1), m(1, 0), m(1, 1));
                let det = a * d - b * c;
                if !(det.abs() > tiny * (a.abs() + d.abs())) {
                    return None;
                }
                dl[0] = (rhs(0) * d - b * rhs(1)) / det;
                dl[1] = (a * rhs(1) - c * rhs(0)) / det;
            }
            _ => {
                let k = [[m(0, 0), m(0, 1), m(0, 2)], [m(1, 0), m(1, 1), m(1, 2)], [
                    m(2, 0),
                    m(2, 1),
                    m(2, 2),
                ]];
                let r = [rhs(0), rhs(1), rhs(2)];
                let det3 = |c: &[[R; 3]; 3]| {
                    c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1])
                        - c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0])
                        + c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0])
                };
                let det = det3(&k);
                let size = k[0][0].abs() + k[1][1].abs() + k[2][2].abs();
                if !(det.abs() > tiny * size * size) {
                    return None;
                }
                // Cramer's rule: column l replaced by the right-hand side.
                for (l, x) in dl.iter_mut().enumerate() {
                    let mut c = k;
                    for (row, &v) in c.iter_mut().zip(&r) {
                        row[l] = v;
                    }
                    *x = det3(&c) / det;
                }
            }
        }
        let mut back = *sig;
        let mut violation = R::ZERO;
        let g2 = el.shear + el.shear;
        for (j, &p) in set.iter().enumerate() {
            for i in 0..3 {
                back[i] -= dl[j] * planes.db[p][i];
            }
            violation = violation.max(-dl[j] * g2);
        }
        let lo = back[0].min(back[1]).min(back[2]);
        let hi = back[0].max(back[1]).max(back[2]);
        violation = violation.max(self.yield_value(lo, hi));
        if self.cut_off {
            violation = violation.max(hi - self.tension);
        }
        Some((back, violation))
    }
}

/// Mohr–Coulomb with tension cut-off (no state: perfect plasticity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MohrCoulomb<R: Real> {
    /// The elastic part.
    pub elastic: LinearElastic<R>,
    /// The yield surface and flow rule.
    pub surface: Surface<R>,
}

impl<R: Real> MohrCoulomb<R> {
    /// From E (kPa), ν, φ (degrees), c (kPa), ψ (degrees), σt (kPa); checked by
    /// [`crate::material::law::LawSpec`].
    pub fn new(
        young: f64,
        poisson: f64,
        friction_deg: f64,
        cohesion: f64,
        dilatancy_deg: f64,
        tension: f64,
    ) -> Self {
        MohrCoulomb {
            elastic: LinearElastic::new(young, poisson),
            surface: Surface::new(friction_deg, cohesion, dilatancy_deg, tension),
        }
    }

    /// Adds the stress increment of the strain increment `de` (xx yy zz xy yz zx, tensor shear
    /// components): the elastic trial, returned to the surface when outside.
    #[inline]
    pub fn update(&self, s: &mut [R; 6], de: &[R; 6]) {
        self.elastic.update(s, de);
        self.surface.return_map(&self.elastic, s);
    }
}
