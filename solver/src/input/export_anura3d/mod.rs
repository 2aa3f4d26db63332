//! `--export-anura3d DIR`: a TOML scene written as an Anura3D case, `DIR/NAME.GOM` and
//! `DIR/NAME.CPS_001` (NAME: the scene file's stem), so that the same problem runs in Anura3D
//! and in `mpm-solve DIR/NAME.GOM`.
//!
//! The mesh becomes `tetrahedral_old`, Anura3D's 3D element: the corners keep their numbers and
//! orientation, elements keep their order (so material-point ids agree in both programs), and a
//! 4-node mesh gets one new node at the midpoint of every distinct edge, numbered after the
//! original nodes in order of first appearance. Fixities go to the surface sections of both
//! phases (a new mid-edge node is fixed in a component when both its corners are), tractions to
//! `$$START_LOAD_ON_NODES_SOLID` (one row per face, the same vector at its six nodes), materials
//! to `dry_material` or `saturated_material_coupled` with their law's Anura3D keys, and materials'
//! `k0` to `$$K0_PROCEDURE 1` with `$$K0_VALUE_SOLID` and the ground's `$$SURFACE_ELEVATION`.
//!
//! What has no exact Anura3D equivalent is refused with the scene item named: the undrained start
//! of a consolidation run, output times that are not equally spaced (Anura3D writes one output
//! per load step of equal length), load ramps other than one over the whole run, an initial pore
//! pressure, a uniform initial stress (and `k0` on some materials only), a cap on the time
//! steps, material-point counts Anura3D does not place, more than 99 output points and the
//! strain-softening law (which Anura3D reads but cannot run).
//! Prescribed velocities go to `$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME` (a physical
//! volume's elements) and `$$PRESCRIBED_NODAL_VELOCITY_SURFACE` (nodes, a new mid-edge node
//! taking a set's velocity where both its corners are in the set) under one CPS
//! `$$PRESCRIBED_VELOCITY` multiplier: entries whose ramps differ are refused. Each nodal
//! set's faces also go to `$$START_OUTPUT_REACTION_FORCES`, so that Anura3D writes the set's
//! reaction every time step (`NAME.RSurf_00k`), to set beside our `reaction.csv`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use mpm_shared::cps::{Cps, Entry};
use mpm_shared::model::{Body, LineEnding, Refs, Section, Table, Token};
use mpm_shared::text::real_to_string;
use mpm_shared::{Dimension, ElementType, Model};

use crate::input::case::Start;
use crate::input::case::{Integration, LoadCurve};
use crate::input::scene::{self, Resolved, SceneError};

/// The version line written at the top of both files (the one the benchmark suite uses).
const VERSION: &str = "### Anura3D_2021 ###";

/// Material points per tetrahedron that Anura3D can place.
const ANURA3D_POINT_COUNTS: [u32; 8] = [0, 1, 4, 7, 8, 10, 13, 20];

/// Anura3D's limit on `$$OUTPUT_NUMBER_OF_MATERIAL_POINTS`.
const MAX_OUTPUT_POINTS: usize = 99;

/// Mid-edge node k (0-based, 4..10) of a `tetrahedral_old` element lies between these corners.
const EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)];

/// Why a scene could not be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The scene itself is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene asks for something Anura3D cannot reproduce exactly.
    #[error("{file}: {item}: cannot be exported to Anura3D: {message}")]
    Unsupported {
        /// Scene file.
        file: String,
        /// The scene item, e.g. `consolidation.start`.
        item: String,
        /// Why, and what would export.
        message: String,
    },
    /// Writing the files failed.
    #[error(transparent)]
    Write(#[from] mpm_shared::Error),
}

/// The files written by [`export_scene`] and notes on what runs differently.
#[derive(Debug, Clone)]
pub struct Exported {
    /// `DIR/NAME.GOM`.
    pub gom: PathBuf,
    /// `DIR/NAME.CPS_001`.
    pub cps: PathBuf,
    /// Differences the files cannot avoid (printed as warnings).
    pub notes: Vec<String>,
}

