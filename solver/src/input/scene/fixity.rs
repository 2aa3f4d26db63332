//! `[[fixity]]`: nodes held in some directions, on a physical boundary group or a plane; with
//! `friction`, a rigid wall the body presses on or leaves, sliding along it against Coulomb
//! friction ([`crate::step::wall_friction`]).

use serde::Deserialize;

use mpm_shared::Model;

use super::keys::{key, Table};
use super::material::Materials;
use super::mesh::{parse_plane, Mesh};
use super::{refuse, Refusal};
use crate::step::wall_friction::WallAxis;

/// The keys of `[[fixity]]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[[fixity]]",
    about: "Nodes held in some directions: those of a physical boundary group (a surface in 3D, \
            a curve in 2D) or of a plane. Give exactly one of `physical` and `plane`.",
    keys: &[
        key("physical", "string", "none", "", "the physical boundary group"),
        key("plane", "string", "none", "", "or a plane selector: \"x = value\", \"y = value\" or \"z = value\""),
        key("fixed", "[bool, bool, bool]", "required", "", "the solid's fixed directions, x y z"),
        key("liquid", "[bool, bool, bool]", "as `fixed`", "", "the liquid's fixed (impermeable) directions"),
        key("friction", "float", "none", "", "Coulomb coefficient μ of a rigid wall normal to the one fixed axis, which the body may press on or leave (dry scenes; 0: smooth)"),
    ],
};

/// A `[[fixity]]` entry as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Fixity {
    #[serde(default)]
    physical: Option<String>,
    #[serde(default)]
    plane: Option<String>,
    fixed: [bool; 3],
    /// Liquid fixities (impermeable directions); default: those of the solid.
    #[serde(default)]
    liquid: Option<[bool; 3]>,
    /// Coulomb friction coefficient μ of a rigid wall: the one "fixed" component is the wall's
    /// normal, which the body may press on or leave, the others slide against friction
    /// ([`crate::step::wall_friction`]).
    #[serde(default)]
    friction: Option<f64>,
}

/// The case's fixities and rigid walls.
pub(super) struct Supports {
    /// The solid's fixed directions per node.
    pub fixed: Vec<[bool; 3]>,
    /// The liquid's fixed directions per node.
    pub liquid_fixed: Vec<[bool; 3]>,
    /// The walls per node and axis (empty when there are none).
    pub walls: Vec<[WallAxis; 3]>,
}

/// The `[[fixity]]` entries on the mesh's nodes, in file order.
pub(super) fn resolve(
    entries: &[Fixity],
    mesh: &Mesh,
    materials: &Materials,
) -> Result<Supports, Refusal> {
    let n = mesh.model.node_count();
    let mut out = Supports {
        fixed: vec![[false; 3]; n],
        liquid_fixed: vec![[false; 3]; n],
        walls: Vec::new(),
    };
    for f in entries {
        let nodes = f.nodes(mesh)?;
        match f.friction {
            // The wall holds the normal, not the fixity (the body may leave it).
            Some(mu) => out.add_wall(f, mu, &nodes, mesh, materials)?,
            None => out.fix(f, &nodes),
        }
    }
    Ok(out)
}

impl Fixity {
    /// The nodes the entry selects (a physical group's or a plane's).
    fn nodes(&self, mesh: &Mesh) -> Result<Vec<u32>, Refusal> {
        match (&self.physical, &self.plane) {
            (Some(name), None) => mesh.boundary_nodes(name).ok_or_else(|| {
                refuse(
                    format!("fixity \"{name}\""),
                    format!("no {} of that name in {}", mesh.groups.boundary, mesh.name),
                )
            }),
            (None, Some(plane)) => {
                let item = || format!("fixity plane \"{plane}\"");
                let (axis, value) = parse_plane(plane).ok_or_else(|| {
                    refuse(item(), "expected 'x = value', 'y = value' or 'z = value'")
                })?;
                let found = mesh.plane_nodes(axis, value);
                if found.is_empty() {
                    return Err(refuse(item(), "selects no node"));
                }
                Ok(found)
            }
            _ => Err(refuse(
                "fixity",
                "give exactly one of physical = \"name\" or plane = \"x = value\"",
            )),
        }
    }
}

