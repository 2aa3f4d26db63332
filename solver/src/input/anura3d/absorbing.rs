//! Anura3D's absorbing boundaries (`$$ABSORBING_BOUNDARY_{SURFACE,LINE,POINT}_{SOLID,LIQUID}`
//! with `$$ABSORBING_BOUNDARY_REFERENCE_MATERIAL_INDEX`, and the CPS's `$$APPLY_NODE_DATA_AB`),
//! resolved to a dashpot and a spring per node and axis as Anura3D forms them
//! (docs/design.md §4.9):
//!
//! - each row is `node (flag a δ) per axis`; per phase the surfaces' rows come first, then the
//!   lines', then the points', a later row of a node replacing an earlier one;
//! - a node's area A sums, over the elements around it (ascending) and their sides on the mesh's
//!   boundary whose nodes all have rows of the phase, half the side's length (2D, whatever the
//!   section) or a third of its area (3D): the side need not hold the node, as in Anura3D;
//! - an axis with a flag takes its kind from the last such side: normal where the side's edge
//!   (2D) has no extent along it or its normal (3D) has one, else shear;
//! - the solid's dashpot is ρ V A a and its spring ρ V² A / δ, ρ the reference material's dry
//!   density (1 − n) ρs, V its P-wave speed sqrt(E_oed / ρ) on normal axes and S-wave speed
//!   sqrt(G / ρ) on shear ones; the liquid's, both kinds alike, ρw V_w A a and ρw V_w² A / δ with
//!   V_w = sqrt(K_w / ρw).

use mpm_shared::model::{Body, Model, Token};

use super::{unsupported, CaseError, Input};
use crate::input::case::MaterialSpec;
use crate::step::absorbing::{AbsorbingNode, AbsorbingRule};

/// The sections' prefix.
const PREFIX: &str = "ABSORBING_BOUNDARY_";

/// One node's row: per axis its flag, coefficient a and spring length δ.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Row {
    on: [bool; 3],
    a: [f64; 3],
    delta: [f64; 3],
}

/// The case's absorbing boundary rows (model nodes) and their rule; `None` without any.
pub(super) fn read(
    input: &Input,
    materials: &[Option<MaterialSpec>],
) -> Result<Option<(Vec<AbsorbingNode>, AbsorbingRule)>, CaseError> {
    let (model, gfile) = (&input.model, input.gfile.as_str());
    let solid = table(model, gfile, "SOLID")?;
    let liquid = table(model, gfile, "LIQUID")?;
    if table(model, gfile, "GAS")?.iter().any(Option::is_some) {
        return Err(unsupported(
            gfile,
            &format!("$${PREFIX}*_GAS"),
            "gas phases are not modelled",
        ));
    }
    if solid.iter().chain(&liquid).all(Option::is_none) {
        return Ok(None);
    }
    let reference = reference(model, gfile, materials)?;
    let dim = model.dimension.coords();
    let solid_areas = areas(model, &solid);
    let liquid_areas = areas(model, &liquid);
    // The dry density (1 − n) ρs, whatever the material's type, and G and E_oed as Anura3D
    // forms them.
    let rho = reference.wave_density;
    let (young, poisson) = reference.law.elastic();
    let g = young / (2.0 * (1.0 + poisson));
    let e_oed = (2.0 * g * (1.0 - poisson)) / (1.0 - 2.0 * poisson);
    let (vp, vs) = ((e_oed / rho).sqrt(), (g / rho).sqrt());
    let liquid_spec = reference.liquid.as_ref();
    if liquid.iter().any(Option::is_some) && liquid_spec.is_none() {
        return Err(unsupported(
            gfile,
            &format!("$${PREFIX}*_LIQUID"),
            "the reference material is not saturated: it gives the liquid no density or bulk modulus",
        ));
    }
    let mut out = Vec::new();
    for n in 0..model.node_count() {
        let mut node = AbsorbingNode {
            node: n as u32,
            dashpot: [0.0; 6],
            spring: [0.0; 6],
            liquid_dashpot: [0.0; 3],
            liquid_spring: [0.0; 3],
        };
        if let (Some(r), (area, normal)) = (&solid[n], &solid_areas[n]) {
            for d in (0..dim).filter(|&d| r.on[d]) {
                let v = if normal[d] { vp } else { vs };
                // Anura3D's order of operations.
                node.dashpot[d] = rho * v * area * r.a[d];
                node.spring[d] = rho * v * v * area / r.delta[d];
            }
        }
        if let (Some(r), (area, _), Some(l)) = (&liquid[n], &liquid_areas[n], liquid_spec) {
            let vw = (l.bulk_modulus / l.density).sqrt();
            for d in (0..dim).filter(|&d| r.on[d]) {
                node.liquid_dashpot[d] = l.density * vw * area * r.a[d];
                node.liquid_spring[d] = l.density * vw * vw * area / r.delta[d];
            }
        }
        if solid[n].is_some() || liquid[n].is_some() {
            out.push(node);
        }
    }
    let point_sums = !node_data(input)?;
    Ok(Some((out, AbsorbingRule::Anura3d { point_sums })))
}

