//! The pore liquid of saturated (two-phase, single-point) materials: its parameters, the
//! two-phase critical wave speed (Mieremet et al., docs/design.md §4) and the per-material constants the
//! kernels use.

use crate::material::error::MaterialError;
use crate::real::Real;

/// Gravity used to turn intrinsic permeability into hydraulic conductivity (m/s²), as Anura3D.
pub const G: f64 = 9.81;

/// Liquid phase of a saturated material (Anura3D's `saturated_material_coupled`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiquidSpec {
    /// Porosity n.
    pub porosity: f64,
    /// Liquid density ρw (t/m³).
    pub density: f64,
    /// Bulk modulus of the liquid K_w (kPa).
    pub bulk_modulus: f64,
    /// Intrinsic permeability κ (m²).
    pub intrinsic_permeability: f64,
    /// Dynamic viscosity μ (kPa·s).
    pub viscosity: f64,
}

impl LiquidSpec {
    /// Checks the ranges: 0 < n < 1, positive density, bulk modulus, permeability and viscosity.
    pub fn new(
        porosity: f64,
        density_kg_m3: f64,
        bulk_modulus: f64,
        intrinsic_permeability: f64,
        viscosity: f64,
    ) -> Result<Self, MaterialError> {
        if !(porosity > 0.0 && porosity < 1.0) {
            return Err(MaterialError::Porosity {
                range: "(0, 1)",
                value: porosity,
            });
        }
        for (name, v) in [
            ("liquid density", density_kg_m3),
            ("liquid bulk modulus", bulk_modulus),
            ("intrinsic permeability", intrinsic_permeability),
            ("liquid viscosity", viscosity),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(MaterialError::NotPositive {
                    what: name,
                    value: v,
                });
            }
        }
        Ok(LiquidSpec {
            porosity,
            density: density_kg_m3 / 1000.0,
            bulk_modulus,
            intrinsic_permeability,
            viscosity,
        })
    }

    /// Hydraulic conductivity k = κ ρw g / μ (m/s).
    pub fn conductivity(&self) -> f64 {
        self.intrinsic_permeability * self.density * G / self.viscosity
    }

    /// Consolidation coefficient c_v = k / (g ρw (1/E_oed + n/K_w)) (m²/s).
    pub fn consolidation_coefficient(&self, e_oed: f64) -> f64 {
        self.conductivity() / (G * self.density * (1.0 / e_oed + self.porosity / self.bulk_modulus))
    }

    /// The two-phase critical wave speed on an element of size `dx` (Mieremet et al.):
    /// the larger of the dynamic speed and the consolidation speed 2 c_v / Δx.
    /// `solid_density` is the grains' density ρs (t/m³), `e_oed` the oedometric modulus.
    pub fn wave_speed(&self, solid_density: f64, e_oed: f64, dx: f64) -> f64 {
        self.speed(solid_density, e_oed, dx, true)
    }

    /// The speed that bounds the step when the drag is treated implicitly: the dynamic speed
    /// without the drag term (a = 0), and no consolidation term. With an implicit drag b, a
    /// pressure mode of wave number κ is stable for Δt ≤ (b + sqrt(b² + 4 ρw K κ²)) / (K κ²),
    /// which is never below the drag-free wave limit, so neither the drag nor the diffusion it
    /// causes bounds the step: the step no longer falls with the permeability.
    pub fn wave_speed_implicit_drag(&self, solid_density: f64, e_oed: f64, dx: f64) -> f64 {
        self.speed(solid_density, e_oed, dx, false)
    }

    fn speed(&self, solid_density: f64, e_oed: f64, dx: f64, drag: bool) -> f64 {
        let (n, rs, rw, kw) = (
            self.porosity,
            solid_density,
            self.density,
            self.bulk_modulus,
        );
        let k = self.conductivity();
        let rm = (1.0 - n) * rs + n * rw;
        let a = if drag {
            n * rm * G / ((1.0 - n) * rs * k)
        } else {
            0.0
        };
        let b = 4.0 * (n * rm * kw + (1.0 - 2.0 * n) * rw * kw + n * rw * e_oed)
            / (n * (1.0 - n) * rs * rw * dx * dx);
        let d = 16.0 * e_oed * kw / ((1.0 - n) * rs * rw * dx.powi(4));
        let s = b + (b * b - 4.0 * d).max(0.0).sqrt();
        let c_dyn = dx * s / (-2.0 * a + (4.0 * a * a + 8.0 * s).sqrt());
        if !drag {
            return c_dyn;
        }
        let c_cons = 2.0 * self.consolidation_coefficient(e_oed) / dx;
        c_dyn.max(c_cons)
    }
}

