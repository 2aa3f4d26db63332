//! The interface between a structure and the soil, resolved once on the initial mesh: its
//! nodes, each node's unit normal out of the structure and its share of the interface (the
//! area, per radian in an axisymmetric section, that the adhesion multiplies).
//!
//! An *interface side* is a side of one of the structure's elements whose neighbour is empty or
//! of another material (a side on the mesh boundary is not one).
//!
//! * 3D: each node takes a third of the area of its interface triangles; its normal sums the
//!   unnormalised normals of each element's last interface side ([`InterfaceRule::Anura3d`]:
//!   Anura3D keeps one side per element) or of all of them ([`InterfaceRule::Tributary`]).
//! * 2D, [`InterfaceRule::Anura3d`]: the sides are taken element by element in the order the
//!   input lists them, each element's sides in Anura3D's order (corners 1–2, 3–1, 2–3); each
//!   node takes the whole length of every interface side it ends (not half: Anura3D's count,
//!   kept so that its inputs give its adhesion), and the normal of the last side in that order
//!   that faces soil, else of the first that faces an empty element.
//! * 2D, [`InterfaceRule::Tributary`]: each node takes its tributary share of each side it
//!   ends, ∫ N ds (half the length), times the radius ∫ N r ds in an axisymmetric section
//!   (the points' masses are per radian there); its normal is the length-weighted mean of its
//!   sides' normals, so that a corner of the structure (a pile's tip) pushes the soil along
//!   the bisector rather than along whichever side was listed last.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::Real;

use super::ContactSpec;

/// How the interface is taken: Anura3D's rules (its inputs) or a scene's, which also holds the
/// structure's inside against soil that slipped past the interface (`Contact::correct`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InterfaceRule {
    /// Anura3D's: in 2D a node takes the whole length of each interface side it ends and the
    /// normal of the last listed side that faces soil; in 3D the normal of each element's last
    /// interface side (its inputs).
    Anura3d,
    /// The tributary length (per radian in an axisymmetric section) and the length- or
    /// area-weighted mean normal (scenes).
    Tributary,
}

/// Anura3D's numbering of a tetrahedron's sides by its corners (0-based): the side's normal
/// (x₂ - x₁) × (x₃ - x₁) in this order points into the element.
const SIDES: [[usize; 3]; 4] = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];

/// Anura3D's order of a triangle's sides (0-based corners), each in the direction of a walk
/// around the counter-clockwise element: the side's outward normal is its direction turned
/// clockwise.
const LINES: [[usize; 2]; 3] = [[0, 1], [2, 0], [1, 2]];

/// The interface nodes (computational, ascending), each one's unit normal out of the structure
/// and its share of the interface.
pub(super) struct Interface {
    pub nodes: Vec<u32>,
    pub normal: Vec<[f64; 3]>,
    pub area: Vec<f64>,
}

impl Interface {
    /// The interface of `spec` on `mesh` (the whole mesh, the case's element order);
    /// `element_material` says which elements are filled (material 0: empty).
    pub fn of<E: Element, R: Real>(
        spec: &ContactSpec,
        mesh: &Mesh<E, R>,
        element_material: &[u32],
    ) -> Self {
        if E::DIM == 3 {
            surfaces(spec, mesh, element_material)
        } else {
            lines(spec, mesh, element_material)
        }
    }
}

/// Whether the side of element `e` through `nodes` borders the soil or an empty element:
/// `Some(the neighbour's material)` (0: empty), `None` when it is not an interface side.
fn beyond<E: Element, R: Real>(
    spec: &ContactSpec,
    mesh: &Mesh<E, R>,
    element_material: &[u32],
    e: u32,
    nodes: &[u32],
) -> Option<u32> {
    let c = mesh.corners[e as usize].as_ref();
    let neighbour = (0..E::FACES).find_map(|f| {
        let face = E::face(f);
        let same = face.len() == nodes.len() && face.iter().all(|&j| nodes.contains(&c[j]));
        same.then(|| mesh.neighbour[e as usize].as_ref()[f])
    })?;
    if neighbour == u32::MAX {
        return None;
    }
    let m = element_material[neighbour as usize];
    (m == 0 || m != spec.material).then_some(m)
}

