//! `[[traction]]`: a uniform traction, or a pressure normal to each face, on a physical
//! boundary group, integrated into nodal forces.

use serde::Deserialize;

use mpm_shared::Model;

use super::keys::{key, Table};
use super::mesh::Mesh;
use super::{refuse, Refusal};
use crate::basis::grid::GridSpec;

/// The keys of `[[traction]]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[[traction]]",
    about: "A load on a physical boundary group (a surface in 3D, a curve in 2D): a uniform \
            traction vector, or a pressure normal to each face. Give exactly one of `traction` \
            and `pressure`. Every traction ramps over the longest `ramp` given.",
    keys: &[
        key("physical", "string", "required", "", "the physical boundary group"),
        key("traction", "[float, float, float]", "none", "kPa", "a uniform traction vector"),
        key("pressure", "float", "none", "kPa", "or a pressure normal to each face, pushing into the body (a tunnel's or a pile's wall)"),
        key("ramp", "float", "0 (sudden)", "s", "time to reach the full load"),
    ],
};

/// A `[[traction]]` entry as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Traction {
    physical: String,
    /// A uniform traction vector (kPa).
    #[serde(default)]
    traction: Option<[f64; 3]>,
    /// Or a pressure (kPa) normal to each face, pushing into the body.
    #[serde(default)]
    pressure: Option<f64>,
    #[serde(default)]
    ramp: f64,
}

/// A `[[traction]]` entry with the faces its physical surface resolved to.
#[derive(Debug, Clone, PartialEq)]
pub struct TractionInput {
    /// The physical surface.
    pub physical: String,
    /// Its faces: model node ids (0-based) of their corners (three of a triangle in 3D, two of
    /// an edge in 2D), in the mesh file's order.
    pub faces: Vec<Vec<u32>>,
    /// Traction vector (kPa; zero for a pressure).
    pub traction: [f64; 3],
    /// Pressure normal to each face, pushing into the body (kPa), instead of `traction`.
    pub pressure: Option<f64>,
    /// Seconds to full load (0: sudden).
    pub ramp: f64,
}

impl TractionInput {
    /// The traction on each face (kPa): the vector, or the pressure along the face's inward
    /// normal (`outward`: the faces' outward unit normals).
    pub fn on_faces(&self, outward: &[[f64; 3]]) -> Vec<[f64; 3]> {
        match self.pressure {
            Some(p) => outward.iter().map(|n| n.map(|c| -p * c)).collect(),
            None => vec![self.traction; self.faces.len()],
        }
    }
}

/// The case's face loads and the entries behind them.
pub(super) struct Loads {
    /// The nodal forces of every traction at full load.
    pub traction: Vec<[f64; 3]>,
    /// The longest ramp given (s).
    pub ramp: f64,
    /// The entries in file order.
    pub inputs: Vec<TractionInput>,
}

/// The `[[traction]]` entries on the mesh's faces, in file order.
/// On a background grid (`grid`), the faces' loads are integrated with the grid's functions
/// ([`super::grid::add_face_loads`]).
pub(super) fn resolve(
    entries: &[Traction],
    mesh: &Mesh,
    grid: Option<&GridSpec>,
) -> Result<Loads, Refusal> {
    let mut out = Loads {
        traction: vec![[0.0; 3]; mesh.model.node_count()],
        ramp: 0.0,
        inputs: Vec::with_capacity(entries.len()),
    };
    for tr in entries {
        let input = tr.resolve(mesh)?;
        // Only a pressure needs the faces' normals.
        let outward = if input.pressure.is_some() {
            let corners: Vec<Vec<usize>> = input
                .faces
                .iter()
                .map(|f| f.iter().map(|&n| n as usize).collect())
                .collect();
            crate::input::faces::outward_normals(&mesh.model, &corners)
                .map_err(|m| refuse(tr.item(), format!("{m} in {}", mesh.name)))?
        } else {
            Vec::new()
        };
        let loads = input.on_faces(&outward);
        match grid {
            Some(g) => {
                super::grid::add_face_loads(g, &mesh.model, &input.faces, &loads, &mut out.traction)
            }
            None => add_face_loads(&mesh.model, &input.faces, &loads, &mut out.traction),
        }
        out.ramp = out.ramp.max(tr.ramp);
        out.inputs.push(input);
    }
    Ok(out)
}

impl Traction {
    /// The entry as messages name it.
    fn item(&self) -> String {
        format!("traction \"{}\"", self.physical)
    }

    /// The entry with its group's faces, each of whose corners must be a node of the model.
    fn resolve(&self, mesh: &Mesh) -> Result<TractionInput, Refusal> {
        let faces = mesh.boundary_faces(&self.physical).ok_or_else(|| {
            refuse(
                self.item(),
                format!("no {} of that name in {}", mesh.groups.boundary, mesh.name),
            )
        })?;
        // A face corner that no volume element uses has no model node to load.
        if let Some(k) = faces.iter().position(|f| f.contains(&u32::MAX)) {
            return Err(refuse(
                self.item(),
                format!(
                    "face {} of the {} in {} has a node that no element uses (it must lie on the meshed {})",
                    k + 1,
                    mesh.groups.boundary,
                    mesh.name,
                    if mesh.model.dimension.coords() == 2 { "surface" } else { "volume" }
                ),
            ));
        }
        let traction = match (self.traction, self.pressure) {
            (Some(t), None) => t,
            (None, Some(_)) => [0.0; 3],
            _ => return Err(refuse(
                self.item(),
                "give either traction = [tx, ty, tz] (kPa) or pressure = p (kPa, normal to each face, pushing into the body)",
            )),
        };
        Ok(TractionInput {
            physical: self.physical.clone(),
            faces,
            traction,
            pressure: self.pressure,
            ramp: self.ramp,
        })
    }
}

/// Adds the nodal forces of tractions `t` (kPa, one per face, uniform on it) on `faces`
/// (model node ids of their corners), integrated exactly: each corner of a triangle (3D) takes
/// a third of its area times the traction, each end of an edge (2D) half its length; in an
/// axisymmetric section the edge's load is per radian, ∫ N_a t r ds = t L (2 r_a + r_b) / 6.
pub fn add_face_loads(model: &Model, faces: &[Vec<u32>], t: &[[f64; 3]], out: &mut [[f64; 3]]) {
    let axisymmetric = model.dimension == mpm_shared::Dimension::Axisymmetric;
    for (f, t) in faces.iter().zip(t) {
        let corners: Vec<usize> = f.iter().map(|&n| n as usize).collect();
        let size = crate::input::faces::size(model, &corners);
        for (i, &n) in corners.iter().enumerate() {
            let share = match corners.len() {
                2 if axisymmetric => {
                    let (ra, rb) = (model.node(n)[0], model.node(corners[1 - i])[0]);
                    size * (2.0 * ra + rb) / 6.0
                }
                k => size / k as f64,
            };
            for d in 0..3 {
                out[n][d] += share * t[d];
            }
        }
    }
}
