//! `[[velocity]]`: a prescribed velocity on the nodes of a physical boundary group or a plane,
//! or on the material points of a physical volume (at most one per scene).

use serde::Deserialize;

use super::keys::{key, Table};
use super::material::Materials;
use super::mesh::{parse_plane, Mesh};
use super::{refuse, Refusal};
use crate::input::case::LoadCurve;
use crate::step::nodal_velocity::{NodalVelocitySet, PrescribedNode};
use crate::step::prescribed::{PrescribedElement, PrescribedVelocity};

/// The keys of `[[velocity]]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[[velocity]]",
    about: "A prescribed velocity: on the nodes of a physical boundary group or a plane (a \
            rigid platen; its reaction goes to reaction.csv), or on the material points of a \
            physical volume (at most one per scene). Give exactly one of `physical` and \
            `plane`. Refused in scenes with a saturated material.",
    keys: &[
        key("physical", "string", "none", "", "a physical boundary group (its nodes) or a physical volume (its points)"),
        key("plane", "string", "none", "", "or a plane selector: \"x = value\", \"y = value\" or \"z = value\""),
        key("velocity", "[float, float, float]", "required", "m/s", "the velocity"),
        key("components", "[bool, bool, bool]", "all three", "", "the prescribed components, x y z"),
        key("ramp", "float", "0 (at once)", "s", "time to reach the full velocity"),
        key("curve", "[[float, float], ...] or string", "none", "s, –", super::curve::CURVE_HELP),
        key("name", "string", "the physical or plane", "", "the set's name in reaction.csv"),
    ],
};

/// A `[[velocity]]` entry as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Velocity {
    #[serde(default)]
    physical: Option<String>,
    #[serde(default)]
    plane: Option<String>,
    velocity: [f64; 3],
    #[serde(default)]
    components: Option<[bool; 3]>,
    #[serde(default)]
    ramp: f64,
    /// A multiplier over time instead of the ramp.
    #[serde(default)]
    curve: Option<toml::Value>,
    #[serde(default)]
    name: Option<String>,
}

/// What a `[[velocity]]` entry prescribes.
#[derive(Debug, Clone, PartialEq)]
pub enum VelocityTarget {
    /// Nodes (model ids, 0-based, ascending) of a physical surface or a plane.
    Nodes(Vec<u32>),
    /// The material points of a physical volume's elements (the case's material-point set).
    Volume(String),
}

/// A `[[velocity]]` entry resolved against the mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct VelocityInput {
    /// The set's name (`name`, else the physical or plane string).
    pub name: String,
    /// What it prescribes.
    pub target: VelocityTarget,
    /// Velocity (m/s).
    pub velocity: [f64; 3],
    /// Prescribed components.
    pub components: [bool; 3],
    /// Seconds to full velocity (0: at once).
    pub ramp: f64,
    /// Its multiplier over time (the ramp's, or the `curve` given).
    pub curve: LoadCurve,
}

/// The case's prescribed velocities and the entries behind them.
pub(super) struct Velocities {
    /// The material-point set (a physical volume's elements), if any.
    pub points: Option<PrescribedVelocity>,
    /// The nodal sets in file order.
    pub nodal: Vec<NodalVelocitySet>,
    /// The entries as resolved, in file order.
    pub inputs: Vec<VelocityInput>,
}

/// The `[[velocity]]` entries against the mesh, in file order. Errors name the entry.
pub(super) fn resolve(
    entries: &[Velocity],
    mesh: &Mesh,
    materials: &Materials,
    (scene_dir, with_contact): (&std::path::Path, bool),
) -> Result<Velocities, Refusal> {
    let mut out = Velocities {
        points: None,
        nodal: Vec::new(),
        inputs: Vec::new(),
    };
    for v in entries {
        let input = v.checked(mesh, materials, (scene_dir, with_contact))?;
        out.add(v, input, mesh, materials)?;
    }
    Ok(out)
}

