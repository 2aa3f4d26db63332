//! Particle relocation: from its previous element, a point walks to the face neighbour across
//! the face with the most negative barycentric coordinate until it is inside.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};

/// Where a walk ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Found {
    /// Inside this element.
    In(u32),
    /// Left the mesh through a boundary face of this element.
    Outside(u32),
    /// The walk left this rank's elements and halo through a face of this element (a point
    /// that moved more than an element in a step, on a rank of several).
    Beyond(u32),
}

/// What walking a range of points found: the first point found outside the mesh or beyond
/// the rank's halo (its index and the element it left by; `(usize::MAX, 0)` for none), how many
/// such points, and whether any point changed element.
pub type Outcome = ((usize, u32), u64, bool);

/// An outcome of no point lost and none moved.
pub const NOTHING_FOUND: Outcome = ((usize::MAX, 0), 0, false);

/// Walks point `index` (at `x`, in element `*el` until now) to the element holding it, which
/// `el` takes, and adds the outcome to `o`: the locate pass's and the stress pass's walk alike
/// (the rare case of both: most points stay in their element, which the batched test of
/// [`run_inside`] settles first).
#[cold]
#[inline(never)]
pub fn relocate<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    o: &mut Outcome,
    index: usize,
    el: &mut u32,
    x: &V3<R>,
) -> Found {
    let found = walk(mesh, *el, x);
    if let Found::Beyond(_) = found {
        // Beyond the halo: moved more than an element in one step, which the rank cannot
        // follow; stops the run as a point leaving the mesh does.
        log::error!(
            "a material point moved beyond this rank's halo in one step (from local element {})",
            *el
        );
    }
    record(o, index, el, found);
    found
}

/// Takes the outcome of point `index` (at `el`, its element until now) ending its walk with
/// `found` into `o`. `el` takes the element the walk ended in.
fn record(o: &mut Outcome, index: usize, el: &mut u32, found: Found) {
    let (Found::In(e) | Found::Outside(e) | Found::Beyond(e)) = found;
    o.2 |= e != *el;
    *el = e;
    if matches!(found, Found::In(_)) {
        return;
    }
    if o.1 == 0 {
        o.0 = (index, e);
    }
    o.1 += 1;
}

/// Adds the outcome of more points, `more`, to `o` (the lowest first point, the counts
/// summed): the same whichever thread walked which points.
#[inline]
pub fn merge(o: &mut Outcome, more: Outcome) {
    o.0 = o.0.min(more.0);
    o.1 += more.1;
    o.2 |= more.2;
}

/// How far outside an element (in local coordinates) a point may lie and still count as in
/// it: 1e-10, or a hundred rounding errors of the precision where that is coarser (f32: 1.2e-5),
/// so that a point on a face is not sent back and forth between its two elements.
pub fn tolerance<R: Real>() -> f64 {
    (100.0 * R::EPSILON).max(1e-10)
}

/// Finds the element holding `p`, starting from `start`.
#[inline]
pub fn walk<E: Element, R: Real>(mesh: &Mesh<E, R>, start: u32, p: &V3<R>) -> Found {
    let tol = R::of(-tolerance::<R>());
    let mut e = start;
    // A walk is bounded by the mesh size; the cap only guards against cycling on round-off.
    for _ in 0..mesh.elements().max(16) {
        let Some(k) = E::exit_face(&mesh.shape(e as usize, p), tol) else {
            return Found::In(e);
        };
        let next = mesh.neighbour[e as usize].as_ref()[k];
        if next == u32::MAX {
            return Found::Outside(e);
        }
        if next == crate::element::mesh::REMOTE {
            return Found::Beyond(e);
        }
        e = next;
    }
    // Cycling: the point lies on faces within round-off of every element it visits, so inside
    // the mesh; it stays in the element it was last found in.
    Found::In(start)
}

/// Points per batch of the locate check ([`run_inside`]), by element type and precision: a
/// triangle's three points, two f64 or four f32 of a tetrahedron's four (one 16-byte vector
/// register of the baseline x86-64 instruction set). Measured on one thread against the other
/// widths (docs/design.md §5.3); the outcome does not depend on it.
pub const fn locate_width<E: Element, R: Real>() -> usize {
    match (E::DIM, R::BYTES) {
        (2, _) => 3,
        (_, 4) => 4,
        _ => 2,
    }
}

