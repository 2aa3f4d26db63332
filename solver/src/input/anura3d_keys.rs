//! What [`crate::input::anura3d::load`] does with each Anura3D input key: GOM sections, keys of GOM
//! material blocks and CPS keys. One table, [`KEYS`], one entry per key (or per family of keys,
//! with `*` standing for any text), each with a short reason; the compatibility matrix
//! (`solver/examples/anura3d_compat.rs`) prints it for every key the benchmark suite uses.
//!
//! The loader checks every key against this table before it builds a case
//! ([`check`]): a key that can change results and is not modelled stops the run unless it holds
//! its inert value, naming the key, its value and the file.

use std::fmt;

/// Where a key lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum KeyKind {
    /// A `$$SECTION` of the GOM file (outside material blocks).
    GomSection,
    /// A `$$KEY` inside a GOM material block (after `$$MATERIAL_INDEX`).
    MaterialKey,
    /// A `$$KEY` of the CPS file.
    CpsKey,
}

impl KeyKind {
    /// A short name for tables.
    pub fn label(self) -> &'static str {
        match self {
            KeyKind::GomSection => "GOM section",
            KeyKind::MaterialKey => "GOM material key",
            KeyKind::CpsKey => "CPS key",
        }
    }
}

/// What the loader does with a key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyStatus {
    /// Read and computed as Anura3D does (possibly refusing values outside what is modelled;
    /// the loader's error then names the value).
    Modelled,
    /// Not read, and cannot change the results of a case the loader accepts: why.
    Ignored(&'static str),
    /// Refused by the loader unless it holds the inert value: what is not modelled; the inert
    /// value.
    RefusedUnlessInert(&'static str),
    /// Always refused: why.
    Refused(&'static str),
    /// Not in [`KEYS`].
    Unknown,
}

impl fmt::Display for KeyStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KeyStatus::Modelled => write!(f, "modelled"),
            KeyStatus::Ignored(w) => write!(f, "ignored: {w}"),
            KeyStatus::RefusedUnlessInert(w) => write!(f, "refused unless inert: {w}"),
            KeyStatus::Refused(w) => write!(f, "refused: {w}"),
            KeyStatus::Unknown => write!(f, "not in the key table"),
        }
    }
}

use KeyKind::{CpsKey, GomSection, MaterialKey};
use KeyStatus::{Ignored, Modelled, RefusedUnlessInert};

