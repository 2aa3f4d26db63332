//! The stresses (and pore pressures) material points start with: Anura3D's K0 procedure
//! (`$$K0_PROCEDURE 1`, a scene material's `k0`) and uniform stresses (a scene material's
//! `initial_stress`). Resolved once from the input into [`InitialStress`]; the engine applies it
//! when it places the points, before the first step (a resumed run takes the checkpoint's
//! stresses instead).
//!
//! Anura3D's K0 procedure, as its source computes it for single-point materials without a
//! soil or phreatic surface given node by node:
//! - every point of an element takes the value at the element's Gauss point (its centroid, from
//!   the initial corner coordinates);
//! - the depth d ≤ 0 of that point is its distance below the ground line through
//!   (0, `$$SURFACE_ELEVATION`) perpendicular to the x-y components of `$$GRAVITY_VECTOR`
//!   (0 above the line); z plays no part;
//! - the total vertical stress is σy = d γ f + q: γ the unit weight of the point's *own*
//!   material (not of the materials above it), f the gravity multiplier at the start (the first
//!   value of `$$GRAVITY_LOAD`), q = `$$INITIAL_VERTICAL_LOAD_K0` times the first value of
//!   `$$SOLID_TRACTION`;
//! - the pore pressure is p = d γw f, capped at `$$K0_MAX_SUCTION`, and 0 in dry materials;
//! - the effective stresses are σ'yy = σy - p and σ'xx = σ'zz = K0 σ'yy, no shear, whatever the
//!   direction of gravity; an undrained-total material takes σ'yy = σy and no pore pressure.

/// Anura3D's K0 procedure, resolved for a case: the settings shared by every material.
#[derive(Debug, Clone, PartialEq)]
pub struct K0Procedure {
    /// A point (x, y) of the ground line: (0, `$$SURFACE_ELEVATION`).
    pub surface_point: [f64; 2],
    /// The x and y components of the gravity direction, as given (`$$GRAVITY_VECTOR`).
    pub gravity_direction: [f64; 2],
    /// Gravity multiplier at the start (the first value of `$$GRAVITY_LOAD`; 0 when off).
    pub gravity_factor: f64,
    /// Vertical stress added at every depth (kPa, tension positive).
    pub surface_load: f64,
    /// Pore pressures above this are cut to it (kPa; `$$K0_MAX_SUCTION`).
    pub max_suction: f64,
}

/// Anura3D's default `$$K0_MAX_SUCTION` (kPa): no cut in practice.
pub const DEFAULT_MAX_SUCTION: f64 = 1e10;

/// How a material's pore pressure enters its K0 stresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum K0Pores {
    /// A dry material: no pore pressure, effective = total.
    Dry,
    /// Anura3D's undrained-total material: effective = total, no pore pressure.
    Total,
    /// Effective stress = total - pore pressure (saturated coupled and drained materials).
    Effective,
}

/// One material's part of the K0 procedure.
#[derive(Debug, Clone, PartialEq)]
pub struct K0Material {
    /// Horizontal over vertical effective stress.
    pub k0: f64,
    /// Unit weight γ the vertical stress grows with (kN/m³), as Anura3D picks it for the case.
    pub unit_weight: f64,
    /// Unit weight of the pore liquid γw (kN/m³; 0 when it carries no pore pressure).
    pub liquid_unit_weight: f64,
    /// How the pore pressure enters.
    pub pores: K0Pores,
    /// Whether the solver keeps a pore pressure for this material's points (a saturated,
    /// two-phase material): the K0 pore pressure is then their initial one.
    pub sets_pore_pressure: bool,
}

/// How one material's points start.
#[derive(Debug, Clone, PartialEq)]
pub enum MaterialStart {
    /// Stresses from the K0 procedure ([`InitialStress::k0`] holds its shared settings).
    K0(K0Material),
    /// The same effective stress everywhere (kPa, tension positive; xx yy zz xy yz zx).
    Uniform([f64; 6]),
}

/// The initial stresses of a case.
#[derive(Debug, Clone, PartialEq)]
pub struct InitialStress {
    /// The K0 procedure's shared settings (`None` when no material uses it).
    pub k0: Option<K0Procedure>,
    /// Per material index (entry 0 unused): how its points start (`None`: unstressed).
    pub materials: Vec<Option<MaterialStart>>,
}

/// A point's initial state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointStart {
    /// Effective stress (kPa, tension positive; xx yy zz xy yz zx).
    pub stress: [f64; 6],
    /// Pore pressure (kPa, compression negative), for points that keep one.
    pub pore_pressure: Option<f64>,
}

