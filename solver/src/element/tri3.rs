//! The 3-node linear triangle of 2D models, in Anura3D's corner order: N1 = 1 - ξ - η, N2 = ξ,
//! N3 = η, the barycentric coordinates of corners 1-3.
//!
//! A triangle lies in the plane z = 0 and its element data are 3-vectors like every element's,
//! with zero z-gradients: the kernels' 3D strain then has ε_zz = γ_yz = γ_zx = 0, which is plane
//! strain, and σ_zz follows from the law. The axisymmetric variant ([`Tri3Axi`], x the radius r,
//! y the axis) is the same element with [`Element::AXISYMMETRIC`] set: the kernels add the hoop
//! strain u_r/r as ε_zz and its force, and every point's mass and volume are per radian (× r),
//! as Anura3D does.

use mpm_shared::{Dimension, ElementType};

use crate::element::{Element, Geometry};
use crate::four::Lanes;
use crate::real::{Real, V3};

/// The 3-node triangle; `AXI` selects the axisymmetric section (see the module's text).
#[derive(Debug, Clone, Copy, Default)]
pub struct Triangle<const AXI: bool>;

/// The plane-strain triangle.
pub type Tri3 = Triangle<false>;

/// The axisymmetric triangle (x radial, y axial).
pub type Tri3Axi = Triangle<true>;

/// Corners of the edge opposite corner `k` (face k is opposite corner k).
pub const EDGE_OPPOSITE: [[usize; 2]; 3] = [[1, 2], [0, 2], [0, 1]];

/// Anura3D's local coordinates of its 3-point rule (ξ, η), written as Anura3D writes them (14
/// digits, not 1/6 and 2/3) so that the points start where Anura3D's do; point k is nearest
/// corner k.
const THREE_POINTS: [[f64; 2]; 3] = [
    [0.166_666_666_666_67, 0.166_666_666_666_67],
    [0.666_666_666_666_67, 0.166_666_666_666_67],
    [0.166_666_666_666_67, 0.666_666_666_666_67],
];

/// Anura3D's one point: its centroid as written in its source.
const ONE_POINT: [f64; 2] = [0.333_333_333_333_33, 0.333_333_333_333_33];

/// Shape values [1 - ξ - η, ξ, η] of local coordinates (ξ, η).
fn barycentric([xi, eta]: [f64; 2]) -> [f64; 3] {
    [1.0 - xi - eta, xi, eta]
}