/// A scene as the two Anura3D files, in memory.
#[derive(Debug, Clone)]
pub struct Anura3dCase {
    /// The geometry, materials, fixities and loads (`.GOM`).
    pub gom: Model,
    /// The calculation parameters (`.CPS_001`).
    pub cps: Cps,
    /// Differences the files cannot avoid.
    pub notes: Vec<String>,
}

/// Reads the scene at `scene_path` and writes it as `dir/NAME.GOM` and `dir/NAME.CPS_001`
/// (`dir` is created if missing; each file appears only once complete).
pub fn export_scene(scene_path: &Path, dir: &Path) -> Result<Exported, ExportError> {
    let file = scene_path.display().to_string();
    let resolved = scene::resolve(scene_path)?;
    let case = build(&resolved, &file)?;
    let name = &resolved.case.name;
    let gom_bytes = mpm_shared::gom::write(&case.gom);
    let cps_bytes = case.cps.write();
    std::fs::create_dir_all(dir).map_err(|e| mpm_shared::Error::io(dir, e))?;
    let gom = dir.join(format!("{name}.GOM"));
    let cps = dir.join(format!("{name}.CPS_001"));
    mpm_shared::io::write_output(&gom, &gom_bytes)?;
    mpm_shared::io::write_output(&cps, &cps_bytes)?;
    Ok(Exported {
        gom,
        cps,
        notes: case.notes,
    })
}

