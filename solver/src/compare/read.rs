//! The two kinds of run folder and their outputs, one at a time: ours (`run.pvd` naming
//! `particles_NNNNN.vtu`) and Anura3D's (`PROJ.CPS_001` beside `PROJ_MPScalar_NNN.vtk`,
//! `..._MPVector_...`, `..._MPTensor_...`, one set per load step).
//!
//! An Anura3D folder may hold no load-step files when it holds its benchmark tables
//! (`PROJ.BMS`, `PROJ_expected.BMS`, see [`super::tables`]): a benchmark folder as shipped.
//!
//! An output is seen through [`Snapshot`], its points in ascending id order whatever their
//! order in the file: our files are mapped, not copied, and only a permutation (4 bytes a point)
//! is built when the ids are not already ascending.

use std::path::{Path, PathBuf};

use mpm_shared::anura3d_vtk::{self, MaterialPointState};
use mpm_shared::vtu_read::{self, ArrayView, VtuFile};

use super::CompareError;

/// A material-point field compared output by output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// Current position (m).
    Position,
    /// Displacement (m).
    Displacement,
    /// Velocity (m/s).
    Velocity,
    /// Effective stress xx yy zz xy yz zx (kPa, tension positive).
    Stress,
    /// Pore pressure (kPa).
    PorePressure,
}

impl Field {
    /// Every field, in report order.
    pub const ALL: [Field; 5] = [
        Field::Position,
        Field::Displacement,
        Field::Velocity,
        Field::Stress,
        Field::PorePressure,
    ];

    /// The name used in reports and tolerance files.
    pub fn name(self) -> &'static str {
        match self {
            Field::Position => "position",
            Field::Displacement => "displacement",
            Field::Velocity => "velocity",
            Field::Stress => "stress",
            Field::PorePressure => "pore_pressure",
        }
    }

    /// Names of the components.
    pub fn components(self) -> &'static [&'static str] {
        match self {
            Field::Position | Field::Displacement | Field::Velocity => &["x", "y", "z"],
            Field::Stress => &["xx", "yy", "zz", "xy", "yz", "zx"],
            Field::PorePressure => &["p"],
        }
    }

    /// The array of our particle files holding it.
    fn vtu_name(self) -> &'static str {
        match self {
            Field::Position => "Points",
            Field::Displacement => "displacement",
            Field::Velocity => "velocity",
            Field::Stress => "stress",
            Field::PorePressure => "pore_pressure",
        }
    }
}

/// A run folder.
#[derive(Debug, Clone)]
pub enum Folder {
    /// Written by `mpm-solve`.
    Ours {
        /// The folder.
        dir: PathBuf,
        /// `run.pvd`'s entries.
        outputs: Vec<vtu_read::DataSet>,
    },
    /// Written by Anura3D.
    Anura3d {
        /// The folder.
        dir: PathBuf,
        /// The project name (the CPS's stem).
        project: String,
        /// Load steps with files, ascending, and their times (`TIME_PER_LOADSTEP × step`).
        steps: Vec<(u32, f64)>,
    },
}

/// One output of a folder: its time and a name for reports.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputRef {
    /// Position in the folder's list.
    pub index: usize,
    /// Simulated time (s).
    pub time: f64,
    /// The file (ours) or `PROJ_MP*_NNN.vtk` (Anura3D's load step).
    pub label: String,
}

fn not_a_run(dir: &Path, why: &str) -> CompareError {
    CompareError::NotARun {
        dir: dir.to_path_buf(),
        reason: why.to_string(),
    }
}

