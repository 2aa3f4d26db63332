//! The contact between a structure and the soil (CPS `$$CONTACT_FORMULATION 1` with the
//! structure's elements in the GOM's `$$START_CONTACT_VOLUME` in 3D,
//! `$$START_BODY_CONTACT_2D` in 2D; [`crate::step::contact`]).

use mpm_shared::model::{Body, Token};
use mpm_shared::Model;

use super::materials::Elements;
use super::{strain_smoothing, unsupported, CaseError, Input};
use crate::input::case::MaterialSpec;
use crate::step::contact::{ContactSpec, InterfaceRule};

/// The CPS key that switches the contact on.
const KEY: &str = "$$CONTACT_FORMULATION";

/// What the loader knows of the case when it reads the contact.
pub(super) struct ContactCase {
    pub has_nodal_load: bool,
    pub has_point_load: bool,
    pub has_nodal_velocity: bool,
    /// The material the moving mesh follows, if there is one.
    pub moving_mesh_follows: Option<u32>,
    /// Elements (0-based) whose points have a prescribed velocity.
    pub prescribed_elements: Vec<u32>,
}

/// The contact, `None` when it is off. Refused by name what it does not model with it: a
/// saturated structure, loads on nodes (on the solid or the liquid) or on material points and
/// prescribed nodal velocities (Anura3D gives each of them rules of its own for the two
/// bodies), and velocities prescribed on the soil.
pub(super) fn read(
    input: &Input,
    materials: &[Option<MaterialSpec>],
    elements: &Elements,
    with: ContactCase,
) -> Result<Option<ContactSpec>, CaseError> {
    if !switched_on(input)? {
        return Ok(None);
    }
    if let Some(what) = not_modelled_with(&with) {
        return Err(unsupported(
            &input.cfile,
            KEY,
            format!("contact is not modelled {what}"),
        ));
    }
    let model = &input.model;
    let names: Vec<(u32, String)> = model
        .materials()
        .iter()
        .map(|m| (m.index.max(0) as u32, m.name.clone()))
        .collect();
    let element_material = &elements.element_material;
    let key = if model.dimension.coords() == 3 {
        "START_CONTACT_VOLUME"
    } else {
        "START_BODY_CONTACT_2D"
    };
    let spec = read_section(
        model,
        key,
        element_material,
        &names,
        &elements.points_per_element,
    )
    .map_err(|(item, why)| unsupported(&input.gfile, &item, why))?;
    // The structure is one body of solid; the soil's liquid meets it at an impermeable wall.
    if materials
        .get(spec.material as usize)
        .and_then(Option::as_ref)
        .is_some_and(|m| m.liquid.is_some())
    {
        return Err(unsupported(
            &input.gfile,
            &format!("${key}"),
            format!(
                "the structure's material {} is saturated: contact models a dry structure (a saturated or dry soil beside it)",
                spec.material
            ),
        ));
    }
    // Anura3D smooths each material's strain with its body's displacements, and takes the
    // structure's body from the moving mesh's reference material: without it, the structure
    // would be smoothed with the soil's.
    if strain_smoothing(&input.cps) && with.moving_mesh_follows != Some(spec.material) {
        return Err(unsupported(
            &input.cfile,
            "$$STRAIN_SMOOTHING",
            format!(
                "with contact, strain smoothing needs the moving mesh to follow the structure's material {} (Anura3D takes the structure's body for the smoothing from the moving mesh)",
                spec.material
            ),
        ));
    }
    // The prescribed velocity acts on the structure's nodes (Anura3D's hard entity).
    if let Some(e) = with
        .prescribed_elements
        .iter()
        .find(|&&e| element_material[e as usize] != spec.material)
    {
        return Err(unsupported(
            &input.gfile,
            "$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME",
            format!(
                "element {} is not of the structure's material {}: with contact, velocities are prescribed on the structure only",
                e + 1,
                spec.material
            ),
        ));
    }
    Ok(Some(spec))
}

/// Whether `$$CONTACT_FORMULATION` is 1 (0 or absent: off; anything else is refused).
pub(super) fn switched_on(input: &Input) -> Result<bool, CaseError> {
    let value = input
        .cps
        .get("CONTACT_FORMULATION")
        .and_then(|e| e.lines.first())
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or("0");
    match value {
        "0" => Ok(false),
        "1" => Ok(true),
        other => Err(unsupported(
            &input.cfile,
            KEY,
            format!("expected 0 or 1, got {other:?}"),
        )),
    }
}

/// What of the case the contact is not modelled with, as the end of the refusal's sentence;
/// `None` when there is nothing.
fn not_modelled_with(with: &ContactCase) -> Option<&'static str> {
    if with.has_nodal_load {
        Some("with loads on nodes")
    } else if with.has_point_load {
        Some("with loads on material points")
    } else if with.has_nodal_velocity {
        Some("with prescribed nodal velocities")
    } else {
        None
    }
}