/// Builds the Anura3D files of a resolved scene; `file` names the scene in errors.
pub fn build(r: &Resolved, file: &str) -> Result<Anura3dCase, ExportError> {
    let refuse = |item: &str, message: String| ExportError::Unsupported {
        file: file.to_string(),
        item: item.to_string(),
        message,
    };
    let case = &r.case;
    let mut notes = Vec::new();

    // What has no Anura3D equivalent.
    if let Some(c) = &case.consolidation {
        if c.start == Start::Undrained {
            return Err(refuse(
                "consolidation.start",
                "\"undrained\" starts from Terzaghi's undrained state, which Anura3D cannot set up; use start = \"rest\"".into(),
            ));
        }
        notes.push("[consolidation]: the Terzaghi report is mpm-solve's own; the export runs the loading only".into());
    }
    if let Some(n) = case.max_steps {
        return Err(refuse(
            "time.max_steps",
            format!("Anura3D has no cap on the time steps of a dynamic run (got {n}); remove it"),
        ));
    }
    let end = case.end_time;
    let n_out = case.output_times.len();
    let interval = case.output_times.first().copied().unwrap_or(end);
    let tol = 1e-9 * end;
    let equal = case
        .output_times
        .iter()
        .enumerate()
        .all(|(k, &t)| (t - (k + 1) as f64 * interval).abs() <= tol);
    if n_out == 0 || !equal {
        return Err(refuse(
            "time.output_interval",
            format!(
                "the outputs are not equally spaced (the end, {end} s, is not a whole number of intervals of {interval} s); Anura3D writes one per load step of equal length"
            ),
        ));
    }
    let multiplier = |curve: LoadCurve, item: &str| -> Result<&'static str, ExportError> {
        match curve {
            LoadCurve::Step => Ok("step  1.0  1.0"),
            LoadCurve::Ramp { over } if (over - end).abs() <= tol => Ok("linear  0.0  1.0"),
            LoadCurve::Ramp { over } => Err(refuse(
                item,
                format!(
                    "Anura3D ramps a load linearly over the whole run only: use 0 (sudden) or {end} (the end time), not {over}"
                ),
            )),
            LoadCurve::Stairs { .. } => Err(refuse(
                item,
                "a load in stairs (from Anura3D input) is not written back".to_string(),
            )),
        }
    };
    let gravity_on = case.gravity.iter().any(|&g| g != 0.0);
    let gravity_load = if gravity_on {
        multiplier(case.gravity_curve, "gravity.ramp")?
    } else {
        "off  0.0  1.0"
    };
    let loaded: Vec<&scene::TractionInput> = r
        .tractions
        .iter()
        .filter(|t| {
            !t.faces.is_empty()
                && (t.traction.iter().any(|&v| v != 0.0) || t.pressure.is_some_and(|p| p != 0.0))
        })
        .collect();
    // The case ramps every traction over the longest ramp given; each must fit Anura3D's.
    for t in &r.tractions {
        multiplier(
            LoadCurve::ramp(t.ramp),
            &format!("traction \"{}\".ramp", t.physical),
        )?;
    }
    let solid_traction = if loaded.is_empty() {
        "off  0.0  1.0"
    } else {
        multiplier(case.traction_curve, "traction.ramp")?
    };
    if case.pic_blend > 0.0 {
        return Err(refuse(
            "pic_blend",
            format!(
                "Anura3D updates the points' velocities by FLIP alone; remove pic_blend = {} (or set it to 0) to export",
                case.pic_blend
            ),
        ));
    }
    if !case.walls.is_empty() {
        return Err(refuse(
            "fixity.friction",
            "Anura3D has no frictional fixity (its friction acts between bodies in contact); \
             remove friction from the fixities to export"
                .into(),
        ));
    }
    // Anura3D has one multiplier for every prescribed velocity.
    let prescribed_velocity = match r.velocities.first() {
        None => "off  0.0  1.0",
        Some(first) => {
            if let Some(v) = r.velocities.iter().find(|v| v.ramp != first.ramp) {
                return Err(refuse(
                    &format!("velocity \"{}\".ramp", v.name),
                    format!(
                        "Anura3D has one multiplier for every prescribed velocity: give every [[velocity]] the ramp of \"{}\" ({} s), not {} s",
                        first.name, first.ramp, v.ramp
                    ),
                ));
            }
            multiplier(
                LoadCurve::ramp(first.ramp),
                &format!("velocity \"{}\".ramp", first.name),
            )?
        }
    };
    if r.case.nodal_velocity.len() > 1 {
        notes.push(format!(
            "[[velocity]]: the {} nodal sets go to one GOM section, so a run of the GOM records one reaction for all of them",
            r.case.nodal_velocity.len()
        ));
    }
    let n_mat = case.materials.len().saturating_sub(1);
    for k in 1..=n_mat {
        let Some(m) = &r.materials[k] else {
            let name = case.model.materials().get(k - 1).map(|m| m.name.clone());
            return Err(refuse(
                &format!("physical volume \"{}\"", name.unwrap_or_default()),
                "has no [[material]] entry".into(),
            ));
        };
        let item = format!("material \"{}\"", m.physical);
        if !ANURA3D_POINT_COUNTS.contains(&m.points_per_element) {
            return Err(refuse(
                &format!("{item}.points_per_element"),
                format!(
                    "Anura3D places {ANURA3D_POINT_COUNTS:?} material points in a tetrahedron, not {}",
                    m.points_per_element
                ),
            ));
        }
        if let crate::material::law::LawSpec::StrainSofteningMohrCoulomb { .. } = m.law {
            return Err(refuse(
                &format!("{item}.law"),
                "Anura3D reads strain_softening_mohr_coulomb but has no stress routine for it (its run stops with a segmentation fault)".into(),
            ));
        }
        if m.initial_stress.is_some() {
            return Err(refuse(
                &format!("{item}.initial_stress"),
                "Anura3D has no uniform initial stress ($$K0_PROCEDURE sets K0 stresses, $$MP_STRESS_INITIALIZATION_FROMFILE reads them from a results file); use k0 or none".into(),
            ));
        }
        if let Some(k0) = m.k0 {
            if k0 > 1.0 {
                return Err(refuse(
                    &format!("{item}.k0"),
                    format!("Anura3D accepts K0 in [0, 1] only, got {k0}"),
                ));
            }
        } else if r.materials.iter().flatten().any(|o| o.k0.is_some()) {
            return Err(refuse(
                &item,
                "Anura3D's K0 procedure stresses every material (a material without K0 would start with its vertical stress): give it k0 too".into(),
            ));
        }
        if let Some(l) = &m.liquid {
            if l.initial_pore_pressure != 0.0 {
                return Err(refuse(
                    &format!("{item}.liquid.initial_pore_pressure"),
                    format!(
                        "Anura3D's coupled material starts without pore pressure (got {} kPa); use 0",
                        l.initial_pore_pressure
                    ),
                ));
            }
        }
    }
    let total_points: u64 = case
        .element_material
        .iter()
        .zip(&case.points_per_element)
        .filter(|(&m, _)| m != 0)
        .map(|(_, &n)| n as u64)
        .sum();
    let mut probes: Vec<u32> = if case.probes.is_empty() && total_points > 0 {
        // A few points: the first, one in the middle and the last.
        vec![1, total_points.div_ceil(2) as u32, total_points as u32]
    } else {
        case.probes.clone()
    };
    probes.sort_unstable();
    probes.dedup();
    if probes.len() > MAX_OUTPUT_POINTS {
        return Err(refuse(
            "probes",
            format!(
                "Anura3D writes at most {MAX_OUTPUT_POINTS} output material points, got {}",
                probes.len()
            ),
        ));
    }
    if let Some(&bad) = probes.iter().find(|&&p| p == 0 || p as u64 > total_points) {
        return Err(refuse(
            "probes",
            format!("material point {bad} does not exist (ids run from 1 to {total_points})"),
        ));
    }
    if case.has_liquid() && case.damping > 0.0 {
        notes.push(format!(
            "damping.local: Anura3D (and mpm-solve on the exported GOM) damps the liquid by {} too, and the mixture's solid and liquid parts separately; the scene damps the mixture against the solid's velocity only",
            case.damping
        ));
    }

    if smooths(case) && !case.strain_smoothing {
        notes.push("STRAIN_SMOOTHING 1: Anura3D (and mpm-solve on the exported GOM) smooths the volumetric strain of both phases element by element; the scene smooths pore-pressure rates through V N-weighted nodal averages".into());
    }
    let mesh = Tet10Mesh::of(&case.model, &case.fixed, &case.liquid_fixed)
        .ok_or_else(|| refuse("mesh", "Anura3D's 3D export needs tetrahedra".into()))?;
    let loads = load_rows(&mesh, &loaded).map_err(|(item, m)| refuse(&item, m))?;
    let gom = gom_model(r, mesh, loads, &mut notes);
    let smoothing = smooths(case);
    let cps = cps_file(
        case,
        CpsValues {
            interval,
            load_steps: n_out,
            gravity_load,
            solid_traction,
            smoothing,
            probes: &probes,
            prescribed_velocity,
            k0_surface: case
                .initial_stress
                .as_ref()
                .and_then(|i| i.k0.as_ref())
                .map(|k| k.surface_point[1]),
        },
    );
    Ok(Anura3dCase { gom, cps, notes })
}

