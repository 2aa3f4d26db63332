//! Incremental small-strain linear elasticity (Anura3D's `linear_elasticity`).

use crate::material::definition::{
    Bound, ConstitutiveLaw, LawDefinition, Parameter, ParameterError,
};
use crate::real::Real;

/// Linear elasticity's parameters, checked: E > 0, -1 < ν < 0.5.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearElasticSpec {
    /// Young's modulus (kPa).
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
}

/// Young's modulus and Poisson's ratio, the elastic part of every law.
pub const ELASTIC_PARAMETERS: [Parameter; 2] = [
    Parameter::new("YOUNG_MODULUS", "kPa", "Young's modulus E")
        .range(Bound::Open(0.0), Bound::Open(f64::INFINITY)),
    Parameter::new("POISSON_RATIO", "", "Poisson's ratio ν")
        .range(Bound::Open(-1.0), Bound::Open(0.5)),
];

impl LinearElasticSpec {
    /// Checked: E > 0 and finite, -1 < ν < 0.5.
    pub fn new(young: f64, poisson: f64) -> Result<Self, ParameterError> {
        if !(young > 0.0 && young.is_finite()) {
            return Err(ParameterError(format!(
                "Young's modulus must be positive, got {young}"
            )));
        }
        if !(poisson > -1.0 && poisson < 0.5) {
            return Err(ParameterError(format!(
                "Poisson's ratio must be in (-1, 0.5), got {poisson}"
            )));
        }
        Ok(LinearElasticSpec { young, poisson })
    }
}

impl LawDefinition for LinearElasticSpec {
    const NAME: &'static str = "linear_elasticity";
    const PARAMETERS: &'static [Parameter] = &ELASTIC_PARAMETERS;
    type Law<R: Real> = LinearElastic<R>;

    fn read(get: &dyn Fn(&str) -> Option<f64>) -> Result<Self, ParameterError> {
        Self::new(
            Self::need(get, "YOUNG_MODULUS")?,
            Self::need(get, "POISSON_RATIO")?,
        )
    }

    fn values(&self) -> Vec<f64> {
        vec![self.young, self.poisson]
    }

    fn elastic(&self) -> (f64, f64) {
        (self.young, self.poisson)
    }

    fn state_len(&self) -> usize {
        0
    }

    fn build<R: Real>(&self) -> LinearElastic<R> {
        LinearElastic::new(self.young, self.poisson)
    }

    fn examples() -> Vec<Self> {
        vec![
            LinearElasticSpec {
                young: 1e4,
                poisson: 0.3,
            },
            // Negative and nearly incompressible.
            LinearElasticSpec {
                young: 2.5e4,
                poisson: -0.4,
            },
            LinearElasticSpec {
                young: 1e3,
                poisson: 0.49,
            },
        ]
    }
}

impl<R: Real> ConstitutiveLaw<R> for LinearElastic<R> {
    #[inline(always)]
    fn update(&self, stress: &mut [R; 6], de: &[R; 6], _: &mut [R]) {
        LinearElastic::update(self, stress, de);
    }

    fn yield_function(&self, _: &[R; 6], _: &[R]) -> Option<R> {
        None
    }
}

/// Isotropic linear elastic law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearElastic<R: Real> {
    /// Lamé's first parameter (kPa).
    pub lambda: R,
    /// Shear modulus (kPa).
    pub shear: R,
}

impl<R: Real> LinearElastic<R> {
    /// From Young's modulus (kPa) and Poisson's ratio.
    pub fn new(young: f64, poisson: f64) -> Self {
        let g = young / (2.0 * (1.0 + poisson));
        let l = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
        LinearElastic {
            lambda: R::of(l),
            shear: R::of(g),
        }
    }

    /// Oedometric (constrained) modulus 2G(1-ν)/(1-2ν) = λ + 2G.
    pub fn oedometric(young: f64, poisson: f64) -> f64 {
        2.0 * young / (2.0 * (1.0 + poisson)) * (1.0 - poisson) / (1.0 - 2.0 * poisson)
    }

    /// Adds the stress increment of strain increment `de` (xx yy zz xy yz zx, tensor shear
    /// components) to `s`.
    #[inline]
    pub fn update(&self, s: &mut [R; 6], de: &[R; 6]) {
        let mut lanes = s.map(|x| [x]);
        self.update_lanes::<1>(&mut lanes, &de.map(|x| [x]));
        *s = lanes.map(|[x]| x);
    }

    /// What [`LinearElastic::update`] adds to each component for strain increment `de`: the
    /// same operations, so `s[c] + increment(de)[c]` is the updated component to the bit (for
    /// passes that share one increment among the points of an element).
    #[inline(always)]
    pub fn increment(&self, de: &[R; 6]) -> [R; 6] {
        let g2 = self.shear + self.shear;
        let tr = self.lambda * (de[0] + de[1] + de[2]);
        std::array::from_fn(|c| if c < 3 { tr + g2 * de[c] } else { g2 * de[c] })
    }

    /// [`LinearElastic::update`] of `W` points at once (`s[c][q]`, `de[c][q]`: component c of
    /// point q), each point's arithmetic the one-point update's.
    #[inline(always)]
    pub fn update_lanes<const W: usize>(&self, s: &mut [[R; W]; 6], de: &[[R; W]; 6]) {
        let g2 = self.shear + self.shear;
        for q in 0..W {
            let tr = self.lambda * (de[0][q] + de[1][q] + de[2][q]);
            s[0][q] += tr + g2 * de[0][q];
            s[1][q] += tr + g2 * de[1][q];
            s[2][q] += tr + g2 * de[2][q];
            s[3][q] += g2 * de[3][q];
            s[4][q] += g2 * de[4][q];
            s[5][q] += g2 * de[5][q];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_increment_is_what_the_update_adds() {
        let law = LinearElastic::<f64>::new(2.5e4, 0.27);
        let mut rng = crate::test_rng::uniform(3);
        for _ in 0..200 {
            let s0: [f64; 6] = std::array::from_fn(|_| (rng() - 0.5) * 1e3);
            let de: [f64; 6] = std::array::from_fn(|_| (rng() - 0.5) * 1e-4);
            let mut s = s0;
            law.update(&mut s, &de);
            let inc = law.increment(&de);
            for c in 0..6 {
                assert_eq!(s[c].to_bits(), (s0[c] + inc[c]).to_bits(), "component {c}");
            }
        }
    }

    #[test]
    fn uniaxial_strain_gives_oedometric_modulus() {
        let law = LinearElastic::<f64>::new(1000.0, 0.3);
        let mut s = [0.0; 6];
        law.update(&mut s, &[0.0, -1e-3, 0.0, 0.0, 0.0, 0.0]);
        let eoed = LinearElastic::<f64>::oedometric(1000.0, 0.3);
        assert!((s[1] + eoed * 1e-3).abs() < 1e-9);
        assert!((eoed - 1346.153846153846).abs() < 1e-9);
        // Lateral stress: K0 = ν / (1 - ν).
        assert!((s[0] / s[1] - 0.3 / 0.7).abs() < 1e-12);
    }
}
