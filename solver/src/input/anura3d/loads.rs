//! Fixities and face loads of a case: the GOM's `$$START_FIXITY_*` sections of both phases,
//! loads on nodes (solid and liquid) and on material points, scaled by their CPS multipliers.

use mpm_shared::model::{Body, Token};
use mpm_shared::{Dimension, Model};

use super::{curve, unsupported, CaseError, Input, LoadSteps};
use crate::input::case::{FaceLoad, LoadCurve, MaterialSpec};

/// The case's fixities and loads.
pub(super) struct Loads {
    /// The solid's fixed directions per node.
    pub fixed: Vec<[bool; 3]>,
    /// The liquid's fixed directions per node.
    pub liquid_fixed: Vec<[bool; 3]>,
    /// Nodal forces of the solid's face loads, times their multiplier's scale.
    pub traction: Vec<[f64; 3]>,
    /// Nodal forces of the liquid's face loads, times their multiplier's scale.
    pub liquid_traction: Vec<[f64; 3]>,
    /// Face loads carried by material points, times the solid's multiplier's scale.
    pub point_loads: Vec<FaceLoad>,
    /// The solid loads' curve (`$$SOLID_TRACTION`).
    pub traction_curve: LoadCurve,
    /// The liquid loads' curve (`$$LIQUID_PRESSURE`).
    pub liquid_curve: LoadCurve,
}

/// The fixities and loads of the GOM with their CPS multipliers; loads on the liquid need a
/// saturated material.
pub(super) fn read(
    input: &Input,
    steps: LoadSteps,
    materials: &[Option<MaterialSpec>],
) -> Result<Loads, CaseError> {
    let (s, cfile) = (&input.settings, input.cfile.as_str());
    let mut loads = sections(input)?;
    let (tm, traction_curve) = curve(s.solid_traction, steps, cfile, "$$SOLID_TRACTION")?;
    for t in loads.traction.iter_mut() {
        for v in t.iter_mut() {
            *v *= tm;
        }
    }
    // The multiplier scales the loads carried by material points as it scales those on nodes.
    for load in &mut loads.point_loads {
        for v in load.force.iter_mut() {
            *v *= tm;
        }
    }
    let (lm, liquid_curve) = curve(s.liquid_pressure, steps, cfile, "$$LIQUID_PRESSURE")?;
    for t in loads.liquid_traction.iter_mut() {
        for v in t.iter_mut() {
            *v *= lm;
        }
    }
    let has_liquid_load = loads.liquid_traction.iter().flatten().any(|&v| v != 0.0);
    if has_liquid_load && !materials.iter().flatten().any(|m| m.liquid.is_some()) {
        return Err(unsupported(
            &input.gfile,
            "$$START_LOAD_ON_NODES_LIQUID",
            "loads the liquid, but no material is saturated",
        ));
    }
    loads.traction_curve = traction_curve;
    loads.liquid_curve = liquid_curve;
    Ok(loads)
}

