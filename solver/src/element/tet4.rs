//! The 4-node linear tetrahedron in Anura3D's corner order: N1 = 1 - ξ - η - ζ, N2 = ζ, N3 = ξ,
//! N4 = η, which are the barycentric coordinates of corners 1-4.

use mpm_shared::{Dimension, ElementType};

use crate::element::{Element, Geometry};
use crate::four::Lanes;
use crate::real::{Real, V3};

/// The 4-node linear tetrahedron (10-node models are computed with their corners, as Anura3D
/// does).
#[derive(Debug, Clone, Copy, Default)]
pub struct Tet4;

/// Corners of the face opposite corner `k` (face k is opposite corner k).
pub const FACE_OPPOSITE: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The edges (corner pairs) of the 10-point rule's points 5 to 10, in Anura3D's order: its local
/// coordinates (ξ, η, ζ) are the shape values of corners 2, 3 and 1, and corner 0 takes the rest.
const TEN_POINT_EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

impl Element for Tet4 {
    const NAME: &'static str = "4-node tetrahedra";
    const DIM: usize = 3;
    const NODES: usize = 4;
    const FACES: usize = 4;
    type Nodes<T: Copy + std::fmt::Debug + Send + Sync + 'static> = [T; 4];
    type Faces<T: Copy + std::fmt::Debug + Send + Sync + 'static> = [T; 4];
    /// Rows 2-4 of the barycentric map: `λ(k+2) = map[k] · (x - x1)`, and `λ1 = 1 - λ2 - λ3 - λ4`.
    type Map<R: Real> = [V3<R>; 3];

    fn computes(dimension: Dimension, element: ElementType) -> bool {
        dimension == Dimension::Cartesian3D
            && matches!(element, ElementType::Tet4 | ElementType::Tet10)
    }

