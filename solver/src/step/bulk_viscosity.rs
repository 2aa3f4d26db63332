//! Bulk viscosity damping (Anura3D's `$$BULK_VISCOSITY_DAMPING 1 b1 b2`, a scene's
//! `[damping] bulk_viscosity`): each point carries a viscous pressure q formed in the stress
//! pass from its volumetric strain rate ε̇_v = tr Δε / Δt,
//!
//! q = b1 ρ c L ε̇_v, plus ∓ ρ (b2 L ε̇_v)² where the point is compressed (ε̇_v < 0),
//!
//! L the smallest altitude of the point's element, ρ and c the density and P-wave speed
//! Anura3D takes (a saturated material's mixture density and undrained speed
//! sqrt((E_oed + K_w/n) / ρ_mix); otherwise the dry ones). The next step's particle to grid adds
//! q to the point's normal stresses for the internal force only: the stress itself, and what
//! the law sees, stay as they were. In compression the linear term is a compressive stress
//! against the compression (a damper of the volumetric motion, the ringing behind a front).
//!
//! The quadratic term's sign: the von Neumann–Richtmyer term resists compression (a
//! compressive stress, `Quadratic::Resisting`, scenes); Anura3D adds it as a tensile stress
//! (`Quadratic::Anura3d`, GOM input), which helps the compression along — kept for the
//! point-by-point match, and noted in the fidelity list.
//!
//! The critical step shrinks by √(1 + χ²) − χ, χ = b1 − b2² Δt_e ε̇_v (Δt_e the element's
//! crossing time), as Anura3D's.

use crate::real::Real;

/// The sign of the quadratic term (see the module's notes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quadratic {
    /// A compressive stress, resisting the compression (scenes).
    Resisting,
    /// A tensile stress, as Anura3D adds it (GOM input).
    Anura3d,
}

/// A case's bulk viscosity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BulkViscosity {
    /// b1, the linear coefficient.
    pub linear: f64,
    /// b2, the quadratic coefficient (0: none).
    pub quadratic: f64,
    /// The quadratic term's sign.
    pub sign: Quadratic,
}

impl BulkViscosity {
    /// The critical step's factor √(1 + χ²) − χ for an element whose crossing time is
    /// `crossing` (s) and whose point strains at the rate `rate` (1/s).
    pub fn step_factor(&self, crossing: f64, rate: f64) -> f64 {
        let chi = self.linear - self.quadratic * self.quadratic * crossing * rate;
        (1.0 + chi * chi).sqrt() - chi
    }
}

/// A material's density ρ (t/m³) and P-wave speed c (m/s) of the damping.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Medium<R: Real> {
    rho: R,
    c: R,
}

/// What the stress pass needs of the bulk viscosity: the coefficients in the run's precision
/// and each material's medium.
#[derive(Debug, Clone)]
pub struct BulkDamping<R: Real> {
    linear: R,
    quadratic: R,
    /// +1 (Anura3D's) or -1 (resisting).
    sign: R,
    /// Per material index (0 unused).
    media: Vec<Medium<R>>,
}

impl<R: Real> BulkDamping<R> {
    /// The damping of `b` for materials of (ρ (t/m³), c (m/s)) `media`, by material index
    /// (`None`: unused; [`crate::input::case::MaterialSpec::bulk_medium`] gives Anura3D's).
    pub fn new(b: &BulkViscosity, media: &[Option<(f64, f64)>]) -> Self {
        BulkDamping {
            linear: R::of(b.linear),
            quadratic: R::of(b.quadratic),
            sign: R::of(match b.sign {
                Quadratic::Resisting => -1.0,
                Quadratic::Anura3d => 1.0,
            }),
            media: media
                .iter()
                .map(|m| {
                    let (rho, c) = m.unwrap_or((0.0, 0.0));
                    Medium {
                        rho: R::of(rho),
                        c: R::of(c),
                    }
                })
                .collect(),
        }
    }

    /// The viscous pressure q (kPa, tension positive) of a point of `material` straining at the
    /// volumetric rate `rate` (1/s) in an element of smallest altitude `length` (m), in
    /// Anura3D's order of operations.
    #[inline(always)]
    pub fn pressure(&self, material: u32, length: R, rate: R) -> R {
        let m = self.media[material as usize];
        let mut q = self.linear * m.rho * m.c * length * rate;
        if rate < R::ZERO && self.quadratic > R::ZERO {
            let s = self.quadratic * length * rate;
            q += self.sign * (m.rho * (s * s));
        }
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The linear term is b1 ρ c L ε̇; the quadratic one enters in compression only, with its
    /// sign.
    #[test]
    fn pressure_terms() {
        let (rho, c) = (2.0, 250.0);
        let b = |sign| BulkViscosity {
            linear: 0.4,
            quadratic: 1.5,
            sign,
        };
        let media = [None, Some((rho, c))];
        let resisting = BulkDamping::<f64>::new(&b(Quadratic::Resisting), &media);
        let anura3d = BulkDamping::<f64>::new(&b(Quadratic::Anura3d), &media);
        let (l, rate) = (0.1, 3.0);
        let linear = 0.4 * rho * c * l * rate;
        assert!((resisting.pressure(1, l, rate) - linear).abs() < 1e-12 * linear);
        assert_eq!(resisting.pressure(1, l, rate), anura3d.pressure(1, l, rate));
        let quad = rho * (1.5f64 * l * rate).powi(2);
        let r = resisting.pressure(1, l, -rate);
        let a = anura3d.pressure(1, l, -rate);
        assert!((r - (-linear - quad)).abs() < 1e-12 * linear);
        assert!((a - (-linear + quad)).abs() < 1e-12 * linear);
    }

    /// The step's factor is √(1 + b1²) − b1 at rest, smaller in compression.
    #[test]
    fn step_factor() {
        let b = BulkViscosity {
            linear: 0.42,
            quadratic: 1.2,
            sign: Quadratic::Anura3d,
        };
        let rest = b.step_factor(1e-5, 0.0);
        assert!((rest - ((1.0f64 + 0.42 * 0.42).sqrt() - 0.42)).abs() < 1e-15);
        assert!(b.step_factor(1e-5, -100.0) < rest);
        assert!(b.step_factor(1e-5, 100.0) > rest);
    }
}