/// The fixity and load sections of the GOM as they are (multipliers not applied); sections of
/// kinds this solver does not model are refused by name.
fn sections(input: &Input) -> Result<Loads, CaseError> {
    let (model, gfile) = (&input.model, input.gfile.as_str());
    let n = model.node_count();
    let mut out = Loads {
        fixed: vec![[false; 3]; n],
        liquid_fixed: vec![[false; 3]; n],
        traction: vec![[0.0; 3]; n],
        liquid_traction: vec![[0.0; 3]; n],
        point_loads: Vec::new(),
        traction_curve: LoadCurve::Step,
        liquid_curve: LoadCurve::Step,
    };
    for sec in &model.sections {
        let k = sec.keyword.as_str();
        let Body::Table { rows, .. } = &sec.body else {
            continue;
        };
        if rows.is_empty() {
            continue;
        }
        let phase = if k.ends_with("_SOLID") {
            Some(&mut out.fixed)
        } else if k.ends_with("_LIQUID") {
            Some(&mut out.liquid_fixed)
        } else {
            None
        };
        if let (true, Some(target)) = (k.starts_with("START_FIXITY_"), phase) {
            for r in rows.rows() {
                let node = r[0].as_int().unwrap_or(0) as usize - 1;
                for a in 0..3 {
                    target[node][a] |= r.get(1 + a).and_then(Token::as_int) == Some(1);
                }
            }
        } else if k == "START_LOAD_ON_NODES_SOLID" {
            add_nodal_face_loads(model, rows, false, &mut out.traction)
                .map_err(|e| unsupported(gfile, &format!("$${k}"), e))?;
        } else if k == "START_LOAD_ON_NODES_LIQUID" {
            add_nodal_face_loads(model, rows, true, &mut out.liquid_traction)
                .map_err(|e| unsupported(gfile, &format!("$${k}"), e))?;
        } else if k == "START_LOAD_ON_MATERIAL_POINTS_SOLID" {
            out.point_loads.extend(face_loads_on_points(model, rows));
        } else if k.starts_with("START_REMOVE_FIXITY_")
            || k.starts_with("START_LOAD_ON_")
            || (k.starts_with("PRESCRIBED_")
                && !crate::step::prescribed::SECTIONS.contains(&k)
                && !crate::step::nodal_velocity::SECTIONS.contains(&k))
            || k.starts_with("START_FIXITY_")
            || k == "START_EXCAVATION_SOLID"
        {
            return Err(unsupported(gfile, &format!("$${k}"), "not supported yet (supported: fixities of either phase, $$START_LOAD_ON_NODES_SOLID, $$START_LOAD_ON_NODES_LIQUID, $$START_LOAD_ON_MATERIAL_POINTS_SOLID, $$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME or _SURFACE and $$PRESCRIBED_NODAL_VELOCITY_VOLUME, _SURFACE, _LINE or _POINT)"));
        }
    }
    Ok(out)
}

/// One row of a face-load table: the loaded face's corner nodes (0-based; three of a
/// tetrahedron's face, two of a triangle's edge) and the traction (kPa) given at each corner
/// (z = 0 in 2D). A row lists all the face's nodes (six of a 10-node tetrahedron's face), then a
/// vector per node; the corners come first.
struct LoadedFace {
    corners: Vec<usize>,
    traction: Vec<[f64; 3]>,
}

/// The rows of a face-load table.
fn loaded_faces(model: &Model, rows: &mpm_shared::model::Table) -> Vec<LoadedFace> {
    let k = model.element_type.face_nodes();
    let dim = model.dimension.coords();
    rows.rows()
        .map(|r| {
            let corners = (0..dim)
                .map(|i| r[i].as_int().unwrap_or(1) as usize - 1)
                .collect();
            let traction = (0..dim)
                .map(|c| {
                    let mut t = [0.0; 3];
                    for (d, v) in t.iter_mut().enumerate().take(dim) {
                        *v = r
                            .get(k + dim * c + d)
                            .and_then(Token::as_f64)
                            .unwrap_or(0.0);
                    }
                    t
                })
                .collect();
            LoadedFace { corners, traction }
        })
        .collect()
}

/// The radius of model node `n` in an axisymmetric model (its x), 1 otherwise: Anura3D's loads
/// on an axisymmetric section are per radian.
fn radius(model: &Model, n: usize) -> f64 {
    if model.dimension == Dimension::Axisymmetric {
        model.node(n)[0]
    } else {
        1.0
    }
}