impl Folder {
    /// Recognises `dir`: ours when it holds `run.pvd`, Anura3D's when it holds one `*.CPS_001`.
    pub fn open(dir: &Path) -> Result<Folder, CompareError> {
        if !dir.is_dir() {
            return Err(not_a_run(dir, "not a folder"));
        }
        let pvd = dir.join("run.pvd");
        if pvd.is_file() {
            let outputs = vtu_read::read_pvd_file(&pvd)?;
            return Ok(Folder::Ours {
                dir: dir.to_path_buf(),
                outputs,
            });
        }
        let mut cps: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| mpm_shared::Error::io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("CPS_001"))
            })
            .collect();
        cps.sort();
        // A benchmark folder (or a copy of Anura3D's tables alone) has tables but may have no
        // load-step files: its tables are still compared.
        let tables = super::table_files::TableFiles::find(dir)?;
        let cps = match cps.as_slice() {
            [one] => one.clone(),
            [] => {
                if let Some(t) = tables.bms.as_ref().or(tables.bmr.as_ref()) {
                    return Ok(Folder::Anura3d {
                        dir: dir.to_path_buf(),
                        project: super::table_files::project_of(t),
                        steps: Vec::new(),
                    });
                }
                return Err(not_a_run(
                    dir,
                    "neither run.pvd (mpm-solve) nor PROJ.CPS_001 (Anura3D) nor a PROJ.BMS/BMR table is there",
                ));
            }
            _ => return Err(not_a_run(dir, "more than one *.CPS_001 (which project?)")),
        };
        let project = cps
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        let data = mpm_shared::io::read_parameters(&cps)?;
        let (parsed, _) = mpm_shared::cps::Cps::read(&data, &cps.display().to_string())?;
        let dt = parsed.settings()?.time_per_load_step;
        let prefix = format!("{project}_MPScalar_");
        let mut steps: Vec<(u32, f64)> = std::fs::read_dir(dir)
            .map_err(|e| mpm_shared::Error::io(dir, e))?
            .filter_map(|e| e.ok())
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().to_string();
                let n = name.strip_prefix(&prefix)?.strip_suffix(".vtk")?;
                n.parse::<u32>().ok()
            })
            // Step 0 is Anura3D's state after its first time step, which we do not write.
            .filter(|&k| k > 0)
            .map(|k| (k, k as f64 * dt))
            .collect();
        steps.sort_by_key(|s| s.0);
        if steps.is_empty() && !tables.any() {
            return Err(not_a_run(
                dir,
                &format!(
                    "{} is there but no {prefix}NNN.vtk (has Anura3D run?)",
                    cps.display()
                ),
            ));
        }
        Ok(Folder::Anura3d {
            dir: dir.to_path_buf(),
            project,
            steps,
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        match self {
            Folder::Ours { dir, .. } | Folder::Anura3d { dir, .. } => dir,
        }
    }

    /// What wrote it, for reports.
    pub fn kind(&self) -> &'static str {
        match self {
            Folder::Ours { .. } => "mpm-solve",
            Folder::Anura3d { .. } => "Anura3D",
        }
    }

    /// The outputs in the folder's order.
    pub fn outputs(&self) -> Vec<OutputRef> {
        match self {
            Folder::Ours { outputs, .. } => outputs
                .iter()
                .enumerate()
                .map(|(index, d)| OutputRef {
                    index,
                    time: d.time,
                    label: d.file.clone(),
                })
                .collect(),
            Folder::Anura3d { project, steps, .. } => steps
                .iter()
                .enumerate()
                .map(|(index, &(k, time))| OutputRef {
                    index,
                    time,
                    label: format!("{project}_MP*_{k:03}.vtk"),
                })
                .collect(),
        }
    }

    /// The Anura3D load step of output `index` (none for our outputs).
    pub fn load_step(&self, index: usize) -> Option<u32> {
        match self {
            Folder::Ours { .. } => None,
            Folder::Anura3d { steps, .. } => steps.get(index).map(|s| s.0),
        }
    }

    /// Reads output `index` (see [`Folder::outputs`]).
    pub fn load(&self, index: usize) -> Result<Snapshot, CompareError> {
        match self {
            Folder::Ours { dir, outputs } => {
                let path = dir.join(&outputs[index].file);
                let vtu = vtu_read::read_vtu_file(&path)?;
                OursSnap::new(vtu).map(Snapshot::Ours)
            }
            Folder::Anura3d {
                dir,
                project,
                steps,
            } => {
                let points = anura3d_vtk::read_step(dir, project, steps[index].0)?;
                Ok(Snapshot::Anura3d(points))
            }
        }
    }
}

/// One of our particle files, mapped, with its points' ascending-id order.
pub struct OursSnap {
    vtu: VtuFile,
    /// Row of the k-th smallest id; `None` when the rows are already in that order.
    order: Option<Vec<u32>>,
}

impl OursSnap {
    fn new(vtu: VtuFile) -> Result<Self, CompareError> {
        let bad = |m: String| CompareError::Points(format!("{}: {m}", vtu.file));
        let ids = vtu
            .point_data("id")
            .ok_or_else(|| bad("no 'id' point array (not a particle file?)".into()))?;
        if ids.components != 1 {
            return Err(bad("'id' has more than one component".into()));
        }
        let n = ids.len();
        if n > u32::MAX as usize {
            return Err(bad(format!("{n} points is more than this reader handles")));
        }
        let ascending = (1..n).all(|i| ids.get(i - 1, 0) < ids.get(i, 0));
        let order = if ascending {
            None
        } else {
            let mut o: Vec<u32> = (0..n as u32).collect();
            o.sort_unstable_by(|&a, &b| ids.get(a as usize, 0).total_cmp(&ids.get(b as usize, 0)));
            if let Some(w) = o
                .windows(2)
                .find(|w| ids.get(w[0] as usize, 0) == ids.get(w[1] as usize, 0))
            {
                return Err(bad(format!(
                    "id {} occurs twice",
                    ids.get(w[0] as usize, 0)
                )));
            }
            Some(o)
        };
        Ok(OursSnap { vtu, order })
    }

