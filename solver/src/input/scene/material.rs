//! `[[material]]` and `[material.liquid]`: what fills each material group of the mesh, with
//! its law's parameters read generically (any key of a law of the registry,
//! [`crate::material::law::keys`], in lower case), so that a law added there needs no change
//! here.

use std::fmt;
use std::sync::OnceLock;

use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;

use mpm_shared::Model;

use super::keys::{key, scene_key, Table};
use super::mesh::Mesh;
use super::{refuse, Refusal};
use crate::input::case::MaterialSpec;
use crate::material::law::{self, LawSpec};
use crate::material::liquid::LiquidSpec;

/// The keys of `[[material]]` (its law's parameters are listed per law from the registry).
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[[material]]",
    about: "What fills a material group of the mesh (a physical volume in 3D, a physical \
            surface in 2D); every group with elements needs one.",
    keys: &[
        key("physical", "string", "required", "", "the material group it fills (also the material's name)"),
        key("density", "float", "required", "kg/m³", "density of the material when dry, of its grains when saturated"),
        key("young", "float", "required where the law takes it", "kPa", "Young's modulus"),
        key("poisson", "float", "required where the law takes it", "", "Poisson's ratio"),
        key("law", "string", "\"linear_elasticity\"", "", "the constitutive law by Anura3D's name; its parameters are listed below"),
        key("points_per_element", "integer", "4 (tetrahedra), 3 (triangles)", "", "material points per element"),
        key("liquid", "table", "none (dry)", "", "the pore liquid of a saturated material: `[material.liquid]`"),
        key("k0", "float", "none", "", "K0 of Anura3D's K0 procedure: the points start from its stresses (gravity along -y)"),
        key("initial_stress", "[float × 6]", "none", "kPa", "a uniform initial effective stress, xx yy zz xy yz zx (tension positive)"),
    ],
};

/// The keys of `[material.liquid]`.
#[rustfmt::skip]
pub(super) const LIQUID_TABLE: Table = Table {
    header: "[material.liquid]",
    about: "The pore liquid of a saturated material (Anura3D's coupled two-phase material); \
            the material's `density` is then that of its grains.",
    keys: &[
        key("porosity", "float", "required", "", "porosity n"),
        key("density", "float", "required", "kg/m³", "density of the liquid"),
        key("bulk_modulus", "float", "required", "kPa", "bulk modulus of the liquid"),
        key("intrinsic_permeability", "float", "required", "m²", "intrinsic permeability"),
        key("viscosity", "float", "required", "kPa·s", "dynamic viscosity of the liquid"),
        key("initial_pore_pressure", "float", "0", "kPa", "pore pressure at t = 0"),
    ],
};

/// A `[[material]]` entry as the scene gives it.
#[derive(Debug)]
pub(super) struct Material {
    physical: String,
    density: f64,
    young: Option<f64>,
    poisson: Option<f64>,
    /// The law by Anura3D's name (`crate::material::law::KNOWN`).
    law: String,
    /// The law parameters given (Anura3D's keys), in the order written.
    parameters: Vec<(&'static str, f64)>,
    /// Points per element; default 4 in tetrahedra, 3 in triangles.
    points_per_element: Option<u32>,
    liquid: Option<Liquid>,
    /// K0: the points start with Anura3D's K0 stresses.
    k0: Option<f64>,
    /// A uniform initial effective stress (kPa, tension positive; xx yy zz xy yz zx).
    initial_stress: Option<[f64; 6]>,
}

/// The pore liquid of a saturated material (`[material.liquid]`); `density` of the material is
/// then the grains' density ρs.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Liquid {
    porosity: f64,
    density: f64,
    bulk_modulus: f64,
    intrinsic_permeability: f64,
    viscosity: f64,
    #[serde(default)]
    initial_pore_pressure: f64,
}

/// The default of law parameter `key` (Anura3D's) of law `law` when the scene leaves it out:
/// the registry's ([`crate::material::definition::Parameter::default`]).
fn law_default(law: &str, key: &str) -> Option<f64> {
    law::parameter_list(law)?
        .iter()
        .find(|p| p.key == key)
        .and_then(|p| p.default)
}

