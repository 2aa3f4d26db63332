//! Anura3D calculation parameters (`.CPS_001`): reader, typed settings and writer.
//!
//! Same layout as the GOM: a version line, `$$KEYWORD` lines each followed by value lines, in any
//! order, ending with `$$END`. Every entry is kept in file order so the file can be written back
//! with only the remapped material-point list changed. The keys of docs/design.md §2.2 are typed by
//! [`Cps::settings`]; unknown keys produce one warning each and never fail.

use crate::error::{Error, Location, Result};
use crate::model::LineEnding;
use crate::text::{self, Lines, Tokens};

/// The most load steps a CPS may ask for: each writes an output, and a count past this (a typo,
/// or a corrupted file) would only reach the output checks after its list of output times
/// had exhausted the memory.
const MAX_LOAD_STEPS: f64 = 1e7;

/// One `$$KEYWORD` entry with its value lines.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Keyword without `$$`.
    pub keyword: String,
    /// Value lines (trailing blanks removed, blank lines dropped).
    pub lines: Vec<String>,
    /// Line number of the keyword in the file read (0 for entries made in memory).
    pub line: usize,
}

/// A CPS file.
#[derive(Debug, Clone, PartialEq)]
pub struct Cps {
    /// File name used in messages.
    pub file: String,
    /// Version line.
    pub version: String,
    /// Line terminator to write.
    pub line_ending: LineEnding,
    /// Entries in file order.
    pub entries: Vec<Entry>,
}

/// How a load multiplier evolves (`off`, `step`, `linear`, `file`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Multiplier {
    /// Not applied.
    Off,
    /// Constant within each load step, in equal stairs from `start` to `value`: load step k of
    /// N takes start + (k / N)(value - start), so the last takes `value` (with one load step, or
    /// equal numbers, `value` from the first step on).
    Step {
        /// The first of the two numbers (`value` when only one is given).
        start: f64,
        /// Multiplier applied in the last load step.
        value: f64,
    },
    /// Ramped linearly from `start` to `end` over the load step.
    Linear {
        /// Value at the start.
        start: f64,
        /// Value at the end.
        end: f64,
    },
    /// Values read from a separate load-curve file (`file start final`).
    File {
        /// Value at the start.
        start: f64,
        /// Value at the end.
        end: f64,
    },
}

/// Computation method (`$$COMPUTATION_METHOD`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Method {
    /// `MPM-MP`: integrate at material points.
    MpmMp,
    /// `MPM-MIXED`: Gauss point in filled elements, material points elsewhere.
    MpmMixed,
    /// Any other (`FEM`, `UL-FEM`): kept for messages.
    Other(String),
}

/// The typed keys of docs/design.md §2.2. Missing keys take Anura3D's defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// `NUMBER_OF_LOADSTEPS`.
    pub load_steps: u32,
    /// `TIME_PER_LOADSTEP` (s).
    pub time_per_load_step: f64,
    /// `TOTAL_TIME` (s) reached by earlier stages.
    pub total_time: f64,
    /// `COURANT_NUMBER`.
    pub courant: f64,
    /// `COMPUTATION_METHOD`.
    pub method: Method,
    /// `DEGREE_OF_FILLING` for MPM-MIXED.
    pub degree_of_filling: f64,
    /// `GRAVITY_ACCELERATION` (m/s²).
    pub gravity_acceleration: f64,
    /// `GRAVITY_VECTOR` (unit direction).
    pub gravity_vector: [f64; 3],
    /// `GRAVITY_LOAD`.
    pub gravity_load: Multiplier,
    /// `SOLID_TRACTION`.
    pub solid_traction: Multiplier,
    /// `SOLID_TRACTION_B`.
    pub solid_traction_b: Multiplier,
    /// `LIQUID_PRESSURE`.
    pub liquid_pressure: Multiplier,
    /// `LIQUID_PRESSURE_B`.
    pub liquid_pressure_b: Multiplier,
    /// `PRESCRIBED_VELOCITY`.
    pub prescribed_velocity: Multiplier,
    /// `HOMOGENEOUS_LOCAL_DAMPING`: factor when switched on.
    pub local_damping: Option<f64>,
    /// `MASS_SCALING`: factor when switched on.
    pub mass_scaling: Option<f64>,
    /// `BULK_VISCOSITY_DAMPING`: the linear and quadratic coefficients [b1, b2] when switched
    /// on.
    pub bulk_viscosity: Option<[f64; 2]>,
    /// `MAXIMUM_TIME_STEPS`.
    pub max_time_steps: Option<u64>,
    /// `QUASISTATIC_CONVERGENCE`.
    pub quasi_static: bool,
    /// `APPLY_OBJECTIVE_STRESS`.
    pub objective_stress: bool,
    /// `TOLERATED_ERROR_SOLID`: tolerated out-of-balance force ratio and kinetic-energy ratio
    /// of the quasi-static convergence check.
    pub tolerated_error_solid: [f64; 2],
    /// `TOLERATED_ERROR_LIQUID`: the same for the liquid (default 0.01, 0.01).
    pub tolerated_error_liquid: [f64; 2],
    /// `OUTPUT_MATERIAL_POINTS` (1-based ids).
    pub output_material_points: Vec<u32>,
}

