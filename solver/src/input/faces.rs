//! Geometry of a model's boundary faces (triangles given by their corner nodes in 3D, edges
//! by their two end nodes in 2D), shared by both input routes' face loads.

use mpm_shared::Model;

/// Area of the triangle with corners at model nodes `n` (0-based).
pub fn triangle_area(model: &Model, n: [usize; 3]) -> f64 {
    let p = n.map(|i| model.node(i));
    let a = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
    let b = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
    let c = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
}

/// Length of the edge between model nodes `a` and `b` (0-based) of a 2D model.
pub fn edge_length(model: &Model, a: usize, b: usize) -> f64 {
    let (p, q) = (model.node(a), model.node(b));
    ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt()
}

/// Area of a 3D face (three corners) or length of a 2D edge (two ends).
pub fn size(model: &Model, corners: &[usize]) -> f64 {
    match *corners {
        [a, b] => edge_length(model, a, b),
        [a, b, c] => triangle_area(model, [a, b, c]),
        _ => 0.0,
    }
}

/// Outward unit normals of boundary faces given by their corner nodes (three in 3D, two in
/// 2D): each face is found in the element that has it, and oriented away from that element's
/// other corner (z = 0 in 2D).
pub fn outward_normals(model: &Model, faces: &[Vec<usize>]) -> Result<Vec<[f64; 3]>, String> {
    if model.dimension.coords() == 2 {
        let edges: Vec<[usize; 2]> = faces.iter().map(|f| [f[0], f[1]]).collect();
        return outward_edge_normals(model, &edges);
    }
    let faces: Vec<[usize; 3]> = faces.iter().map(|f| [f[0], f[1], f[2]]).collect();
    outward_face_normals(model, &faces)
}

/// Outward unit normals of the boundary edges of a 2D model, each oriented away from the
/// third corner of the (first) triangle that has it.
fn outward_edge_normals(model: &Model, edges: &[[usize; 2]]) -> Result<Vec<[f64; 3]>, String> {
    let key = |e: [usize; 2]| [e[0].min(e[1]), e[0].max(e[1])];
    let mut opposite: std::collections::HashMap<[usize; 2], Option<usize>> =
        edges.iter().map(|&e| (key(e), None)).collect();
    for e in 0..model.element_count() {
        let c = &model.element(e)[..3];
        for skip in 0..3 {
            let (a, b) = (c[(skip + 1) % 3] as usize, c[(skip + 2) % 3] as usize);
            // An edge between two elements takes the first's side, as Anura3D does (checked
            // against it on an edge inside a filled column).
            if let Some(slot @ None) = opposite.get_mut(&key([a, b])) {
                *slot = Some(c[skip] as usize);
            }
        }
    }
    edges
        .iter()
        .map(|&[a, b]| {
            let inner = opposite[&key([a, b])].ok_or_else(|| {
                format!(
                    "the loaded edge between nodes {} and {} is not an edge of any element",
                    a + 1,
                    b + 1
                )
            })?;
            let (p, q, o) = (model.node(a), model.node(b), model.node(inner));
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            let len = (dx * dx + dy * dy).sqrt();
            let mut n = [dy / len, -dx / len, 0.0];
            if n[0] * (o[0] - p[0]) + n[1] * (o[1] - p[1]) > 0.0 {
                n = [-n[0], -n[1], 0.0];
            }
            Ok(n)
        })
        .collect()
}

/// Outward unit normals of the boundary faces of a 3D model, each oriented away from the
/// fourth corner of the tetrahedron that has it (the last one, for a face between two).
fn outward_face_normals(model: &Model, faces: &[[usize; 3]]) -> Result<Vec<[f64; 3]>, String> {
    let key = |f: &[usize]| {
        let mut k = [f[0], f[1], f[2]];
        k.sort_unstable();
        k
    };
    let mut opposite: std::collections::HashMap<[usize; 3], Option<usize>> =
        faces.iter().map(|f| (key(f), None)).collect();
    for e in 0..model.element_count() {
        for (face, off) in element_faces(model, e) {
            if let Some(slot) = opposite.get_mut(&key(&face)) {
                *slot = Some(off);
            }
        }
    }
    faces
        .iter()
        .map(|f| {
            let inner = opposite[&key(f)].ok_or_else(|| {
                format!(
                    "the loaded face with corner nodes {} {} {} is not a face of any element",
                    f[0] + 1,
                    f[1] + 1,
                    f[2] + 1
                )
            })?;
            Ok(outward_normal(model, f, inner))
        })
        .collect()
}