/// Whether the CPS's `$$APPLY_NODE_DATA_AB` is 1 (the nodes' own displacements and
/// accelerations; 0, the default, sums over the points).
fn node_data(input: &Input) -> Result<bool, CaseError> {
    let Some(e) = input.cps.get("APPLY_NODE_DATA_AB") else {
        return Ok(false);
    };
    match e.lines.first().and_then(|l| l.split_whitespace().next()) {
        Some("0") | None => Ok(false),
        Some("1") => Ok(true),
        Some(other) => Err(unsupported(
            &input.cfile,
            "$$APPLY_NODE_DATA_AB",
            format!("expected 0 or 1, got {other}"),
        )),
    }
}

/// The reference material of `$${PREFIX}REFERENCE_MATERIAL_INDEX`.
fn reference<'m>(
    model: &Model,
    gfile: &str,
    materials: &'m [Option<MaterialSpec>],
) -> Result<&'m MaterialSpec, CaseError> {
    let item = format!("$${PREFIX}REFERENCE_MATERIAL_INDEX");
    let index = match model.section(&format!("{PREFIX}REFERENCE_MATERIAL_INDEX")) {
        Some(s) => match &s.body {
            Body::Text(lines) => lines
                .iter()
                .flat_map(|l| l.split_whitespace())
                .next()
                .and_then(|w| w.parse::<usize>().ok()),
            _ => None,
        },
        None => {
            return Err(unsupported(
                gfile,
                &item,
                "missing: Anura3D takes the dashpots' density and wave speeds from it",
            ))
        }
    };
    index
        .and_then(|i| materials.get(i)?.as_ref())
        .ok_or_else(|| unsupported(gfile, &item, "expected the index of a material of the GOM"))
}

/// Per model node, its row of the phase's sections (surfaces, then lines, then points, a later
/// row replacing an earlier one); rows of nodes that are not element corners are left out.
fn table(model: &Model, gfile: &str, phase: &str) -> Result<Vec<Option<Row>>, CaseError> {
    let dim = model.dimension.coords();
    let corners = corner_nodes(model);
    let mut out = vec![None; model.node_count()];
    for kind in ["SURFACE", "LINE", "POINT"] {
        let keyword = format!("{PREFIX}{kind}_{phase}");
        let Some(section) = model.section(&keyword) else {
            continue;
        };
        let item = format!("$${keyword}");
        let Body::Table { rows, .. } = &section.body else {
            return Err(unsupported(gfile, &item, "expected a count and rows"));
        };
        for (k, r) in rows.rows().enumerate() {
            let (node, row) = parse_row(r, dim, model.node_count())
                .map_err(|m| unsupported(gfile, &item, format!("row {}: {m}", k + 1)))?;
            if corners[node] {
                out[node] = Some(row);
            }
        }
    }
    Ok(out)
}

/// A row `node (flag a δ) per axis` (0-based node).
fn parse_row(r: &[Token], dim: usize, nodes: usize) -> Result<(usize, Row), String> {
    let v: Vec<f64> = r.iter().map(|t| t.as_f64().unwrap_or(f64::NAN)).collect();
    if v.len() != 1 + 3 * dim || v.iter().any(|x| !x.is_finite()) {
        return Err(format!(
            "expected {} numbers: the node, then flag, a and δ per axis",
            1 + 3 * dim
        ));
    }
    let node = v[0];
    if node.fract() != 0.0 || node < 1.0 || node > nodes as f64 {
        return Err(format!("node {node} is not in the mesh (1..={nodes})"));
    }
    let mut row = Row {
        on: [false; 3],
        a: [0.0; 3],
        delta: [0.0; 3],
    };
    for d in 0..dim {
        let (flag, a, delta) = (v[1 + 3 * d], v[2 + 3 * d], v[3 + 3 * d]);
        row.on[d] = match flag {
            0.0 => false,
            1.0 => true,
            _ => return Err(format!("flag {flag} of axis {}: expected 0 or 1", d + 1)),
        };
        if row.on[d] && !(delta > 0.0) {
            return Err(format!(
                "axis {}: δ = {delta}; Anura3D divides the spring by it (give a positive length)",
                d + 1
            ));
        }
        row.a[d] = a;
        row.delta[d] = delta;
    }
    Ok((node as usize - 1, row))
}