/// Keys Anura3D's CPS files are known to carry (the 2024 template and the benchmark suite).
/// CPS key marking `$$OUTPUT_MATERIAL_POINTS` as file ids of the ordered GOM whose element count
/// and input-number checksum follow on one line (see [`crate::points`]).
pub const CPS_FILE_ORDER: &str = "OUTPUT_MATERIAL_POINTS_GOM_ORDER";

const KNOWN: &[&str] = &[
    "NUMBER_OF_LOADSTEPS",
    "TIME_PER_LOADSTEP",
    "TOTAL_TIME",
    "COURANT_NUMBER",
    "COMPUTATION_METHOD",
    "GRAVITY_ACCELERATION",
    "GRAVITY_VECTOR",
    "GRAVITY_LOAD",
    "SOLID_TRACTION",
    "SOLID_TRACTION_B",
    "LIQUID_PRESSURE",
    "LIQUID_PRESSURE_B",
    "GAS_PRESSURE",
    "GAS_PRESSURE_B",
    "HYDRAULIC_HEAD",
    "APPLY_SEEPAGE_FACE",
    "APPLY_INFILTRATION",
    "PRESCRIBED_VELOCITY",
    "QUASISTATIC_CONVERGENCE",
    "TOLERATED_ERROR_SOLID",
    "TOLERATED_ERROR_LIQUID",
    "MAXIMUM_TIME_STEPS",
    "APPLY_IMPLICIT_QUASISTATIC",
    "QS_MIN_ITER",
    "QS_MAX_ITER",
    "QS_UPSCALE_FACTOR",
    "QS_DOWNSCALE_FACTOR",
    "QS_MAX_ITERATIONS",
    "APPLY_ZLS",
    "APPLY_ARC_LENGTH_CONTROL",
    "APPLY_ENHANCED_STIFFNESS",
    "QS_STIFFNESS_INCREASE_FACTOR",
    "QS_DANGLING_ELEMENT_FACTOR",
    "APPLY_STEP_EXTRAPOLATION",
    "APPLY_JACOBIAN_CHECK",
    "LIMIT_JACOBIAN_CHANGE",
    "APPLY_AUTOMATIC_LOADSTEPPING",
    "INCR_MULTIPLIER_SOILA",
    "INCR_MULTIPLIER_GRAVITY",
    "INCR_MULTIPLIER_WATERA",
    "INCR_MULTIPLIER_GASA",
    "MASS_SCALING",
    "HOMOGENEOUS_LOCAL_DAMPING",
    "BULK_VISCOSITY_DAMPING",
    "APPLY_DIVERGENCE_CHECK",
    "SKIP_CONVECTION_TIME_STEPS",
    "AUTOMATIC_SKIP_CONVECTION",
    "MINIMUM_DETERMINANT_RATIO",
    "NUMBER_OF_THREADS",
    "APPLY_NODE_DATA_AB",
    "CONTACT_FORMULATION",
    "APPLY_CONTACT_MESH_BOUNDARY",
    "APPLY_TRACTION_CONTACT",
    "MONOPILE_SLICE_CONTACT",
    "APPLY_CONTACT_VELOCITY_SCALING",
    "VELOCITY_SCALING_FACTOR",
    "APPLY_CONTACT_NORMAL_CORRECTION",
    "NUMBER_OF_CORRECTED_NORMALS",
    "NODE_NORMAL_DATA",
    "EXCAVATION",
    "CONSTRUCTION",
    "FILL_EMPTY_ELEMENTS",
    "FIX_SOLID_SKELETON",
    "STRAIN_SMOOTHING",
    "APPLY_STRAIN_SMOOTHING_LIQUID_TWOLAYERFORM",
    "LIQUID_CAVITATION",
    "PERMEABILITY_UPDATE",
    "INTRINSIC_PERMEABILITY",
    "GRAIN_SIZE_DIAMETER",
    "ERGUN_CONSTANTS",
    "NO_TENSILE_STRESS_LIQUID_MP_WITH_LIQUID_STATUS",
    "MAXIMUM_POROSITY",
    "DETECT_FREE_SURFACE",
    "RESET_DISPLACEMENTS",
    "REMOVE_FIXITIES",
    "K0_PROCEDURE",
    "MP_STRESS_INITIALIZATION_FROMFILE",
    "SUBMERGED_CALCULATION",
    "APPLY_OBJECTIVE_STRESS",
    "DEGREE_OF_FILLING",
    "NUMBER_OF_ACTIVE_ELEMENTS",
    "VISUALIZATION_OPTION",
    "OUTPUT_NUMBER_OF_MATERIAL_POINTS",
    "OUTPUT_MATERIAL_POINTS",
    CPS_FILE_ORDER,
    "INITIAL_WATER_PRESSURE",
    "APPLY_POROSITY_UPDATE",
    "INITIAL_VELOCITY",
    "APPLY_SMOOTHENING_LIQUID_PRESSURE_INCREMENT",
    "SURFACE_ELEVATION",
    "INITIAL_VERTICAL_LOAD_K0",
    "OUTPUT_NUMBER_OF_NODES",
    "OUTPUT_NODES",
    "APPLY_MATERIAL_UPDATE",
    "K0_MAX_SUCTION",
    "THICKNESS_SOIL_LAYERS",
    "QUICK_CHECK_OUTPUT",
    "PARTICLE_FILE_COUNTER",
    "OUTPUT_EACH_LOAD_STEP",
    "OUTPUT_DEBUG_DATA",
    "OUTPUT_CURVES_INTERVAL",
    "OUTPUT_BASIC_DATA",
    "NUMBER_SOIL_LAYERS",
    "MASS_FACTOR_VIRTUAL_PARTICLES",
    "LIQUID_SURFACE",
    "GROUP_THRESHOLD",
    "FILE_COUNTER",
    "FEEDBACK_LEVEL",
    "CONSIDERED_LOAD_K0",
    "APPLY_EMPTY_ELEMENTS",
    "UPDATE_PERMEABILITY_DARCY_ERGUN",
    "STAGE",
    "APPLY_BULK_VISCOSITY_DAMPING",
];

