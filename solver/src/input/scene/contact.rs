//! `[[contact]]`: contact between a structure (one material group: a pile, a footing) and the
//! soil (every other material), Bardenhagen's two-body correction as Anura3D's (docs/design.md
//! §4.19), with the interface's tributary shares ([`InterfaceRule::Tributary`]).

use serde::Deserialize;

use super::keys::{key, Table};
use super::material::Materials;
use super::mesh::Mesh;
use super::{refuse, Refusal};
use crate::step::contact::{ContactSpec, InterfaceRule};
use crate::step::prescribed::PrescribedVelocity;

/// The keys of `[[contact]]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[[contact]]",
    about: "Contact between a structure and the soil: the points of the structure's material \
            group are one body, every other material's the other, each mapped to nodes of its \
            own; where they meet (the structure's sides that border the soil or an empty \
            element, on the initial mesh) a body that approaches the other loses its normal \
            relative velocity and as much of its tangential one as friction and adhesion take. \
            One structure per scene, dry (the soil may be saturated: the structure is then \
            impermeable); one process. The interface is the initial one: a structure that \
            moves across the mesh needs `[moving_mesh]`.",
    keys: &[
        key("structure", "string", "required", "", "the structure's material group (a physical volume in 3D, a physical surface in 2D)"),
        key("friction", "float", "0 (smooth)", "", "Coulomb coefficient μ between the structure and the soil"),
        key("adhesion", "float", "0", "kPa", "adhesion c: a tangential force up to c A at an interface node while the bodies press together there, A the node's share of the interface (per radian in an axisymmetric section)"),
        key("rigid", "bool", "false", "", "the structure moves as one rigid body in translation (no rotation) under its weight, its loads and the soil's push, instead of deforming with its material's law"),
    ],
};

/// A `[[contact]]` entry as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Contact {
    structure: String,
    #[serde(default)]
    friction: f64,
    #[serde(default)]
    adhesion: f64,
    #[serde(default)]
    rigid: bool,
}

/// What a scene with contact may not hold, checked against its other sections.
pub(super) struct With<'a> {
    /// A background grid.
    pub grid: bool,
    /// Velocities prescribed on nodes.
    pub nodal_velocity: bool,
    /// The velocity prescribed on material points, if any.
    pub driven: Option<&'a PrescribedVelocity>,
}

/// The scene's contact: `None` without `[[contact]]`, else the spec, or what cannot be used.
pub(super) fn resolve(
    entries: &[Contact],
    mesh: &Mesh,
    materials: &Materials,
    with: With<'_>,
) -> Result<Option<ContactSpec>, Refusal> {
    let Some(entry) = entries.first() else {
        return Ok(None);
    };
    let item = format!("contact \"{}\"", entry.structure);
    if entries.len() > 1 {
        return Err(refuse(
            item,
            format!(
                "a second [[contact]] (\"{}\"): one structure per scene",
                entries[1].structure
            ),
        ));
    }
    for (value, name) in [(entry.friction, "friction"), (entry.adhesion, "adhesion")] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(refuse(
                &item,
                format!("{name} = {value}: expected a number ≥ 0"),
            ));
        }
    }
    let material = mesh
        .material_group(&entry.structure)
        .map_err(|e| refuse(&item, e))?;
    if let Some(what) = not_modelled_with(materials, &with, material) {
        return Err(refuse(item, format!("contact is not modelled {what}")));
    }
    let listed: Vec<u32> = (0..materials.element_material.len() as u32)
        .filter(|&e| materials.element_material[e as usize] == material)
        .collect();
    if listed.is_empty() || materials.element_material.iter().all(|&e| e == material) {
        return Err(refuse(
            item,
            format!(
                "the structure needs elements of its own and soil beside it ({} \"{}\")",
                mesh.groups.material, entry.structure
            ),
        ));
    }
    let mut interfaces = vec![(entry.friction, entry.adhesion); materials.specs.len()];
    interfaces[material as usize] = (0.0, 0.0);
    Ok(Some(ContactSpec {
        material,
        listed,
        interfaces,
        rule: InterfaceRule::Tributary,
        rigid: entry.rigid,
    }))
}

/// What of the scene contact is not modelled with, as the end of the refusal's sentence.
fn not_modelled_with(materials: &Materials, with: &With<'_>, structure: u32) -> Option<String> {
    if materials
        .specs
        .get(structure as usize)
        .and_then(Option::as_ref)
        .is_some_and(|m| m.liquid.is_some())
    {
        return Some(
            "for a saturated structure: give the structure a dry material (the soil beside it may be saturated)"
                .into(),
        );
    }
    if with.grid {
        return Some("on a background grid ([grid]) yet; run it on the mesh's elements".into());
    }
    if with.nodal_velocity {
        return Some(
            "with velocities prescribed on nodes ([[velocity]] on a boundary group or a plane)"
                .into(),
        );
    }
    let element_material = &materials.element_material;
    match with.driven {
        Some(v)
            if v.rows
                .iter()
                .any(|r| element_material[r.element as usize] != structure) =>
        {
            Some(format!(
                "with a velocity prescribed on the points of another material (velocity \"{}\"): only the structure's may be driven",
                v.name
            ))
        }
        _ => None,
    }
}