/// Whether the CPS switches `STRAIN_SMOOTHING` on: when the scene asks for Anura3D's strain
/// smoothing, or when it smooths pore pressures and has some (for a dry case without
/// `strain_smoothing` Anura3D's smoothing would act on the solid strain, which the scene does
/// not smooth).
fn smooths(case: &crate::input::case::Case) -> bool {
    case.strain_smoothing || (case.smooth_pressure && case.has_liquid())
}

/// The mesh as 10-node tetrahedra with the fixities of every node.
struct Tet10Mesh {
    coords: Vec<f64>,
    connectivity: Vec<u32>,
    fixed: Vec<[bool; 3]>,
    liquid_fixed: Vec<[bool; 3]>,
    /// Mid-edge node of each edge (corner ids sorted).
    mid: HashMap<(u32, u32), u32>,
}

impl Tet10Mesh {
    /// `model` (4- or 10-node tetrahedra) with its fixities; a 4-node mesh gets its mid-edge
    /// nodes, numbered after the others in order of first appearance.
    fn of(model: &Model, fixed: &[[bool; 3]], liquid_fixed: &[[bool; 3]]) -> Option<Self> {
        let n_el = model.element_count();
        let mut coords = model.coords.clone();
        let mut fixed = fixed.to_vec();
        let mut liquid_fixed = liquid_fixed.to_vec();
        let mut mid = HashMap::with_capacity(n_el * 2);
        let mut connectivity = Vec::with_capacity(n_el * 10);
        let key = |a: u32, b: u32| (a.min(b), a.max(b));
        match model.element_type {
            ElementType::Tet10 => {
                connectivity.extend_from_slice(&model.connectivity);
                for e in 0..n_el {
                    let el = model.element(e);
                    for (k, (a, b)) in EDGES.iter().enumerate() {
                        mid.insert(key(el[*a], el[*b]), el[4 + k]);
                    }
                }
            }
            ElementType::Tet4 => {
                for e in 0..n_el {
                    let c: [u32; 4] = model.element(e).try_into().expect("4 corners");
                    connectivity.extend_from_slice(&c);
                    for (a, b) in EDGES {
                        let next = (coords.len() / 3) as u32;
                        let id = *mid.entry(key(c[a], c[b])).or_insert_with(|| {
                            let (p, q) = (model.node(c[a] as usize), model.node(c[b] as usize));
                            for d in 0..3 {
                                coords.push(0.5 * (p[d] + q[d]));
                            }
                            let both = |f: &[[bool; 3]]| {
                                let (f, g) = (f[c[a] as usize], f[c[b] as usize]);
                                [f[0] && g[0], f[1] && g[1], f[2] && g[2]]
                            };
                            fixed.push(both(&fixed));
                            liquid_fixed.push(both(&liquid_fixed));
                            next
                        });
                        connectivity.push(id);
                    }
                }
            }
            ElementType::Tri3 => return None,
        }
        Some(Tet10Mesh {
            coords,
            connectivity,
            fixed,
            liquid_fixed,
            mid,
        })
    }