/// The law parameters of every law of the registry other than the elastic constants (which
/// every law takes, as `young` and `poisson`): (scene key, Anura3D key), each once, law by law
/// in the registry's order.
fn law_parameters() -> &'static [(&'static str, &'static str)] {
    static PARAMETERS: OnceLock<Vec<(&'static str, &'static str)>> = OnceLock::new();
    PARAMETERS.get_or_init(|| {
        let mut out: Vec<(&'static str, &'static str)> = Vec::new();
        for name in law::KNOWN {
            for &k in law::keys(name).unwrap_or_default() {
                let elastic = matches!(k, "YOUNG_MODULUS" | "POISSON_RATIO");
                if !elastic && !out.iter().any(|p| p.1 == k) {
                    // Built once per process: the scene names live as long as the registry's.
                    out.push((Box::leak(scene_key(k).into_boxed_str()), k));
                }
            }
        }
        out
    })
}

/// The keys of `[[material]]` before the law parameters, and after them, in the order a
/// refused key's message lists them.
const KEYS_BEFORE: [&str; 5] = ["physical", "density", "young", "poisson", "law"];
const KEYS_AFTER: [&str; 4] = ["points_per_element", "liquid", "k0", "initial_stress"];

/// Every key `[[material]]` accepts: its own and every law's parameters.
pub(super) fn accepted_keys() -> &'static [&'static str] {
    static KEYS: OnceLock<Vec<&'static str>> = OnceLock::new();
    KEYS.get_or_init(|| {
        let parameters = law_parameters().iter().map(|p| p.0);
        KEYS_BEFORE
            .into_iter()
            .chain(parameters)
            .chain(KEYS_AFTER)
            .collect()
    })
}

/// A key of a `[[material]]` table: one of its own, or a law parameter (Anura3D's key).
enum MaterialKey {
    Own(&'static str),
    Parameter(&'static str),
}

impl<'de> Deserialize<'de> for MaterialKey {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_identifier(MaterialKeyVisitor)
    }
}

/// Sorts a key as it is read, so that the TOML reader points at a refused key's line.
struct MaterialKeyVisitor;

impl Visitor<'_> for MaterialKeyVisitor {
    type Value = MaterialKey;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("field identifier")
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<MaterialKey, E> {
        if let Some(k) = KEYS_BEFORE.iter().chain(&KEYS_AFTER).find(|k| **k == v) {
            return Ok(MaterialKey::Own(k));
        }
        match law_parameters().iter().find(|p| p.0 == v) {
            Some(p) => Ok(MaterialKey::Parameter(p.1)),
            None => Err(E::unknown_field(v, accepted_keys())),
        }
    }
}

impl<'de> Deserialize<'de> for Material {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_struct("Material", accepted_keys(), MaterialVisitor)
    }
}

/// Reads a `[[material]]` table as serde's derived reader would (same messages: unknown,
/// duplicate and missing keys), with the law parameters collected by key.
struct MaterialVisitor;

/// Reads the value of key `name` into `slot`, refusing a second one.
fn once<'de, A: MapAccess<'de>, T: Deserialize<'de>>(
    map: &mut A,
    slot: &mut Option<T>,
    name: &'static str,
) -> Result<(), A::Error> {
    if slot.is_some() {
        return Err(de::Error::duplicate_field(name));
    }
    *slot = Some(map.next_value()?);
    Ok(())
}