/// Every known key: kind, key (a `*` stands for any text), status with its reason. An exact key
/// wins over a pattern; among patterns the first match wins.
pub const KEYS: &[(KeyKind, &str, KeyStatus)] = &[
    // --- GOM: geometry.
    (GomSection, "DIMENSION", Modelled), // 3D; 2D meshes are refused (ELEMENTTYPE)
    (GomSection, "ELEMENTTYPE", Modelled), // tetrahedral_old, tetrahedral_4-noded; triangles refused
    (GomSection, "STARTCOUNTERS", Modelled),
    (GomSection, "STARTNODES", Modelled),
    (GomSection, "STARTELEMCON", Modelled),
    (GomSection, "STARTELMMAT", Modelled),
    (GomSection, "START_NUMBER_OF_MATERIAL_POINTS", Modelled), // first column: solid points
    // Written by sfcb: each element's number in the original input; point ids and messages
    // follow it. Anura3D skips it.
    (GomSection, "START_INPUT_ELEMENT_NUMBERS", Modelled),
    (
        GomSection,
        "FORMULATION",
        RefusedUnlessInert("double-point (separate liquid material points) is not modelled; inert: single-point"),
    ),
    (
        GomSection,
        "NUMBER_OF_MATERIALS",
        Ignored("a count; the material blocks are read themselves"),
    ),
    (
        GomSection,
        "STARTDAMPING",
        RefusedUnlessInert("per-element local damping (values > 0 switch it on); inert: all 0"),
    ),
    // --- GOM: boundary conditions and loads.
    (GomSection, "START_FIXITY_*_SOLID", Modelled),
    (GomSection, "START_FIXITY_*_LIQUID", Modelled),
    (
        GomSection,
        "START_FIXITY_*_GAS",
        RefusedUnlessInert("gas-phase fixities; inert: an empty list"),
    ),
    (
        GomSection,
        "START_REMOVE_FIXITY_*",
        RefusedUnlessInert("removing fixities during the calculation; inert: an empty list"),
    ),
    (GomSection, "START_LOAD_ON_NODES_SOLID", Modelled),
    (GomSection, "START_LOAD_ON_NODES_LIQUID", Modelled),
    (GomSection, "START_LOAD_ON_MATERIAL_POINTS_SOLID", Modelled),
    (
        GomSection,
        "START_LOAD_ON_*",
        RefusedUnlessInert("other load systems (liquid on material points, gas, system B); inert: an empty list"),
    ),
    // Velocities prescribed on the points of listed elements (with CPS $$PRESCRIBED_VELOCITY).
    (
        GomSection,
        "PRESCRIBED_MATERIAL_POINT_VELOCITY_*",
        Modelled,
    ),
    // Velocities prescribed on listed nodes (with CPS $$PRESCRIBED_VELOCITY).
    (GomSection, "PRESCRIBED_NODAL_VELOCITY_VOLUME", Modelled),
    (GomSection, "PRESCRIBED_NODAL_VELOCITY_SURFACE", Modelled),
    (GomSection, "PRESCRIBED_NODAL_VELOCITY_LINE", Modelled),
    (GomSection, "PRESCRIBED_NODAL_VELOCITY_POINT", Modelled),
    (
        GomSection,
        "PRESCRIBED_*",
        RefusedUnlessInert("other prescribed quantities; inert: an empty list"),
    ),
    (GomSection, "ABSORBING_BOUNDARY_REFERENCE_MATERIAL_INDEX", Modelled), // the dashpots' material
    (GomSection, "ABSORBING_BOUNDARY_*", Modelled), // solid and liquid; gas refused
    (
        GomSection,
        "INITIAL_VELOCITY_MATERIAL_POINT",
        RefusedUnlessInert("initial material-point velocities (with CPS $$INITIAL_VELOCITY 1); inert: an empty list"),
    ),
    // The structure of the contact algorithm (`step::contact`), read with CPS
    // $$CONTACT_FORMULATION 1, ignored otherwise: 3D models and 2D ones.
    (GomSection, "START_CONTACT_VOLUME", Modelled),
    (GomSection, "START_BODY_CONTACT_2D", Modelled),
    (
        GomSection,
        "START_BOUNDARY_CONTACT_2D",
        Ignored("Anura3D reads these rows but no computation uses them"),
    ),
    (
        GomSection,
        "START_EXCAVATION_SOLID",
        RefusedUnlessInert("excavation; inert: an empty list"),
    ),
    (
        GomSection,
        "START_OUTPUT_REACTION_FORCES",
        Ignored("output only: faces whose reaction forces Anura3D reports"),
    ),
    // --- GOM: initial state and hydraulics.
    (
        GomSection,
        "START_SOIL_SURFACE_NODES",
        Ignored("only used by the K0 procedure (CPS $$K0_PROCEDURE), which refuses a non-empty list"),
    ),
    (
        GomSection,
        "START_PHREATIC_SURFACE_NODES",
        Ignored("only used by the K0 procedure (CPS $$K0_PROCEDURE), which refuses a non-empty list"),
    ),
    (
        GomSection,
        "INITIAL_WATER_SURFACE_FROM_FILE",
        Ignored("only used by the K0 procedure (CPS $$K0_PROCEDURE), which refuses the section"),
    ),
    (
        GomSection,
        "BOUNDARY_SEEPAGE_AREA",
        Ignored("only used with CPS $$APPLY_SEEPAGE_FACE 1"),
    ),
    (
        GomSection,
        "BOUNDARY_INFILTRATION_AREA",
        Ignored("only used with CPS $$APPLY_INFILTRATION 1"),
    ),
    (
        GomSection,
        "INFILTRATION_RATE",
        Ignored("only used with CPS $$APPLY_INFILTRATION 1"),
    ),
    (
        GomSection,
        "BOUNDARY_HYDRAULIC_HEAD_AREA",
        Ignored("only used with CPS $$HYDRAULIC_HEAD"),
    ),
    // --- GOM: moving mesh (`step::moving_mesh`).
    (GomSection, "MOVING_MESH_CORNER_NODES", Modelled),
    (GomSection, "COMPRESSING_MESH_CORNER_NODES", Modelled),
    (GomSection, "EXTENDING_MESH_CORNER_NODES", Modelled),
    (GomSection, "MOVING_MESH_DIRECTION", Modelled),
    (GomSection, "MOVING_MESH_REFERENCE_MATERIAL_INDEX", Modelled),
    // --- GOM material blocks.
    (MaterialKey, "MATERIAL_INDEX", Modelled),
    (MaterialKey, "MATERIAL_NAME", Ignored("a label")),
    (MaterialKey, "MATERIAL_TYPE", Modelled), // dry, saturated coupled, drained, undrained total; others refused
    (MaterialKey, "MATERIAL_MODEL_SOLID", Modelled), // linear_elasticity, mohr_coulomb, strain_softening_mohr_coulomb; others refused
    (MaterialKey, "POROSITY_SOLID", Modelled),
    (MaterialKey, "DENSITY_SOLID", Modelled),
    (MaterialKey, "YOUNG_MODULUS", Modelled),
    (MaterialKey, "POISSON_RATIO", Modelled),
    (MaterialKey, "DENSITY_LIQUID", Modelled), // saturated materials; unused for dry ones
    (MaterialKey, "BULK_MODULUS_LIQUID", Modelled),
    (MaterialKey, "INTRINSIC_PERMEABILITY_LIQUID", Modelled),
    (MaterialKey, "DYNAMIC_VISCOSITY_LIQUID", Modelled),
    (MaterialKey, "K0_VALUE_SOLID", Modelled), // with CPS $$K0_PROCEDURE 1; in [0, 1]
    (
        MaterialKey,
        "MATERIAL_MODEL_LIQUID",
        Ignored("liquid law of the liquid-only material types, which are refused"),
    ),
    (
        MaterialKey,
        "POISSON_RATIO_UNDRAINED",
        Ignored("for undrained effective-stress materials, which are refused"),
    ),
    // Mohr-Coulomb (mohr_coulomb) and strain-softening Mohr-Coulomb parameters.
    (MaterialKey, "FRICTION_ANGLE", Modelled),
    (MaterialKey, "COHESION", Modelled),
    (MaterialKey, "DILATANCY_ANGLE", Modelled),
    (MaterialKey, "TENSILE_STRENGTH", Modelled),
    (MaterialKey, "PEAK_COHESION", Modelled),
    (MaterialKey, "RESIDUAL_COHESION", Modelled),
    (MaterialKey, "PEAK_FRICTION_ANGLE", Modelled),
    (MaterialKey, "RESIDUAL_FRICTION_ANGLE", Modelled),
    (MaterialKey, "PEAK_DILATANCY_ANGLE", Modelled),
    (MaterialKey, "RESIDUAL_DILATANCY_ANGLE", Modelled),
    (MaterialKey, "SHAPE_FACTOR", Modelled),
    // Modified Cam Clay (modified_cam_clay): Anura3D names the law but its reader takes no
    // parameters for it (they go to an external DLL), so these keys are this project's.
    (MaterialKey, "SHEAR_MODULUS", Modelled),
    (MaterialKey, "LAMBDA", Modelled),
    (MaterialKey, "KAPPA", Modelled),
    (MaterialKey, "CRITICAL_STATE_SLOPE", Modelled),
    (MaterialKey, "INITIAL_VOID_RATIO", Modelled),
    (MaterialKey, "NCL_INTERCEPT", Modelled),
    (MaterialKey, "OCR", Modelled),
    (MaterialKey, "PRECONSOLIDATION_PRESSURE", Modelled),
    (MaterialKey, "MINIMUM_PRESSURE", Modelled),
    (MaterialKey, "MAXIMUM_PRESSURE", Modelled),
    // Hypoplasticity (hypoplasticity): as for Modified Cam Clay, Anura3D's reader takes no
    // parameters for it, so these keys are this project's.
    (MaterialKey, "CRITICAL_FRICTION_ANGLE", Modelled),
    (MaterialKey, "GRANULAR_HARDNESS", Modelled),
    (MaterialKey, "EXPONENT_N", Modelled),
    (MaterialKey, "MINIMUM_VOID_RATIO", Modelled),
    (MaterialKey, "CRITICAL_VOID_RATIO", Modelled),
    (MaterialKey, "MAXIMUM_VOID_RATIO", Modelled),
    (MaterialKey, "EXPONENT_ALPHA", Modelled),
    (MaterialKey, "EXPONENT_BETA", Modelled),
    (MaterialKey, "IGS_R", Modelled),
    (MaterialKey, "IGS_MR", Modelled),
    (MaterialKey, "IGS_MT", Modelled),
    (MaterialKey, "IGS_BETA_R", Modelled),
    (MaterialKey, "IGS_CHI", Modelled),
    (MaterialKey, "IGS_INITIAL", Modelled),
    (MaterialKey, "INTEGRATION_TOLERANCE", Modelled),
    (
        MaterialKey,
        "MATERIAL_MODEL_DLL",
        Ignored("external soil model; only linear_elasticity, mohr_coulomb, strain_softening_mohr_coulomb, modified_cam_clay and hypoplasticity are accepted"),
    ),
    (
        MaterialKey,
        "UMAT_DIMENSION",
        Ignored("external soil model; only linear_elasticity, mohr_coulomb, strain_softening_mohr_coulomb, modified_cam_clay and hypoplasticity are accepted"),
    ),
    (
        MaterialKey,
        "MATERIAL_PARAMETER_SOLID_*",
        Ignored("external soil model parameters; only linear_elasticity, mohr_coulomb, strain_softening_mohr_coulomb, modified_cam_clay and hypoplasticity are accepted"),
    ),
    (
        MaterialKey,
        "INITIAL_STATE_VARIABLE_SOLID_*",
        Ignored("external soil model state; only linear_elasticity, mohr_coulomb, strain_softening_mohr_coulomb, modified_cam_clay and hypoplasticity are accepted"),
    ),
    (
        MaterialKey,
        "*_GAS",
        Ignored("gas phase of three-phase material types, which are refused"),
    ),
    (
        MaterialKey,
        "WATER_RETENTION_CURVE",
        Ignored("unsaturated material types, which are refused"),
    ),
    (
        MaterialKey,
        "HYDR_CONDUCTIVITY_CURVE",
        Ignored("unsaturated material types, which are refused"),
    ),
    (
        MaterialKey,
        "av",
        Ignored("retention/conductivity curve parameter of unsaturated types, which are refused"),
    ),
    (
        MaterialKey,
        "Smin",
        Ignored("retention curve parameter of unsaturated types, which are refused"),
    ),
    (
        MaterialKey,
        "Smax",
        Ignored("retention curve parameter of unsaturated types, which are refused"),
    ),
    (
        MaterialKey,
        "P0",
        Ignored("retention curve parameter of unsaturated types, which are refused"),
    ),
    (
        MaterialKey,
        "L",
        Ignored("retention curve parameter of unsaturated types, which are refused"),
    ),
    (
        MaterialKey,
        "lambda",
        Ignored("retention curve parameter of unsaturated types, which are refused"),
    ),
    (
        MaterialKey,
        "*_vg",
        Ignored("van Genuchten parameter of unsaturated types, which are refused"),
    ),
    // --- CPS: time, method, loads.
    (CpsKey, "NUMBER_OF_LOADSTEPS", Modelled),
    (CpsKey, "TIME_PER_LOADSTEP", Modelled),
    (CpsKey, "COURANT_NUMBER", Modelled),
    (CpsKey, "COMPUTATION_METHOD", Modelled), // MPM-MP, MPM-MIXED; FEM and UL-FEM refused
    (CpsKey, "DEGREE_OF_FILLING", Modelled),
    (CpsKey, "GRAVITY_ACCELERATION", Modelled),
    (CpsKey, "GRAVITY_VECTOR", Modelled),
    (CpsKey, "GRAVITY_LOAD", Modelled), // off, step, linear from 0; file refused
    (CpsKey, "SOLID_TRACTION", Modelled), // as GRAVITY_LOAD
    (CpsKey, "LIQUID_PRESSURE", Modelled), // as GRAVITY_LOAD
    (CpsKey, "HOMOGENEOUS_LOCAL_DAMPING", Modelled),
    (CpsKey, "BULK_VISCOSITY_DAMPING", Modelled), // a viscous pressure in the internal force
    (CpsKey, "APPLY_NODE_DATA_AB", Modelled), // absorbing boundaries from nodal or point data
    (CpsKey, "QUASISTATIC_CONVERGENCE", Modelled),
    (CpsKey, "TOLERATED_ERROR_SOLID", Modelled),
    (CpsKey, "MAXIMUM_TIME_STEPS", Modelled), // the quasi-static step limit
    (CpsKey, "APPLY_OBJECTIVE_STRESS", Modelled),
    (CpsKey, "STRAIN_SMOOTHING", Modelled), // volumetric strain smoothing of both phases
    (CpsKey, "OUTPUT_NUMBER_OF_MATERIAL_POINTS", Modelled), // output: probes
    (CpsKey, "OUTPUT_MATERIAL_POINTS", Modelled),           // output: probes
    // Written by sfcb --cps: the probes are ids in the ordered GOM's order (element count and
    // checksum of its input numbers); converted back to input ids. Anura3D skips it.
    (CpsKey, "OUTPUT_MATERIAL_POINTS_GOM_ORDER", Modelled),
    // The liquid's force tolerance; its kinetic-energy tolerance is not checked.
    (CpsKey, "TOLERATED_ERROR_LIQUID", Modelled),
    (
        CpsKey,
        "TOTAL_TIME",
        RefusedUnlessInert("time reached by earlier stages (staged calculations); inert: 0"),
    ),
    (
        CpsKey,
        "SOLID_TRACTION_B",
        Ignored("multiplies load system B, whose sections are refused unless empty"),
    ),
    (
        CpsKey,
        "LIQUID_PRESSURE_B",
        Ignored("multiplies load system B, whose sections are refused unless empty"),
    ),
    (CpsKey, "PRESCRIBED_VELOCITY", Modelled), // multiplier of the prescribed velocities
    (
        CpsKey,
        "GAS_PRESSURE*",
        Ignored("gas loads, whose sections are refused unless empty"),
    ),
    // --- CPS: numerics not modelled.
    (
        CpsKey,
        "MASS_SCALING",
        Modelled, // mass scaling: accelerations over f m, the step √f longer (dry materials)
    ),
    (
        CpsKey,
        "APPLY_SMOOTHENING_LIQUID_PRESSURE_INCREMENT",
        RefusedUnlessInert("smoothing of liquid pressure increments; inert: 0"),
    ),
    (
        CpsKey,
        "FIX_SOLID_SKELETON",
        RefusedUnlessInert("solid points kept in place; inert: 0"),
    ),
    (
        CpsKey,
        "APPLY_POROSITY_UPDATE",
        RefusedUnlessInert("porosity updated with volumetric strain; inert: 0"),
    ),
    (
        CpsKey,
        "APPLY_MATERIAL_UPDATE",
        RefusedUnlessInert("material changes between stages; inert: 0"),
    ),
    // Contact between a structure and the soil (`step::contact`): 3D and 2D, dry.
    (CpsKey, "CONTACT_FORMULATION", Modelled),
    (
        CpsKey,
        "APPLY_CONTACT_MESH_BOUNDARY",
        RefusedUnlessInert("contact faces found on the mesh boundary; inert: 0"),
    ),
    (
        CpsKey,
        "APPLY_CONTACT_VELOCITY_SCALING",
        RefusedUnlessInert("a limit on the contact's velocity correction; inert: 0"),
    ),
    (
        CpsKey,
        "VELOCITY_SCALING_FACTOR",
        Ignored("only used with $$APPLY_CONTACT_VELOCITY_SCALING 1 (refused)"),
    ),
    (
        CpsKey,
        "APPLY_TRACTION_CONTACT",
        Ignored("Anura3D computes the nodal contact traction but never uses it"),
    ),
    (
        CpsKey,
        "MONOPILE_SLICE_CONTACT",
        Ignored("only used for the rotated boundaries of 3D cylindrical models (refused)"),
    ),
    (
        CpsKey,
        "APPLY_CONTACT_NORMAL_CORRECTION",
        RefusedUnlessInert("2D contact normals set by hand; inert: 0"),
    ),
    (
        CpsKey,
        "NUMBER_OF_CORRECTED_NORMALS",
        Ignored("only used with $$APPLY_CONTACT_NORMAL_CORRECTION 1 (refused)"),
    ),
    (
        CpsKey,
        "NODE_NORMAL_DATA",
        Ignored("only used with $$APPLY_CONTACT_NORMAL_CORRECTION 1 (refused)"),
    ),
    (
        CpsKey,
        "SUBMERGED_CALCULATION",
        RefusedUnlessInert("submerged (buoyant) weight; inert: first value 0"),
    ),
    (
        CpsKey,
        "RESET_DISPLACEMENTS",
        RefusedUnlessInert("displacements reset to zero at the start; inert: 0"),
    ),
    // --- CPS: initial state and hydraulics.
    // K0 stresses (and pore pressures) below the horizontal line at $$SURFACE_ELEVATION.
    (CpsKey, "K0_PROCEDURE", Modelled),
    (
        CpsKey,
        "INITIAL_WATER_PRESSURE",
        RefusedUnlessInert("initial pore pressure of every saturated point; inert: 0"),
    ),
    (
        CpsKey,
        "INITIAL_VELOCITY",
        RefusedUnlessInert("initial material-point velocities from the GOM; inert: 0"),
    ),
    (
        CpsKey,
        "MP_STRESS_INITIALIZATION_FROMFILE",
        RefusedUnlessInert("initial stresses read from a file; inert: 0"),
    ),
    (
        CpsKey,
        "APPLY_SEEPAGE_FACE",
        RefusedUnlessInert("seepage face boundary; inert: 0"),
    ),
    (
        CpsKey,
        "APPLY_INFILTRATION",
        RefusedUnlessInert("infiltration boundary; inert: 0"),
    ),
    (
        CpsKey,
        "HYDRAULIC_HEAD",
        RefusedUnlessInert("prescribed hydraulic head; inert: off"),
    ),
    // The K0 procedure's settings (read only when it is on).
    (CpsKey, "K0_MAX_SUCTION", Modelled),
    (CpsKey, "INITIAL_VERTICAL_LOAD_K0", Modelled), // times SOLID_TRACTION's first value
    (CpsKey, "CONSIDERED_LOAD_K0", Modelled),       // the same load; the last one read wins
    (CpsKey, "SURFACE_ELEVATION", Modelled),        // first number: the surface's y
    (CpsKey, "NUMBER_SOIL_LAYERS", Modelled), // with the K0 procedure: more than 1 refused
    (
        CpsKey,
        "THICKNESS_SOIL_LAYERS",
        Ignored("only read with $$NUMBER_SOIL_LAYERS above 1, which the K0 procedure refuses"),
    ),
    (
        CpsKey,
        "LIQUID_SURFACE",
        Ignored("only used by the double-point formulation's K0 procedure; double-point is refused"),
    ),
    // --- CPS: staging and output.
    (
        CpsKey,
        "EXCAVATION",
        Ignored("acts on $$START_EXCAVATION_SOLID elements, refused unless empty"),
    ),
    (
        CpsKey,
        "REMOVE_FIXITIES",
        Ignored("acts on $$START_REMOVE_FIXITY_* lists, refused unless empty"),
    ),
    (
        CpsKey,
        "NUMBER_OF_ACTIVE_ELEMENTS",
        Ignored("Anura3D reads it only when continuing a stage; a first stage starts from 0"),
    ),
    (
        CpsKey,
        "STAGE",
        Ignored("selects the stage's files; the matrix and the CLI name them"),
    ),
    (
        CpsKey,
        "VISUALIZATION_OPTION",
        Ignored("output format"),
    ),
    (
        CpsKey,
        "OUTPUT_NUMBER_OF_NODES",
        Ignored("output only: nodes Anura3D reports"),
    ),
    (CpsKey, "OUTPUT_NODES", Ignored("output only: nodes Anura3D reports")),
    (CpsKey, "NUMBER_OF_THREADS", Ignored("parallelism, not results")),
];