/// Per-material constants of the liquid kernels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fluid<R: Real> {
    /// Porosity n.
    pub n: R,
    /// ρw.
    pub rho_w: R,
    /// Drag per unit mixture volume, n ρw g / k = n μ / κ.
    pub drag: R,
    /// K_w / n.
    pub kw_over_n: R,
    /// n / K_w (the liquid's compression energy, without a division per point).
    pub n_over_kw: R,
}

impl<R: Real> Fluid<R> {
    /// The constants of `spec`.
    pub fn new(spec: &LiquidSpec) -> Self {
        Fluid {
            n: R::of(spec.porosity),
            rho_w: R::of(spec.density),
            drag: R::of(spec.porosity * spec.density * G / spec.conductivity()),
            kw_over_n: R::of(spec.bulk_modulus / spec.porosity),
            n_over_kw: R::of(spec.porosity / spec.bulk_modulus),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::linear_elastic::LinearElastic;

    /// Anura3D's workshop oedometer (2D, right triangles with 0.1 m legs, so Δx = 0.1/√2)
    /// reports MaxWaveSpeed 0.1932E+03 and MinTimeStep 0.3660E-03.
    #[test]
    fn workshop_wave_speed_and_time_step() {
        let l = LiquidSpec::new(0.4, 1000.0, 2.15e4, 1.0214e-9, 1e-6).unwrap();
        assert!((l.conductivity() - 1.002e-2).abs() < 1e-5);
        let e_oed = LinearElastic::<f64>::oedometric(1000.0, 0.3);
        let dx = 0.1 / 2f64.sqrt();
        let c = l.wave_speed(2.65, e_oed, dx);
        assert!((c - 193.2).abs() < 0.05, "c = {c}");
        let dt = dx / c;
        assert!((dt - 3.660e-4).abs() < 5e-8, "dt = {dt}");
        // c_v of docs/design.md §6 (k E_oed / γw ≈ 1.37 m²/s) with the liquid's compressibility.
        let cv = l.conductivity() * e_oed / (G * 1.0) / (1.0 + 0.4 * e_oed / 2.15e4);
        assert!((l.consolidation_coefficient(e_oed) - cv).abs() < 1e-12);
        assert!((cv - 1.34).abs() < 0.01);
        // Without the explicit drag term the fastest wave is 4.6% slower here.
        let ci = l.wave_speed_implicit_drag(2.65, e_oed, dx);
        assert!((ci / c - 0.954).abs() < 0.001, "{ci} vs {c}");
    }

    #[test]
    fn implicit_drag_speed_does_not_depend_on_permeability() {
        let e_oed = LinearElastic::<f64>::oedometric(1000.0, 0.3);
        let speed = |kappa: f64| {
            LiquidSpec::new(0.4, 1000.0, 2.15e4, kappa, 1e-6)
                .unwrap()
                .wave_speed_implicit_drag(2.65, e_oed, 0.05)
        };
        let (high, low) = (speed(1e-6), speed(1e-16));
        assert!((high - low).abs() / low < 1e-9, "{high} vs {low}");
        // Faster than the undrained mixture's P wave, so the step is safe in that limit too.
        let undrained = ((e_oed + 2.15e4 / 0.4) / (0.6 * 2.65 + 0.4)).sqrt();
        assert!(low > undrained);
        // The explicit-drag formula explodes at low permeability: what the implicit drag avoids.
        let explicit = LiquidSpec::new(0.4, 1000.0, 2.15e4, 1e-16, 1e-6)
            .unwrap()
            .wave_speed(2.65, e_oed, 0.05);
        assert!(explicit > 1e3 * low, "{explicit} vs {low}");
        assert!(LiquidSpec::new(1.0, 1000.0, 1.0, 1.0, 1.0).is_err());
    }
}
