//! Structured meshes of a box (tetrahedra) or a rectangle (triangles), for benchmarks and
//! analytical tests where a Gmsh mesh of a given size is not at hand. Each hexahedral cell is cut
//! into the 6 tetrahedra of its Kuhn subdivision (every tetrahedron spans the cell's main
//! diagonal), which is conforming across cells; mid-edge nodes of 10-node meshes are shared
//! between neighbours. Each rectangular cell is cut along its main diagonal into 2 triangles, the
//! 2D analogue.

use crate::geometry::tet_det;
use crate::model::{Body, Dimension, ElementType, Model, Section, Table, Token};

/// Builds a box `[0, size[0]] × [0, size[1]] × [0, size[2]]` with `n[0] × n[1] × n[2]` cells
/// (6 tetrahedra each), 4- or 10-node, one material, empty fixity sections, and 4 material points
/// per element in `$$START_NUMBER_OF_MATERIAL_POINTS`.
pub fn box_mesh(n: [usize; 3], size: [f64; 3], element_type: ElementType) -> Model {
    assert!(
        element_type != ElementType::Tri3,
        "box_mesh makes tetrahedra"
    );
    let quadratic = element_type == ElementType::Tet10;
    // Lattice of node positions: step h/2 for 10-node meshes, h for 4-node ones.
    let r = if quadratic { 2 } else { 1 };
    let dims = [n[0] * r + 1, n[1] * r + 1, n[2] * r + 1];
    let id = |i: usize, j: usize, k: usize| (i + dims[0] * (j + dims[1] * k)) as u32;
    let mut coords = Vec::with_capacity(dims[0] * dims[1] * dims[2] * 3);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                coords.push(size[0] * i as f64 / (dims[0] - 1) as f64);
                coords.push(size[1] * j as f64 / (dims[1] - 1) as f64);
                coords.push(size[2] * k as f64 / (dims[2] - 1) as f64);
            }
        }
    }
    const PATHS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let per = element_type.nodes();
    let cells = n[0] * n[1] * n[2];
    let mut conn = Vec::with_capacity(cells * 6 * per);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                for path in PATHS {
                    // Corners on the lattice (in units of the lattice step).
                    let mut c = [[i * r, j * r, k * r]; 4];
                    for s in 0..3 {
                        c[s + 1] = c[s];
                        c[s + 1][path[s]] += r;
                    }
                    let p = |q: [usize; 3]| {
                        let x = id(q[0], q[1], q[2]) as usize * 3;
                        [coords[x], coords[x + 1], coords[x + 2]]
                    };
                    if tet_det(&p(c[0]), &p(c[1]), &p(c[2]), &p(c[3])) < 0.0 {
                        c.swap(1, 2);
                    }
                    // Anura3D order: A1 = c0, A2 = c3, A3 = c1, A4 = c2.
                    let a = [c[0], c[3], c[1], c[2]];
                    for q in a {
                        conn.push(id(q[0], q[1], q[2]));
                    }
                    if quadratic {
                        for (u, v) in [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)] {
                            let m = [
                                (a[u][0] + a[v][0]) / 2,
                                (a[u][1] + a[v][1]) / 2,
                                (a[u][2] + a[v][2]) / 2,
                            ];
                            conn.push(id(m[0], m[1], m[2]));
                        }
                    }
                }
            }
        }
    }
    soil_model(Dimension::Cartesian3D, element_type, coords, conn, 4)
}

/// A model of one material, "soil", filling every element with `points` material points each.
fn soil_model(
    dimension: Dimension,
    element_type: ElementType,
    coords: Vec<f64>,
    conn: Vec<u32>,
    points: i64,
) -> Model {
    let n_el = conn.len() / element_type.nodes();
    let mut model = Model::from_mesh(
        dimension,
        element_type,
        coords,
        conn,
        &["soil".to_string()],
        &vec![1; n_el],
    );
    let mut mps = Table::with_capacity(n_el, 2);
    for _ in 0..n_el {
        mps.push_row([Token::Int(points), Token::Int(0)]);
    }
    model.sections.push(Section {
        keyword: "START_NUMBER_OF_MATERIAL_POINTS".into(),
        body: Body::PerElement(mps),
    });
    model
}

