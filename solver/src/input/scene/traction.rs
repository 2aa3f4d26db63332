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
            traction vector, a pressure normal to each face, or a hammer's blows. Give exactly \
            one of `traction`, `pressure` and `hammer`. Every traction ramps over the longest \
            `ramp` given, or follows the one `curve` (or `hammer`) they all give.",
    keys: &[
        key("physical", "string", "required", "", "the physical boundary group"),
        key("traction", "[float, float, float]", "none", "kPa", "a uniform traction vector"),
        key("pressure", "float", "none", "kPa", "or a pressure normal to each face, pushing into the body (a tunnel's or a pile's wall)"),
        key("ramp", "float", "0 (sudden)", "s", "time to reach the full load"),
        key("curve", "[[float, float], ...] or string", "none", "s, –", super::curve::CURVE_HELP),
        key("hammer", "table", "none", "", "blows of a ram pushing into the body: `{ ram_mass = t, velocity = m/s, impedance = kN·s/m, cushion = kN/m (optional), blows = 1, interval = s, first = s (0) }`; the first blow at `first`, then one every `interval`; F(t) = Z v₀ exp(−Z t / m) per blow (through a cushion, its spring-dashpot response), as a pressure F / A over the group's area A"),
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
    /// A multiplier over time instead of the ramp.
    #[serde(default)]
    curve: Option<toml::Value>,
    /// Blows of a ram.
    #[serde(default)]
    hammer: Option<super::curve::Hammer>,
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
    /// Its multiplier over time, when it gives a `curve` or a `hammer`.
    pub curve: Option<crate::step::load_curve::LoadCurve>,
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
    /// The nodal forces of every traction at full load (with contact, of the faces of the
    /// soil's elements).
    pub traction: Vec<[f64; 3]>,
    /// With contact, the nodal forces of the loaded faces of the structure's elements (empty
    /// without).
    pub structure_traction: Vec<[f64; 3]>,
    /// Their multiplier: the ramp over the longest one given, or the one curve they all give.
    pub curve: crate::step::load_curve::LoadCurve,
    /// The entries in file order.
    pub inputs: Vec<TractionInput>,
}

/// A contact's structure as the face loads see it: each element's material and number of
/// points, and the structure's material.
pub(super) struct Structure<'a> {
    pub element_material: &'a [u32],
    pub points_per_element: &'a [u32],
    pub material: u32,
}

impl Structure<'_> {
    /// Whether `face` (held by `elements`) loads the structure: its filled elements are the
    /// structure's (a pile's head between the pile and an empty element); `Err` for a face
    /// between the structure and the soil.
    fn loads(&self, elements: &[usize]) -> Result<bool, &'static str> {
        let filled = elements.iter().filter(|&&e| self.points_per_element[e] > 0);
        let (mut ours, mut other) = (false, false);
        for &e in filled {
            if self.element_material[e] == self.material {
                ours = true;
            } else {
                other = true;
            }
        }
        match (ours, other) {
            (true, true) => Err("a face between the structure and the soil: load one or the other"),
            (ours, _) => Ok(ours),
        }
    }
}