    fn row(&self, k: usize) -> usize {
        self.order.as_ref().map_or(k, |o| o[k] as usize)
    }
}

/// One output's material points, seen in ascending id order.
pub enum Snapshot {
    /// A particle file of ours.
    Ours(OursSnap),
    /// An Anura3D load step (read whole: its three files are read in full anyway).
    Anura3d(Vec<MaterialPointState>),
}

/// Read access to one field of a [`Snapshot`].
pub enum FieldView<'a> {
    /// An array of our file, through the snapshot's order.
    Ours(ArrayView<'a>, &'a OursSnap),
    /// Anura3D's points and the field.
    Anura3d(&'a [MaterialPointState], Field),
}

impl FieldView<'_> {
    /// Component `c` of the point of rank `k` (ascending id).
    pub fn get(&self, k: usize, c: usize) -> f64 {
        match self {
            FieldView::Ours(v, s) => v.get(s.row(k), c),
            FieldView::Anura3d(p, f) => {
                let m = &p[k];
                match f {
                    Field::Position => m.position[c],
                    Field::Displacement => m.displacement_solid[c],
                    Field::Stress => m.eff_stress_solid[c],
                    Field::PorePressure => m.pressure_liquid.unwrap_or(0.0),
                    Field::Velocity => f64::NAN,
                }
            }
        }
    }
}

impl Snapshot {
    /// Number of material points.
    pub fn len(&self) -> usize {
        match self {
            Snapshot::Ours(s) => s.vtu.points,
            Snapshot::Anura3d(p) => p.len(),
        }
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The points' ids, by rank.
    pub fn ids(&self) -> Whole<'_> {
        match self {
            Snapshot::Ours(s) => match s.vtu.point_data("id") {
                Some(v) => Whole::Ours(v, s),
                None => Whole::Absent,
            },
            Snapshot::Anura3d(p) => Whole::Ids(p),
        }
    }

    /// The rank of the point of id `id`, if this output has it (ids ascend with rank).
    pub fn rank_of(&self, id: u64) -> Option<usize> {
        let ids = self.ids();
        let (mut lo, mut hi) = (0, self.len());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            match ids.get(mid)?.cmp(&id) {
                std::cmp::Ordering::Less => lo = mid + 1,
                std::cmp::Ordering::Greater => hi = mid,
                std::cmp::Ordering::Equal => return Some(mid),
            }
        }
        None
    }

    /// The points' elements (1-based) by rank, when the file has them (ours).
    pub fn elements(&self) -> Whole<'_> {
        match self {
            Snapshot::Ours(s) => match s.vtu.point_data("element") {
                Some(v) => Whole::Ours(v, s),
                None => Whole::Absent,
            },
            Snapshot::Anura3d(_) => Whole::Absent,
        }
    }

    /// The field, when this output has it with the expected number of components.
    pub fn field(&self, f: Field) -> Result<Option<FieldView<'_>>, CompareError> {
        match self {
            Snapshot::Ours(s) => {
                let Some(v) = s.vtu.array(
                    if f == Field::Position {
                        vtu_read::Section::Points
                    } else {
                        vtu_read::Section::PointData
                    },
                    f.vtu_name(),
                ) else {
                    return Ok(None);
                };
                if v.components != f.components().len() {
                    return Err(CompareError::Points(format!(
                        "{}: '{}' has {} components, expected {}",
                        s.vtu.file,
                        f.vtu_name(),
                        v.components,
                        f.components().len()
                    )));
                }
                Ok(Some(FieldView::Ours(v, s)))
            }
            Snapshot::Anura3d(p) => {
                let has = match f {
                    Field::Velocity => false,
                    Field::PorePressure => p.iter().all(|m| m.pressure_liquid.is_some()),
                    _ => true,
                };
                Ok(has.then_some(FieldView::Anura3d(p, f)))
            }
        }
    }
}

/// A whole-number array of a [`Snapshot`] by rank (ids, elements).
pub enum Whole<'a> {
    /// An array of our file, through the snapshot's order.
    Ours(ArrayView<'a>, &'a OursSnap),
    /// Anura3D's material-point ids.
    Ids(&'a [MaterialPointState]),
    /// Not in this output.
    Absent,
}

impl Whole<'_> {
    /// The value for the point of rank `k`, `None` when the output has no such array.
    pub fn get(&self, k: usize) -> Option<u64> {
        match self {
            Whole::Ours(v, s) => Some(v.get(s.row(k), 0) as u64),
            Whole::Ids(p) => Some(p[k].id as u64),
            Whole::Absent => None,
        }
    }
}