/// Whether `key` matches the table entry `pattern` (`*` stands for any text, at most once).
fn matches(pattern: &str, key: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == key,
        Some((head, tail)) => {
            key.len() >= head.len() + tail.len() && key.starts_with(head) && key.ends_with(tail)
        }
    }
}

/// The table entry for `key` of `kind`: its key or pattern and its status.
pub fn lookup(kind: KeyKind, key: &str) -> Option<(&'static str, KeyStatus)> {
    let of_kind = || KEYS.iter().filter(move |e| e.0 == kind);
    of_kind()
        .find(|e| e.1 == key)
        .or_else(|| of_kind().find(|e| e.1.contains('*') && matches(e.1, key)))
        .map(|e| (e.1, e.2))
}

/// Whether `lines` (a CPS key's value lines, or a GOM section's text lines) hold the inert value
/// of a key refused unless inert: an empty list (nothing, or a count of 0), a first word that
/// is 0 (`0`, `0.0`: a switch that is off), `off`, or the single-point formulation.
pub fn is_inert(lines: &[String]) -> bool {
    let words: Vec<&str> = lines.iter().flat_map(|l| l.split_whitespace()).collect();
    match words.first() {
        None => true,
        Some(&w) => {
            w.parse::<f64>().is_ok_and(|v| v == 0.0)
                || w.eq_ignore_ascii_case("off")
                || w.eq_ignore_ascii_case("single-point")
        }
    }
}