    fn node(&self, n: u32) -> [f64; 3] {
        let i = n as usize * 3;
        [self.coords[i], self.coords[i + 1], self.coords[i + 2]]
    }
}

/// One `$$START_LOAD_ON_NODES_SOLID` row per loaded face: corners ordered as Anura3D's
/// pre-processor writes boundary faces ((c2 - c1) × (c3 - c1) points into the element), the
/// mid-edge nodes of edges 12, 23 and 31, then the traction at each of the six nodes.
fn load_rows(
    mesh: &Tet10Mesh,
    tractions: &[&scene::TractionInput],
) -> Result<Table, (String, String)> {
    let sorted = |f: [u32; 3]| {
        let mut k = f;
        k.sort_unstable();
        k
    };
    // The corner opposite each loaded face in an element that has it.
    let mut opposite: HashMap<[u32; 3], Option<u32>> = tractions
        .iter()
        .flat_map(|t| t.faces.iter().map(|f| (sorted([f[0], f[1], f[2]]), None)))
        .collect();
    for c in mesh.connectivity.chunks_exact(10) {
        for skip in 0..4 {
            let mut f = [0u32; 3];
            let mut j = 0;
            for (i, &n) in c[..4].iter().enumerate() {
                if i != skip {
                    f[j] = n;
                    j += 1;
                }
            }
            if let Some(slot) = opposite.get_mut(&sorted(f)) {
                slot.get_or_insert(c[skip]);
            }
        }
    }
    let mut rows = Table::with_capacity(tractions.iter().map(|t| t.faces.len()).sum(), 24);
    for t in tractions {
        for f in &t.faces {
            // A 3D scene's faces are triangles (2D scenes are refused before this).
            let f = [f[0], f[1], f[2]];
            let item = || format!("traction \"{}\"", t.physical);
            let inner = opposite[&sorted(f)].ok_or_else(|| {
                (
                    item(),
                    format!(
                        "the face with corner nodes {} {} {} is not a face of any element",
                        f[0] + 1,
                        f[1] + 1,
                        f[2] + 1
                    ),
                )
            })?;
            let [p, q, s] = f.map(|n| mesh.node(n));
            let o = mesh.node(inner);
            let (a, b) = (
                [0, 1, 2].map(|d| q[d] - p[d]),
                [0, 1, 2].map(|d| s[d] - p[d]),
            );
            let n = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let inward: f64 = (0..3).map(|d| n[d] * (o[d] - p[d])).sum();
            let c = if inward < 0.0 { [f[0], f[2], f[1]] } else { f };
            // A pressure pushes along the face's inward normal.
            let traction = match t.pressure {
                Some(pressure) => {
                    let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    let s = pressure * inward.signum() / length;
                    n.map(|c| s * c)
                }
                None => t.traction,
            };
            let mid = |i: usize, j: usize| mesh.mid[&(c[i].min(c[j]), c[i].max(c[j]))];
            let ids = [c[0], c[1], c[2], mid(0, 1), mid(1, 2), mid(2, 0)];
            rows.push_row(
                ids.iter()
                    .map(|&i| Token::Int(i as i64 + 1))
                    .chain((0..6).flat_map(|_| traction.map(Token::Real))),
            );
        }
    }
    Ok(rows)
}

