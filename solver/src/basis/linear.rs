//! The linear element as a basis: a point touches its element's corners, with the element's
//! shape functions ([`Element::shape`]) and their gradients, one per element
//! ([`crate::element::Geometry::grad`]). The passes take its points in their element kernels
//! ([`Basis::LINEAR`]); its stencil is what those kernels use, point by point.

use crate::basis::{Basis, Stencil};
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};

/// The mesh's linear elements (4-node tetrahedra, 3-node triangles) as the basis.
#[derive(Debug, Clone, Copy, Default)]
pub struct Linear;

impl<E: Element, R: Real> Basis<E, R> for Linear {
    const LINEAR: bool = true;

    fn stencil(&self, mesh: &Mesh<E, R>, e: usize, x: &V3<R>, out: &mut Stencil<R>) {
        out.clear();
        let n = mesh.shape(e, x);
        let (corners, grad) = (mesh.corners[e].as_ref(), mesh.grad[e].as_ref());
        for k in 0..E::NODES {
            out.push(corners[k], n.as_ref()[k], grad[k]);
        }
    }

    fn reach(&self, mesh: &Mesh<E, R>, e: usize, out: &mut Vec<u32>) {
        out.clear();
        out.extend_from_slice(mesh.corners[e].as_ref());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;
    use mpm_shared::{generate, ElementType};

    /// A point's stencil is its element's corners with the element's shape values and
    /// gradients: a partition of unity that reproduces the point's position.
    #[test]
    fn a_point_s_stencil_is_its_element_s_corners() {
        let model = generate::box_mesh([2, 2, 2], [1.0; 3], ElementType::Tet4);
        let mesh = Mesh::<Tet4, f64>::new(&model).unwrap();
        let mut s = Stencil::default();
        for e in 0..mesh.elements() {
            let corners = mesh.corners[e];
            let x: V3<f64> = std::array::from_fn(|a| {
                (0..4).map(|k| mesh.x[corners[k] as usize][a]).sum::<f64>() / 4.0
            });
            Linear.stencil(&mesh, e, &x, &mut s);
            assert_eq!(s.nodes(), &corners[..]);
            assert_eq!(s.gradients(), &mesh.grad[e][..]);
            let total: f64 = s.weights().iter().sum();
            assert!((total - 1.0).abs() < 1e-14);
            for a in 0..3 {
                let back: f64 = (0..4)
                    .map(|k| s.weights()[k] * mesh.x[s.nodes()[k] as usize][a])
                    .sum();
                assert!((back - x[a]).abs() < 1e-14);
            }
        }
    }
}