impl<'de> Visitor<'de> for MaterialVisitor {
    type Value = Material;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("struct Material")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Material, A::Error> {
        let (mut physical, mut density, mut young, mut poisson) = (None, None, None, None);
        let (mut law, mut points, mut liquid) = (None, None, None);
        let (mut k0, mut initial_stress) = (None, None);
        let mut parameters: Vec<(&'static str, f64)> = Vec::new();
        while let Some(k) = map.next_key::<MaterialKey>()? {
            match k {
                MaterialKey::Own(name @ "physical") => once(&mut map, &mut physical, name)?,
                MaterialKey::Own(name @ "density") => once(&mut map, &mut density, name)?,
                MaterialKey::Own(name @ "young") => once(&mut map, &mut young, name)?,
                MaterialKey::Own(name @ "poisson") => once(&mut map, &mut poisson, name)?,
                MaterialKey::Own(name @ "law") => once(&mut map, &mut law, name)?,
                MaterialKey::Own(name @ "points_per_element") => once(&mut map, &mut points, name)?,
                MaterialKey::Own(name @ "liquid") => once(&mut map, &mut liquid, name)?,
                MaterialKey::Own(name @ "k0") => once(&mut map, &mut k0, name)?,
                // The last of KEYS_AFTER.
                MaterialKey::Own(name) => once(&mut map, &mut initial_stress, name)?,
                MaterialKey::Parameter(k) => {
                    if parameters.iter().any(|p| p.0 == k) {
                        return Err(de::Error::duplicate_field(
                            law_parameters()
                                .iter()
                                .find(|p| p.1 == k)
                                .map_or(k, |p| p.0),
                        ));
                    }
                    if let Some(v) = map.next_value::<Option<f64>>()? {
                        parameters.push((k, v));
                    }
                }
            }
        }
        let need = |name: &'static str| de::Error::missing_field(name);
        Ok(Material {
            physical: physical.ok_or_else(|| need("physical"))?,
            density: density.ok_or_else(|| need("density"))?,
            young,
            poisson,
            law: law.unwrap_or_else(|| "linear_elasticity".into()),
            parameters,
            points_per_element: points.unwrap_or_default(),
            liquid: liquid.unwrap_or_default(),
            k0: k0.unwrap_or_default(),
            initial_stress: initial_stress.unwrap_or_default(),
        })
    }
}

impl Material {
    /// The value the scene gives law parameter `key` (Anura3D's), if any.
    fn given(&self, key: &str) -> Option<f64> {
        match key {
            "YOUNG_MODULUS" => self.young,
            "POISSON_RATIO" => self.poisson,
            k => self.parameters.iter().find(|p| p.0 == k).map(|p| p.1),
        }
    }