/// Which model nodes are element corners.
fn corner_nodes(model: &Model) -> Vec<bool> {
    let k = model.element_type.corners();
    let mut out = vec![false; model.node_count()];
    for e in 0..model.element_count() {
        for &n in &model.element(e)[..k] {
            out[n as usize] = true;
        }
    }
    out
}

/// The local corners of each side of a triangle and of a tetrahedron, in Anura3D's order.
const TRIANGLE_SIDES: [&[usize]; 3] = [&[0, 1], &[2, 0], &[1, 2]];
const TETRAHEDRON_SIDES: [&[usize]; 4] = [&[0, 1, 2], &[0, 3, 1], &[0, 2, 3], &[1, 3, 2]];

/// Per model node with a row in `rows`, its area and, per axis, whether its last qualifying
/// side makes the axis normal (Anura3D's classification); `(0, [false; 3])` elsewhere.
fn areas(model: &Model, rows: &[Option<Row>]) -> Vec<(f64, [bool; 3])> {
    let mut out = vec![(0.0, [false; 3]); model.node_count()];
    if rows.iter().all(Option::is_none) {
        return out;
    }
    let two_d = model.dimension.coords() == 2;
    let sides: &[&[usize]] = if two_d {
        &TRIANGLE_SIDES
    } else {
        &TETRAHEDRON_SIDES
    };
    let k = model.element_type.corners();
    let key = |e: usize, side: &[usize]| {
        let c = model.element(e);
        let mut s: Vec<u32> = side.iter().map(|&i| c[i]).collect();
        s.sort_unstable();
        s
    };
    // How many elements have each side: once, the mesh's boundary.
    let mut count: std::collections::HashMap<Vec<u32>, u32> = std::collections::HashMap::new();
    for e in 0..model.element_count() {
        for side in sides {
            *count.entry(key(e, side)).or_insert(0) += 1;
        }
    }
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); model.node_count()];
    for e in 0..model.element_count() {
        for &n in &model.element(e)[..k] {
            around[n as usize].push(e);
        }
    }
    let x = |n: u32, d: usize| model.node(n as usize).get(d).copied().unwrap_or(0.0);
    for (n, row) in rows.iter().enumerate() {
        let Some(row) = row else { continue };
        let (area, normal) = &mut out[n];
        for &e in &around[n] {
            let c = model.element(e);
            for side in sides {
                let nodes: Vec<u32> = side.iter().map(|&i| c[i]).collect();
                if count[&key(e, side)] != 1 || nodes.iter().any(|&m| rows[m as usize].is_none()) {
                    continue;
                }
                let normal_to: [bool; 3] = if two_d {
                    let v = [0, 1].map(|d| x(nodes[1], d) - x(nodes[0], d));
                    *area += (v[0] * v[0] + v[1] * v[1]).sqrt() / 2.0;
                    // An edge with no extent along an axis is normal to it.
                    [v[0] == 0.0, v[1] == 0.0, false]
                } else {
                    let u = [0, 1, 2].map(|d| x(nodes[1], d) - x(nodes[0], d));
                    let v = [0, 1, 2].map(|d| x(nodes[2], d) - x(nodes[0], d));
                    let w = [
                        u[1] * v[2] - u[2] * v[1],
                        u[2] * v[0] - u[0] * v[2],
                        u[0] * v[1] - u[1] * v[0],
                    ];
                    *area += ((w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt() / 2.0) / 3.0;
                    // A face whose normal has a component along an axis is normal to it.
                    w.map(|c| c != 0.0)
                };
                for d in (0..3).filter(|&d| row.on[d]) {
                    normal[d] = normal_to[d];
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tokens(v: &[f64]) -> Vec<Token> {
        v.iter().map(|&x| Token::Real(x)).collect()
    }

    #[test]
    fn rows_are_read_and_bad_ones_named() {
        let (node, row) = parse_row(&tokens(&[3.0, 0.0, 0.0, 0.0, 1.0, 1.5, 15.0]), 2, 10).unwrap();
        assert_eq!(node, 2);
        assert_eq!(row.on, [false, true, false]);
        assert_eq!((row.a[1], row.delta[1]), (1.5, 15.0));
        let e = parse_row(&tokens(&[3.0, 0.0, 0.0, 0.0, 1.0, 1.5, 0.0]), 2, 10).unwrap_err();
        assert!(e.contains("δ = 0"), "{e}");
        let e = parse_row(&tokens(&[11.0, 0.0, 0.0, 0.0, 1.0, 1.5, 1.0]), 2, 10).unwrap_err();
        assert!(e.contains("not in the mesh"), "{e}");
        let e = parse_row(&tokens(&[1.0, 2.0, 0.0, 0.0, 1.0, 1.5, 1.0]), 2, 10).unwrap_err();
        assert!(e.contains("expected 0 or 1"), "{e}");
        assert!(parse_row(&tokens(&[1.0, 0.0]), 2, 10).is_err());
    }
}