impl K0Procedure {
    /// Depth of `p` (its x and y) below the ground line, ≤ 0 (0 on or above it), as Anura3D
    /// measures it: along the normal to gravity's x-y direction.
    pub fn depth(&self, p: [f64; 2]) -> f64 {
        let s = self.surface_point;
        let g = self.gravity_direction;
        // The ground line's direction: gravity's x-y part turned by a right angle.
        let along = [-g[1], g[0]];
        let offset = [p[0] - s[0], p[1] - s[1]];
        let t = offset[0] * along[0] + offset[1] * along[1];
        let foot = [s[0] + t * along[0], s[1] + t * along[1]];
        let to_foot = [foot[0] - p[0], foot[1] - p[1]];
        let mut depth = (to_foot[0] * to_foot[0] + to_foot[1] * to_foot[1]).sqrt();
        // Which side of the line: at or below it the depth counts negative.
        let side = along[0] * (p[1] - s[1]) - along[1] * (p[0] - s[0]);
        if side <= 0.0 {
            depth = -depth;
        }
        if depth >= 0.0 {
            0.0
        } else {
            depth
        }
    }

    /// The K0 state of a point of material `m` at `p` (its x and y).
    pub fn at(&self, m: &K0Material, p: [f64; 2]) -> PointStart {
        let depth = self.depth(p);
        let f = self.gravity_factor;
        // Same order of operations as Anura3D, so the two agree to the last bit.
        let total = depth * m.unit_weight * f + self.surface_load;
        let mut pore = depth * m.liquid_unit_weight * f;
        if pore > self.max_suction {
            pore = self.max_suction;
        }
        let (vertical, pore) = match m.pores {
            K0Pores::Dry | K0Pores::Total => (total, 0.0),
            K0Pores::Effective => (total - pore, pore),
        };
        let horizontal = m.k0 * vertical;
        PointStart {
            stress: [horizontal, vertical, horizontal, 0.0, 0.0, 0.0],
            pore_pressure: m.sets_pore_pressure.then_some(pore),
        }
    }
}

impl InitialStress {
    /// The initial state of a point of material `material` whose element has the corner
    /// coordinates `corners` (four of a tetrahedron, three of a triangle; `None`: the material
    /// starts unstressed).
    pub fn at(&self, material: usize, corners: &[[f64; 3]]) -> Option<PointStart> {
        match self.materials.get(material)?.as_ref()? {
            MaterialStart::Uniform(s) => Some(PointStart {
                stress: *s,
                pore_pressure: None,
            }),
            MaterialStart::K0(m) => {
                let k0 = self.k0.as_ref()?;
                let c = gauss_point(corners);
                Some(k0.at(m, [c[0], c[1]]))
            }
        }
    }

    /// Whether any material starts stressed.
    pub fn is_empty(&self) -> bool {
        self.materials.iter().all(Option::is_none)
    }
}

/// The Gauss point of a linear tetrahedron or triangle (its centroid), summed corner by corner
/// with Anura3D's shape values there (for a triangle its local coordinates 0.33333333333333, as
/// its source writes them).
pub fn gauss_point(corners: &[[f64; 3]]) -> [f64; 3] {
    const THIRD: f64 = 0.333_333_333_333_33;
    let weight = |k: usize| match corners.len() {
        3 if k == 0 => 1.0 - THIRD - THIRD,
        3 => THIRD,
        n => 1.0 / n as f64,
    };
    let mut c = [0.0; 3];
    for (k, p) in corners.iter().enumerate() {
        for d in 0..3 {
            c[d] += weight(k) * p[d];
        }
    }
    c
}