/// Reads the structure's section of `model` (`key`: `START_CONTACT_VOLUME` in 3D,
/// `START_BODY_CONTACT_2D` in 2D): rows `element n "material" μ c "material" μ c "material" μ c
/// "material" μ c` ("NAN" for an unused slot). `element_material` is each
/// element's material index (0: empty), `names` each material index's name. Returns the section
/// and what is wrong with it when it is missing or the rows ask for what is not modelled:
///
/// * rows with different materials, frictions or adhesions (Anura3D takes the names from the
///   first row and each face's numbers from its own row, with an off-by-one on one face side);
/// * a structure that is not one whole material (every listed element of one material, every
///   filled element of that material listed): the bodies here are materials;
/// * a structure that is not the last material index (Anura3D looks up the frictions of the
///   other materials only).
fn read_section(
    model: &Model,
    key: &str,
    element_material: &[u32],
    names: &[(u32, String)],
    points: &[u32],
) -> Result<ContactSpec, (String, String)> {
    let item = format!("$${key}");
    let Some(section) = model.section(key) else {
        return Err((
            item,
            "missing: contact ($$CONTACT_FORMULATION 1) needs the structure's elements".into(),
        ));
    };
    let Body::Table { rows, .. } = &section.body else {
        return Err((item, "expected a count and rows".into()));
    };
    let (listed, slots) = read_rows(rows, element_material, &item)?;
    let mut elements = listed.clone();
    let material = element_material[elements[0] as usize];
    if material == 0 {
        return Err((
            item,
            format!(
                "element {} is empty: the structure must be filled",
                elements[0] + 1
            ),
        ));
    }
    elements.sort_unstable();
    elements.dedup();
    check_structure(material, &elements, element_material, points)
        .map_err(|e| (item.clone(), e))?;
    let last = names.iter().map(|n| n.0).max().unwrap_or(0);
    if material != last {
        return Err((
            item,
            format!(
                "the structure is material {material}; Anura3D takes it to be the last material ({last})"
            ),
        ));
    }
    let interfaces = interfaces_of(&slots, names, last).map_err(|e| (item, e))?;
    Ok(ContactSpec {
        material,
        listed,
        interfaces,
        rule: InterfaceRule::Anura3d,
        rigid: false,
    })
}

/// A token as the input wrote it (a text without its quotes).
fn token_text(t: &Token) -> String {
    match t {
        Token::Text(s) => s.trim_matches('"').to_string(),
        Token::Int(i) => i.to_string(),
        Token::Real(x) => x.to_string(),
    }
}

/// The rows of the section `item`: each row's element (0-based, in the rows' order) and the
/// first row's four `material friction adhesion` triples, as text, once every row was checked
/// to name an element of the mesh (`element_material`: one per element), numbers for the
/// frictions and adhesions and the same triples as the first row.
fn read_rows(
    rows: &mpm_shared::model::Table,
    element_material: &[u32],
    item: &str,
) -> Result<(Vec<u32>, Vec<String>), (String, String)> {
    let mut elements = Vec::new();
    let mut first: Option<Vec<String>> = None;
    for (k, r) in rows.rows().enumerate() {
        let bad = |what: String| (item.to_string(), format!("row {}: {what}", k + 1));
        if r.len() < 14 {
            return Err(bad(
                "expected 'element n' and four 'material friction adhesion' triples".into(),
            ));
        }
        let e = r[0].as_int().unwrap_or(0);
        if e < 1 || e as usize > element_material.len() {
            return Err(bad(format!(
                "element {} is not in the mesh (1..={})",
                token_text(&r[0]),
                element_material.len()
            )));
        }
        elements.push(e as u32 - 1);
        let rest: Vec<String> = r[2..14].iter().map(token_text).collect();
        for t in [1, 2, 4, 5, 7, 8, 10, 11] {
            if rest[t].parse::<f64>().map_or(true, |v| !v.is_finite()) {
                return Err(bad(format!(
                    "friction and adhesion must be numbers, got {}",
                    rest[t]
                )));
            }
        }
        match &first {
            None => first = Some(rest),
            Some(f) if *f != rest => {
                return Err(bad(
                    "its materials, frictions or adhesions differ from row 1's; give every row the same (Anura3D mixes the rows' values face by face)".into(),
                ))
            }
            Some(_) => {}
        }
    }
    match first {
        Some(slots) => Ok((elements, slots)),
        None => Err((
            item.to_string(),
            "no rows: contact needs the structure's elements".into(),
        )),
    }
}

/// Checks that the structure is one whole material: every listed element (`elements`,
/// ascending) of `material`, and every element of `material` that holds points listed.
fn check_structure(
    material: u32,
    elements: &[u32],
    element_material: &[u32],
    points: &[u32],
) -> Result<(), String> {
    for e in 0..element_material.len() {
        let listed = elements.binary_search(&(e as u32)).is_ok();
        let of_it = element_material[e] == material;
        if listed && !of_it {
            return Err(format!(
                "element {} is of material {}, the structure (row 1's element) of material {material}: the structure must be one material",
                e + 1,
                element_material[e]
            ));
        }
        if of_it && !listed && points[e] > 0 {
            return Err(format!(
                "element {} is of the structure's material {material} but not listed: the structure must be every element of its material",
                e + 1
            ));
        }
    }
    Ok(())
}

/// Per material index up to `last`: (friction, adhesion) with the structure, from the first
/// row's triples `slots` (a material by its name in `names`; "NAN" for an unused triple).
fn interfaces_of(
    slots: &[String],
    names: &[(u32, String)],
    last: u32,
) -> Result<Vec<(f64, f64)>, String> {
    let mut interfaces = vec![(0.0, 0.0); last as usize + 1];
    for k in 0..4 {
        let name = &slots[3 * k];
        if name.eq_ignore_ascii_case("NAN") {
            continue;
        }
        let Some(&(m, _)) = names.iter().find(|n| &n.1 == name) else {
            return Err(format!(
                "row 1 names material \"{name}\", which is not defined"
            ));
        };
        let number = |t: usize| slots[3 * k + t].parse::<f64>().unwrap_or(0.0);
        interfaces[m as usize] = (number(1), number(2));
    }
    Ok(interfaces)
}