impl Cps {
    /// Reads a CPS from memory; returns it with one warning per unknown key.
    pub fn read(data: &[u8], file: &str) -> Result<(Cps, Vec<String>)> {
        let mut lines = Lines::new(data, 1);
        let at = |n: usize, s: Option<&str>| Location::new(file, n, s);
        let (version, line_ending) = loop {
            let Some((n, l)) = lines.next() else {
                return Err(Error::format(
                    at(0, None),
                    "empty file: expected a version line such as '### Anura3D_2021 ###'",
                ));
            };
            if text::is_blank(l) {
                continue;
            }
            let t = text::trim(l);
            if !t.starts_with(b"###") {
                return Err(Error::format(
                    at(n, None),
                    format!(
                        "expected a CPS version line such as '### Anura3D_2021 ###', found {}",
                        text::show(l)
                    ),
                ));
            }
            let crlf = data.get(lines.offset().wrapping_sub(2)) == Some(&b'\r');
            break (
                String::from_utf8_lossy(t).into_owned(),
                if crlf {
                    LineEnding::CrLf
                } else {
                    LineEnding::Lf
                },
            );
        };
        let mut entries: Vec<Entry> = Vec::new();
        let mut ended = false;
        for (n, l) in lines {
            let t = text::trim(l);
            if let Some(kw) = t.strip_prefix(b"$$") {
                let kw = String::from_utf8_lossy(kw).into_owned();
                if kw == "END" {
                    ended = true;
                    break;
                }
                entries.push(Entry {
                    keyword: kw,
                    lines: Vec::new(),
                    line: n,
                });
            } else if !text::is_blank(l) {
                match entries.last_mut() {
                    Some(e) => {
                        let end = l
                            .iter()
                            .rposition(|&b| !text::is_separator(b))
                            .map_or(0, |e| e + 1);
                        e.lines
                            .push(String::from_utf8_lossy(&l[..end]).into_owned());
                    }
                    None => {
                        return Err(Error::format(
                            at(n, None),
                            format!("expected a '$$KEYWORD' line, found {}", text::show(l)),
                        ))
                    }
                }
            }
        }
        if !ended {
            return Err(Error::format(
                at(0, None),
                "file ends without '$$END' (truncated?)",
            ));
        }
        // Anura3D reads its CPS top to bottom, so a repeated key silently takes its last value:
        // almost always an edit that missed the first one. Say so instead of guessing (unknown
        // keys are only warned about, once).
        let mut first_line = std::collections::HashMap::new();
        for e in entries
            .iter()
            .filter(|e| KNOWN.contains(&e.keyword.as_str()))
        {
            if let Some(first) = first_line.insert(e.keyword.as_str(), e.line) {
                return Err(Error::format(
                    at(e.line, None),
                    format!(
                        "'$${}' is given twice (lines {first} and {}); keep one",
                        e.keyword, e.line
                    ),
                ));
            }
        }
        let mut warnings = Vec::new();
        let mut warned: Vec<&str> = Vec::new();
        for e in &entries {
            if !KNOWN.contains(&e.keyword.as_str()) && !warned.contains(&e.keyword.as_str()) {
                warned.push(&e.keyword);
                warnings.push(format!(
                    "{file}:{}: unknown CPS key '$${}' ignored",
                    e.line, e.keyword
                ));
            }
        }
        Ok((
            Cps {
                file: file.to_string(),
                version,
                line_ending,
                entries,
            },
            warnings,
        ))
    }

