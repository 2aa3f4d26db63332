//! The exported GOM: the mesh, fixities, loads, prescribed velocities, material blocks and
//! element tables, in the order Anura3D's pre-processor writes its sections.

use mpm_shared::model::{Body, LineEnding, Refs, Section, Table, Token};
use mpm_shared::text::real_to_string;
use mpm_shared::{Dimension, ElementType, Model};

use super::mesh::{reaction_rows, safe_name, Tet10Mesh};
use super::VERSION;
use crate::input::case::Case;
use crate::input::scene::{MaterialInput, Resolved};

/// The GOM of the resolved scene `r` on `mesh`, with the face-load rows `loads`; differences
/// the file cannot avoid go to `notes`.
pub(super) fn gom_model(
    r: &Resolved,
    mesh: Tet10Mesh,
    loads: Table,
    notes: &mut Vec<String>,
) -> Model {
    let case = &r.case;
    let mut sections = mpm_shared::model::geometry_sections();
    fixity_sections(&mesh, &mut sections);
    if !loads.is_empty() {
        sections.push(counted("START_LOAD_ON_NODES_SOLID", Refs::Nodes(6), loads));
    }
    velocity_sections(case, &mesh, &mut sections);
    sections.push(counted("START_CONTACT_VOLUME", Refs::Element, Table::new()));
    let n_mat = case.body.materials.len().saturating_sub(1);
    sections.push(text("NUMBER_OF_MATERIALS", &[&n_mat.to_string()]));
    for (k, m) in r.materials.iter().enumerate().skip(1) {
        let m = m.as_ref().expect("checked in build");
        material_block(k, m, notes, &mut sections);
    }
    element_sections(case, &mut sections);
    Model {
        version: VERSION.into(),
        line_ending: LineEnding::Lf,
        dimension: Dimension::Cartesian3D,
        element_type: ElementType::Tet10,
        coords: mesh.coords,
        connectivity: mesh.connectivity,
        sections,
    }
}

/// The fixity sections of every phase and kind (the solid's and the liquid's on surfaces, the
/// others empty), then the empty fixity removals.
fn fixity_sections(mesh: &Tet10Mesh, sections: &mut Vec<Section>) {
    let fixity_rows = |f: &[[bool; 3]]| {
        let mut t = Table::new();
        for (n, x) in f.iter().enumerate() {
            if x.iter().any(|&v| v) {
                t.push_row(
                    std::iter::once(Token::Int(n as i64 + 1))
                        .chain(x.iter().map(|&v| Token::Int(v as i64))),
                );
            }
        }
        t
    };
    let one = Refs::Nodes(1);
    for phase in ["SOLID", "LIQUID", "GAS"] {
        for kind in ["SURFACE", "LINE", "POINT"] {
            let rows = match (phase, kind) {
                ("SOLID", "SURFACE") => fixity_rows(&mesh.fixed),
                ("LIQUID", "SURFACE") => fixity_rows(&mesh.liquid_fixed),
                _ => Table::new(),
            };
            sections.push(counted(&format!("START_FIXITY_{kind}_{phase}"), one, rows));
        }
    }
    for phase in ["SOLID", "LIQUID", "GAS"] {
        for kind in ["SURFACE", "LINE", "POINT"] {
            sections.push(counted(
                &format!("START_REMOVE_FIXITY_{kind}_{phase}"),
                one,
                Table::new(),
            ));
        }
    }
}

/// The prescribed velocities: on material points by element, on nodes (a new mid-edge node
/// between two of a set's nodes taking the set's velocity) with the faces Anura3D writes each
/// nodal set's reaction on.
fn velocity_sections(case: &Case, mesh: &Tet10Mesh, sections: &mut Vec<Section>) {
    let row = |id: u32, d: [bool; 3], v: [f64; 3]| {
        std::iter::once(Token::Int(id as i64 + 1))
            .chain(d.map(|x| Token::Int(x as i64)))
            .chain(v.map(Token::Real))
    };
    if let Some(pv) = &case.boundary.prescribed {
        let mut t = Table::with_capacity(pv.rows.len(), 7);
        for p in &pv.rows {
            t.push_row(row(p.element, p.directions, p.velocity));
        }
        sections.push(counted(
            "PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME",
            Refs::Element,
            t,
        ));
    }
    if case.boundary.nodal_velocity.is_empty() {
        return;
    }
    let original = case.model.node_count() as u32;
    let mut t = Table::new();
    for set in &case.boundary.nodal_velocity {
        for p in &set.rows {
            t.push_row(row(p.node, p.directions, p.velocity));
        }
        // New mid-edge nodes between two of the set's nodes, in node order.
        let mut inside = vec![false; original as usize];
        for p in &set.rows {
            inside[p.node as usize] = true;
        }
        let first = set.rows.first().expect("a set has nodes");
        let mut mids: Vec<u32> = mesh
            .mid
            .iter()
            .filter(|(&(a, b), &m)| m >= original && inside[a as usize] && inside[b as usize])
            .map(|(_, &m)| m)
            .collect();
        mids.sort_unstable();
        for m in mids {
            t.push_row(row(m, first.directions, first.velocity));
        }
    }
    sections.push(counted(
        "PRESCRIBED_NODAL_VELOCITY_SURFACE",
        Refs::Nodes(1),
        t,
    ));
    sections.push(counted(
        "START_OUTPUT_REACTION_FORCES",
        Refs::LabelElementNodes(6),
        reaction_rows(mesh, &case.boundary.nodal_velocity),
    ));
}

