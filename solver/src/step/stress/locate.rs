//! Locating the points as they move ([`locate_moved`]): where nothing between the stress pass
//! and the next bears on a point's element, the stress pass finds it, the element's points at
//! their new positions still in the nearest cache, and the locate pass has nothing left to do.

use crate::element::locate::{locate_width, relocate, run_inside, Outcome};
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::Real;

use super::ChunkPoints;

/// Element `e`'s points `from..end` of the chunk (`offset`: the chunk's first point), at their
/// new positions: runs of [`locate_width`] of them tested at once (most points stay in their
/// element), the others walked, as the locate pass does, the walks' outcome added to `found`.
#[inline(always)]
pub(super) fn locate_moved<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    e: usize,
    p: &mut ChunkPoints<'_, R>,
    (from, end): (usize, usize),
    (found, offset): (&mut Outcome, usize),
) {
    let (x, active) = (&*p.x, p.active);
    let w = locate_width::<E, R>();
    let mut i = from;
    while i < end {
        if w > 1 && i + w <= end && active[i..i + w].iter().all(|&a| a) {
            let inside = match w {
                4 => run_inside::<E, R, 4>(mesh, e, &x[i..i + 4]),
                3 => run_inside::<E, R, 3>(mesh, e, &x[i..i + 3]),
                _ => run_inside::<E, R, 2>(mesh, e, &x[i..i + 2]),
            };
            if inside {
                i += w;
                continue;
            }
        }
        if active[i] {
            relocate(mesh, found, offset + i, &mut p.element[i], &x[i]);
        }
        i += 1;
    }
}
