//! Geometry of a model's boundary faces (triangles given by their corner nodes), shared by
//! both input routes' face loads.

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

/// Outward unit normals of boundary faces given by their corner nodes: each face is found in
/// the element that has it, and oriented away from that element's fourth corner.
pub fn outward_normals(model: &Model, faces: &[[usize; 3]]) -> Result<Vec<[f64; 3]>, String> {
    let key = |f: [usize; 3]| {
        let mut k = f;
        k.sort_unstable();
        k
    };
    let mut opposite: std::collections::HashMap<[usize; 3], Option<usize>> =
        faces.iter().map(|&f| (key(f), None)).collect();
    for e in 0..model.element_count() {
        let c = &model.element(e)[..4];
        for skip in 0..4 {
            let mut f = [0usize; 3];
            let mut j = 0;
            for (i, &n) in c.iter().enumerate() {
                if i != skip {
                    f[j] = n as usize;
                    j += 1;
                }
            }
            if let Some(slot) = opposite.get_mut(&key(f)) {
                *slot = Some(c[skip] as usize);
            }
        }
    }
    faces
        .iter()
        .map(|&f| {
            let inner = opposite[&key(f)].ok_or_else(|| {
                format!(
                    "the loaded face with corner nodes {} {} {} is not a face of any element",
                    f[0] + 1,
                    f[1] + 1,
                    f[2] + 1
                )
            })?;
            let p = f.map(|n| model.node(n));
            let q = model.node(inner);
            let (a, b) = (
                [0, 1, 2].map(|d| p[1][d] - p[0][d]),
                [0, 1, 2].map(|d| p[2][d] - p[0][d]),
            );
            let mut n = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let len = n.iter().map(|v| v * v).sum::<f64>().sqrt();
            let towards_inner: f64 = (0..3).map(|d| n[d] * (q[d] - p[0][d])).sum();
            let sign = if towards_inner > 0.0 { -1.0 } else { 1.0 };
            for v in n.iter_mut() {
                *v *= sign / len;
            }
            Ok(n)
        })
        .collect()
}