    /// The first entry with `keyword`.
    pub fn get(&self, keyword: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.keyword == keyword)
    }

    fn at(&self, e: &Entry, offset: usize) -> Location {
        Location::new(
            &self.file,
            e.line + offset,
            Some(&format!("$${}", e.keyword)),
        )
    }

    fn tokens<'a>(&self, e: &'a Entry) -> Result<Vec<&'a [u8]>> {
        let first = e
            .lines
            .first()
            .ok_or_else(|| Error::format(self.at(e, 0), "expected a value line after the key"))?;
        Ok(Tokens::new(first.as_bytes()).collect())
    }

    fn real(&self, key: &str, default: f64) -> Result<f64> {
        let Some(e) = self.get(key) else {
            return Ok(default);
        };
        let toks = self.tokens(e)?;
        let t = toks.first().copied().unwrap_or_default();
        text::parse_real(t).ok_or_else(|| {
            Error::format(
                self.at(e, 1),
                format!("expected a number, found {}", text::show(t)),
            )
        })
    }

    /// Two numbers on the key's line (`force energy` tolerances).
    fn pair(&self, key: &str, default: [f64; 2]) -> Result<[f64; 2]> {
        let Some(e) = self.get(key) else {
            return Ok(default);
        };
        let toks = self.tokens(e)?;
        let mut v = [0.0; 2];
        for (i, x) in v.iter_mut().enumerate() {
            *x = toks
                .get(i)
                .and_then(|t| text::parse_real(t))
                .ok_or_else(|| Error::format(self.at(e, 1), "expected two numbers"))?;
        }
        Ok(v)
    }

    fn flag_value(&self, key: &str) -> Result<Option<f64>> {
        Ok(self.flag_values::<1>(key)?.map(|[v]| v))
    }

    /// `flag v1 .. vN`: the N values when the flag is on (not 0).
    fn flag_values<const N: usize>(&self, key: &str) -> Result<Option<[f64; N]>> {
        let Some(e) = self.get(key) else {
            return Ok(None);
        };
        let values = " value".repeat(N);
        let toks = self.tokens(e)?;
        let flag = toks
            .first()
            .and_then(|t| text::parse_int(t))
            .ok_or_else(|| Error::format(self.at(e, 1), format!("expected '0|1{values}'")))?;
        if flag == 0 {
            return Ok(None);
        }
        let mut out = [0.0; N];
        for (k, v) in out.iter_mut().enumerate() {
            *v = toks
                .get(1 + k)
                .and_then(|t| text::parse_real(t))
                .ok_or_else(|| {
                    Error::format(
                        self.at(e, 1),
                        format!("expected '1{values}' with numeric values"),
                    )
                })?;
        }
        Ok(Some(out))
    }

    fn flag(&self, key: &str) -> Result<bool> {
        let Some(e) = self.get(key) else {
            return Ok(false);
        };
        let toks = self.tokens(e)?;
        toks.first()
            .and_then(|t| text::parse_int(t))
            .map(|v| v != 0)
            .ok_or_else(|| Error::format(self.at(e, 1), "expected 0 or 1"))
    }

    fn multiplier(&self, key: &str) -> Result<Multiplier> {
        let Some(e) = self.get(key) else {
            return Ok(Multiplier::Off);
        };
        let toks = self.tokens(e)?;
        let word = toks
            .first()
            .map(|t| t.to_ascii_lowercase())
            .unwrap_or_default();
        let num = |i: usize| -> Result<f64> {
            toks.get(i)
                .and_then(|t| text::parse_real(t))
                .ok_or_else(|| {
                    Error::format(
                        self.at(e, 1),
                        format!(
                            "expected '{} start final' with two numbers",
                            String::from_utf8_lossy(&word)
                        ),
                    )
                })
        };
        match word.as_slice() {
            b"off" => Ok(Multiplier::Off),
            b"step" => {
                let value = num(2).or_else(|_| num(1))?;
                Ok(Multiplier::Step {
                    start: if toks.len() > 2 { num(1)? } else { value },
                    value,
                })
            }
            b"linear" => Ok(Multiplier::Linear {
                start: num(1)?,
                end: num(2)?,
            }),
            b"file" => Ok(Multiplier::File {
                start: num(1)?,
                end: num(2)?,
            }),
            _ => Err(Error::format(
                self.at(e, 1),
                format!(
                    "expected off, step, linear or file, found {}",
                    text::show(toks.first().copied().unwrap_or_default())
                ),
            )),
        }
    }

    /// The typed settings of docs/design.md §2.2, with Anura3D's defaults for missing keys.
    pub fn settings(&self) -> Result<Settings> {
        let load_steps = self.real("NUMBER_OF_LOADSTEPS", 1.0)?;
        if load_steps < 1.0 || load_steps.fract() != 0.0 || load_steps > MAX_LOAD_STEPS {
            let e = self
                .get("NUMBER_OF_LOADSTEPS")
                .expect("present when not default");
            return Err(Error::invalid(
                self.at(e, 1),
                "expected a positive whole number of load steps, at most 10,000,000 (each \
                 writes an output)",
            ));
        }
        let method = match self.get("COMPUTATION_METHOD") {
            None => Method::MpmMixed,
            Some(e) => {
                let t = self.tokens(e)?;
                match t.first().copied().unwrap_or_default() {
                    b"MPM-MP" => Method::MpmMp,
                    b"MPM-MIXED" => Method::MpmMixed,
                    other => Method::Other(String::from_utf8_lossy(other).into_owned()),
                }
            }
        };
        let gravity_vector = match self.get("GRAVITY_VECTOR") {
            None => [0.0, -1.0, 0.0],
            Some(e) => {
                let t = self.tokens(e)?;
                let mut v = [0.0; 3];
                if t.len() < 2 {
                    return Err(Error::format(self.at(e, 1), "expected 2 or 3 components"));
                }
                for (i, tok) in t.iter().take(3).enumerate() {
                    v[i] = text::parse_real(tok).ok_or_else(|| {
                        Error::format(
                            self.at(e, 1),
                            format!("expected a number, found {}", text::show(tok)),
                        )
                    })?;
                }
                v
            }
        };
        let max_time_steps = match self.get("MAXIMUM_TIME_STEPS") {
            None => None,
            Some(_) => Some(self.real("MAXIMUM_TIME_STEPS", 0.0)? as u64),
        };
        let output_material_points = self.output_material_points()?;
        let tolerated_error_solid = self.pair("TOLERATED_ERROR_SOLID", [0.01, 0.01])?;
        let tolerated_error_liquid = self.pair("TOLERATED_ERROR_LIQUID", [0.01, 0.01])?;
        Ok(Settings {
            load_steps: load_steps as u32,
            time_per_load_step: self.real("TIME_PER_LOADSTEP", 0.0)?,
            total_time: self.real("TOTAL_TIME", 0.0)?,
            courant: self.real("COURANT_NUMBER", 0.98)?,
            method,
            degree_of_filling: self.real("DEGREE_OF_FILLING", 0.9)?,
            gravity_acceleration: self.real("GRAVITY_ACCELERATION", 9.81)?,
            gravity_vector,
            gravity_load: self.multiplier("GRAVITY_LOAD")?,
            solid_traction: self.multiplier("SOLID_TRACTION")?,
            solid_traction_b: self.multiplier("SOLID_TRACTION_B")?,
            liquid_pressure: self.multiplier("LIQUID_PRESSURE")?,
            liquid_pressure_b: self.multiplier("LIQUID_PRESSURE_B")?,
            prescribed_velocity: self.multiplier("PRESCRIBED_VELOCITY")?,
            local_damping: self.flag_value("HOMOGENEOUS_LOCAL_DAMPING")?,
            mass_scaling: self.flag_value("MASS_SCALING")?,
            bulk_viscosity: self.flag_values::<2>("BULK_VISCOSITY_DAMPING")?,
            max_time_steps,
            quasi_static: self.flag("QUASISTATIC_CONVERGENCE")?,
            objective_stress: self.flag("APPLY_OBJECTIVE_STRESS")?,
            tolerated_error_solid,
            tolerated_error_liquid,
            output_material_points,
        })
    }

    /// The `OUTPUT_MATERIAL_POINTS` ids: as many as `OUTPUT_NUMBER_OF_MATERIAL_POINTS` says (a
    /// count of 0 or -1 means none, whatever placeholder follows).
    pub fn output_material_points(&self) -> Result<Vec<u32>> {
        let count = match self.get("OUTPUT_NUMBER_OF_MATERIAL_POINTS") {
            None => None,
            Some(e) => {
                let t = self.tokens(e)?;
                let v = t.first().and_then(|t| text::parse_int(t)).ok_or_else(|| {
                    Error::format(
                        self.at(e, 1),
                        "expected the number of output material points",
                    )
                })?;
                Some(v.max(0) as usize)
            }
        };
        if count == Some(0) {
            return Ok(Vec::new());
        }
        let Some(e) = self.get("OUTPUT_MATERIAL_POINTS") else {
            return match count {
                Some(n) => Err(Error::format(
                    Location::new(&self.file, 0, Some("$$OUTPUT_MATERIAL_POINTS")),
                    format!("$$OUTPUT_NUMBER_OF_MATERIAL_POINTS says {n} but the list is missing"),
                )),
                None => Ok(Vec::new()),
            };
        };
        let mut ids = Vec::new();
        'lines: for (i, l) in e.lines.iter().enumerate() {
            for tok in Tokens::new(l.as_bytes()) {
                if count.is_some_and(|n| ids.len() == n) {
                    break 'lines;
                }
                let id = text::parse_u32(tok).filter(|&v| v > 0).ok_or_else(|| {
                    Error::format(
                        self.at(e, i + 1),
                        format!(
                            "expected a material point id (positive integer), found {}",
                            text::show(tok)
                        ),
                    )
                })?;
                ids.push(id);
            }
        }
        if let Some(n) = count {
            if ids.len() < n {
                return Err(Error::format(
                    self.at(e, 0),
                    format!(
                        "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS says {n}, found {} ids",
                        ids.len()
                    ),
                ));
            }
        }
        Ok(ids)
    }

    /// Replaces the output material-point list (and its count) with `ids`.
    pub fn set_output_material_points(&mut self, ids: &[u32]) {
        let lines: Vec<String> = ids.iter().map(|i| i.to_string()).collect();
        let count = vec![ids.len().to_string()];
        for e in &mut self.entries {
            match e.keyword.as_str() {
                "OUTPUT_MATERIAL_POINTS" => e.lines = lines.clone(),
                "OUTPUT_NUMBER_OF_MATERIAL_POINTS" => e.lines = count.clone(),
                _ => {}
            }
        }
    }

    /// Sets `keyword` to `lines`: the first entry with it is replaced, or a new one is added
    /// after `$$OUTPUT_MATERIAL_POINTS` (at the end when there is none).
    pub fn set(&mut self, keyword: &str, lines: Vec<String>) {
        if let Some(e) = self.entries.iter_mut().find(|e| e.keyword == keyword) {
            e.lines = lines;
            return;
        }
        let at = self
            .entries
            .iter()
            .position(|e| e.keyword == "OUTPUT_MATERIAL_POINTS")
            .map_or(self.entries.len(), |i| i + 1);
        self.entries.insert(
            at,
            Entry {
                keyword: keyword.to_string(),
                lines,
                line: 0,
            },
        );
    }

    /// Removes every entry with `keyword`.
    pub fn remove(&mut self, keyword: &str) {
        self.entries.retain(|e| e.keyword != keyword);
    }

    /// Writes the CPS back in its original order.
    pub fn write(&self) -> Vec<u8> {
        let eol = self.line_ending.bytes();
        let mut out = Vec::new();
        out.extend_from_slice(self.version.as_bytes());
        out.extend_from_slice(eol);
        for e in &self.entries {
            out.extend_from_slice(b"$$");
            out.extend_from_slice(e.keyword.as_bytes());
            out.extend_from_slice(eol);
            for l in &e.lines {
                out.extend_from_slice(l.as_bytes());
                out.extend_from_slice(eol);
            }
        }
        out.extend_from_slice(b"$$END");
        out.extend_from_slice(eol);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRC: &str = "### Anura3D_2024 ###\n$$NUMBER_OF_LOADSTEPS\n50\n$$TIME_PER_LOADSTEP\n0.05\n$$COURANT_NUMBER\n0.5\n$$COMPUTATION_METHOD\nMPM-MP\n$$GRAVITY_LOAD\noff 0.0 1.0\n$$SOLID_TRACTION\nstep 1.0 1.0\n$$PRESCRIBED_VELOCITY\nlinear 0.0 2.0\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.05\n$$MASS_SCALING\n0 1.0\n$$BULK_VISCOSITY_DAMPING\n1 0.42 1.2\n$$SOMETHING_NEW\n1\n$$SOMETHING_NEW\n2\n$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n2\n$$OUTPUT_MATERIAL_POINTS\n3\n5\n$$END\n";

    #[test]
    fn refuses_load_step_counts_that_are_not_whole_or_past_the_limit() {
        for (count, ok) in [
            ("10000000", true),
            ("10000001", false),
            ("4294967295", false),
            ("1e30", false),
            ("0", false),
            ("2.5", false),
        ] {
            let src = SRC.replace(
                "$$NUMBER_OF_LOADSTEPS\n50\n",
                &format!("$$NUMBER_OF_LOADSTEPS\n{count}\n"),
            );
            let (cps, _) = Cps::read(src.as_bytes(), "a.CPS_001").unwrap();
            match cps.settings() {
                Ok(s) => {
                    assert!(ok, "{count} taken");
                    assert_eq!(s.load_steps as f64, count.parse::<f64>().unwrap());
                }
                Err(e) => {
                    assert!(!ok, "{count}: {e}");
                    let e = e.to_string();
                    assert!(
                        e.contains("a.CPS_001:3") && e.contains("at most 10,000,000"),
                        "{e}"
                    );
                }
            }
        }
    }

    #[test]
    fn types_the_design_keys_and_warns_once() {
        let (cps, warnings) = Cps::read(SRC.as_bytes(), "a.CPS_001").unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].contains("a.CPS_001:22: unknown CPS key '$$SOMETHING_NEW'"));
        let s = cps.settings().unwrap();
        assert_eq!(s.load_steps, 50);
        assert_eq!(s.courant, 0.5);
        assert_eq!(s.method, Method::MpmMp);
        assert_eq!(s.gravity_load, Multiplier::Off);
        assert_eq!(
            s.solid_traction,
            Multiplier::Step {
                start: 1.0,
                value: 1.0
            }
        );
        assert_eq!(
            s.prescribed_velocity,
            Multiplier::Linear {
                start: 0.0,
                end: 2.0
            }
        );
        assert_eq!(s.local_damping, Some(0.05));
        assert_eq!(s.mass_scaling, None);
        assert_eq!(s.bulk_viscosity, Some([0.42, 1.2]));
        assert_eq!(s.output_material_points, vec![3, 5]);
        assert_eq!(s.gravity_vector, [0.0, -1.0, 0.0]);
    }

    #[test]
    fn writes_back_and_remaps_output_points() {
        let (mut cps, _) = Cps::read(SRC.as_bytes(), "a").unwrap();
        assert_eq!(String::from_utf8(cps.write()).unwrap(), SRC);
        cps.set_output_material_points(&[7, 1, 9]);
        let (again, _) = Cps::read(&cps.write(), "b").unwrap();
        assert_eq!(
            again.settings().unwrap().output_material_points,
            vec![7, 1, 9]
        );
        assert_eq!(
            again.get("OUTPUT_NUMBER_OF_MATERIAL_POINTS").unwrap().lines,
            vec!["3"]
        );
    }

    #[test]
    fn bad_values_name_the_line() {
        let bad = SRC.replace("0.5\n", "fast\n");
        let (cps, _) = Cps::read(bad.as_bytes(), "a").unwrap();
        let e = cps.settings().unwrap_err().to_string();
        assert!(
            e.contains("a:7 (in $$COURANT_NUMBER): expected a number, found 'fast'"),
            "{e}"
        );
        let e = Cps::read(b"### x ###\n$$COURANT_NUMBER\n1\n", "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("without '$$END'"), "{e}");
        let bad = SRC.replace("1 0.42 1.2", "1 0.42");
        let (cps, _) = Cps::read(bad.as_bytes(), "a").unwrap();
        let e = cps.settings().unwrap_err().to_string();
        assert!(
            e.contains("$$BULK_VISCOSITY_DAMPING") && e.contains("'1 value value'"),
            "{e}"
        );
        let twice = SRC.replace("$$END", "$$COURANT_NUMBER\n0.9\n$$END");
        let e = Cps::read(twice.as_bytes(), "t").unwrap_err().to_string();
        assert!(
            e.contains("t:31: '$$COURANT_NUMBER' is given twice (lines 6 and 31)"),
            "{e}"
        );
    }
}