/// The `[[traction]]` entries on the mesh's faces, in file order.
/// On a background grid (`grid`), the faces' loads are integrated with the grid's functions
/// ([`super::grid::add_face_loads`]). With a contact's `structure`, a face of the structure's
/// elements loads the structure alone.
pub(super) fn resolve(
    entries: &[Traction],
    mesh: &Mesh,
    (grid, structure): (Option<&GridSpec>, Option<Structure<'_>>),
    scene_dir: &std::path::Path,
) -> Result<Loads, Refusal> {
    let nodes = mesh.model.node_count();
    let mut out = Loads {
        traction: vec![[0.0; 3]; nodes],
        structure_traction: if structure.is_some() {
            vec![[0.0; 3]; nodes]
        } else {
            Vec::new()
        },
        curve: crate::step::load_curve::LoadCurve::Step,
        inputs: Vec::with_capacity(entries.len()),
    };
    let mut ramp = 0.0f64;
    for tr in entries {
        let input = tr.resolve(mesh, scene_dir)?;
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
        match (grid, &structure) {
            (Some(g), _) => {
                super::grid::add_face_loads(g, &mesh.model, &input.faces, &loads, &mut out.traction)
            }
            (None, Some(structure)) => {
                let holders = face_elements(&mesh.model, &input.faces);
                for (k, elements) in holders.iter().enumerate() {
                    let ours = structure
                        .loads(elements)
                        .map_err(|m| refuse(tr.item(), format!("face {}: {m}", k + 1)))?;
                    let to = if ours {
                        &mut out.structure_traction
                    } else {
                        &mut out.traction
                    };
                    let (face, load) = (&input.faces[k..=k], &loads[k..=k]);
                    add_face_loads(&mesh.model, face, load, to);
                }
            }
            (None, None) => add_face_loads(&mesh.model, &input.faces, &loads, &mut out.traction),
        }
        ramp = ramp.max(tr.ramp);
        out.inputs.push(input);
    }
    out.curve = one_curve(&out.inputs, ramp)?;
    Ok(out)
}

/// The face loads' one multiplier: the ramp over the longest `ramp`, or the curve every entry
/// gives (the loads share one multiplier, as Anura3D's load system does).
fn one_curve(
    inputs: &[TractionInput],
    ramp: f64,
) -> Result<crate::step::load_curve::LoadCurve, Refusal> {
    let Some(with) = inputs.iter().find(|t| t.curve.is_some()) else {
        return Ok(crate::step::load_curve::LoadCurve::ramp(ramp));
    };
    match inputs.iter().find(|t| t.curve != with.curve) {
        Some(other) => Err(refuse(
            format!("traction \"{}\"", other.physical),
            format!(
                "its multiplier differs from traction \"{}\"'s curve: the face loads share one \
                 multiplier (give them all the same `curve` or `hammer`, or none)",
                with.physical
            ),
        )),
        None => Ok(with.curve.clone().expect("found with a curve")),
    }
}

impl Traction {
    /// The entry as messages name it.
    fn item(&self) -> String {
        format!("traction \"{}\"", self.physical)
    }

    /// The entry with its group's faces, each of whose corners must be a node of the model.
    fn resolve(&self, mesh: &Mesh, scene_dir: &std::path::Path) -> Result<TractionInput, Refusal> {
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
        if self.curve.is_some() && self.ramp != 0.0 {
            return Err(refuse(self.item(), "give a ramp or a curve, not both"));
        }
        let mut curve = match &self.curve {
            Some(v) => Some(super::curve::resolve(
                v,
                scene_dir,
                &format!("{}.curve", self.item()),
            )?),
            None => None,
        };
        let (traction, pressure) = match (self.traction, self.pressure, &self.hammer) {
            (Some(t), None, None) => (t, None),
            (None, Some(p), None) => ([0.0; 3], Some(p)),
            (None, None, Some(h)) => {
                if self.curve.is_some() || self.ramp != 0.0 {
                    return Err(refuse(self.item(), "a hammer is its own curve: remove curve and ramp"));
                }
                let (blows, peak) = h.resolve(&format!("{}.hammer", self.item()))?;
                curve = Some(blows);
                ([0.0; 3], Some(peak / real_area(&mesh.model, &faces)))
            }
            _ => return Err(refuse(
                self.item(),
                "give one of traction = [tx, ty, tz] (kPa), pressure = p (kPa, normal to each face, pushing into the body) or hammer = { ... }",
            )),
        };
        Ok(TractionInput {
            physical: self.physical.clone(),
            faces,
            traction,
            pressure,
            ramp: self.ramp,
            curve,
        })
    }
}

/// The area of `faces` (m²): of the triangles in 3D, of the edges times a metre in plane
/// strain, of the surface of revolution (2π ∫ r ds) in an axisymmetric section.
fn real_area(model: &Model, faces: &[Vec<u32>]) -> f64 {
    let per_radian = model.dimension == mpm_shared::Dimension::Axisymmetric;
    let sum: f64 = faces
        .iter()
        .map(|f| {
            let corners: Vec<usize> = f.iter().map(|&n| n as usize).collect();
            crate::input::faces::corner_shares(model, &corners)
                .iter()
                .sum::<f64>()
        })
        .sum();
    if per_radian {
        2.0 * std::f64::consts::PI * sum
    } else {
        sum
    }
}

/// The elements holding each face (all the face's corners are nodes of each: one for a face on
/// the mesh's boundary, two inside it).
fn face_elements(model: &Model, faces: &[Vec<u32>]) -> Vec<Vec<usize>> {
    // The elements around each node, `around[start[n]..start[n + 1]]`.
    let mut start = vec![0usize; model.node_count() + 1];
    for e in 0..model.element_count() {
        for &n in model.element(e) {
            start[n as usize + 1] += 1;
        }
    }
    for n in 0..model.node_count() {
        start[n + 1] += start[n];
    }
    let mut next = start.clone();
    let mut around = vec![0usize; start[model.node_count()]];
    for e in 0..model.element_count() {
        for &n in model.element(e) {
            around[next[n as usize]] = e;
            next[n as usize] += 1;
        }
    }
    faces
        .iter()
        .map(|f| {
            let Some(&first) = f.first() else {
                return Vec::new();
            };
            let first = first as usize;
            around[start[first]..start[first + 1]]
                .iter()
                .copied()
                .filter(|&e| f.iter().all(|c| model.element(e).contains(c)))
                .collect()
        })
        .collect()
}

/// Adds the nodal forces of tractions `t` (kPa, one per face, uniform on it) on `faces`
/// (model node ids of their corners), integrated exactly: each corner of a triangle (3D) takes
/// a third of its area times the traction, each end of an edge (2D) half its length; in an
/// axisymmetric section the edge's load is per radian, ∫ N_a t r ds = t L (2 r_a + r_b) / 6.
pub fn add_face_loads(model: &Model, faces: &[Vec<u32>], t: &[[f64; 3]], out: &mut [[f64; 3]]) {
    for (f, t) in faces.iter().zip(t) {
        let corners: Vec<usize> = f.iter().map(|&n| n as usize).collect();
        let shares = crate::input::faces::corner_shares(model, &corners);
        for (&n, share) in corners.iter().zip(shares) {
            for d in 0..3 {
                out[n][d] += share * t[d];
            }
        }
    }
}
