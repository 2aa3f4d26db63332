//! Geometry shared by the readers, the model and the generators.

/// Signed volume × 6 of a tetrahedron with corners `a, b, c, d`: det[b-a, c-a, d-a].
pub fn tet_det(a: &[f64], b: &[f64], c: &[f64], d: &[f64]) -> f64 {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
    u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
}