impl Supports {
    /// Fixes `nodes` in the entry's directions (both phases).
    fn fix(&mut self, f: &Fixity, nodes: &[u32]) {
        let liquid = f.liquid.unwrap_or(f.fixed);
        for &n in nodes {
            for a in 0..3 {
                self.fixed[n as usize][a] |= f.fixed[a];
                self.liquid_fixed[n as usize][a] |= liquid[a];
            }
        }
    }

    /// Makes `nodes` a rigid wall with friction `mu`, normal to the entry's one fixed axis, on
    /// the side of the mesh each node lies on.
    fn add_wall(
        &mut self,
        f: &Fixity,
        mu: f64,
        nodes: &[u32],
        mesh: &Mesh,
        materials: &Materials,
    ) -> Result<(), Refusal> {
        let item = match (&f.physical, &f.plane) {
            (Some(name), _) => format!("fixity \"{name}\".friction"),
            (_, Some(plane)) => format!("fixity plane \"{plane}\".friction"),
            _ => unreachable!("a fixity without nodes is refused before"),
        };
        let axes: Vec<usize> = (0..3).filter(|&a| f.fixed[a]).collect();
        let &[axis] = axes.as_slice() else {
            return Err(refuse(
                item,
                format!(
                    "a frictional wall fixes its normal component alone; fixed = {:?} has {} \
                     fixed components",
                    f.fixed,
                    axes.len()
                ),
            ));
        };
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(refuse(
                item,
                format!("must be a finite coefficient >= 0, got {mu}"),
            ));
        }
        if materials.any_saturated() {
            return Err(refuse(
                item,
                "is modelled for dry scenes only (this one has a saturated material)",
            ));
        }
        let model = &mesh.model;
        if axis >= model.dimension.coords() {
            return Err(refuse(
                item,
                format!("the wall's normal, axis {axis}, is not an axis of this 2D mesh"),
            ));
        }
        let sides = wall_sides(model, nodes, axis).map_err(|n| {
            refuse(
                item.clone(),
                format!(
                    "the node at {:?} has elements on both sides along the wall's normal \
                     ({}): a wall must bound the mesh",
                    model.node(n as usize),
                    ["x", "y", "z"][axis]
                ),
            )
        })?;
        if self.walls.is_empty() {
            self.walls = vec![[WallAxis::default(); 3]; model.node_count()];
        }
        for (&n, side) in nodes.iter().zip(sides) {
            self.walls[n as usize][axis] = WallAxis { side, friction: mu };
        }
        Ok(())
    }
}

/// For each of the wall's `nodes`, the side of the mesh along `axis`: +1 where the elements
/// around the node lie on its + side, -1 on its - side; `Err(node)` for a node with elements on
/// both sides (or none), which no wall can bound.
fn wall_sides(model: &Model, nodes: &[u32], axis: usize) -> Result<Vec<f64>, u32> {
    // Per node, the lowest and highest element centroid along the axis, relative to the node.
    let mut range = vec![(f64::INFINITY, f64::NEG_INFINITY); model.node_count()];
    let mut on_wall = vec![false; model.node_count()];
    for &n in nodes {
        on_wall[n as usize] = true;
    }
    let corners = model.element_type.corners();
    for e in 0..model.element_count() {
        let el = &model.element(e)[..corners];
        if !el.iter().any(|&n| on_wall[n as usize]) {
            continue;
        }
        let centroid = el
            .iter()
            .map(|&n| model.node(n as usize)[axis])
            .sum::<f64>()
            / corners as f64;
        for &n in el {
            let r = &mut range[n as usize];
            let d = centroid - model.node(n as usize)[axis];
            *r = (r.0.min(d), r.1.max(d));
        }
    }
    nodes
        .iter()
        .map(|&n| match range[n as usize] {
            (lo, _) if lo > 0.0 => Ok(1.0),
            (_, hi) if hi < 0.0 => Ok(-1.0),
            _ => Err(n),
        })
        .collect()
}