    /// The law with its parameters: each given key must belong to the law, each key of the law
    /// must be given or have a default ([`law_default`]).
    fn law(&self) -> Result<LawSpec, String> {
        let keys = law::keys(&self.law).ok_or_else(|| {
            format!(
                "law {:?} is not known (known: {})",
                self.law,
                law::KNOWN.join(", ")
            )
        })?;
        let elastic = [("young", "YOUNG_MODULUS"), ("poisson", "POISSON_RATIO")];
        if let Some((name, _)) = law_parameters()
            .iter()
            .chain(&elastic)
            .find(|(_, k)| self.given(k).is_some() && !keys.contains(k))
        {
            return Err(format!(
                "{name} does not belong to law {} (its keys: {})",
                self.law,
                keys.iter()
                    .map(|k| scene_key(k))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        let get = |k: &str| self.given(k).or(law_default(&self.law, k));
        if let Some(k) = keys.iter().find(|k| get(k).is_none()) {
            return Err(format!("law {} needs {}", self.law, scene_key(k)));
        }
        LawSpec::by_name(&self.law, &get).map_err(|e| e.to_string())
    }

    /// The case's material: dry, or saturated with its liquid.
    fn spec(&self, law: LawSpec) -> Result<MaterialSpec, String> {
        match &self.liquid {
            None => MaterialSpec::with_law(&self.physical, self.density, law),
            Some(l) => LiquidSpec::new(
                l.porosity,
                l.density,
                l.bulk_modulus,
                l.intrinsic_permeability,
                l.viscosity,
            )
            .and_then(|liquid| {
                let mut s = MaterialSpec::saturated(&self.physical, self.density, law, liquid)?;
                s.initial_pore_pressure = l.initial_pore_pressure;
                Ok(s)
            }),
        }
        .map_err(|e| e.to_string())
    }

    /// The entry as [`Resolved`](super::Resolved) keeps it.
    fn input(&self, law: LawSpec, points_per_element: u32) -> MaterialInput {
        MaterialInput {
            physical: self.physical.clone(),
            density: self.density,
            young: self.young,
            poisson: self.poisson,
            law,
            points_per_element,
            liquid: self.liquid.as_ref().map(|l| LiquidInput {
                porosity: l.porosity,
                density: l.density,
                bulk_modulus: l.bulk_modulus,
                intrinsic_permeability: l.intrinsic_permeability,
                viscosity: l.viscosity,
                initial_pore_pressure: l.initial_pore_pressure,
            }),
            k0: self.k0,
            initial_stress: self.initial_stress,
        }
    }
}

/// A `[[material]]` entry as the scene gives it (densities in kg/m³, as written).
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialInput {
    /// The physical volume it fills (also the material's name).
    pub physical: String,
    /// Density (kg/m³): of the material when dry, of its grains when saturated.
    pub density: f64,
    /// Young's modulus (kPa), where the law takes it.
    pub young: Option<f64>,
    /// Poisson's ratio, where the law takes it.
    pub poisson: Option<f64>,
    /// The law with all its parameters (defaults filled in).
    pub law: LawSpec,
    /// Material points per element.
    pub points_per_element: u32,
    /// The pore liquid of a saturated material.
    pub liquid: Option<LiquidInput>,
    /// K0 of the K0 procedure, when the material starts from it.
    pub k0: Option<f64>,
    /// A uniform initial effective stress (kPa; xx yy zz xy yz zx).
    pub initial_stress: Option<[f64; 6]>,
}

/// A `[material.liquid]` entry as the scene gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct LiquidInput {
    /// Porosity n.
    pub porosity: f64,
    /// Liquid density (kg/m³).
    pub density: f64,
    /// Bulk modulus of the liquid (kPa).
    pub bulk_modulus: f64,
    /// Intrinsic permeability (m²).
    pub intrinsic_permeability: f64,
    /// Dynamic viscosity (kPa·s).
    pub viscosity: f64,
    /// Pore pressure at t = 0 (kPa).
    pub initial_pore_pressure: f64,
}

/// The scene's materials resolved against the mesh, by model material index (entry 0 unused).
pub(super) struct Materials {
    /// The case's materials.
    pub specs: Vec<Option<MaterialSpec>>,
    /// The entries as the scene gives them.
    pub inputs: Vec<Option<MaterialInput>>,
    /// Each element's material index.
    pub element_material: Vec<u32>,
    /// Each element's material points.
    pub points_per_element: Vec<u32>,
}

impl Materials {
    /// Whether some material is saturated.
    pub fn any_saturated(&self) -> bool {
        self.specs.iter().flatten().any(|m| m.liquid.is_some())
    }
}

/// Points per element when a material does not say: the 4-point rule of tetrahedra, the
/// 3-point rule of triangles (Anura3D's usual choices).
fn default_points(model: &Model) -> u32 {
    if model.dimension.coords() == 2 {
        3
    } else {
        4
    }
}

/// The `[[material]]` entries against the mesh's material groups: each entry must name one,
/// each group with elements must have an entry.
pub(super) fn resolve(entries: &[Material], mesh: &Mesh) -> Result<Materials, Refusal> {
    let names = &mesh.volumes;
    let mut specs = vec![None; names.len() + 1];
    let mut inputs = vec![None; names.len() + 1];
    let mut points = vec![0u32; names.len() + 1];
    for m in entries {
        let item = format!("material \"{}\"", m.physical);
        let k = names.iter().position(|n| *n == m.physical).ok_or_else(|| {
            refuse(
                item.clone(),
                format!(
                    "no {} of that name in {} (it has {names:?})",
                    mesh.groups.material, mesh.name
                ),
            )
        })? + 1;
        let law = m.law().map_err(|e| refuse(item.clone(), e))?;
        specs[k] = Some(m.spec(law).map_err(|e| refuse(item, e))?);
        points[k] = m.points_per_element.unwrap_or(default_points(&mesh.model));
        inputs[k] = Some(m.input(law, points[k]));
    }
    let element_material: Vec<u32> = mesh
        .model
        .element_materials()
        .unwrap_or_default()
        .iter()
        .map(|&m| m as u32)
        .collect();
    for (k, m) in specs.iter().enumerate().skip(1) {
        if m.is_none() && element_material.contains(&(k as u32)) {
            return Err(refuse(
                format!("{} \"{}\"", mesh.groups.material, names[k - 1]),
                "has elements but no [[material]] entry",
            ));
        }
    }
    let points_per_element = element_material
        .iter()
        .map(|&m| points[m as usize])
        .collect();
    Ok(Materials {
        specs,
        inputs,
        element_material,
        points_per_element,
    })
}