/// Material `k`'s block: its index, name, type, densities (and liquid), K0, law and the law's
/// parameters under Anura3D's keys.
fn material_block(
    k: usize,
    m: &MaterialInput,
    notes: &mut Vec<String>,
    sections: &mut Vec<Section>,
) {
    let name = safe_name(&m.physical);
    if name != m.physical {
        notes.push(format!(
            "material \"{}\" is named {name} in the GOM (Anura3D reads a name up to a blank, comma, slash or quote)",
            m.physical
        ));
    }
    let num = real_to_string;
    let mut block: Vec<(&str, String)> =
        vec![("MATERIAL_INDEX", k.to_string()), ("MATERIAL_NAME", name)];
    match &m.liquid {
        None => block.extend([
            ("MATERIAL_TYPE", "dry_material".to_string()),
            // Anura3D's dry mass is (1 - n) ρs: with n = 0 it is the scene's density.
            ("POROSITY_SOLID", num(0.0)),
            ("DENSITY_SOLID", num(m.density)),
        ]),
        Some(l) => block.extend([
            ("MATERIAL_TYPE", "saturated_material_coupled".to_string()),
            ("POROSITY_SOLID", num(l.porosity)),
            ("DENSITY_SOLID", num(m.density)),
            ("DENSITY_LIQUID", num(l.density)),
            (
                "INTRINSIC_PERMEABILITY_LIQUID",
                num(l.intrinsic_permeability),
            ),
            ("BULK_MODULUS_LIQUID", num(l.bulk_modulus)),
            ("DYNAMIC_VISCOSITY_LIQUID", num(l.viscosity)),
        ]),
    }
    block.extend([
        ("K0_VALUE_SOLID", num(m.k0.unwrap_or(0.0))),
        ("MATERIAL_MODEL_SOLID", m.law.name().to_string()),
    ]);
    // The law's keys in the order Anura3D reads them.
    block.extend(m.law.parameters().into_iter().map(|(k, v)| (k, num(v))));
    for (key, value) in block {
        sections.push(text(key, &[&value]));
    }
}

/// Each element's material and material points.
fn element_sections(case: &Case, sections: &mut Vec<Section>) {
    let body = &case.body;
    let mut elmmat = Table::with_capacity(body.element_material.len(), 1);
    let mut points = Table::with_capacity(body.element_material.len(), 2);
    for (&m, &n) in body.element_material.iter().zip(&body.points_per_element) {
        // Anura3D refuses an element with a material but no points: an element the scene
        // leaves empty (`points_per_element = 0`) is written as inactive (material 0).
        let m = if n == 0 { 0 } else { m };
        elmmat.push_row([Token::Int(m as i64)]);
        let n = if m == 0 { 0 } else { n };
        points.push_row([Token::Int(n as i64), Token::Int(0)]);
    }
    let section = |k: &str, body: Body| Section {
        keyword: k.into(),
        body,
    };
    sections.push(section("STARTELMMAT", Body::PerElement(elmmat)));
    sections.push(section(
        "START_NUMBER_OF_MATERIAL_POINTS",
        Body::PerElement(points),
    ));
}

/// A section of text lines.
fn text(keyword: &str, lines: &[&str]) -> Section {
    Section {
        keyword: keyword.into(),
        body: Body::Text(lines.iter().map(|l| l.to_string()).collect()),
    }
}

/// A table section whose row count precedes its rows.
fn counted(keyword: &str, refs: Refs, rows: Table) -> Section {
    Section {
        keyword: keyword.into(),
        body: Body::Table {
            counted: true,
            refs,
            rows,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_anura3d_would_cut_are_made_one_token() {
        assert_eq!(safe_name("soil"), "soil");
        assert_eq!(safe_name("soft clay/2"), "soft_clay_2");
        assert_eq!(safe_name(""), "material");
    }
}