impl<const AXI: bool> Element for Triangle<AXI> {
    const NAME: &'static str = if AXI {
        "3-node triangles (axisymmetric)"
    } else {
        "3-node triangles (plane strain)"
    };
    const DIM: usize = 2;
    const NODES: usize = 3;
    const FACES: usize = 3;
    const AXISYMMETRIC: bool = AXI;
    type Nodes<T: Copy + std::fmt::Debug + Send + Sync + 'static> = [T; 3];
    type Faces<T: Copy + std::fmt::Debug + Send + Sync + 'static> = [T; 3];
    /// Rows of J⁻¹ in the plane: `ξ = map[0] · (x - x1)`, `η = map[1] · (x - x1)` (x and y).
    type Map<R: Real> = [[R; 2]; 2];

    fn computes(dimension: Dimension, element: ElementType) -> bool {
        let section = if AXI {
            Dimension::Axisymmetric
        } else {
            Dimension::PlaneStrain
        };
        element == ElementType::Tri3 && dimension == section
    }

    fn nodes<T: Copy + std::fmt::Debug + Send + Sync + 'static>(
        f: impl FnMut(usize) -> T,
    ) -> [T; 3] {
        std::array::from_fn(f)
    }

    fn faces<T: Copy + std::fmt::Debug + Send + Sync + 'static>(
        f: impl FnMut(usize) -> T,
    ) -> [T; 3] {
        std::array::from_fn(f)
    }

    fn face(k: usize) -> &'static [usize] {
        &EDGE_OPPOSITE[k]
    }

    fn geometry<R: Real>(p: &[[f64; 3]; 3]) -> Result<Geometry<Self, R>, f64> {
        // Columns of J: corners 2 and 3 relative to corner 1, in the plane.
        let a = [p[1][0] - p[0][0], p[1][1] - p[0][1]];
        let b = [p[2][0] - p[0][0], p[2][1] - p[0][1]];
        let det = a[0] * b[1] - a[1] * b[0];
        // Counter-clockwise corners, as Anura3D's meshes have them.
        if det <= 0.0 || !det.is_finite() {
            return Err(det / 2.0);
        }
        let xi = [b[1] / det, -b[0] / det];
        let eta = [-a[1] / det, a[0] / det];
        let g1 = [-(xi[0] + eta[0]), -(xi[1] + eta[1])];
        let edge = |i: usize, j: usize| {
            let d = [p[j][0] - p[i][0], p[j][1] - p[i][1]];
            (d[0] * d[0] + d[1] * d[1]).sqrt()
        };
        let longest = edge(0, 1).max(edge(1, 2)).max(edge(0, 2));
        let g3 = |g: [f64; 2]| [R::of(g[0]), R::of(g[1]), R::ZERO];
        Ok(Geometry {
            map: [xi.map(R::of), eta.map(R::of)],
            grad: [g3(g1), g3(xi), g3(eta)],
            volume: R::of(det / 2.0),
            // Altitude over the longest edge: 2A / L.
            min_altitude: R::of(det / longest),
        })
    }

    #[inline(always)]
    fn shape<R: Real>(m: &[[R; 2]; 2], x1: &V3<R>, p: &V3<R>) -> [R; 3] {
        let d = [p[0] - x1[0], p[1] - x1[1]];
        let xi = m[0][0] * d[0] + m[0][1] * d[1];
        let eta = m[1][0] * d[0] + m[1][1] * d[1];
        [R::ONE - xi - eta, xi, eta]
    }

    #[inline(always)]
    fn shape_lanes<R: Real, const W: usize>(
        m: &[[R; 2]; 2],
        x1: &V3<R>,
        x: &[[R; W]; 3],
    ) -> [[R; W]; 4] {
        let d: [[R; W]; 2] = std::array::from_fn(|a| x[a].map(|v| v - x1[a]));
        let xi = std::array::from_fn(|q| m[0][0] * d[0][q] + m[0][1] * d[1][q]);
        let eta = std::array::from_fn(|q| m[1][0] * d[0][q] + m[1][1] * d[1][q]);
        let n1 = std::array::from_fn(|q| R::ONE - xi[q] - eta[q]);
        [n1, xi, eta, [R::ZERO; W]]
    }

    #[inline(always)]
    fn shape_four<R: Real, F: Lanes<R>>(
        t: F::Token,
        m: &[[R; 2]; 2],
        x1: &V3<R>,
        x: &[F; 3],
    ) -> [F; 4] {
        let s = |v: R| F::splat(t, v);
        let d: [F; 2] = std::array::from_fn(|a| x[a] - s(x1[a]));
        let xi = s(m[0][0]) * d[0] + s(m[0][1]) * d[1];
        let eta = s(m[1][0]) * d[0] + s(m[1][1]) * d[1];
        [s(R::ONE) - xi - eta, xi, eta, s(R::ZERO)]
    }

    #[inline]
    fn exit_face<R: Real>(l: &[R; 3], tol: R) -> Option<usize> {
        let (mut k, mut lo) = (0, l[0]);
        for (j, &v) in l.iter().enumerate().skip(1) {
            if v < lo {
                (k, lo) = (j, v);
            }
        }
        (lo < tol).then_some(k)
    }

    /// 1 (the centroid) and 3 (the 3-point Gauss rule, point k nearest corner k), at Anura3D's
    /// local coordinates; equal areas.
    fn point_placement(n: u32) -> Option<Vec<[f64; 3]>> {
        match n {
            0 => Some(Vec::new()),
            1 => Some(vec![barycentric(ONE_POINT)]),
            3 => Some(THREE_POINTS.iter().map(|&l| barycentric(l)).collect()),
            _ => None,
        }
    }

    /// The one point of a 1-point element; of 3, the two nearest the edge's corners (Anura3D's
    /// side table for three points).
    fn face_load_points(n: usize, face: usize) -> Vec<usize> {
        match n {
            3 => (0..3).filter(|&k| k != face).collect(),
            n => (0..n).collect(),
        }
    }

    fn supported_point_counts() -> &'static str {
        "1 or 3"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placed_points_are_inside_and_near_their_corners() {
        for n in [1, 3] {
            let pts = Tri3::point_placement(n).unwrap();
            assert_eq!(pts.len(), n as usize);
            for l in &pts {
                assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-15);
                assert!(l.iter().all(|&v| v > 0.0));
            }
        }
        let three = Tri3::point_placement(3).unwrap();
        for (k, l) in three.iter().enumerate() {
            assert!(l[k] > 0.6, "point {k} is nearest corner {k}");
        }
        assert!(Tri3::point_placement(4).is_none());
        // An edge load on edge k is carried by the two points nearest that edge.
        for k in 0..3 {
            let on = Tri3::face_load_points(3, k);
            assert!(on.iter().all(|&i| three[i][k] < 0.2), "edge {k}");
        }
    }

    #[test]
    fn geometry_of_a_right_triangle() {
        let x = [[1.0, 2.0, 0.0], [3.0, 2.0, 0.0], [1.0, 3.0, 0.0]];
        let g = Tri3::geometry::<f64>(&x).unwrap();
        assert!((g.volume - 1.0).abs() < 1e-15);
        // Altitude over the hypotenuse √5: 2A/L.
        assert!((g.min_altitude - 2.0 / 5f64.sqrt()).abs() < 1e-15);
        // Gradients reproduce a linear field f = 2x - 3y exactly, and have no z-part.
        let f = x.map(|p| 2.0 * p[0] - 3.0 * p[1]);
        for d in 0..2 {
            let s: f64 = (0..3).map(|k| f[k] * g.grad[k][d]).sum();
            assert!((s - [2.0, -3.0][d]).abs() < 1e-14);
        }
        assert!(g.grad.iter().all(|v| v[2] == 0.0));
        // Shape values at the corners are the identity, and the exit face is the edge opposite
        // the most negative coordinate.
        for (k, p) in x.iter().enumerate() {
            let n = Tri3::shape(&g.map, &x[0], p);
            for (j, v) in n.iter().enumerate() {
                assert!((v - if j == k { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        let out = Tri3::shape(&g.map, &x[0], &[0.5, 2.5, 0.0]);
        assert_eq!(Tri3::exit_face(&out, -1e-10), Some(1));
        // Clockwise corners are refused with the signed area.
        let cw = [x[0], x[2], x[1]];
        assert_eq!(Tri3::geometry::<f64>(&cw).unwrap_err(), -1.0);
    }

    #[test]
    fn each_variant_computes_its_own_section() {
        assert!(Tri3::computes(Dimension::PlaneStrain, ElementType::Tri3));
        assert!(!Tri3::computes(Dimension::Axisymmetric, ElementType::Tri3));
        assert!(Tri3Axi::computes(
            Dimension::Axisymmetric,
            ElementType::Tri3
        ));
        assert!(!Tri3Axi::computes(
            Dimension::Cartesian3D,
            ElementType::Tet4
        ));
    }
}
