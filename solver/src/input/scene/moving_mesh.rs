//! `[moving_mesh]`: Anura3D's moving mesh from a scene: the box of the mesh around a structure
//! follows it along one axis, the box ahead of it is compressed and the one behind stretched
//! (docs/design.md §4.18). The boxes are given by two opposite corners, each of whose
//! corners must be a node of the mesh.

use serde::Deserialize;

use super::keys::{key, Table};
use super::mesh::Mesh;
use super::{refuse, Refusal};
use crate::step::moving_mesh::MovingMeshSpec;

/// The keys of `[moving_mesh]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[moving_mesh]",
    about: "The part of the mesh around a structure follows it along one axis, so that it \
            keeps its elements (and a contact its interface): the `moving` box moves with the \
            mean displacement of the structure's nodes, the `compressing` box ahead of it \
            shrinks and the `extending` box behind it stretches, each about its far end. Each \
            box is [[x, y(, z)], [x, y(, z)]], two opposite corners, and its corners must be \
            mesh nodes; give `compressing`, `extending` or both. The time step stays that of \
            the initial mesh: leave the compressed box room. One process.",
    keys: &[
        key("follows", "string", "required", "", "the material group (the structure) whose elements' nodes the mesh follows"),
        key("axis", "string", "\"y\"", "", "the axis it moves along: \"x\", \"y\" or \"z\""),
        key("moving", "[[float, ...], [float, ...]]", "required", "m", "the box that moves with the structure"),
        key("compressing", "[[float, ...], [float, ...]]", "none", "m", "the box ahead of it, compressed"),
        key("extending", "[[float, ...], [float, ...]]", "none", "m", "the box behind it, stretched"),
    ],
};

/// `[moving_mesh]` as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MovingMesh {
    follows: String,
    #[serde(default)]
    axis: Option<String>,
    moving: Vec<Vec<f64>>,
    #[serde(default)]
    compressing: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    extending: Option<Vec<Vec<f64>>>,
}

/// The scene's moving mesh (`None` without the table), or what cannot be used.
pub(super) fn resolve(
    entry: Option<&MovingMesh>,
    mesh: &Mesh,
    grid: bool,
) -> Result<Option<MovingMeshSpec>, Refusal> {
    let Some(entry) = entry else {
        return Ok(None);
    };
    const ITEM: &str = "moving_mesh";
    if grid {
        return Err(refuse(
            ITEM,
            "not on a background grid ([grid]); run it on the mesh's elements",
        ));
    }
    let material = mesh
        .material_group(&entry.follows)
        .map_err(|e| refuse(ITEM, format!("follows: {e}")))?;
    let dim = mesh.model.dimension.coords();
    let axis = match entry.axis.as_deref().unwrap_or("y") {
        "x" => 0,
        "y" => 1,
        "z" if dim == 3 => 2,
        other => {
            return Err(refuse(
                ITEM,
                format!(
                    "axis = \"{other}\": expected \"x\", \"y\"{}",
                    if dim == 3 { " or \"z\"" } else { "" }
                ),
            ))
        }
    };
    let moving = corners(mesh, "moving", &entry.moving)?;
    let mut storage = Vec::new();
    for (name, b) in [
        ("extending", &entry.extending),
        ("compressing", &entry.compressing),
    ] {
        let Some(b) = b else { continue };
        let mut c = corners(mesh, name, b)?;
        // Its fixed end first: a corner that is not also the moving box's.
        let Some(far) = c.iter().position(|n| !moving.contains(n)) else {
            return Err(refuse(
                format!("moving_mesh.{name}"),
                "every corner is also a corner of the moving box: the box has no far end",
            ));
        };
        c.swap(0, far);
        storage.push(c);
    }
    if storage.is_empty() {
        return Err(refuse(
            ITEM,
            "give the box ahead of the structure (compressing), the one behind it (extending) or both",
        ));
    }
    Ok(Some(MovingMeshSpec {
        storage,
        moving,
        axis,
        material,
    }))
}

/// The mesh nodes (model ids, 0-based) at the 2^dim corners of the box `b` (two opposite
/// corners), in the order of the corners' bits (x fastest).
fn corners(mesh: &Mesh, name: &str, b: &[Vec<f64>]) -> Result<Vec<u32>, Refusal> {
    let item = format!("moving_mesh.{name}");
    let model = &mesh.model;
    let dim = model.dimension.coords();
    if b.len() != 2
        || b.iter()
            .any(|c| c.len() != dim || c.iter().any(|v| !v.is_finite()))
    {
        return Err(refuse(
            item,
            format!(
                "expected two opposite corners of {dim} coordinates each, [[x, y{}], [x, y{}]]",
                if dim == 3 { ", z" } else { "" },
                if dim == 3 { ", z" } else { "" }
            ),
        ));
    }
    let nodes: Vec<&[f64]> = (0..model.node_count()).map(|n| model.node(n)).collect();
    let size = nodes
        .iter()
        .flat_map(|p| p.iter())
        .fold(0.0f64, |s, v| s.max(v.abs()))
        .max(1.0);
    let mut out = Vec::with_capacity(1 << dim);
    for bits in 0..1usize << dim {
        let want: Vec<f64> = (0..dim).map(|a| b[(bits >> a) & 1][a]).collect();
        let found = nodes.iter().position(|p| {
            p.iter()
                .zip(&want)
                .all(|(x, w)| (x - w).abs() <= 1e-9 * size)
        });
        match found {
            Some(n) => out.push(n as u32),
            None => {
                return Err(refuse(
                    item,
                    format!(
                        "no mesh node at the box's corner {want:?}: each corner must be a node"
                    ),
                ))
            }
        }
    }
    Ok(out)
}