/// The sorted, distinct nodes of `sides`, and a node's slot among them.
fn nodes_of<const N: usize>(sides: impl Iterator<Item = [u32; N]>) -> Vec<u32> {
    let mut nodes: Vec<u32> = sides.flatten().collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// The 3D interface (Anura3D's rule).
fn surfaces<E: Element, R: Real>(
    spec: &ContactSpec,
    mesh: &Mesh<E, R>,
    element_material: &[u32],
) -> Interface {
    debug_assert_eq!(E::NODES, 4, "3D contact is modelled for tetrahedra");
    let x = |n: u32| -> [f64; 3] { mesh.x[n as usize].map(|c| c.f64()) };
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    // Element by element, ascending (the listed order only matters in 2D).
    let mut elements = spec.listed.clone();
    elements.sort_unstable();
    elements.dedup();
    let mut faces: Vec<(u32, [u32; 3])> = Vec::new();
    for &e in &elements {
        let c = mesh.corners[e as usize].as_ref();
        for side in SIDES {
            let nodes = side.map(|k| c[k]);
            if beyond(spec, mesh, element_material, e, &nodes).is_some() {
                faces.push((e, nodes));
            }
        }
    }
    let nodes = nodes_of(faces.iter().map(|f| f.1));
    let slot = |n: u32| nodes.binary_search(&n).expect("an interface node");
    let mut sum = vec![[0.0f64; 3]; nodes.len()];
    let mut area = vec![0.0; nodes.len()];
    let inward = |f: [u32; 3]| {
        let (a, b) = (sub(x(f[1]), x(f[0])), sub(x(f[2]), x(f[0])));
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    for &(_, f) in &faces {
        let c = inward(f);
        let third = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() / 2.0 / 3.0;
        for &n in &f {
            area[slot(n)] += third;
        }
    }
    // Anura3D's: each element's last interface side only, its unnormalised inward normal
    // summed at its corners; a scene's: every side (the area-weighted mean, so that a corner
    // of the structure pushes along the bisector of its faces).
    for (k, &(e, f)) in faces.iter().enumerate() {
        let later = faces.get(k + 1).is_some_and(|next| next.0 == e);
        if later && spec.rule == InterfaceRule::Anura3d {
            continue;
        }
        let c = inward(f);
        for &n in &f {
            let s = &mut sum[slot(n)];
            for d in 0..3 {
                s[d] += c[d];
            }
        }
    }
    let normal = sum
        .iter()
        .map(|s| {
            let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt() + 1e-60;
            s.map(|c| -c / len)
        })
        .collect();
    Interface {
        nodes,
        normal,
        area,
    }
}

/// The 2D interface, by `spec.rule`.
fn lines<E: Element, R: Real>(
    spec: &ContactSpec,
    mesh: &Mesh<E, R>,
    element_material: &[u32],
) -> Interface {
    debug_assert_eq!(E::NODES, 3, "2D contact is modelled for triangles");
    let x = |n: u32| -> [f64; 3] { mesh.x[n as usize].map(|c| c.f64()) };
    // Each interface side: its nodes, and the material beyond it.
    let mut sides: Vec<([u32; 2], u32)> = Vec::new();
    for &e in &spec.listed {
        let c = mesh.corners[e as usize].as_ref();
        for side in LINES {
            let nodes = side.map(|k| c[k]);
            if let Some(m) = beyond(spec, mesh, element_material, e, &nodes) {
                sides.push((nodes, m));
            }
        }
    }
    let nodes = nodes_of(sides.iter().map(|s| s.0));
    let slot = |n: u32| nodes.binary_search(&n).expect("an interface node");
    let mut normal = vec![[0.0f64; 3]; nodes.len()];
    let mut area = vec![0.0; nodes.len()];
    for &([a, b], m) in &sides {
        let (xa, xb) = (x(a), x(b));
        let t = [xb[0] - xa[0], xb[1] - xa[1]];
        let length = (t[1] * t[1] + t[0] * t[0]).sqrt();
        let out = [t[1] / (length + 1e-60), -t[0] / (length + 1e-60), 0.0];
        match spec.rule {
            InterfaceRule::Anura3d => {
                for n in [a, b] {
                    let k = slot(n);
                    area[k] += length;
                    if m > 0 || normal[k] == [0.0; 3] {
                        normal[k] = out;
                    }
                }
            }
            InterfaceRule::Tributary => {
                // ∫ N_a r ds over the side: L (2 r_a + r_b) / 6 (r = 1 in plane strain).
                let r = |p: [f64; 3]| {
                    if E::AXISYMMETRIC {
                        p[0] + mesh.origin[0]
                    } else {
                        1.0
                    }
                };
                for (n, own, other) in [(a, xa, xb), (b, xb, xa)] {
                    let k = slot(n);
                    area[k] += length * (2.0 * r(own) + r(other)) / 6.0;
                    for d in 0..2 {
                        normal[k][d] += length * out[d];
                    }
                }
            }
        }
    }
    if spec.rule == InterfaceRule::Tributary {
        for v in &mut normal {
            let len = (v[0] * v[0] + v[1] * v[1]).sqrt() + 1e-60;
            *v = [v[0] / len, v[1] / len, 0.0];
        }
    }
    Interface {
        nodes,
        normal,
        area,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tri3::{Tri3, Tri3Axi};

    /// A 2 m square section in cells of 0.5 m: the structure (material 2) is x < 0.5, 1 < y
    /// < 2 (on the left, mesh, boundary), empty beside its upper half (x > 0.5, y > 1.5),
    /// soil (material 1) elsewhere; the spec with `rule`, the elements listed ascending or
    /// descending.
    fn section<E: Element>(
        rule: InterfaceRule,
        descending: bool,
    ) -> (Mesh<E, f64>, Vec<u32>, ContactSpec) {
        let mut model = mpm_shared::generate::rect_mesh([4, 4], [2.0, 2.0]);
        if E::AXISYMMETRIC {
            model.dimension = mpm_shared::Dimension::Axisymmetric;
        }
        let mesh = Mesh::<E, f64>::new(&model).unwrap();
        let material: Vec<u32> = (0..mesh.elements())
            .map(|e| {
                let c = mesh.corners[e].as_ref();
                let centre = |a: usize| {
                    c.iter().map(|&n| mesh.x[n as usize][a]).sum::<f64>() / 3.0 + mesh.origin[a]
                };
                match (centre(0), centre(1)) {
                    (x, y) if x < 0.5 && y > 1.0 => 2,
                    (x, y) if x > 0.5 && y > 1.5 => 0,
                    _ => 1,
                }
            })
            .collect();
        let mut listed: Vec<u32> = (0..mesh.elements() as u32)
            .filter(|&e| material[e as usize] == 2)
            .collect();
        if descending {
            listed.reverse();
        }
        let spec = ContactSpec {
            material: 2,
            listed,
            interfaces: vec![(0.0, 0.0), (0.3, 1.0), (0.0, 0.0)],
            rule,
            rigid: false,
        };
        (mesh, material, spec)
    }

    /// The interface's nodes by position, with their normals and shares.
    fn by_position<E: Element>(
        rule: InterfaceRule,
        descending: bool,
    ) -> Vec<([f64; 2], [f64; 2], f64)> {
        let (mesh, material, spec) = section::<E>(rule, descending);
        let i = Interface::of(&spec, &mesh, &material);
        let mut out: Vec<([f64; 2], [f64; 2], f64)> = i
            .nodes
            .iter()
            .enumerate()
            .map(|(k, &n)| {
                let x = mesh.x[n as usize];
                (
                    [x[0] + mesh.origin[0], x[1] + mesh.origin[1]],
                    [i.normal[k][0], i.normal[k][1]],
                    i.area[k],
                )
            })
            .collect();
        out.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
        out
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn anura3ds_2d_rule_takes_whole_lengths_and_the_last_side_facing_soil() {
        for descending in [false, true] {
            let got = by_position::<Tri3>(InterfaceRule::Anura3d, descending);
            // The bottom (soil below), the right side's lower half (soil) and upper half
            // (empty); the left side and the top are on the mesh boundary.
            let want = [
                ([0.0, 1.0], [0.0, -1.0], 0.5),
                ([0.5, 1.0], [1.0, 0.0], 1.0),
                ([0.5, 1.5], [1.0, 0.0], 1.0),
                ([0.5, 2.0], [1.0, 0.0], 0.5),
            ];
            assert_eq!(got.len(), want.len(), "{got:?}");
            for (g, w) in got.iter().zip(&want) {
                assert!(close(g.0[0], w.0[0]) && close(g.0[1], w.0[1]), "{got:?}");
                assert!(close(g.1[0], w.1[0]) && close(g.1[1], w.1[1]), "{g:?}");
                assert!(close(g.2, w.2), "{g:?}");
            }
        }
    }

    #[test]
    fn the_tributary_rule_halves_the_sides_and_weighs_the_radius() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let plane = by_position::<Tri3>(InterfaceRule::Tributary, false);
        let axi = by_position::<Tri3Axi>(InterfaceRule::Tributary, false);
        // Plane strain: half of each side; the corner's normal bisects its two sides.
        let want_plane = [
            ([0.0, -1.0], 0.25),
            ([h, -h], 0.5),
            ([1.0, 0.0], 0.5),
            ([1.0, 0.0], 0.25),
        ];
        // Axisymmetric: ∫ N r ds, L (2 r_a + r_b) / 6 per side.
        let want_axi = [
            0.5 * 0.5 / 6.0,
            0.5 * 1.0 / 6.0 + 0.5 * 1.5 / 6.0,
            2.0 * 0.5 * 1.5 / 6.0,
            0.5 * 1.5 / 6.0,
        ];
        for k in 0..4 {
            let (n, a) = want_plane[k];
            assert!(
                close(plane[k].1[0], n[0]) && close(plane[k].1[1], n[1]),
                "{plane:?}"
            );
            assert!(close(plane[k].2, a), "{plane:?}");
            assert!(close(axi[k].2, want_axi[k]), "{axi:?}");
            assert_eq!(axi[k].1, plane[k].1);
        }
    }
}
