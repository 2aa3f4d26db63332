//! The scene's mesh (top-level `mesh` and `section`): the Gmsh file read into a model, its
//! physical groups, and the node selectors of the boundary sections (a physical group or a
//! plane `x = value`).

use std::path::Path;

use mpm_shared::msh::{self, MshMesh};
use mpm_shared::Model;

use super::{refuse, Refusal};

/// What a mesh's physical groups are called: materials fill groups of the elements' own
/// dimension (volumes in 3D, surfaces in 2D), loads and fixities sit on groups one below
/// (surfaces in 3D, curves in 2D).
#[derive(Debug, Clone, Copy)]
pub(super) struct Groups {
    /// The boundary groups' dimension.
    pub dim: usize,
    /// Name of a material group in messages.
    pub material: &'static str,
    /// Name of a boundary group in messages.
    pub boundary: &'static str,
}

impl Groups {
    /// The groups of a 2D (triangle) or a 3D (tetrahedron) model.
    fn of(model: &Model) -> Self {
        if model.dimension.coords() == 2 {
            Groups {
                dim: 1,
                material: "physical surface",
                boundary: "physical curve",
            }
        } else {
            Groups {
                dim: 2,
                material: "physical volume",
                boundary: "physical surface",
            }
        }
    }
}

/// The scene's mesh: the Gmsh file as read and as a model.
pub(super) struct Mesh {
    /// The file as read (its physical groups and boundary elements).
    pub msh: MshMesh,
    /// Model node id of each `.msh` node index (`u32::MAX` for a node no element uses).
    pub node_map: Vec<u32>,
    /// The model the case runs.
    pub model: Model,
    /// The mesh file as messages name it.
    pub name: String,
    /// The material groups by model material index less one (the names `[[material]]` uses).
    pub volumes: Vec<String>,
    /// What its groups are called.
    pub groups: Groups,
}

impl Mesh {
    /// The material index (1-based) of the material group `name`, or the message saying the
    /// mesh has no such group and naming those it has.
    pub fn material_group(&self, name: &str) -> Result<u32, String> {
        let m = self.groups.material;
        match self.volumes.iter().position(|v| v == name) {
            Some(k) => Ok(k as u32 + 1),
            None => Err(format!(
                "no {m} \"{name}\" in {} ({m}s: {:?})",
                self.name, self.volumes
            )),
        }
    }

    /// Reads the mesh `mesh` (relative to the scene file `scene_path`).
    pub fn read(scene_path: &Path, mesh: &Path) -> Result<Self, mpm_shared::Error> {
        let path = scene_path.parent().unwrap_or(Path::new(".")).join(mesh);
        let data = mpm_shared::io::read_input(&path)?;
        let name = path.display().to_string();
        let msh = msh::read(&data, &name)?;
        let (model, node_map) = msh::to_model_with_map(&msh, &name)?;
        // Model material k is the k-th physical group of the elements' dimension by tag (see
        // msh::to_model).
        let volumes = model.materials().iter().map(|m| m.name.clone()).collect();
        let groups = Groups::of(&model);
        Ok(Mesh {
            msh,
            node_map,
            model,
            name,
            volumes,
            groups,
        })
    }

    /// Applies the scene's `section`: triangles make a 2D section, plane strain unless the
    /// scene says axisymmetric; a 3D mesh takes neither.
    pub fn set_section(&mut self, section: Option<&str>) -> Result<(), Refusal> {
        match (section, self.model.dimension.coords()) {
            (None | Some("plane_strain"), 2) => {}
            (Some("axisymmetric"), 2) => {
                self.model.dimension = mpm_shared::Dimension::Axisymmetric;
            }
            (None, _) => {}
            (Some(s @ ("plane_strain" | "axisymmetric")), _) => {
                return Err(refuse(
                    "section",
                    format!("\"{s}\" is for 2D (triangle) meshes; {} is 3D", self.name),
                ))
            }
            (Some(other), _) => {
                return Err(refuse(
                    "section",
                    format!("expected \"plane_strain\" or \"axisymmetric\", got \"{other}\""),
                ))
            }
        }
        Ok(())
    }

    /// The mesh's largest extent along an axis (the scale of the plane selectors' tolerance).
    pub fn size(&self) -> f64 {
        let dim = self.model.dimension.coords();
        (0..3)
            .map(|a| {
                let (lo, hi) = self
                    .model
                    .coords
                    .chunks_exact(dim)
                    .filter_map(|p| p.get(a))
                    .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
                hi - lo
            })
            .fold(0.0, f64::max)
    }

    /// The node lists (`.msh` node indices, corners first) of the boundary elements
    /// (triangles in 3D, lines in 2D) of the boundary group `name`, or `None` if the mesh has
    /// no such group.
    fn boundary_elements(&self, name: &str) -> Option<Vec<&[u32]>> {
        let dim = self.groups.dim;
        let tag = self
            .msh
            .physical_names
            .iter()
            .find(|p| p.dim == dim && p.name == name)?
            .tag;
        let mut out = Vec::new();
        for set in self.msh.sets.iter().filter(|s| s.dim() == dim) {
            for (e, &phys) in set.physical.iter().enumerate() {
                if phys == tag {
                    out.push(&set.nodes[e * set.nodes_per..(e + 1) * set.nodes_per]);
                }
            }
        }
        Some(out)
    }

    /// The faces (model node ids of their corners: three of a triangle in 3D, two of a line in
    /// 2D; `u32::MAX` for a corner no element uses) of the boundary group `name`.
    pub fn boundary_faces(&self, name: &str) -> Option<Vec<Vec<u32>>> {
        let faces = self.boundary_elements(name)?;
        Some(
            faces
                .iter()
                .map(|f| {
                    (0..=self.groups.dim)
                        .map(|k| self.node_map[f[k] as usize])
                        .collect()
                })
                .collect(),
        )
    }

    /// All nodes (model numbering, corner and mid-edge, ascending) of the boundary group
    /// `name`.
    pub fn boundary_nodes(&self, name: &str) -> Option<Vec<u32>> {
        let mut out: Vec<u32> = self
            .boundary_elements(name)?
            .iter()
            .flat_map(|f| f.iter().map(|&n| self.node_map[n as usize]))
            .filter(|&n| n != u32::MAX)
            .collect();
        out.sort_unstable();
        out.dedup();
        Some(out)
    }

    /// The nodes on the plane `axis = value` (within a billionth of the mesh's size),
    /// ascending.
    pub fn plane_nodes(&self, axis: usize, value: f64) -> Vec<u32> {
        let tol = 1e-9 * self.size().max(1e-300);
        (0..self.model.node_count() as u32)
            .filter(|&n| (coordinate(&self.model, n, axis) - value).abs() <= tol)
            .collect()
    }
}

/// Parses `x = 0.5` style selectors: (axis, value).
pub(super) fn parse_plane(s: &str) -> Option<(usize, f64)> {
    let (a, v) = s.split_once('=')?;
    let axis = match a.trim() {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => return None,
    };
    Some((axis, v.trim().parse().ok()?))
}

/// Coordinate `axis` of model node `n` (0 for z in a 2D model).
fn coordinate(model: &Model, n: u32, axis: usize) -> f64 {
    model.node(n as usize).get(axis).copied().unwrap_or(0.0)
}
