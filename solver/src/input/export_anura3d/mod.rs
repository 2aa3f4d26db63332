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

use std::path::{Path, PathBuf};

use mpm_shared::cps::Cps;
use mpm_shared::Model;

use crate::input::scene::{self, Resolved, SceneError};

mod checks;
mod cps;
mod gom;
mod mesh;

/// The version line written at the top of both files (the one the benchmark suite uses).
const VERSION: &str = "### Anura3D_2021 ###";

/// Material points per tetrahedron that Anura3D can place.
const ANURA3D_POINT_COUNTS: [u32; 8] = [0, 1, 4, 7, 8, 10, 13, 20];

/// Anura3D's limit on `$$OUTPUT_NUMBER_OF_MATERIAL_POINTS`.
const MAX_OUTPUT_POINTS: usize = 99;

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
    /// The prescribed velocities' multiplier file (`.PVF`: time, multiplier), when their curve
    /// is a table.
    pub pvf: Option<Vec<(f64, f64)>>,
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
    if let Some(rows) = &case.pvf {
        // Shortest round-trip decimals: Anura3D reads the same doubles.
        let text: String = rows.iter().map(|(t, m)| format!("{t:e} {m:e}\n")).collect();
        mpm_shared::io::write_output(&dir.join(format!("{name}.PVF")), text.as_bytes())?;
    }
    Ok(Exported {
        gom,
        cps,
        notes: case.notes,
    })
}

/// Builds the Anura3D files of a resolved scene; `file` names the scene in errors.
pub fn build(r: &Resolved, file: &str) -> Result<Anura3dCase, ExportError> {
    files(r).map_err(|u| ExportError::Unsupported {
        file: file.to_string(),
        item: u.item,
        message: u.message,
    })
}

/// The two files of a resolved scene, after the checks of what Anura3D cannot reproduce.
fn files(r: &Resolved) -> Result<Anura3dCase, checks::Refusal> {
    let case = &r.case;
    let mut notes = Vec::new();
    checks::run(case, &mut notes)?;
    let (interval, load_steps) = checks::load_steps(case)?;
    let gravity_load = checks::gravity_load(case)?;
    let solid_traction = checks::solid_traction(r)?;
    checks::solver_only(case)?;
    let (prescribed_velocity, pvf) = checks::prescribed_velocity(r, &mut notes)?;
    checks::materials(r)?;
    let probes = checks::probes(case)?;
    checks::differences(case, &mut notes);
    let mesh = mesh::Tet10Mesh::of(
        &case.model,
        &case.boundary.fixed,
        &case.boundary.liquid_fixed,
    )
    .ok_or_else(|| checks::refuse("mesh", "Anura3D's 3D export needs tetrahedra"))?;
    let loads =
        mesh::load_rows(&mesh, &checks::loaded(r)).map_err(|(item, m)| checks::refuse(item, m))?;
    let gom = gom::gom_model(r, mesh, loads, &mut notes);
    let cps = cps::cps_file(
        case,
        cps::CpsValues {
            interval,
            load_steps,
            gravity_load,
            solid_traction,
            smoothing: smooths(case),
            probes: &probes,
            prescribed_velocity,
            k0_surface: case
                .start
                .initial_stress
                .as_ref()
                .and_then(|i| i.k0.as_ref())
                .map(|k| k.surface_point[1]),
        },
    );
    Ok(Anura3dCase {
        gom,
        cps,
        pvf,
        notes,
    })
}

/// Whether the CPS switches `STRAIN_SMOOTHING` on: when the scene asks for Anura3D's strain
/// smoothing, or when it smooths pore pressures and has some (for a dry case without
/// `strain_smoothing` Anura3D's smoothing would act on the solid strain, which the scene does
/// not smooth).
fn smooths(case: &crate::input::case::Case) -> bool {
    case.numerics.strain_smoothing || (case.numerics.smooth_pressure && case.has_liquid())
}