/// Why a key stops a case.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}: $${key} = {value:?}{at}: {what}")]
pub struct Refusal {
    /// The file holding the key.
    pub file: String,
    /// The key or section.
    pub key: String,
    /// Its value (first line), as written.
    pub value: String,
    /// `" (line N)"` when the line is known.
    pub at: String,
    /// What is not modelled, and the value that would be accepted.
    pub what: String,
}

impl Refusal {
    /// The refusal with its line set (when `line` > 0 and none was known).
    pub fn at_line(mut self, line: usize) -> Self {
        if line > 0 && self.at.is_empty() {
            self.at = format!(" (line {line})");
        }
        self
    }
}

/// Checks `key` of `kind` with its value `lines` (line `line` of `file`, 0 when unknown)
/// against the table: a refused key, or one refused unless inert holding another value, is a
/// [`Refusal`]. Unknown keys pass (the caller warns).
pub fn check(
    kind: KeyKind,
    key: &str,
    lines: &[String],
    file: &str,
    line: usize,
) -> Result<(), Refusal> {
    let what = match status(kind, key) {
        KeyStatus::Refused(w) => w,
        KeyStatus::RefusedUnlessInert(w) if !is_inert(lines) => w,
        _ => return Ok(()),
    };
    Err(Refusal {
        file: file.to_string(),
        key: key.to_string(),
        value: lines
            .first()
            .map_or(String::new(), |l| l.trim().to_string()),
        at: if line > 0 {
            format!(" (line {line})")
        } else {
            String::new()
        },
        what: format!("not modelled ({what})"),
    })
}

