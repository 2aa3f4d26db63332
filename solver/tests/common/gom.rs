//! Anura3D inputs written by the tests themselves: a box of `tetrahedral_old` elements (ten
//! nodes, computed as four-node ones, Anura3D's 3D element) or a rectangle of 3-node triangles
//! (a plane-strain or axisymmetric section) with materials, fixities, material points and
//! extra GOM sections, and a CPS with the keys a test sets.

use std::path::{Path, PathBuf};

use mpm_shared::model::{Body, Refs, Section, Table, Token};
use mpm_shared::{generate, ElementType, Model};

/// A linear-elastic material of a generated GOM, dry or saturated.
pub struct Material {
    /// `$$MATERIAL_NAME`.
    pub name: &'static str,
    /// `$$POROSITY_SOLID`.
    pub porosity: f64,
    /// `$$DENSITY_SOLID` (kg/m³).
    pub density: f64,
    /// `$$YOUNG_MODULUS` (kPa).
    pub young: f64,
    /// Saturated with water (`saturated_material_coupled`: density 1000 kg/m³, intrinsic
    /// permeability 1e-9 m², bulk modulus 2e4 kPa, dynamic viscosity 1e-6 kPa s); the
    /// liquid takes the solid's fixities.
    pub saturated: bool,
}

impl Material {
    /// The material's keys in Anura3D's order, from `$$MATERIAL_TYPE` to `$$POISSON_RATIO`.
    fn keys(&self) -> Vec<(&'static str, String)> {
        let kind = if self.saturated {
            "saturated_material_coupled"
        } else {
            "dry_material"
        };
        let mut keys = vec![
            ("MATERIAL_TYPE", kind.to_string()),
            ("POROSITY_SOLID", self.porosity.to_string()),
            ("DENSITY_SOLID", self.density.to_string()),
        ];
        if self.saturated {
            keys.extend([
                ("DENSITY_LIQUID", "1000".to_string()),
                ("INTRINSIC_PERMEABILITY_LIQUID", "1e-9".to_string()),
                ("BULK_MODULUS_LIQUID", "20000".to_string()),
                ("DYNAMIC_VISCOSITY_LIQUID", "1e-6".to_string()),
            ]);
        }
        keys.extend([
            ("K0_VALUE_SOLID", "0.5".to_string()),
            ("MATERIAL_MODEL_SOLID", "linear_elasticity".to_string()),
            ("YOUNG_MODULUS", self.young.to_string()),
            ("POISSON_RATIO", "0.3".to_string()),
        ]);
        keys
    }
}

/// A box of `cells` cells of six `tetrahedral_old` elements, `size` metres: element e takes
/// material `material(centre of e)` (1-based index into `materials`, 0 for empty; 4 points per
/// filled element), node n the fixities `fixed(position of n)`.
pub fn box_model(
    cells: [usize; 3],
    size: [f64; 3],
    materials: &[Material],
    material: impl Fn([f64; 3]) -> i64,
    fixed: impl Fn([f64; 3]) -> [bool; 3],
) -> Model {
    let base = generate::box_mesh(cells, size, ElementType::Tet10);
    with_materials(base, 4, "SURFACE", materials, material, fixed)
}

/// A rectangle of `cells` cells of two 3-node triangles, `size` metres, in plane strain or (x
/// the radius) an axisymmetric section: element e takes material `material(centre of e)`
/// (1-based index into `materials`, 0 for empty; 3 points per filled element), node n the
/// fixities `fixed(position of n)` (x and y; z is 0 in 2D).
pub fn rect_model(
    cells: [usize; 2],
    size: [f64; 2],
    axisymmetric: bool,
    materials: &[Material],
    material: impl Fn([f64; 3]) -> i64,
    fixed: impl Fn([f64; 3]) -> [bool; 2],
) -> Model {
    let mut base = generate::rect_mesh(cells, size);
    if axisymmetric {
        base.dimension = mpm_shared::Dimension::Axisymmetric;
    }
    with_materials(base, 3, "LINE", materials, material, |p| {
        let f = fixed(p);
        [f[0], f[1], false]
    })
}

