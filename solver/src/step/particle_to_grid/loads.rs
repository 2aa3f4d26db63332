//! The face loads carried by points (Anura3D's loads on material points), added to the nodes'
//! external force after the pass.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;

/// Adds the face loads carried by points, `scale` times their force, at the points' positions
/// (a short list, in its fixed order).
pub fn add_point_loads<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    p: &Particles<R>,
    loads: &[(u32, V3<R>)],
    scale: R,
    g: &mut Grid<R>,
) {
    for &(i, f) in loads {
        let i = i as usize;
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let n = n.as_ref();
        for k in 0..E::NODES {
            let node = mesh.corners[e].as_ref()[k] as usize;
            for a in 0..3 {
                g.f_ext[node][a] += n[k] * scale * f[a];
            }
        }
    }
}
