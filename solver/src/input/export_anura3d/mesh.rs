//! The exported mesh: 10-node tetrahedra (Anura3D's `tetrahedral_old`), with the rows of its
//! face loads and of the reaction faces of its nodal-velocity sets.

use std::collections::HashMap;

use mpm_shared::model::{Table, Token};
use mpm_shared::{ElementType, Model};

use crate::input::scene;

/// Mid-edge node k (0-based, 4..10) of a `tetrahedral_old` element lies between these corners.
const EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)];

/// The mesh as 10-node tetrahedra with the fixities of every node.
pub(super) struct Tet10Mesh {
    pub coords: Vec<f64>,
    pub connectivity: Vec<u32>,
    pub fixed: Vec<[bool; 3]>,
    pub liquid_fixed: Vec<[bool; 3]>,
    /// Mid-edge node of each edge (corner ids sorted).
    pub mid: HashMap<(u32, u32), u32>,
}

impl Tet10Mesh {
    /// `model` (4- or 10-node tetrahedra) with its fixities; a 4-node mesh gets its mid-edge
    /// nodes, numbered after the others in order of first appearance.
    pub fn of(model: &Model, fixed: &[[bool; 3]], liquid_fixed: &[[bool; 3]]) -> Option<Self> {
        let n_el = model.element_count();
        let mut coords = model.coords.clone();
        let mut fixed = fixed.to_vec();
        let mut liquid_fixed = liquid_fixed.to_vec();
        let mut mid = HashMap::with_capacity(n_el * 2);
        let mut connectivity = Vec::with_capacity(n_el * 10);
        let key = |a: u32, b: u32| (a.min(b), a.max(b));
        match model.element_type {
            ElementType::Tet10 => {
                connectivity.extend_from_slice(&model.connectivity);
                for e in 0..n_el {
                    let el = model.element(e);
                    for (k, (a, b)) in EDGES.iter().enumerate() {
                        mid.insert(key(el[*a], el[*b]), el[4 + k]);
                    }
                }
            }
            ElementType::Tet4 => {
                for e in 0..n_el {
                    let c: [u32; 4] = model.element(e).try_into().expect("4 corners");
                    connectivity.extend_from_slice(&c);
                    for (a, b) in EDGES {
                        let next = (coords.len() / 3) as u32;
                        let id = *mid.entry(key(c[a], c[b])).or_insert_with(|| {
                            let (p, q) = (model.node(c[a] as usize), model.node(c[b] as usize));
                            for d in 0..3 {
                                coords.push(0.5 * (p[d] + q[d]));
                            }
                            let both = |f: &[[bool; 3]]| {
                                let (f, g) = (f[c[a] as usize], f[c[b] as usize]);
                                [f[0] && g[0], f[1] && g[1], f[2] && g[2]]
                            };
                            fixed.push(both(&fixed));
                            liquid_fixed.push(both(&liquid_fixed));
                            next
                        });
                        connectivity.push(id);
                    }
                }
            }
            ElementType::Tri3 => return None,
        }
        Some(Tet10Mesh {
            coords,
            connectivity,
            fixed,
            liquid_fixed,
            mid,
        })
    }

    /// Node `n`'s coordinates.
    pub fn node(&self, n: u32) -> [f64; 3] {
        let i = n as usize * 3;
        [self.coords[i], self.coords[i + 1], self.coords[i + 2]]
    }
}

/// One `$$START_LOAD_ON_NODES_SOLID` row per loaded face: corners ordered as Anura3D's
/// pre-processor writes boundary faces ((c2 - c1) × (c3 - c1) points into the element), the
/// mid-edge nodes of edges 12, 23 and 31, then the traction at each of the six nodes.
pub(super) fn load_rows(
    mesh: &Tet10Mesh,
    tractions: &[&scene::TractionInput],
) -> Result<Table, (String, String)> {
    let sorted = |f: [u32; 3]| {
        let mut k = f;
        k.sort_unstable();
        k
    };
    // The corner opposite each loaded face in an element that has it.
    let mut opposite: HashMap<[u32; 3], Option<u32>> = tractions
        .iter()
        .flat_map(|t| t.faces.iter().map(|f| (sorted([f[0], f[1], f[2]]), None)))
        .collect();
    for c in mesh.connectivity.chunks_exact(10) {
        for skip in 0..4 {
            let mut f = [0u32; 3];
            let mut j = 0;
            for (i, &n) in c[..4].iter().enumerate() {
                if i != skip {
                    f[j] = n;
                    j += 1;
                }
            }
            if let Some(slot) = opposite.get_mut(&sorted(f)) {
                slot.get_or_insert(c[skip]);
            }
        }
    }
    let mut rows = Table::with_capacity(tractions.iter().map(|t| t.faces.len()).sum(), 24);
    for t in tractions {
        for f in &t.faces {
            // A 3D scene's faces are triangles (2D scenes are refused before this).
            let f = [f[0], f[1], f[2]];
            let item = || format!("traction \"{}\"", t.physical);
            let inner = opposite[&sorted(f)].ok_or_else(|| {
                (
                    item(),
                    format!(
                        "the face with corner nodes {} {} {} is not a face of any element",
                        f[0] + 1,
                        f[1] + 1,
                        f[2] + 1
                    ),
                )
            })?;
            let [p, q, s] = f.map(|n| mesh.node(n));
            let o = mesh.node(inner);
            let (a, b) = (
                [0, 1, 2].map(|d| q[d] - p[d]),
                [0, 1, 2].map(|d| s[d] - p[d]),
            );
            let n = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let inward: f64 = (0..3).map(|d| n[d] * (o[d] - p[d])).sum();
            let c = if inward < 0.0 { [f[0], f[2], f[1]] } else { f };
            // A pressure pushes along the face's inward normal.
            let traction = match t.pressure {
                Some(pressure) => {
                    let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    let s = pressure * inward.signum() / length;
                    n.map(|c| s * c)
                }
                None => t.traction,
            };
            let mid = |i: usize, j: usize| mesh.mid[&(c[i].min(c[j]), c[i].max(c[j]))];
            let ids = [c[0], c[1], c[2], mid(0, 1), mid(1, 2), mid(2, 0)];
            rows.push_row(
                ids.iter()
                    .map(|&i| Token::Int(i as i64 + 1))
                    .chain((0..6).flat_map(|_| traction.map(Token::Real))),
            );
        }
    }
    Ok(rows)
}