impl Velocity {
    /// The entry checked and resolved against the mesh; `with_contact`: the scene has a
    /// `[[contact]]` (which lets a velocity drive its dry structure beside a saturated soil).
    fn checked(
        &self,
        mesh: &Mesh,
        materials: &Materials,
        (scene_dir, with_contact): (&std::path::Path, bool),
    ) -> Result<VelocityInput, Refusal> {
        let label = self
            .physical
            .as_ref()
            .or(self.plane.as_ref())
            .cloned()
            .unwrap_or_default();
        let name = self.name.clone().unwrap_or(label);
        let item = format!("velocity \"{name}\"");
        let components = self.components.unwrap_or([true; 3]);
        if !components.iter().any(|&c| c) {
            return Err(refuse(item, "components = [false, false, false] prescribes nothing; mark at least one component true"));
        }
        if !self.velocity.iter().all(|x| x.is_finite()) {
            return Err(refuse(
                item,
                format!("velocity must be three numbers, got {:?}", self.velocity),
            ));
        }
        if !(self.ramp >= 0.0 && self.ramp.is_finite()) {
            return Err(refuse(
                item,
                format!("ramp must be 0 or more seconds, got {}", self.ramp),
            ));
        }
        if materials.any_saturated() && !with_contact {
            return Err(refuse(
                item,
                "prescribed velocities are not supported yet in scenes with a saturated material (except on a dry [[contact]] structure)",
            ));
        }
        let curve = match &self.curve {
            Some(_) if self.ramp != 0.0 => {
                return Err(refuse(item, "give a ramp or a curve, not both"))
            }
            Some(v) => super::curve::resolve(v, scene_dir, &format!("{item}.curve"))?,
            None => LoadCurve::ramp(self.ramp),
        };
        let target = self.target(mesh).map_err(|m| refuse(item, m))?;
        Ok(VelocityInput {
            name,
            target,
            velocity: self.velocity,
            components,
            ramp: self.ramp,
            curve,
        })
    }

    /// What the entry prescribes: a boundary group's or a plane's nodes, or a volume's points.
    fn target(&self, mesh: &Mesh) -> Result<VelocityTarget, String> {
        let (b, m) = (mesh.groups.boundary, mesh.groups.material);
        match (&self.physical, &self.plane) {
            (Some(p), None) => {
                let surface = mesh.boundary_nodes(p);
                let volume = mesh.volumes.iter().position(|n| n == p);
                match (surface, volume) {
                    (Some(_), Some(_)) => {
                        Err(format!("\"{p}\" names both a {b} and a {m}; rename one"))
                    }
                    (Some(nodes), None) => Ok(VelocityTarget::Nodes(nodes)),
                    (None, Some(_)) => Ok(VelocityTarget::Volume(p.clone())),
                    (None, None) => Err(format!(
                        "no {b} or {m} \"{p}\" in {} ({m}s: {:?})",
                        mesh.name, mesh.volumes
                    )),
                }
            }
            (None, Some(plane)) => {
                let (axis, value) = parse_plane(plane).ok_or_else(|| {
                    format!("plane \"{plane}\": expected 'x = value', 'y = value' or 'z = value'")
                })?;
                let found = mesh.plane_nodes(axis, value);
                if found.is_empty() {
                    return Err(format!("plane \"{plane}\" selects no node"));
                }
                Ok(VelocityTarget::Nodes(found))
            }
            _ => Err("give exactly one of physical = \"name\" or plane = \"x = value\"".into()),
        }
    }
}

impl Velocities {
    /// Adds a resolved entry: a nodal set, or the one material-point set.
    fn add(
        &mut self,
        v: &Velocity,
        input: VelocityInput,
        mesh: &Mesh,
        materials: &Materials,
    ) -> Result<(), Refusal> {
        let curve = input.curve.clone();
        let name = input.name.clone();
        match &input.target {
            VelocityTarget::Nodes(nodes) => self.nodal.push(NodalVelocitySet {
                name,
                rows: nodes
                    .iter()
                    .map(|&node| PrescribedNode {
                        node,
                        directions: input.components,
                        velocity: v.velocity,
                    })
                    .collect(),
                scale: 1.0,
                curve,
            }),
            VelocityTarget::Volume(p) => {
                let item = format!("velocity \"{name}\"");
                if let Some(first) = &self.points {
                    return Err(refuse(item, format!("a second material-point velocity (after \"{}\"); give one {} per scene, or prescribe nodes", first.name, mesh.groups.material)));
                }
                let k = mesh
                    .volumes
                    .iter()
                    .position(|n| n == p)
                    .expect("found above") as u32
                    + 1;
                let element_material = &materials.element_material;
                let rows: Vec<PrescribedElement> = (0..element_material.len() as u32)
                    .filter(|&e| element_material[e as usize] == k)
                    .map(|element| PrescribedElement {
                        element,
                        directions: input.components,
                        velocity: v.velocity,
                    })
                    .collect();
                if rows.is_empty() {
                    return Err(refuse(
                        item,
                        format!("{} \"{p}\" has no elements", mesh.groups.material),
                    ));
                }
                self.points = Some(PrescribedVelocity {
                    name,
                    rows,
                    scale: 1.0,
                    curve,
                });
            }
        }
        self.inputs.push(input);
        Ok(())
    }
}