/// `base` with `materials`, element e of material `material(centre of e)` holding `points`
/// points when filled, and the fixities `fixed(position of n)` of its first
/// `base.dimension.coords()` components in `$$START_FIXITY_{kind}_SOLID`.
fn with_materials(
    base: Model,
    points: i64,
    kind: &str,
    materials: &[Material],
    material: impl Fn([f64; 3]) -> i64,
    fixed: impl Fn([f64; 3]) -> [bool; 3],
) -> Model {
    let dim = base.dimension.coords();
    let element_material: Vec<i64> = (0..base.element_count())
        .map(|e| {
            let mut c = [0.0; 3];
            let nodes = base.element(e);
            for &n in nodes {
                for (a, v) in c.iter_mut().enumerate().take(dim) {
                    *v += base.node(n as usize)[a] / nodes.len() as f64;
                }
            }
            material(c)
        })
        .collect();
    let names: Vec<String> = materials.iter().map(|m| m.name.to_string()).collect();
    let mut model = Model::from_mesh(
        base.dimension,
        base.element_type,
        base.coords.clone(),
        base.connectivity.clone(),
        &names,
        &element_material,
    );
    for (m, mat) in materials.iter().enumerate() {
        let at = model
            .sections
            .iter()
            .position(|s| {
                s.keyword == "MATERIAL_INDEX"
                    && matches!(&s.body, Body::Text(l) if l[0] == (m + 1).to_string())
            })
            .unwrap()
            + 2;
        for (k, v) in mat.keys().into_iter().rev() {
            model.sections.insert(
                at,
                Section {
                    keyword: k.into(),
                    body: Body::Text(vec![v]),
                },
            );
        }
    }
    let mut fixities = Table::new();
    for n in 0..base.node_count() {
        let p = base.node(n);
        let mut at = [0.0; 3];
        at[..dim].copy_from_slice(&p[..dim]);
        let f = fixed(at);
        if f.iter().any(|&b| b) {
            fixities.push_row(
                std::iter::once(Token::Int(n as i64 + 1))
                    .chain(f[..dim].iter().map(|&b| Token::Int(i64::from(b)))),
            );
        }
    }
    let phases: &[&str] = if materials.iter().any(|m| m.saturated) {
        &["SOLID", "LIQUID"]
    } else {
        &["SOLID"]
    };
    for phase in phases {
        let section = format!("START_FIXITY_{kind}_{phase}");
        let fix = model
            .sections
            .iter_mut()
            .find(|s| s.keyword == section)
            .unwrap();
        fix.body = Body::Table {
            counted: true,
            refs: Refs::Nodes(1),
            rows: fixities.clone(),
        };
    }
    let mut rows = Table::new();
    for &m in &element_material {
        rows.push_row([Token::Int(if m > 0 { points } else { 0 }), Token::Int(0)]);
    }
    model.sections.push(Section {
        keyword: "START_NUMBER_OF_MATERIAL_POINTS".into(),
        body: Body::PerElement(rows),
    });
    model
}

/// The elements of `model` (1-based) of material `m`.
pub fn elements_of(model: &Model, m: i64) -> Vec<usize> {
    model
        .element_materials()
        .unwrap()
        .iter()
        .enumerate()
        .filter(|(_, &k)| k == m)
        .map(|(e, _)| e + 1)
        .collect()
}

/// The corner nodes (1-based) of the box `lo`..`hi` of `model`'s nodes: those at its corners
/// (a rectangle's in 2D, whose `lo` and `hi` z are not read).
pub fn box_corners(model: &Model, lo: [f64; 3], hi: [f64; 3]) -> Vec<usize> {
    let mut out = Vec::new();
    for n in 0..model.node_count() {
        let p = model.node(n);
        if (0..p.len()).all(|a| (p[a] - lo[a]).abs() < 1e-9 || (p[a] - hi[a]).abs() < 1e-9) {
            out.push(n + 1);
        }
    }
    assert_eq!(
        out.len(),
        1 << model.dimension.coords(),
        "a box's corners are nodes"
    );
    out
}