/// `$$START_OUTPUT_REACTION_FORCES` rows, so that Anura3D writes each nodal-velocity set's
/// reaction (`NAME.RSurf_00k`, k the set's place among those with faces; every time step): per
/// set, every element face whose three corners are in the set (once), as the set's name
/// (quoted), the element and the face's corners and mid-edge nodes. Anura3D sums its nodes' B^T sigma less
/// their weight over these faces' nodes; the set's mid-edge nodes are the faces' (see
/// `gom_model`), so the nodes summed are the set's unless some of its nodes lie on no face.
pub(super) fn reaction_rows(
    mesh: &Tet10Mesh,
    sets: &[crate::step::nodal_velocity::NodalVelocitySet],
) -> Table {
    const FACES: [[usize; 3]; 4] = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
    let mut t = Table::new();
    let n_nodes = mesh.coords.len() / 3;
    for set in sets {
        let mut inside = vec![false; n_nodes];
        for p in &set.rows {
            inside[p.node as usize] = true;
        }
        let label = Token::Text(format!("\"{}\"", safe_name(&set.name)).into());
        // A face inside the mesh (the footing under an empty layer) once, in its first element.
        let mut seen = std::collections::HashSet::new();
        for (e, c) in mesh.connectivity.chunks_exact(10).enumerate() {
            for f in FACES {
                let k = f.map(|i| c[i]);
                let mut key = k;
                key.sort_unstable();
                if !k.iter().all(|&n| inside[n as usize]) || !seen.insert(key) {
                    continue;
                }
                let mid = |a: u32, b: u32| mesh.mid[&(a.min(b), a.max(b))];
                let ids = [
                    k[0],
                    k[1],
                    k[2],
                    mid(k[0], k[1]),
                    mid(k[1], k[2]),
                    mid(k[2], k[0]),
                ];
                t.push_row(
                    [label.clone(), Token::Int(e as i64 + 1)]
                        .into_iter()
                        .chain(ids.map(|n| Token::Int(n as i64 + 1))),
                );
            }
        }
    }
    t
}

/// A material name Anura3D reads whole (its list-directed read stops at blanks, commas, slashes
/// and quotes): other characters become `_`.
pub(super) fn safe_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "_-.+()[]".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        "material".into()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpm_shared::generate::box_mesh;

    #[test]
    fn mid_edge_nodes_of_a_4_node_box_are_those_of_the_10_node_box() {
        // The structured 10-node box has a node at the midpoint of every edge of the 4-node one
        // (same elements, same corner order): adding mid-edge nodes must give the same geometry
        // node for node, and as many nodes.
        let (n, size) = ([2, 3, 2], [1.0, 1.5, 0.5]);
        let tet4 = box_mesh(n, size, ElementType::Tet4);
        let tet10 = box_mesh(n, size, ElementType::Tet10);
        let fixed: Vec<[bool; 3]> = (0..tet4.node_count())
            .map(|i| {
                let p = tet4.node(i);
                [p[0] == 0.0, p[1] == 0.0, p[0] == 0.0 && p[2] == 0.0]
            })
            .collect();
        let mesh = Tet10Mesh::of(&tet4, &fixed, &fixed).unwrap();
        assert_eq!(mesh.coords.len(), tet10.coords.len());
        assert_eq!(mesh.connectivity.len(), tet10.connectivity.len());
        for (a, b) in mesh.connectivity.iter().zip(&tet10.connectivity) {
            assert_eq!(mesh.node(*a).as_slice(), tet10.node(*b as usize));
        }
        // New nodes follow the original ones in order of first appearance.
        let mut seen = tet4.node_count() as u32;
        for el in mesh.connectivity.chunks_exact(10) {
            for &m in &el[4..] {
                assert!(m < seen + 1 && m >= tet4.node_count() as u32);
                seen = seen.max(m + 1);
            }
        }
        // A mid-edge node is fixed in a component where both corners are: on the planes
        // x = 0 and y = 0, and on the line x = z = 0.
        for (i, f) in mesh.fixed.iter().enumerate() {
            let p = mesh.node(i as u32);
            assert_eq!(*f, [p[0] == 0.0, p[1] == 0.0, p[0] == 0.0 && p[2] == 0.0]);
        }
    }
}