    fn nodes<T: Copy + std::fmt::Debug + Send + Sync + 'static>(
        f: impl FnMut(usize) -> T,
    ) -> [T; 4] {
        std::array::from_fn(f)
    }

    fn faces<T: Copy + std::fmt::Debug + Send + Sync + 'static>(
        f: impl FnMut(usize) -> T,
    ) -> [T; 4] {
        std::array::from_fn(f)
    }

    fn face(k: usize) -> &'static [usize] {
        &FACE_OPPOSITE[k]
    }

    fn geometry<R: Real>(p: &[[f64; 3]; 4]) -> Result<Geometry<Self, R>, f64> {
        // Columns of J: corners 2, 3, 4 relative to corner 1.
        let (a, b, d) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
        let det = dot(a, cross(b, d));
        // Anura3D's orientation: det[x3-x1, x4-x1, x2-x1] = det[a, b, d] by cyclic shift.
        if det <= 0.0 || !det.is_finite() {
            return Err(det / 6.0);
        }
        // Rows of J^-1 = (b×d, d×a, a×b) / det give λ2, λ3, λ4.
        let rows = [cross(b, d), cross(d, a), cross(a, b)].map(|r| r.map(|v| v / det));
        let g1 = [0, 1, 2].map(|k| -(rows[0][k] + rows[1][k] + rows[2][k]));
        let max_area2 = FACE_OPPOSITE
            .iter()
            .map(|f| {
                let n = cross(sub(p[f[1]], p[f[0]]), sub(p[f[2]], p[f[0]]));
                dot(n, n).sqrt()
            })
            .fold(0.0, f64::max);
        Ok(Geometry {
            map: rows.map(|r| r.map(R::of)),
            grad: [g1, rows[0], rows[1], rows[2]].map(|g| g.map(R::of)),
            volume: R::of(det / 6.0),
            // Altitude over the largest face: 3V / A = det / |n|.
            min_altitude: R::of(det / max_area2),
        })
    }

    // Always inlined: a dozen flops called once per point in every pass over the points, which
    // the compiler otherwise left as a call (measured: 4 % of a step in the call alone).
    #[inline(always)]
    fn shape<R: Real>(m: &[V3<R>; 3], x1: &V3<R>, p: &V3<R>) -> [R; 4] {
        let d = [p[0] - x1[0], p[1] - x1[1], p[2] - x1[2]];
        let l2 = m[0][0] * d[0] + m[0][1] * d[1] + m[0][2] * d[2];
        let l3 = m[1][0] * d[0] + m[1][1] * d[1] + m[1][2] * d[2];
        let l4 = m[2][0] * d[0] + m[2][1] * d[1] + m[2][2] * d[2];
        [R::ONE - l2 - l3 - l4, l2, l3, l4]
    }

    #[inline(always)]
    fn shape_lanes<R: Real, const W: usize>(
        m: &[V3<R>; 3],
        x1: &V3<R>,
        x: &[[R; W]; 3],
    ) -> [[R; W]; 4] {
        let d: [[R; W]; 3] = std::array::from_fn(|a| x[a].map(|v| v - x1[a]));
        let row = |r: &V3<R>| -> [R; W] {
            std::array::from_fn(|q| r[0] * d[0][q] + r[1] * d[1][q] + r[2] * d[2][q])
        };
        let (l2, l3, l4) = (row(&m[0]), row(&m[1]), row(&m[2]));
        let l1 = std::array::from_fn(|q| R::ONE - l2[q] - l3[q] - l4[q]);
        [l1, l2, l3, l4]
    }

    #[inline(always)]
    fn shape_four<R: Real, F: Lanes<R>>(
        t: F::Token,
        m: &[V3<R>; 3],
        x1: &V3<R>,
        x: &[F; 3],
    ) -> [F; 4] {
        let s = |v: R| F::splat(t, v);
        let d: [F; 3] = std::array::from_fn(|a| x[a] - s(x1[a]));
        let row = |r: &V3<R>| s(r[0]) * d[0] + s(r[1]) * d[1] + s(r[2]) * d[2];
        let (l2, l3, l4) = (row(&m[0]), row(&m[1]), row(&m[2]));
        [s(R::ONE) - l2 - l3 - l4, l2, l3, l4]
    }

    #[inline]
    fn exit_face<R: Real>(l: &[R; 4], tol: R) -> Option<usize> {
        let (mut k, mut lo) = (0, l[0]);
        for (j, &v) in l.iter().enumerate().skip(1) {
            if v < lo {
                (k, lo) = (j, v);
            }
        }
        (lo < tol).then_some(k)
    }

    /// 1 (centroid), 4 (the 4-point Gauss rule, a = (5 - √5)/20 ≈ 0.1381966,
    /// b = (5 + 3√5)/20 ≈ 0.5854102, point k nearest corner k) and 10 (those four, then one
    /// point per edge with the edge's two coordinates c = (a + b)/2 and the other two a, edges
    /// in Anura3D's order 0–1, 0–2, 0–3, 1–2, 1–3, 2–3), exactly as Anura3D places them; equal
    /// volumes.
    fn point_placement(n: u32) -> Option<Vec<[f64; 4]>> {
        // (5 - √5)/20 and (5 + 3√5)/20, written out (sqrt is not const).
        const A: f64 = 0.138_196_601_125_010_5;
        const B: f64 = 0.585_410_196_624_968_5;
        match n {
            0 => Some(Vec::new()),
            1 => Some(vec![[0.25; 4]]),
            4 => Some(
                (0..4)
                    .map(|k| {
                        let mut l = [A; 4];
                        l[k] = B;
                        l
                    })
                    .collect(),
            ),
            10 => {
                const C: f64 = (A + B) / 2.0;
                let mut pts = Tet4::point_placement(4)?;
                pts.extend(TEN_POINT_EDGES.iter().map(|&(i, j)| {
                    let mut l = [A; 4];
                    (l[i], l[j]) = (C, C);
                    l
                }));
                Some(pts)
            }
            _ => None,
        }
    }

    /// The one point of a 1-point element; of 4 points, the three nearest the face's corners;
    /// of 10, the six on the face's side (the three corner points and the three edge points of
    /// the face's edges: those farthest from the opposite corner).
    fn face_load_points(n: usize, face: usize) -> Vec<usize> {
        match n {
            4 => (0..4).filter(|&k| k != face).collect(),
            10 => (0..4)
                .filter(|&k| k != face)
                .chain(
                    (0..6)
                        .filter(|&e| TEN_POINT_EDGES[e].0 != face && TEN_POINT_EDGES[e].1 != face)
                        .map(|e| 4 + e),
                )
                .collect(),
            n => (0..n).collect(),
        }
    }

    fn supported_point_counts() -> &'static str {
        "1, 4 or 10"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placed_points_are_inside_and_share_the_volume_evenly() {
        for n in [1, 4, 10] {
            let pts = Tet4::point_placement(n).unwrap();
            assert_eq!(pts.len(), n as usize);
            let mut centroid = [0.0; 4];
            for l in &pts {
                assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-15);
                assert!(l.iter().all(|&v| v > 0.0));
                for k in 0..4 {
                    centroid[k] += l[k] / n as f64;
                }
            }
            // A symmetric rule: the points' mean is the centroid.
            assert!(centroid.iter().all(|&c| (c - 0.25).abs() < 1e-15));
            // Distinct points.
            for (i, a) in pts.iter().enumerate() {
                assert!(pts[..i].iter().all(|b| b != a), "point {i} of {n}");
            }
        }
        assert!(Tet4::point_placement(3).is_none());
        // Anura3D's 10-point rule: its fifth point (A, A, C) and tenth (C, C, A) in (ξ, η, ζ).
        let ten = Tet4::point_placement(10).unwrap();
        let (a, b) = (0.138_196_601_125_010_5, 0.585_410_196_624_968_5);
        let c = (a + b) / 2.0;
        let local = |l: &[f64; 4]| [l[2], l[3], l[1]];
        assert_eq!(local(&ten[4]), [a, a, c]);
        assert_eq!(local(&ten[9]), [c, c, a]);
        assert!((ten[4][0] - c).abs() < 1e-15 && (ten[9][0] - a).abs() < 1e-15);
        // A face load on face k is carried by the six points nearest that face.
        for k in 0..4 {
            let on = Tet4::face_load_points(10, k);
            assert_eq!(on.len(), 6);
            assert!(
                on.iter().all(|&i| (ten[i][k] - a).abs() < 1e-15),
                "face {k}"
            );
        }
    }

    #[test]
    fn an_inverted_tetrahedron_is_refused_with_its_signed_volume() {
        let x = [[0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let g = Tet4::geometry::<f64>(&x).unwrap();
        assert!((g.volume - 1.0 / 6.0).abs() < 1e-15);
        let swapped = [x[0], x[2], x[1], x[3]];
        assert_eq!(Tet4::geometry::<f64>(&swapped).unwrap_err(), -1.0 / 6.0);
    }

    #[test]
    fn the_exit_face_is_the_most_negative_coordinate() {
        assert_eq!(Tet4::exit_face(&[0.5, 0.2, 0.2, 0.1], -1e-10), None);
        assert_eq!(Tet4::exit_face(&[0.5, -0.2, 0.8, -0.1], -1e-10), Some(1));
    }
}