/// `$$START_OUTPUT_REACTION_FORCES` rows, so that Anura3D writes each nodal-velocity set's
/// reaction (`NAME.RSurf_00k`, k the set's place among those with faces; every time step): per
/// set, every element face whose three corners are in the set (once), as the set's name
/// (quoted), the element and the face's corners and mid-edge nodes. Anura3D sums its nodes' B^T sigma less
/// their weight over these faces' nodes; the set's mid-edge nodes are the faces' (see
/// `gom_model`), so the nodes summed are the set's unless some of its nodes lie on no face.
fn reaction_rows(
    mesh: &Tet10Mesh,
    sets: &[crate::step::nodal_velocity::NodalVelocitySet],
) -> Table {
    const FACES: [[usize; 3]; 4] = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
    let mut t = Table::new();
    let n_nodes = mesh.coords.len() / 3;
    for set in sets {
        let mut inside = vec![false; n_nodes];
        for p in &set.rows {
            inside[p.node as usize] = true;
        }
        let label = Token::Text(format!("\"{}\"", safe_name(&set.name)).into());
        // A face inside the mesh (the footing under an empty layer) once, in its first element.
        let mut seen = std::collections::HashSet::new();
        for (e, c) in mesh.connectivity.chunks_exact(10).enumerate() {
            for f in FACES {
                let k = f.map(|i| c[i]);
                let mut key = k;
                key.sort_unstable();
                if !k.iter().all(|&n| inside[n as usize]) || !seen.insert(key) {
                    continue;
                }
                let mid = |a: u32, b: u32| mesh.mid[&(a.min(b), a.max(b))];
                let ids = [
                    k[0],
                    k[1],
                    k[2],
                    mid(k[0], k[1]),
                    mid(k[1], k[2]),
                    mid(k[2], k[0]),
                ];
                t.push_row(
                    [label.clone(), Token::Int(e as i64 + 1)]
                        .into_iter()
                        .chain(ids.map(|n| Token::Int(n as i64 + 1))),
                );
            }
        }
    }
    t
}

fn text(keyword: &str, lines: &[&str]) -> Section {
    Section {
        keyword: keyword.into(),
        body: Body::Text(lines.iter().map(|l| l.to_string()).collect()),
    }
}

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

/// A material name Anura3D reads whole (its list-directed read stops at blanks, commas, slashes
/// and quotes): other characters become `_`.
fn safe_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "_-.+()[]".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        "material".into()
    } else {
        s
    }
}