/// What the loader does with `key` of `kind` ([`KeyStatus::Unknown`] when not in [`KEYS`]).
pub fn status(kind: KeyKind, key: &str) -> KeyStatus {
    lookup(kind, key).map_or(KeyStatus::Unknown, |e| e.1)
}

/// Where [`markdown`] is written in the repository, relative to its root.
pub const DOC_PATH: &str = "docs/anura3d-keys.md";

/// The key table as Markdown, one table per [`KeyKind`] in [`KEYS`]' order: key, status and
/// reason (a refused-unless-inert key's inert value in its status). `docs/anura3d-keys.md` is
/// this text; a test keeps the two equal.
pub fn markdown() -> String {
    // Table cells may not hold a bare `|`.
    let cell = |s: &str| s.replace('|', "\\|");
    let mut out = String::from(
        "# Anura3D keys\n\n\
         <!-- Generated from solver/src/input/anura3d_keys.rs (KEYS) by anura3d_keys::markdown(); do not \
         edit. Regenerate: UPDATE_DOCS=1 cargo test -p mpm-solve --test keys -->\n\n\
         What `mpm-solve` does with each key of an Anura3D case: **modelled** (computed as \
         Anura3D does), **ignored** (cannot change the results of a case the loader accepts), \
         **refused unless inert** (the run stops before the first step, naming the key, its value, \
         the file and, for CPS keys, the line, unless the key holds its inert value, shown in \
         brackets) or **refused**. A `*` stands for any text; an exact key wins over a pattern, \
         and among patterns the first listed wins. GOM sections and CPS keys not listed are \
         named in a warning and ignored.\n",
    );
    for kind in [KeyKind::GomSection, KeyKind::MaterialKey, KeyKind::CpsKey] {
        out += &format!(
            "\n## {}s\n\n| Key | Status | Reason |\n|---|---|---|\n",
            kind.label()
        );
        for (_, key, status) in KEYS.iter().filter(|e| e.0 == kind) {
            let (status, reason) = match *status {
                KeyStatus::Modelled => ("modelled".to_string(), ""),
                KeyStatus::Ignored(why) => ("ignored".to_string(), why),
                KeyStatus::RefusedUnlessInert(what) => match what.rsplit_once("; inert: ") {
                    Some((what, inert)) => (format!("refused unless inert ({inert})"), what),
                    None => ("refused unless inert".to_string(), what),
                },
                KeyStatus::Refused(why) => ("refused".to_string(), why),
                KeyStatus::Unknown => ("unknown".to_string(), ""),
            };
            out += &format!("| `$${key}` | {} | {} |\n", cell(&status), cell(reason));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_keys_win_over_patterns() {
        assert_eq!(
            status(GomSection, "START_LOAD_ON_NODES_SOLID"),
            KeyStatus::Modelled
        );
        assert!(matches!(
            status(GomSection, "START_LOAD_ON_MATERIAL_POINTS_LIQUID"),
            KeyStatus::RefusedUnlessInert(_)
        ));
        assert_eq!(
            status(GomSection, "START_FIXITY_SURFACE_SOLID"),
            KeyStatus::Modelled
        );
        assert!(matches!(
            status(GomSection, "START_FIXITY_LINE_GAS"),
            KeyStatus::RefusedUnlessInert(_)
        ));
        assert_eq!(
            status(GomSection, "ABSORBING_BOUNDARY_REFERENCE_MATERIAL_INDEX"),
            KeyStatus::Modelled
        );
        assert_eq!(
            lookup(MaterialKey, "MATERIAL_PARAMETER_SOLID_07").map(|e| e.0),
            Some("MATERIAL_PARAMETER_SOLID_*")
        );
        assert_eq!(status(CpsKey, "NO_SUCH_KEY"), KeyStatus::Unknown);
        // Kinds are separate name spaces.
        assert_eq!(status(GomSection, "COURANT_NUMBER"), KeyStatus::Unknown);
    }

    #[test]
    fn markdown_has_a_row_per_entry_under_its_kind() {
        let md = markdown();
        let rows = md.lines().filter(|l| l.starts_with("| `$$")).count();
        assert_eq!(rows, KEYS.len());
        let gom = md.find("## GOM sections").unwrap();
        let material = md.find("## GOM material keys").unwrap();
        let cps = md.find("## CPS keys").unwrap();
        assert!(gom < material && material < cps);
        let formulation = md
            .find("| `$$FORMULATION` | refused unless inert (single-point) | double-point")
            .unwrap();
        assert!(gom < formulation && formulation < material);
        let total_time = md
            .find("| `$$TOTAL_TIME` | refused unless inert (0) |")
            .unwrap();
        assert!(total_time > cps);
        assert!(md.contains("| `$$MATERIAL_NAME` | ignored | a label |\n"));
    }

    #[test]
    fn the_table_has_one_entry_per_key() {
        for (i, a) in KEYS.iter().enumerate() {
            assert!(a.1.matches('*').count() <= 1, "{}", a.1);
            for b in &KEYS[..i] {
                assert!(!(a.0 == b.0 && a.1 == b.1), "{} twice", a.1);
            }
        }
    }

    #[test]
    fn every_key_the_loader_reads_is_modelled() {
        for k in [
            "NUMBER_OF_LOADSTEPS",
            "TIME_PER_LOADSTEP",
            "COURANT_NUMBER",
            "COMPUTATION_METHOD",
            "DEGREE_OF_FILLING",
            "GRAVITY_ACCELERATION",
            "GRAVITY_VECTOR",
            "GRAVITY_LOAD",
            "SOLID_TRACTION",
            "LIQUID_PRESSURE",
            "HOMOGENEOUS_LOCAL_DAMPING",
            "BULK_VISCOSITY_DAMPING",
            "MAXIMUM_TIME_STEPS",
            "QUASISTATIC_CONVERGENCE",
            "TOLERATED_ERROR_SOLID",
            "APPLY_OBJECTIVE_STRESS",
            "STRAIN_SMOOTHING",
        ] {
            assert_eq!(status(CpsKey, k), KeyStatus::Modelled, "{k}");
        }
        for k in [
            "MATERIAL_TYPE",
            "MATERIAL_MODEL_SOLID",
            "POROSITY_SOLID",
            "DENSITY_SOLID",
            "YOUNG_MODULUS",
            "POISSON_RATIO",
            "DENSITY_LIQUID",
            "BULK_MODULUS_LIQUID",
            "INTRINSIC_PERMEABILITY_LIQUID",
            "DYNAMIC_VISCOSITY_LIQUID",
        ]
        .into_iter()
        .chain(
            crate::material::law::KNOWN
                .iter()
                .flat_map(|&l| crate::material::law::keys(l).unwrap_or(&[]).iter().copied()),
        ) {
            assert_eq!(status(MaterialKey, k), KeyStatus::Modelled, "{k}");
        }
    }
}