/// Each corner's share of a face's size: a third of a triangle's area (3D), half an edge's
/// length (plane strain) or, in an axisymmetric section, ∫ N_a r ds = L (2 r_a + r_b) / 6 per
/// radian. What a uniform load or a boundary's dashpot per unit area gives each corner.
pub fn corner_shares(model: &Model, corners: &[usize]) -> Vec<f64> {
    let axisymmetric = model.dimension == mpm_shared::Dimension::Axisymmetric;
    let size = size(model, corners);
    (0..corners.len())
        .map(|i| match corners.len() {
            2 if axisymmetric => {
                let (ra, rb) = (model.node(corners[i])[0], model.node(corners[1 - i])[0]);
                size * (2.0 * ra + rb) / 6.0
            }
            k => size / k as f64,
        })
        .collect()
}

/// The corners of element `e` (four of a tetrahedron, three of a triangle) with the faces they
/// make: each face's corners and the corner off it.
fn element_faces(model: &Model, e: usize) -> impl Iterator<Item = (Vec<usize>, usize)> + '_ {
    let k = model.dimension.coords() + 1;
    let c = &model.element(e)[..k];
    (0..k).map(move |skip| {
        let face = (0..k)
            .filter(|&i| i != skip)
            .map(|i| c[i] as usize)
            .collect();
        (face, c[skip] as usize)
    })
}

/// The element that has each of `faces` and its corner off the face. An error names a face
/// that no element has, or that two have (it lies inside the mesh, not on its boundary).
pub fn boundary_owners(model: &Model, faces: &[Vec<usize>]) -> Result<Vec<(usize, usize)>, String> {
    let key = |f: &[usize]| {
        let mut k = f.to_vec();
        k.sort_unstable();
        k
    };
    let mut found: std::collections::HashMap<Vec<usize>, Vec<(usize, usize)>> =
        faces.iter().map(|f| (key(f), Vec::new())).collect();
    for e in 0..model.element_count() {
        for (face, off) in element_faces(model, e) {
            if let Some(list) = found.get_mut(&key(&face)) {
                list.push((e, off));
            }
        }
    }
    faces
        .iter()
        .map(|f| {
            let named = || f.iter().map(|n| (n + 1).to_string()).collect::<Vec<_>>().join(" ");
            match found[&key(f)].as_slice() {
                [one] => Ok(*one),
                [] => Err(format!("the face with corner nodes {} is not a face of any element", named())),
                [a, b, ..] => Err(format!(
                    "the face with corner nodes {} lies between elements {} and {}, inside the mesh",
                    named(),
                    a.0 + 1,
                    b.0 + 1
                )),
            }
        })
        .collect()
}

/// Outward unit normal of the face `corners` (three in 3D, two in 2D, z = 0) away from node
/// `inner` of its element.
pub fn outward_normal(model: &Model, corners: &[usize], inner: usize) -> [f64; 3] {
    let p: Vec<&[f64]> = corners.iter().map(|&n| model.node(n)).collect();
    let q = model.node(inner);
    let at = |v: &[f64], d: usize| v.get(d).copied().unwrap_or(0.0);
    let mut n = if let [a, b] = p[..] {
        [at(b, 1) - at(a, 1), at(a, 0) - at(b, 0), 0.0]
    } else {
        let u = [0, 1, 2].map(|d| at(p[1], d) - at(p[0], d));
        let v = [0, 1, 2].map(|d| at(p[2], d) - at(p[0], d));
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let len = n.iter().map(|v| v * v).sum::<f64>().sqrt();
    let towards_inner: f64 = (0..3).map(|d| n[d] * (at(q, d) - at(p[0], d))).sum();
    let sign = if towards_inner > 0.0 { -1.0 } else { 1.0 };
    for v in n.iter_mut() {
        *v *= sign / len;
    }
    n
}

/// The elements' faces whose corners all lie on the plane `axis = value` (within `tol`), each
/// once, in the order the elements first have them.
pub fn plane_faces(model: &Model, axis: usize, value: f64, tol: f64) -> Vec<Vec<usize>> {
    let on = |n: usize| (model.node(n).get(axis).copied().unwrap_or(0.0) - value).abs() <= tol;
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    for e in 0..model.element_count() {
        for (face, _) in element_faces(model, e) {
            if face.iter().all(|&n| on(n)) {
                let mut k = face.clone();
                k.sort_unstable();
                if seen.insert(k) {
                    out.push(face);
                }
            }
        }
    }
    out
}