/// Writes `dir/NAME.GOM` (`model` with the GOM text `extra` before its materials) and
/// `dir/NAME.CPS_001`: Anura3D's defaults of the suite's cases (MPM-MIXED, Courant 0.9,
/// gravity, local damping 0.05, dynamic load steps), with the keys of `cps` (key without `$$`,
/// value line) replacing or added.
pub fn write(
    dir: &Path,
    name: &str,
    model: &Model,
    extra: &str,
    cps: &[(&str, &str)],
) -> (PathBuf, PathBuf) {
    let text = String::from_utf8(mpm_shared::gom::write(model)).unwrap();
    let text = text.replacen(
        "$$NUMBER_OF_MATERIALS",
        &format!("{extra}$$NUMBER_OF_MATERIALS"),
        1,
    );
    let gom = dir.join(format!("{name}.GOM"));
    std::fs::write(&gom, text).unwrap();
    let mut keys: Vec<(String, String)> = [
        ("NUMBER_OF_LOADSTEPS", "1"),
        ("TIME_PER_LOADSTEP", "1.0"),
        ("TOTAL_TIME", "0.0"),
        ("COURANT_NUMBER", "0.9"),
        ("COMPUTATION_METHOD", "MPM-MIXED"),
        ("GRAVITY_ACCELERATION", "9.81"),
        ("GRAVITY_VECTOR", "0.0 -1.0 0.0"),
        ("GRAVITY_LOAD", "step  1.0  1.0"),
        ("SOLID_TRACTION", "off  0.0  1.0"),
        ("LIQUID_PRESSURE", "off  0.0  1.0"),
        ("PRESCRIBED_VELOCITY", "step  1.0  1.0"),
        ("QUASISTATIC_CONVERGENCE", "0"),
        ("TOLERATED_ERROR_SOLID", "0.01 0.01"),
        ("TOLERATED_ERROR_LIQUID", "0.01 0.01"),
        ("MAXIMUM_TIME_STEPS", "1"),
        ("MASS_SCALING", "0 1.0"),
        ("HOMOGENEOUS_LOCAL_DAMPING", "1 0.05"),
        ("BULK_VISCOSITY_DAMPING", "0 0.06 1.2"),
        ("FIX_SOLID_SKELETON", "0"),
        ("STRAIN_SMOOTHING", "0"),
        ("CONTACT_FORMULATION", "0"),
        ("INITIAL_WATER_PRESSURE", "0.0"),
        ("APPLY_POROSITY_UPDATE", "0"),
        ("INITIAL_VELOCITY", "0"),
        ("RESET_DISPLACEMENTS", "0"),
        ("REMOVE_FIXITIES", "0 0 0"),
        ("EXCAVATION", "0"),
        ("SUBMERGED_CALCULATION", "0 1"),
        ("APPLY_OBJECTIVE_STRESS", "0"),
        ("DEGREE_OF_FILLING", "0.9"),
        ("NUMBER_OF_ACTIVE_ELEMENTS", "0"),
        ("OUTPUT_NUMBER_OF_MATERIAL_POINTS", "0"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    for &(k, v) in cps {
        match keys.iter_mut().find(|e| e.0 == k) {
            Some(e) => e.1 = v.to_string(),
            None => keys.push((k.to_string(), v.to_string())),
        }
    }
    let mut text = String::from("### Anura3D_2021 ###\n");
    for (k, v) in keys {
        text.push_str(&format!("$${k}\n{v}\n"));
    }
    text.push_str("$$END\n");
    let cps = dir.join(format!("{name}.CPS_001"));
    std::fs::write(&cps, text).unwrap();
    (gom, cps)
}

/// `$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME` for `elements` (1-based): the components
/// `flags` at `velocity` (two of each in 2D, three in 3D).
pub fn prescribed_section(elements: &[usize], flags: &[u8], velocity: &[f64]) -> String {
    let mut s = format!(
        "$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME\n{}\n",
        elements.len()
    );
    for e in elements {
        let words: Vec<String> = std::iter::once(e.to_string())
            .chain(flags.iter().map(u8::to_string))
            .chain(velocity.iter().map(f64::to_string))
            .collect();
        s.push_str(&words.join(" "));
        s.push('\n');
    }
    s
}