/// The nodal forces of edge `[a, b]` of length `size` with tractions `t` at its ends, by
/// Anura3D's one Gauss point: each end takes L/2 (t_a r_a + t_b r_b)/2 (r the radius in an
/// axisymmetric section, else 1), and an end on the axis gives 7/8 of it to the other end.
fn edge_forces(
    model: &Model,
    [a, b]: [usize; 2],
    size: f64,
    t: [[f64; 3]; 2],
) -> [(usize, [f64; 3]); 2] {
    let (ra, rb) = (radius(model, a), radius(model, b));
    let half = [0, 1, 2].map(|d| size / 2.0 * (t[0][d] * ra + t[1][d] * rb) / 2.0);
    let on_axis = |r: f64| model.dimension == Dimension::Axisymmetric && r < f64::MIN_POSITIVE;
    // The share each end gives or takes: 0 unless one end is on the axis.
    let shift = match (on_axis(ra), on_axis(rb)) {
        (true, false) => -7.0 / 8.0,
        (false, true) => 7.0 / 8.0,
        _ => 0.0,
    };
    [
        (a, half.map(|h| h * (1.0 + shift))),
        (b, half.map(|h| h * (1.0 - shift))),
    ]
}

/// The loads of `$$START_LOAD_ON_MATERIAL_POINTS_SOLID` rows: Anura3D takes the traction at the
/// face's centroid (one Gauss point), the mean of the corner values (times the radius in an
/// axisymmetric section), times the face's area (an edge's length in 2D) as the face's total
/// force.
fn face_loads_on_points(model: &Model, rows: &mpm_shared::model::Table) -> Vec<FaceLoad> {
    loaded_faces(model, rows)
        .into_iter()
        .map(|f| {
            let size = crate::input::faces::size(model, &f.corners);
            let n = f.corners.len() as f64;
            let mut force = [0.0; 3];
            for (&c, t) in f.corners.iter().zip(&f.traction) {
                for (d, v) in force.iter_mut().enumerate() {
                    *v += size / n * t[d] * radius(model, c);
                }
            }
            FaceLoad {
                corners: f.corners,
                force,
            }
        })
        .collect()
}

/// Adds the nodal forces of `$$START_LOAD_ON_NODES_SOLID` (or `_LIQUID`) rows.
///
/// 3D: the corner tractions are interpolated linearly over the face and integrated exactly:
/// F_a = A/12 (2 t_a + t_b + t_c). For the liquid (`normal`), Anura3D applies the load normal
/// to the face: each component is multiplied by that of the face's outward unit normal, so
/// negative values push into the body.
///
/// 2D: Anura3D integrates an edge with one Gauss point at its middle, so each of its two nodes
/// takes half the edge's force, L/2 (t_a + t_b)/2 (in an axisymmetric section the traction
/// times the node's radius, and when a node lies on the axis 7/8 of that half moves to the other
/// node, as Anura3D does). For the liquid the first component of each node's value is a
/// pressure, applied along the edge's outward normal.
fn add_nodal_face_loads(
    model: &Model,
    rows: &mpm_shared::model::Table,
    normal: bool,
    out: &mut [[f64; 3]],
) -> Result<(), String> {
    let faces = loaded_faces(model, rows);
    let corners: Vec<Vec<usize>> = faces.iter().map(|f| f.corners.clone()).collect();
    let normals = if normal {
        crate::input::faces::outward_normals(model, &corners)?
    } else {
        vec![[1.0; 3]; faces.len()]
    };
    for (f, n) in faces.iter().zip(&normals) {
        let size = crate::input::faces::size(model, &f.corners);
        if let [a, b] = f.corners[..] {
            // A liquid row's first value is a pressure along the normal.
            let t = [0, 1].map(|c| {
                let t = f.traction[c];
                if normal {
                    n.map(|v| v * t[0])
                } else {
                    t
                }
            });
            for (node, force) in edge_forces(model, [a, b], size, t) {
                for d in 0..3 {
                    out[node][d] += force[d];
                }
            }
            continue;
        }
        let t: Vec<[f64; 3]> = f
            .traction
            .iter()
            .map(|t| [0, 1, 2].map(|d| n[d] * t[d]))
            .collect();
        let ids = &f.corners;
        for i in 0..3 {
            let (j, l) = ((i + 1) % 3, (i + 2) % 3);
            for d in 0..3 {
                out[ids[i]][d] += size / 12.0 * (2.0 * t[i][d] + t[j][d] + t[l][d]);
            }
        }
    }
    Ok(())
}