/// Builds a plane-strain rectangle `[0, size[0]] × [0, size[1]]` with `n[0] × n[1]` cells (2
/// counter-clockwise 3-node triangles each, cut along the diagonal from the cell's lower-left to
/// its upper-right corner), one material, empty fixity sections, and 3 material points per element
/// in `$$START_NUMBER_OF_MATERIAL_POINTS`: [`box_mesh`]'s layout in 2D, with 2 coordinates per
/// node. Setting the model's `dimension` to [`Dimension::Axisymmetric`] gives the same mesh as an
/// axisymmetric section (x the radius), the layout being identical.
pub fn rect_mesh(n: [usize; 2], size: [f64; 2]) -> Model {
    let dims = [n[0] + 1, n[1] + 1];
    let id = |i: usize, j: usize| (i + dims[0] * j) as u32;
    let mut coords = Vec::with_capacity(dims[0] * dims[1] * 2);
    for j in 0..dims[1] {
        for i in 0..dims[0] {
            coords.push(size[0] * i as f64 / n[0] as f64);
            coords.push(size[1] * j as f64 / n[1] as f64);
        }
    }
    let n_el = n[0] * n[1] * 2;
    let mut conn = Vec::with_capacity(n_el * 3);
    for j in 0..n[1] {
        for i in 0..n[0] {
            // Lower-left, lower-right, upper-right, upper-left: both halves listed in this
            // circular order are counter-clockwise, as the solver's triangles must be.
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            conn.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    soil_model(Dimension::PlaneStrain, ElementType::Tri3, coords, conn, 3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_is_conforming_positive_and_fills_the_volume() {
        for et in [ElementType::Tet4, ElementType::Tet10] {
            let m = box_mesh([3, 2, 2], [1.0, 2.0, 0.5], et);
            assert_eq!(m.element_count(), 72);
            m.check_shapes(1e-12).unwrap();
            let mut vol = 0.0;
            for e in 0..m.element_count() {
                let el = m.element(e);
                let x = |k: usize| m.node(el[k] as usize);
                vol += tet_det(x(0), x(2), x(3), x(1)) / 6.0;
            }
            assert!((vol - 1.0).abs() < 1e-12);
            // Conforming: every interior face is shared by exactly two tetrahedra.
            let mut faces = std::collections::HashMap::new();
            for e in 0..m.element_count() {
                let el = m.element(e);
                for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
                    let mut key = [el[f[0]], el[f[1]], el[f[2]]];
                    key.sort_unstable();
                    *faces.entry(key).or_insert(0) += 1;
                }
            }
            assert!(faces.values().all(|&c| c == 1 || c == 2));
            let boundary = faces.values().filter(|&&c| c == 1).count();
            // 2 triangles per boundary square: 2 * 2 * (3*2 + 3*2 + 2*2).
            assert_eq!(boundary, 64);
        }
    }

    #[test]
    fn rectangle_is_conforming_counter_clockwise_and_fills_the_area() {
        let m = rect_mesh([3, 2], [1.5, 0.5]);
        assert_eq!(m.dimension, Dimension::PlaneStrain);
        assert_eq!(m.element_type, ElementType::Tri3);
        assert_eq!((m.node_count(), m.element_count()), (12, 12));
        assert_eq!(m.coords.len(), 24);
        assert_eq!(m.node(11), &[1.5, 0.5]);
        assert_eq!(m.material_points_per_element().unwrap(), vec![3; 12]);
        m.check_shapes(1e-12).unwrap();
        let mut area = 0.0;
        for e in 0..m.element_count() {
            let el = m.element(e);
            let (a, b, c) = (
                m.node(el[0] as usize),
                m.node(el[1] as usize),
                m.node(el[2] as usize),
            );
            let twice = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(twice > 0.0, "element {e} is not counter-clockwise");
            area += twice / 2.0;
        }
        assert!((area - 0.75).abs() < 1e-14);
        // Conforming: every interior edge is shared by exactly two triangles, and the boundary
        // edges are the 2 * (3 + 2) cell sides of the rectangle's perimeter.
        let mut edges = std::collections::HashMap::new();
        for e in 0..m.element_count() {
            let el = m.element(e);
            for (u, v) in [(0, 1), (1, 2), (0, 2)] {
                let key = (el[u].min(el[v]), el[u].max(el[v]));
                *edges.entry(key).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 1 || c == 2));
        assert_eq!(edges.values().filter(|&&c| c == 1).count(), 10);
    }
}
