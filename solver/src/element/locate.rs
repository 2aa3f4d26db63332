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
}

/// Finds the element holding `p`, starting from `start`.
#[inline]
pub fn walk<E: Element, R: Real>(mesh: &Mesh<E, R>, start: u32, p: &V3<R>) -> Found {
    let tol = R::of(-1e-10);
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
        e = next;
    }
    Found::Outside(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::mesh::TetMesh;
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
}