/// Whether each of the `W` points `x` lies inside element `e` within the locate tolerance:
/// where this says so, [`walk`] from `e` ends at once with [`Found::In`] for each of them (the
/// same shape values, [`Element::shape_lanes`], and the same test); where it does not, walk the
/// points one by one.
#[inline(always)]
pub fn run_inside<E: Element, R: Real, const W: usize>(
    mesh: &Mesh<E, R>,
    e: usize,
    x: &[V3<R>],
) -> bool {
    let xl: [[R; W]; 3] = std::array::from_fn(|a| std::array::from_fn(|q| x[q][a]));
    let tol = R::of(-tolerance::<R>());
    let first = &mesh.x[mesh.corners[e].as_ref()[0] as usize];
    let n = E::shape_lanes(&mesh.map[e], first, &xl);
    // Not `n >= tol`: a NaN shape value is inside for the walk too (no face is more negative).
    let mut out = false;
    for nk in n.iter().take(E::NODES) {
        for &v in nk {
            out |= v < tol;
        }
    }
    !out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::mesh::TetMesh;
    use crate::element::tet4::Tet4;
    use mpm_shared::{generate, ElementType};

    #[test]
    fn walks_across_the_mesh_and_detects_leaving() {
        let model = generate::box_mesh([4, 4, 4], [1.0; 3], ElementType::Tet4);
        let mesh = TetMesh::<f64>::new(&model).unwrap();
        let target = [0.91, 0.13, 0.77];
        let Found::In(e) = walk(&mesh, 0, &target) else {
            panic!("lost")
        };
        let l = mesh.shape(e as usize, &target);
        assert!(l.iter().all(|&v| v >= -1e-10));
        assert!(matches!(
            walk(&mesh, e, &[1.2, 0.5, 0.5]),
            Found::Outside(_)
        ));
    }

    #[test]
    fn in_single_precision_points_on_interior_faces_stay_in_the_mesh() {
        // A mesh away from the origin's scale, in f32: face points computed in f32 lie off
        // their face by rounding errors far above 1e-10.
        let mut model = generate::box_mesh([6, 6, 6], [0.37, 1.3, 0.11], ElementType::Tet4);
        // Interior nodes moved off the lattice (by up to 15 % of a cell), so that faces are
        // oblique and their points' coordinates round in every direction.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let size = [0.37, 1.3, 0.11];
        for p in model.coords.chunks_exact_mut(3) {
            let inside = (0..3).all(|a| p[a] > 1e-9 && p[a] < size[a] - 1e-9);
            for a in 0..3 {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                if inside {
                    p[a] += (seed as f64 / u64::MAX as f64 - 0.5) * 0.3 * size[a] / 6.0;
                }
            }
        }
        let mesh = TetMesh::<f32>::new(&model).unwrap();
        let mut checked = 0;
        for e in 0..mesh.elements() {
            for k in 0..4 {
                let other = mesh.neighbour[e][k];
                if other == u32::MAX {
                    continue;
                }
                let f = crate::element::tet4::FACE_OPPOSITE[k];
                let mut p = [0.0f32; 3];
                for &j in &f {
                    let x = mesh.x[mesh.corners[e][j] as usize];
                    for a in 0..3 {
                        p[a] += x[a] / 3.0;
                    }
                }
                for start in [e as u32, other] {
                    assert!(
                        matches!(walk(&mesh, start, &p), Found::In(_)),
                        "a point on the face between {e} and {other} was lost"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 1000);
    }

    /// [`run_inside`] says "inside" exactly when the walk from the element ends there at once
    /// for every point of the batch: points near and across the element's faces, in both
    /// precisions, for each batch width the engine uses.
    fn run_inside_agrees_with_walk<R: Real, const W: usize>() {
        let model = generate::box_mesh([3, 3, 3], [1.0, 0.7, 1.3], ElementType::Tet4);
        let mesh = TetMesh::<R>::new(&model).unwrap();
        let mut next = crate::element::samples(0x9e37_79b9_7f4a_7c15);
        let (mut inside, mut not) = (0, 0);
        for e in 0..mesh.elements() {
            let c: Vec<[f64; 3]> = mesh.corners[e]
                .iter()
                .map(|&n| mesh.x[n as usize].map(|v| v.f64()))
                .collect();
            for _ in 0..20 {
                // Barycentric weights mostly inside, some a little outside.
                let x: Vec<V3<R>> = (0..W)
                    .map(|_| {
                        let mut l: [f64; 4] = std::array::from_fn(|_| next() + 0.02);
                        let total: f64 = l.iter().sum();
                        l.iter_mut().for_each(|v| *v /= total);
                        if next() < 0.05 {
                            l[0] -= 0.05;
                            l[1] += 0.05;
                        }
                        std::array::from_fn(|a| R::of((0..4).map(|k| l[k] * c[k][a]).sum()))
                    })
                    .collect();
                let walked = x
                    .iter()
                    .all(|p| walk(&mesh, e as u32, p) == Found::In(e as u32));
                let batched = run_inside::<Tet4, R, W>(&mesh, e, &x);
                assert_eq!(batched, walked, "element {e}");
                if batched {
                    inside += 1;
                } else {
                    not += 1;
                }
            }
        }
        assert!(inside > 100 && not > 10, "{inside} inside, {not} not");
    }

    #[test]
    fn batched_inside_check_is_the_walks_first_step() {
        run_inside_agrees_with_walk::<f64, 2>();
        run_inside_agrees_with_walk::<f32, 4>();
    }
}