/// The GOM: sections in the order Anura3D's pre-processor writes them.
fn gom_model(r: &Resolved, mesh: Tet10Mesh, loads: Table, notes: &mut Vec<String>) -> Model {
    let case = &r.case;
    let placeholder = |k: &str, body: Body| Section {
        keyword: k.into(),
        body,
    };
    let mut sections = mpm_shared::model::geometry_sections();
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
    if !loads.is_empty() {
        sections.push(counted("START_LOAD_ON_NODES_SOLID", Refs::Nodes(6), loads));
    }
    let row = |id: u32, d: [bool; 3], v: [f64; 3]| {
        std::iter::once(Token::Int(id as i64 + 1))
            .chain(d.map(|x| Token::Int(x as i64)))
            .chain(v.map(Token::Real))
    };
    if let Some(pv) = &case.prescribed {
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
    if !case.nodal_velocity.is_empty() {
        let original = case.model.node_count() as u32;
        let mut t = Table::new();
        for set in &case.nodal_velocity {
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
            reaction_rows(&mesh, &case.nodal_velocity),
        ));
    }
    sections.push(counted("START_CONTACT_VOLUME", Refs::Element, Table::new()));
    let n_mat = case.materials.len().saturating_sub(1);
    sections.push(text("NUMBER_OF_MATERIALS", &[&n_mat.to_string()]));
    for (k, m) in r.materials.iter().enumerate().skip(1) {
        let m = m.as_ref().expect("checked in build");
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
    let mut elmmat = Table::with_capacity(case.element_material.len(), 1);
    let mut points = Table::with_capacity(case.element_material.len(), 2);
    for (&m, &n) in case.element_material.iter().zip(&case.points_per_element) {
        // Anura3D refuses an element with a material but no points: an element the scene
        // leaves empty (`points_per_element = 0`) is written as inactive (material 0).
        let m = if n == 0 { 0 } else { m };
        elmmat.push_row([Token::Int(m as i64)]);
        let n = if m == 0 { 0 } else { n };
        points.push_row([Token::Int(n as i64), Token::Int(0)]);
    }
    sections.push(placeholder("STARTELMMAT", Body::PerElement(elmmat)));
    sections.push(placeholder(
        "START_NUMBER_OF_MATERIAL_POINTS",
        Body::PerElement(points),
    ));
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

/// The CPS values that come from the checks in [`build`].
struct CpsValues<'a> {
    interval: f64,
    load_steps: usize,
    gravity_load: &'static str,
    solid_traction: &'static str,
    smoothing: bool,
    probes: &'a [u32],
    prescribed_velocity: &'static str,
    /// Height of the ground surface when the K0 procedure is on.
    k0_surface: Option<f64>,
}

/// The CPS: the scene's controls, every other key at the inert value of Anura3D's template.
fn cps_file(case: &crate::input::case::Case, v: CpsValues) -> Cps {
    let g = case.gravity;
    let g_abs = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    // Without gravity the load is off, but the acceleration keeps Anura3D's default: Anura3D
    // turns the intrinsic permeability into a hydraulic conductivity with it (ρw g κ / μ), and
    // 0 there makes a saturated material's drag infinite.
    let (g_abs, dir) = if g_abs > 0.0 {
        (g_abs, g.map(|c| c / g_abs))
    } else {
        // Without gravity (GRAVITY_LOAD off) Anura3D still needs g: it turns intrinsic
        // permeability into conductivity with it (a 0 makes its drag 0/0).
        (crate::material::liquid::G, [0.0, -1.0, 0.0])
    };
    let r = real_to_string;
    let damping = if case.damping > 0.0 {
        format!("1 {}", r(case.damping))
    } else {
        "0 0.0".into()
    };
    let probes: Vec<String> = if v.probes.is_empty() {
        vec!["-1".into()]
    } else {
        v.probes.iter().map(|p| p.to_string()).collect()
    };
    let one = |s: &str| vec![s.to_string()];
    let mut entries: Vec<(&str, Vec<String>)> = vec![
        ("NUMBER_OF_LOADSTEPS", one(&v.load_steps.to_string())),
        ("TIME_PER_LOADSTEP", one(&r(v.interval))),
        ("TOTAL_TIME", one("0.0")),
        ("COURANT_NUMBER", one(&r(case.courant))),
        (
            "COMPUTATION_METHOD",
            one(match case.integration {
                Integration::MaterialPoints => "MPM-MP",
                Integration::Mixed { .. } => "MPM-MIXED",
            }),
        ),
        ("GRAVITY_ACCELERATION", one(&r(g_abs))),
        (
            "GRAVITY_VECTOR",
            one(&format!("{} {} {}", r(dir[0]), r(dir[1]), r(dir[2]))),
        ),
        ("GRAVITY_LOAD", one(v.gravity_load)),
        ("SOLID_TRACTION", one(v.solid_traction)),
        ("SOLID_TRACTION_B", one("off  0.0  1.0")),
        ("LIQUID_PRESSURE", one("off  0.0  1.0")),
        ("LIQUID_PRESSURE_B", one("off  0.0  1.0")),
        ("PRESCRIBED_VELOCITY", one(v.prescribed_velocity)),
        ("QUASISTATIC_CONVERGENCE", one("0")),
        ("TOLERATED_ERROR_SOLID", one("0.01 0.01")),
        ("TOLERATED_ERROR_LIQUID", one("0.01 0.01")),
        ("MAXIMUM_TIME_STEPS", one("10000")),
        ("MASS_SCALING", one("0 1.0")),
        ("HOMOGENEOUS_LOCAL_DAMPING", one(&damping)),
        ("BULK_VISCOSITY_DAMPING", one("0 0.0 0.0")),
        ("FIX_SOLID_SKELETON", one("0")),
        ("STRAIN_SMOOTHING", one(if v.smoothing { "1" } else { "0" })),
        ("CONTACT_FORMULATION", one("0")),
        ("EXCAVATION", one("0")),
        ("INITIAL_WATER_PRESSURE", one("0.0")),
        ("APPLY_POROSITY_UPDATE", one("0")),
        ("INITIAL_VELOCITY", one("0")),
        ("RESET_DISPLACEMENTS", one("0")),
        ("REMOVE_FIXITIES", one("0 0 0")),
        (
            "K0_PROCEDURE",
            one(if v.k0_surface.is_some() { "1" } else { "0" }),
        ),
        ("SUBMERGED_CALCULATION", one("0 1")),
        (
            "APPLY_OBJECTIVE_STRESS",
            one(if case.objective_stress { "1" } else { "0" }),
        ),
        (
            "DEGREE_OF_FILLING",
            one(&match case.integration {
                Integration::Mixed { filling, .. } => r(filling),
                Integration::MaterialPoints => "0.9".into(),
            }),
        ),
        ("NUMBER_OF_ACTIVE_ELEMENTS", one("0")),
        (
            "OUTPUT_NUMBER_OF_MATERIAL_POINTS",
            one(&v.probes.len().to_string()),
        ),
        ("OUTPUT_MATERIAL_POINTS", probes),
    ];
    if let Some(y) = v.k0_surface {
        // Anura3D reads the surface's height as the first number.
        let at = entries
            .iter()
            .position(|e| e.0 == "K0_PROCEDURE")
            .expect("listed")
            + 1;
        entries.insert(at, ("SURFACE_ELEVATION", one(&r(y))));
    }
    Cps {
        file: String::new(),
        version: VERSION.into(),
        line_ending: LineEnding::Lf,
        entries: entries
            .into_iter()
            .map(|(k, lines)| Entry {
                keyword: k.into(),
                lines,
                line: 0,
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpm_shared::generate::box_mesh;

    #[test]
    fn mid_edge_nodes_of_a_4_node_box_are_those_of_the_10_node_box() {
        // The structured 10-node box has a node at the midpoint of every edge of the 4-node one
        // (same elements, same corner order): adding mid-edge nodes must give the same geometry
        // node for node, and as many nodes.
        let (n, size) = ([2, 3, 2], [1.0, 1.5, 0.5]);
        let tet4 = box_mesh(n, size, ElementType::Tet4);
        let tet10 = box_mesh(n, size, ElementType::Tet10);
        let fixed: Vec<[bool; 3]> = (0..tet4.node_count())
            .map(|i| {
                let p = tet4.node(i);
                [p[0] == 0.0, p[1] == 0.0, p[0] == 0.0 && p[2] == 0.0]
            })
            .collect();
        let mesh = Tet10Mesh::of(&tet4, &fixed, &fixed).unwrap();
        assert_eq!(mesh.coords.len(), tet10.coords.len());
        assert_eq!(mesh.connectivity.len(), tet10.connectivity.len());
        for (a, b) in mesh.connectivity.iter().zip(&tet10.connectivity) {
            assert_eq!(mesh.node(*a).as_slice(), tet10.node(*b as usize));
        }
        // New nodes follow the original ones in order of first appearance.
        let mut seen = tet4.node_count() as u32;
        for el in mesh.connectivity.chunks_exact(10) {
            for &m in &el[4..] {
                assert!(m < seen + 1 && m >= tet4.node_count() as u32);
                seen = seen.max(m + 1);
            }
        }
        // A mid-edge node is fixed in a component where both corners are: on the planes
        // x = 0 and y = 0, and on the line x = z = 0.
        for (i, f) in mesh.fixed.iter().enumerate() {
            let p = mesh.node(i as u32);
            assert_eq!(*f, [p[0] == 0.0, p[1] == 0.0, p[0] == 0.0 && p[2] == 0.0]);
        }
    }

    #[test]
    fn names_anura3d_would_cut_are_made_one_token() {
        assert_eq!(safe_name("soil"), "soil");
        assert_eq!(safe_name("soft clay/2"), "soft_clay_2");
        assert_eq!(safe_name(""), "material");
    }
}