/// Anura3D's K0 unit weights (kN/m³) of a material: (γ, γw). `grains` ρs, `liquid` ρw
/// (kg/m³, 0 for a dry material), porosity `n`, gravity `g` (m/s²); `coupled_case`: some
/// material of the case is saturated and coupled (Anura3D then uses the mixture's weight);
/// `submerged`: some material is drained (Anura3D's submerged calculation: buoyant weights, no
/// pore pressure); `mixture`: the material itself holds liquid in its weight (not a dry one).
pub fn k0_unit_weights(
    n: f64,
    grains: f64,
    liquid: f64,
    g: f64,
    coupled_case: bool,
    submerged: bool,
    mixture: bool,
) -> (f64, f64) {
    let dry_density = (1.0 - n) * grains;
    let mixture_density = if mixture {
        (1.0 - n) * grains + n * liquid
    } else {
        dry_density
    };
    if submerged {
        ((mixture_density - liquid) * g / 1000.0, 0.0)
    } else if coupled_case {
        (mixture_density * g / 1000.0, liquid * g / 1000.0)
    } else {
        ((1.0 - n) * grains * g / 1000.0, liquid * g / 1000.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn procedure(surface: f64) -> K0Procedure {
        K0Procedure {
            surface_point: [0.0, surface],
            gravity_direction: [0.0, -1.0],
            gravity_factor: 1.0,
            surface_load: 0.0,
            max_suction: DEFAULT_MAX_SUCTION,
        }
    }

    #[test]
    fn depth_is_below_the_surface_and_zero_above() {
        let k = procedure(10.0);
        assert_eq!(k.depth([3.0, 7.5]), -2.5);
        assert_eq!(k.depth([-4.0, 0.0]), -10.0);
        assert_eq!(k.depth([0.0, 10.0]), 0.0);
        assert_eq!(k.depth([0.0, 12.0]), 0.0);
        // Gravity along -x: the ground line is vertical, depth counts along x.
        let k = K0Procedure {
            surface_point: [0.0, 0.0],
            gravity_direction: [-1.0, 0.0],
            ..procedure(0.0)
        };
        assert_eq!(k.depth([-2.0, 5.0]), -2.0);
        assert_eq!(k.depth([2.0, 5.0]), 0.0);
    }

    #[test]
    fn dry_column_by_hand() {
        // 2000 kg/m³ dry, g = 10: γ = 20 kN/m³; 3 m below the surface σ'yy = -60 kPa, and
        // σ'xx = σ'zz = 0.5 × -60 = -30 kPa; a surface load of -5 kPa adds to the vertical.
        let (gamma, gw) = k0_unit_weights(0.0, 2000.0, 0.0, 10.0, false, false, false);
        assert_eq!((gamma, gw), (20.0, 0.0));
        let m = K0Material {
            k0: 0.5,
            unit_weight: gamma,
            liquid_unit_weight: gw,
            pores: K0Pores::Dry,
            sets_pore_pressure: false,
        };
        let s = procedure(4.0).at(&m, [0.3, 1.0]);
        assert_eq!(s.stress, [-30.0, -60.0, -30.0, 0.0, 0.0, 0.0]);
        assert_eq!(s.pore_pressure, None);
        let k = K0Procedure {
            surface_load: -5.0,
            ..procedure(4.0)
        };
        assert_eq!(k.at(&m, [0.0, 1.0]).stress[1], -65.0);
        // Half the gravity at the start: half the weight.
        let k = K0Procedure {
            gravity_factor: 0.5,
            ..procedure(4.0)
        };
        assert_eq!(k.at(&m, [0.0, 1.0]).stress[1], -30.0);
    }

    #[test]
    fn saturated_column_by_hand() {
        // n = 0.5, ρs = 2000, ρw = 1000, g = 10: γ = (1000 + 500) × 10 / 1000 = 15, γw = 10;
        // 2 m deep: σ = -30, p = -20, σ' = -10, horizontal 0.4 × -10 = -4.
        let (gamma, gw) = k0_unit_weights(0.5, 2000.0, 1000.0, 10.0, true, false, true);
        assert_eq!((gamma, gw), (15.0, 10.0));
        let m = K0Material {
            k0: 0.4,
            unit_weight: gamma,
            liquid_unit_weight: gw,
            pores: K0Pores::Effective,
            sets_pore_pressure: true,
        };
        let s = procedure(0.0).at(&m, [0.0, -2.0]);
        assert_eq!(s.stress, [-4.0, -10.0, -4.0, 0.0, 0.0, 0.0]);
        assert_eq!(s.pore_pressure, Some(-20.0));
        // A suction cap below the pressure replaces it.
        let k = K0Procedure {
            max_suction: -25.0,
            ..procedure(0.0)
        };
        let s = k.at(&m, [0.0, -2.0]);
        assert_eq!((s.stress[1], s.pore_pressure), (-5.0, Some(-25.0)));
        // Undrained total: σ' = σ, no pore pressure.
        let t = K0Material {
            pores: K0Pores::Total,
            sets_pore_pressure: false,
            ..m
        };
        assert_eq!(procedure(0.0).at(&t, [0.0, -2.0]).stress[1], -30.0);
    }

    #[test]
    fn weights_follow_anura3d_choice_per_case() {
        // One-phase case: the dry weight (1 - n) ρs g, even for an undrained-total soil.
        let (g1, _) = k0_unit_weights(0.4, 2500.0, 1000.0, 10.0, false, false, true);
        assert!((g1 - 15.0).abs() < 1e-12);
        // Submerged (a drained material in the case): buoyant, no liquid weight.
        let (g2, w2) = k0_unit_weights(0.4, 2500.0, 1000.0, 10.0, false, true, true);
        assert!((g2 - 9.0).abs() < 1e-12 && w2 == 0.0);
        // A dry material in a submerged case keeps its dry weight.
        let (g3, _) = k0_unit_weights(0.4, 2500.0, 0.0, 10.0, false, true, false);
        assert!((g3 - 15.0).abs() < 1e-12);
    }

    #[test]
    fn every_point_of_an_element_takes_its_centroid_value() {
        let init = InitialStress {
            k0: Some(procedure(1.0)),
            materials: vec![
                None,
                Some(MaterialStart::K0(K0Material {
                    k0: 0.5,
                    unit_weight: 20.0,
                    liquid_unit_weight: 0.0,
                    pores: K0Pores::Dry,
                    sets_pore_pressure: false,
                })),
                Some(MaterialStart::Uniform([
                    -100.0, -100.0, -100.0, 0.0, 0.0, 0.0,
                ])),
                None,
            ],
        };
        let tet = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        assert_eq!(gauss_point(&tet), [0.25, 0.25, 0.25]);
        // Centroid 0.75 below the surface: σ'yy = -15.
        assert_eq!(init.at(1, &tet).unwrap().stress[1], -15.0);
        assert_eq!(init.at(2, &tet).unwrap().stress[0], -100.0);
        assert_eq!(init.at(3, &tet), None);
        assert_eq!(init.at(9, &tet), None);
        assert!(!init.is_empty());
    }
}
