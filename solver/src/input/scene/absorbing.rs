//! `[[absorbing]]`: a boundary that lets waves leave the model, a dashpot and a spring per node
//! on a physical boundary group or on the mesh's faces in a plane
//! ([`crate::step::absorbing`]).

use serde::Deserialize;

use super::keys::{key, Table};
use super::material::Materials;
use super::mesh::{parse_plane, Mesh};
use super::{refuse, Refusal};
use crate::input::faces;
use crate::step::absorbing::{merged, AbsorbingNode};

/// The keys of `[[absorbing]]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[[absorbing]]",
    about: "An absorbing boundary (Lysmer–Kuhlemeyer dashpots with an optional spring) on a \
            physical boundary group or on the mesh's faces in a plane: each face of area A in an \
            element of density ρ gives its corners a dashpot a ρ V_p A along its normal and \
            b ρ V_s A across it, and a spring ρ V² A / δ (V_p, V_s the element's P- and S-wave \
            speeds); in a saturated element also the liquid's a ρ_w V_w A and K_w A / δ along the \
            normal (faces normal to an axis). Faces of elements without material points (the \
            air above the ground) take none. Give exactly one of `physical` and `plane`. One \
            process.",
    keys: &[
        key("physical", "string", "none", "", "the physical boundary group"),
        key("plane", "string", "none", "", "or the boundary faces in a plane: \"x = value\", \"y = value\" or \"z = value\""),
        key("normal", "float", "1", "", "a: the normal dashpot's share of the P-wave impedance (1 absorbs a plane wave at normal incidence)"),
        key("shear", "float", "1", "", "b: the tangential dashpot's share of the S-wave impedance"),
        key("spring_length", "float", "0 (no spring)", "m", "δ: the spring's length, a spring ρ V² A / δ that keeps a loaded model from creeping on its dashpots"),
    ],
};

fn one() -> f64 {
    1.0
}

/// An `[[absorbing]]` entry as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Absorbing {
    #[serde(default)]
    physical: Option<String>,
    #[serde(default)]
    plane: Option<String>,
    /// a.
    #[serde(default = "one")]
    normal: f64,
    /// b.
    #[serde(default = "one")]
    shear: f64,
    /// δ (m; 0: no spring).
    #[serde(default)]
    spring_length: f64,
}

/// The `[[absorbing]]` entries' dashpots and springs on the model's nodes, one row per node in
/// node order.
pub(super) fn resolve(
    entries: &[Absorbing],
    mesh: &Mesh,
    materials: &Materials,
) -> Result<Vec<AbsorbingNode>, Refusal> {
    let mut rows = Vec::new();
    for entry in entries {
        entry.check()?;
        let faces = entry.faces(mesh)?;
        let owners = faces::boundary_owners(&mesh.model, &faces)
            .map_err(|m| refuse(entry.item(), format!("{m} in {}", mesh.name)))?;
        let before = rows.len();
        for (face, (element, inner)) in faces.iter().zip(owners) {
            // An element without points (the air above the ground) has no material to send
            // the wave into: its faces take no dashpot. With them, a soil point that strayed
            // into such a cell at the monopile job's far side was crushed (on a node of almost
            // no mass the dashpot and spring, not the soil, set the velocity).
            if materials.points_per_element[element] == 0 {
                continue;
            }
            let index = materials.element_material[element] as usize;
            let Some(m) = materials.specs.get(index).and_then(|m| m.as_ref()) else {
                return Err(refuse(
                    entry.item(),
                    format!("element {} of {} holds no material", element + 1, mesh.name),
                ));
            };
            let (young, poisson) = m.law.elastic();
            let shear_modulus = young / (2.0 * (1.0 + poisson));
            let speeds = (
                (m.oedometric() / m.density).sqrt(),
                (shear_modulus / m.density).sqrt(),
            );
            let n = faces::outward_normal(&mesh.model, face, inner);
            let liquid = m.liquid.map(|l| (l.density, l.bulk_modulus));
            if liquid.is_some() && n.iter().filter(|c| c.abs() > 1e-9).count() != 1 {
                return Err(refuse(
                    entry.item(),
                    format!(
                        "a face of saturated element {} of {} is not normal to x, y or z: the liquid's dashpots lie on such faces only",
                        element + 1,
                        mesh.name
                    ),
                ));
            }
            let shares = faces::corner_shares(&mesh.model, face);
            for (&node, w) in face.iter().zip(shares) {
                rows.push(AbsorbingNode::of_face(
                    node as u32,
                    w,
                    n,
                    m.density,
                    speeds,
                    (entry.normal, entry.shear),
                    entry.spring_length,
                    liquid,
                ));
            }
        }
        if rows.len() == before {
            return Err(refuse(
                entry.item(),
                format!(
                    "selects only faces of elements without material points in {}: nothing there absorbs",
                    mesh.name
                ),
            ));
        }
    }
    Ok(merged(rows))
}

impl Absorbing {
    /// The entry as messages name it.
    fn item(&self) -> String {
        match (&self.physical, &self.plane) {
            (Some(name), _) => format!("absorbing \"{name}\""),
            (_, Some(plane)) => format!("absorbing plane \"{plane}\""),
            _ => "absorbing".to_string(),
        }
    }

    /// Refuses negative or non-finite coefficients and lengths.
    fn check(&self) -> Result<(), Refusal> {
        for (name, v) in [
            ("normal", self.normal),
            ("shear", self.shear),
            ("spring_length", self.spring_length),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(refuse(
                    format!("{}.{name}", self.item()),
                    format!("{v}: expected a number at least 0"),
                ));
            }
        }
        Ok(())
    }

    /// The faces the entry selects (model node ids of their corners).
    fn faces(&self, mesh: &Mesh) -> Result<Vec<Vec<usize>>, Refusal> {
        let faces = match (&self.physical, &self.plane) {
            (Some(name), None) => {
                let faces = mesh.boundary_faces(name).ok_or_else(|| {
                    refuse(
                        self.item(),
                        format!("no {} of that name in {}", mesh.groups.boundary, mesh.name),
                    )
                })?;
                if faces.iter().any(|f| f.contains(&u32::MAX)) {
                    return Err(refuse(
                        self.item(),
                        format!(
                            "a face of it in {} has a node that no element uses",
                            mesh.name
                        ),
                    ));
                }
                faces
                    .iter()
                    .map(|f| f.iter().map(|&n| n as usize).collect())
                    .collect()
            }
            (None, Some(plane)) => {
                let (axis, value) = parse_plane(plane).ok_or_else(|| {
                    refuse(
                        self.item(),
                        "expected 'x = value', 'y = value' or 'z = value'",
                    )
                })?;
                let tol = 1e-9 * mesh.size().max(1e-300);
                faces::plane_faces(&mesh.model, axis, value, tol)
            }
            _ => {
                return Err(refuse(
                    "absorbing",
                    "give exactly one of physical = \"name\" or plane = \"x = value\"",
                ))
            }
        };
        if faces.is_empty() {
            return Err(refuse(
                self.item(),
                format!("selects no face of {}", mesh.name),
            ));
        }
        Ok(faces)
    }
}
