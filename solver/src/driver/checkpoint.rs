//! Checkpoints and the output folder's rules (docs/design.md §4.15): the complete state of a run
//! between two steps in `OUT/checkpoint/state.ckpt`, written atomically, from which `--resume`
//! continues so that the folder ends byte-identical to an uninterrupted run; the advisory lock
//! `OUT/.lock` that keeps two runs out of one folder.
//!
//! The file: the magic `MPMCKPT\0`, a format version (u32), the sections below, and an FNV-1a
//! 64-bit checksum of everything before it. Integers and floating-point bits are little-endian;
//! a string or byte run is its length (u64) and its bytes. Sections, in order: the fingerprint
//! (named hashes of the case and of every result-changing option), the driver's counters, the
//! engine's scalars (by name), every per-point array of the field list (name, values per point,
//! bytes per value, value count, raw bits), the output bookkeeping (the `run.pvd` entries, the
//! text of `history.csv`, `energy.csv` and `reaction.csv`) and the observers' state (a job's records).

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::input::case::{
    Body, BoundaryConditions, Case, Execution, Loading, Numerics, StartState, TimeControls,
};
use crate::real::Real;
use crate::state::particles::{Field, FieldReader, FieldVisitor, Particles, Value};

/// The first bytes of a checkpoint.
pub const MAGIC: &[u8; 8] = b"MPMCKPT\0";
/// Version of the layout: raised whenever a section changes.
pub const VERSION: u32 = 3;
/// The checkpoint's folder inside the output folder.
pub const FOLDER: &str = "checkpoint";
/// The checkpoint's file name in [`FOLDER`].
pub const FILE: &str = "state.ckpt";
/// The lock file in the output folder.
pub const LOCK: &str = ".lock";

/// Why a checkpoint could not be written, read or used, or a folder not taken.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// A file could not be written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a checkpoint this build reads (damaged, truncated, another version).
    #[error("{}: not a usable checkpoint: {what}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// The checkpoint belongs to another case or other result-changing options.
    #[error("{}: cannot resume: {what}; resume with the case and options of the interrupted run, or start afresh with --overwrite", dir.display())]
    Mismatch {
        /// The output folder.
        dir: PathBuf,
        /// The differences, named.
        what: String,
    },
    /// Another run holds the folder's lock.
    #[error("{}: another run is writing into this folder (it holds {}); wait for it to end or choose another --out", dir.display(), dir.join(LOCK).display())]
    Busy {
        /// The output folder.
        dir: PathBuf,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> CheckpointError + '_ {
    move |source| CheckpointError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// FNV-1a, 64 bits: the checksum and the fingerprint's hashes (stable across builds).
#[derive(Debug, Clone, Copy)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Adds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// One entry of a fingerprint.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Item {
    /// What it covers (`materials`, `precision`, ...).
    pub name: String,
    /// Hash of its value.
    pub hash: u64,
    /// The value in words when it is short (empty otherwise).
    pub shown: String,
}

/// Named hashes of a case and of every option that changes results; the thread count and
/// placement, progress and limits that only refuse or stop a run are left out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fingerprint(pub Vec<Item>);

/// A fingerprint item before hashing: its name and the value whose `Debug` text is hashed.
type Named<'a> = (&'static str, &'a dyn std::fmt::Debug);

/// Hashes a value's `Debug` text, keeping it when short.
struct Capture {
    hash: Fnv,
    text: String,
    long: bool,
}

impl std::fmt::Write for Capture {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.hash.update(s.as_bytes());
        if !self.long {
            if self.text.len() + s.len() > 80 {
                self.long = true;
                self.text.clear();
            } else {
                self.text.push_str(s);
            }
        }
        Ok(())
    }
}

impl Item {
    /// The entry `name` of `value`: the hash of its `Debug` text, and the text when short.
    fn of(name: &str, value: &dyn std::fmt::Debug) -> Self {
        let mut c = Capture {
            hash: Fnv::default(),
            text: String::new(),
            long: false,
        };
        let _ = write!(c, "{value:?}");
        Item {
            name: name.to_string(),
            hash: c.hash.0,
            shown: c.text,
        }
    }
}

impl Fingerprint {
    /// The fingerprint of `case` run with `drop_lost`. Every field of [`Case`] and of its parts
    /// is taken apart, here or in the lists of the body and of the loads, so a field added to
    /// any of them does not compile until it is placed in or out.
    pub fn of(case: &Case, drop_lost: bool) -> Self {
        let Case {
            name,
            inputs,
            model,
            body,
            boundary,
            loads,
            time,
            numerics,
            start,
            run,
        } = case;
        let BoundaryConditions {
            fixed,
            liquid_fixed,
            walls,
            prescribed,
            nodal_velocity,
            moving_mesh,
            contact,
            absorbing,
            absorbing_rule,
        } = boundary;
        let TimeControls {
            courant,
            courant_item,
            end_time,
            output_times,
            max_steps,
            quasi_static,
            anura3d_time_step,
            critical_step,
            initial_step,
        } = time;
        let Numerics {
            damping,
            objective_stress,
            pic_blend,
            integration,
            damping_rule,
            drag,
            smooth_pressure,
            fixed_liquid_mass,
            hoop_in_volume,
            strain_smoothing,
            bulk_viscosity,
            mass_scaling,
            scheme,
            precision,
            grid,
            gradient,
        } = numerics;
        let StartState {
            consolidation,
            initial_state,
            initial_stress,
        } = start;
        let Execution {
            guards,
            probes,
            // Threads, pinning and first touch: the results do not depend on them.
            engine: _,
        } = run;
        let version = env!("CARGO_PKG_VERSION");
        // The items' order is that of the checkpoints already written: the body's and the
        // loads' lists fall in runs of their own, the other parts' items are interleaved.
        let mut items: Vec<Named> = vec![
            ("solver version", &version),
            ("case name", name),
            ("input files", inputs),
            ("mesh", model),
        ];
        items.extend(Self::body(body));
        items.extend_from_slice(&[
            ("fixities", fixed),
            ("liquid fixities", liquid_fixed),
            ("walls", walls),
        ]);
        items.extend(Self::loads(loads));
        items.extend_from_slice(&[
            ("Courant number", courant),
            ("Courant number's source", courant_item),
            ("guard rails (--energy-tolerance)", guards),
            ("damping", damping),
            ("end time", end_time),
            ("output times", output_times),
            ("step limit", max_steps),
            ("quasi-static load steps", quasi_static),
            ("objective stress rate", objective_stress),
            ("PIC blend", pic_blend),
            ("integration", integration),
            ("Anura3D time step", anura3d_time_step),
            ("critical time step rule", critical_step),
            ("damping rule", damping_rule),
            ("drag (--drag)", drag),
            ("initial step", initial_step),
            ("pore-pressure smoothing", smooth_pressure),
            ("fixed liquid mass", fixed_liquid_mass),
            ("hoop strain in the volume", hoop_in_volume),
            ("strain smoothing", strain_smoothing),
            ("consolidation job", consolidation),
            ("initial state", initial_state),
            ("initial stresses", initial_stress),
            ("probes (--probe)", probes),
            ("prescribed velocities", prescribed),
            ("prescribed nodal velocities", nodal_velocity),
            ("moving mesh", moving_mesh),
            ("contact", contact),
            ("precision (--precision)", precision),
            ("--drop-lost", &drop_lost),
        ]);
        // Last and only where there is one: the checkpoints of cases without them keep their
        // items.
        items.extend(Self::optional(grid, gradient, absorbing, bulk_viscosity));
        items.extend(Self::optional_more(absorbing_rule, mass_scaling, scheme));
        Fingerprint(items.iter().map(|&(n, v)| Item::of(n, v)).collect())
    }

    /// The fingerprint's last items, each only where the case has it.
    // (The list as a `&Vec`: a slice is unsized and cannot be a `&dyn Debug`.)
    #[allow(clippy::ptr_arg)]
    fn optional<'a>(
        grid: &'a Option<crate::basis::grid::GridSpec>,
        gradient: &'a crate::input::case::Gradient,
        absorbing: &'a Vec<crate::step::absorbing::AbsorbingNode>,
        bulk: &'a Option<crate::step::bulk_viscosity::BulkViscosity>,
    ) -> Vec<Named<'a>> {
        let mut out: Vec<Named<'a>> = Vec::new();
        if let Some(g) = grid {
            out.push(("background grid", g));
        }
        if *gradient != crate::input::case::Gradient::Element {
            out.push(("gradients", gradient));
        }
        if !absorbing.is_empty() {
            out.push(("absorbing boundaries", absorbing));
        }
        if let Some(b) = bulk {
            out.push(("bulk viscosity", b));
        }
        out
    }

    /// The fingerprint's items after [`Fingerprint::optional`]'s, each only where the case has
    /// it.
    fn optional_more<'a>(
        absorbing_rule: &'a crate::step::absorbing::AbsorbingRule,
        mass_scaling: &'a f64,
        scheme: &'a crate::input::case::Scheme,
    ) -> Vec<Named<'a>> {
        let mut out: Vec<Named<'a>> = Vec::new();
        if *absorbing_rule != crate::step::absorbing::AbsorbingRule::EndOfStep {
            out.push(("absorbing boundaries' rule", absorbing_rule));
        }
        if *mass_scaling != 1.0 {
            out.push(("mass scaling", mass_scaling));
        }
        if scheme.semi_implicit() {
            out.push(("scheme (--scheme)", scheme));
        }
        out
    }

    /// The fingerprint's items of the mesh's filling, in order, every field taken apart.
    fn body(body: &Body) -> [Named<'_>; 5] {
        let Body {
            materials,
            element_material,
            points_per_element,
            input_element,
            input_node,
        } = body;
        [
            ("materials", materials),
            ("element materials", element_material),
            ("points per element", points_per_element),
            ("element numbers", input_element),
            ("node numbers", input_node),
        ]
    }

    /// The fingerprint's items of the loads, in order, every field taken apart.
    fn loads(loads: &Loading) -> [Named<'_>; 9] {
        let Loading {
            traction,
            structure_traction,
            point_loads,
            traction_curve,
            liquid_traction,
            liquid_curve,
            liquid_load_on_mixture,
            gravity,
            gravity_curve,
        } = loads;
        [
            ("tractions", traction),
            ("tractions on the structure", structure_traction),
            ("loads on material points", point_loads),
            ("traction curve", traction_curve),
            ("liquid tractions", liquid_traction),
            ("liquid load curve", liquid_curve),
            ("liquid load on the mixture", liquid_load_on_mixture),
            ("gravity", gravity),
            ("gravity curve", gravity_curve),
        ]
    }

    /// What differs from `now` (`self`: the checkpoint's), in words; `None` when nothing.
    pub fn difference(&self, now: &Fingerprint) -> Option<String> {
        let mut out = Vec::new();
        for a in &self.0 {
            match now.0.iter().find(|b| b.name == a.name) {
                Some(b) if b.hash == a.hash => {}
                Some(b) if !a.shown.is_empty() && !b.shown.is_empty() => out.push(format!(
                    "{} differs (checkpoint: {}, now: {})",
                    a.name, a.shown, b.shown
                )),
                Some(_) => out.push(format!("{} differs", a.name)),
                None => out.push(format!("{} is not known to this build", a.name)),
            }
        }
        for b in &now.0 {
            if !self.0.iter().any(|a| a.name == b.name) {
                out.push(format!("{} is not in the checkpoint", b.name));
            }
        }
        (!out.is_empty()).then(|| out.join("; "))
    }
}

/// How often a run writes its checkpoint (besides at the end and when stopped by a signal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Every {
    /// After every output, and after any step once this many seconds of wall time have passed
    /// since the last checkpoint.
    Outputs {
        /// Seconds.
        max_wall: f64,
    },
    /// Every so many steps.
    Steps(u64),
    /// After the first step once this many seconds of wall time have passed since the last.
    Wall(f64),
}

impl Default for Every {
    fn default() -> Self {
        Every::Outputs { max_wall: 600.0 }
    }
}

/// The driver's counters between two steps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Driver {
    /// Output times completed (the index of the next one).
    pub next_output: usize,
    /// Steps taken in the current load step.
    pub taken: u64,
    /// Time at which the current load step began.
    pub begun: f64,
    /// End of the previous load step (its output time).
    pub load_step_start: f64,
    /// Wall seconds spent stepping so far.
    pub stepping: f64,
    /// Wall seconds of the run so far.
    pub wall: f64,
}

/// The output bookkeeping: what `run.pvd`, `history.csv` and `energy.csv` hold.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// `run.pvd`'s entries: time and particle file.
    pub pvd: Vec<(f64, String)>,
    /// Text of `history.csv`.
    pub history: String,
    /// Text of `energy.csv`.
    pub energy: String,
    /// Text of `reaction.csv` (empty when the case has no prescribed velocities).
    pub reaction: String,
}

/// A checkpoint read back; the particle arrays stay in the file's bytes until applied.
pub struct Saved {
    /// The bytes of the file.
    bytes: Vec<u8>,
    /// Where it was read.
    pub path: PathBuf,
    /// The case's fingerprint.
    pub fingerprint: Fingerprint,
    /// The driver's counters.
    pub driver: Driver,
    /// The engine's scalars, by name (bits of f64 values, or counts).
    pub scalars: Vec<(String, u64)>,
    /// Per-point arrays: name, values per point, bytes per value, value count, and the byte
    /// range of their bits in `bytes`.
    fields: Vec<(String, usize, usize, usize, std::ops::Range<usize>)>,
    /// The output bookkeeping.
    pub series: Series,
    /// The observers' state.
    pub observer: Vec<u8>,
}

/// The encoder: a writer with a running checksum.
struct Enc<W: Write> {
    w: W,
    sum: Fnv,
    scratch: Vec<u8>,
}

impl<W: Write> Enc<W> {
    fn raw(&mut self, b: &[u8]) -> std::io::Result<()> {
        self.sum.update(b);
        self.w.write_all(b)
    }
    fn u64(&mut self, v: u64) -> std::io::Result<()> {
        self.raw(&v.to_le_bytes())
    }
    fn f64(&mut self, v: f64) -> std::io::Result<()> {
        self.u64(v.to_bits())
    }
    fn bytes(&mut self, b: &[u8]) -> std::io::Result<()> {
        self.u64(b.len() as u64)?;
        self.raw(b)
    }
    fn str(&mut self, s: &str) -> std::io::Result<()> {
        self.bytes(s.as_bytes())
    }
}

/// Writes every per-point array of the field list, raw.
struct PutFields<'a, W: Write> {
    enc: &'a mut Enc<W>,
    result: std::io::Result<()>,
}

impl<W: Write> FieldReader for PutFields<'_, W> {
    fn field<T: Value>(&mut self, field: Field, values: &[T]) {
        if self.result.is_err() {
            return;
        }
        self.result = (|| {
            let e = &mut *self.enc;
            e.str(field.name)?;
            e.u64(field.per_point as u64)?;
            e.u64(T::BYTES as u64)?;
            e.u64(values.len() as u64)?;
            e.scratch.clear();
            for v in values {
                v.put_bits(&mut e.scratch);
                if e.scratch.len() >= 1 << 16 {
                    let s = std::mem::take(&mut e.scratch);
                    e.raw(&s)?;
                    e.scratch = s;
                    e.scratch.clear();
                }
            }
            let s = std::mem::take(&mut e.scratch);
            e.raw(&s)?;
            e.scratch = s;
            Ok(())
        })();
    }
}

/// What a checkpoint is written from.
pub struct State<'a, R: Real> {
    /// The case's fingerprint.
    pub fingerprint: &'a Fingerprint,
    /// The driver's counters.
    pub driver: Driver,
    /// The engine's scalars.
    pub scalars: &'a [(&'static str, u64)],
    /// The material points.
    pub particles: &'a Particles<R>,
    /// The output bookkeeping.
    pub series: &'a Series,
    /// The observers' state.
    pub observer: &'a [u8],
}

/// Writes the checkpoint of `dir` atomically: into a temporary file beside it, flushed to disk,
/// then renamed over the previous one (which stays whole until then).
pub fn write<R: Real>(dir: &Path, state: &State<'_, R>) -> Result<(), CheckpointError> {
    let folder = dir.join(FOLDER);
    std::fs::create_dir_all(&folder).map_err(io(&folder))?;
    let path = folder.join(FILE);
    let tmp = folder.join(format!("{FILE}.tmp"));
    let result = write_file(&tmp, state).and_then(|()| {
        std::fs::rename(&tmp, &path).map_err(io(&path))?;
        // The rename itself reaches the disk with the folder.
        if let Ok(d) = std::fs::File::open(&folder) {
            let _ = d.sync_all();
        }
        Ok(())
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn write_file<R: Real>(tmp: &Path, s: &State<'_, R>) -> Result<(), CheckpointError> {
    let file = std::fs::File::create(tmp).map_err(io(tmp))?;
    let mut enc = Enc {
        w: std::io::BufWriter::with_capacity(1 << 20, file),
        sum: Fnv::default(),
        scratch: Vec::new(),
    };
    (|| -> std::io::Result<()> {
        enc.raw(MAGIC)?;
        enc.raw(&VERSION.to_le_bytes())?;
        enc.u64(s.fingerprint.0.len() as u64)?;
        for it in &s.fingerprint.0 {
            enc.str(&it.name)?;
            enc.u64(it.hash)?;
            enc.str(&it.shown)?;
        }
        let d = &s.driver;
        enc.u64(d.next_output as u64)?;
        enc.u64(d.taken)?;
        enc.f64(d.begun)?;
        enc.f64(d.load_step_start)?;
        enc.f64(d.stepping)?;
        enc.f64(d.wall)?;
        enc.u64(s.scalars.len() as u64)?;
        for (name, v) in s.scalars {
            enc.str(name)?;
            enc.u64(*v)?;
        }
        let mut count = CountFields(0);
        s.particles.read_fields(&mut count);
        enc.u64(count.0)?;
        let mut put = PutFields {
            enc: &mut enc,
            result: Ok(()),
        };
        s.particles.read_fields(&mut put);
        put.result?;
        enc.u64(s.series.pvd.len() as u64)?;
        for (t, name) in &s.series.pvd {
            enc.f64(*t)?;
            enc.str(name)?;
        }
        enc.str(&s.series.history)?;
        enc.str(&s.series.energy)?;
        enc.str(&s.series.reaction)?;
        enc.bytes(s.observer)?;
        let sum = enc.sum.0;
        enc.w.write_all(&sum.to_le_bytes())?;
        let file = enc.w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()
    })()
    .map_err(io(tmp))
}

struct CountFields(u64);

impl FieldReader for CountFields {
    fn field<T: Value>(&mut self, _: Field, _: &[T]) {
        self.0 += 1;
    }
}

/// The decoder: a cursor over the file's bytes that checks every length against what is left.
struct Dec<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Dec<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        if n > self.b.len() - self.at {
            return Err(format!(
                "{n} bytes announced at offset {} but only {} left",
                self.at,
                self.b.len() - self.at
            ));
        }
        let s = &self.b[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }
    fn u64(&mut self) -> Result<u64, String> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes(b.try_into().map_err(|_| "short")?))
    }
    fn f64(&mut self) -> Result<f64, String> {
        self.u64().map(f64::from_bits)
    }
    /// A count of items of at least `min_bytes` each, checked against the bytes left.
    fn count(&mut self, min_bytes: usize) -> Result<usize, String> {
        let n = self.u64()?;
        let left = (self.b.len() - self.at) as u64;
        if n.saturating_mul(min_bytes.max(1) as u64) > left {
            return Err(format!(
                "a count of {n} at offset {} exceeds the file",
                self.at
            ));
        }
        Ok(n as usize)
    }
    fn bytes(&mut self) -> Result<&'a [u8], String> {
        let n = self.count(1)?;
        self.take(n)
    }
    fn str(&mut self) -> Result<String, String> {
        let b = self.bytes()?;
        String::from_utf8(b.to_vec()).map_err(|_| "a name that is not UTF-8".to_string())
    }
}

/// The checkpoint file of output folder `dir`.
pub fn path(dir: &Path) -> PathBuf {
    dir.join(FOLDER).join(FILE)
}

/// Reads the checkpoint of `dir`: `Ok(None)` when there is none.
pub fn read(dir: &Path) -> Result<Option<Saved>, CheckpointError> {
    let path = path(dir);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io(&path)(e)),
    };
    decode(bytes, &path)
        .map(Some)
        .map_err(|what| CheckpointError::Corrupt {
            path: path.clone(),
            what,
        })
}

fn decode(bytes: Vec<u8>, path: &Path) -> Result<Saved, String> {
    if bytes.len() < MAGIC.len() + 4 + 8 || &bytes[..MAGIC.len()] != MAGIC {
        return Err("no checkpoint header".into());
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().map_err(|_| "short")?);
    if version != VERSION {
        return Err(format!(
            "format version {version}; this build reads version {VERSION}"
        ));
    }
    let body = bytes.len() - 8;
    let mut sum = Fnv::default();
    sum.update(&bytes[..body]);
    if sum.0.to_le_bytes() != bytes[body..] {
        return Err("checksum mismatch (a damaged or truncated file)".into());
    }
    let mut d = Dec {
        b: &bytes[..body],
        at: 12,
    };
    let n = d.count(24)?;
    let mut items = Vec::with_capacity(n);
    for _ in 0..n {
        items.push(Item {
            name: d.str()?,
            hash: d.u64()?,
            shown: d.str()?,
        });
    }
    let driver = Driver {
        next_output: d.u64()? as usize,
        taken: d.u64()?,
        begun: d.f64()?,
        load_step_start: d.f64()?,
        stepping: d.f64()?,
        wall: d.f64()?,
    };
    let n = d.count(16)?;
    let mut scalars = Vec::with_capacity(n);
    for _ in 0..n {
        scalars.push((d.str()?, d.u64()?));
    }
    let n = d.count(32)?;
    let mut fields = Vec::with_capacity(n);
    for _ in 0..n {
        let name = d.str()?;
        let per_point = d.u64()? as usize;
        let size = d.u64()? as usize;
        let count = d.count(size)?;
        let start = d.at;
        d.take(count * size)?;
        fields.push((name, per_point, size, count, start..d.at));
    }
    let n = d.count(16)?;
    let mut pvd = Vec::with_capacity(n);
    for _ in 0..n {
        pvd.push((d.f64()?, d.str()?));
    }
    let series = Series {
        pvd,
        history: d.str()?,
        energy: d.str()?,
        reaction: d.str()?,
    };
    let observer = d.bytes()?.to_vec();
    if d.at != body {
        return Err(format!("{} unread bytes at the end", body - d.at));
    }
    Ok(Saved {
        bytes,
        path: path.to_path_buf(),
        fingerprint: Fingerprint(items),
        driver,
        scalars,
        fields,
        series,
        observer,
    })
}

/// Copies the saved arrays into the points' arrays in place (they keep their placement), after
/// checking that each matches the field list: name, values per point, size and count.
struct Load<'a> {
    saved: &'a Saved,
    next: usize,
    error: Option<String>,
}

impl FieldVisitor for Load<'_> {
    fn field<T: Value>(&mut self, field: Field, values: &mut Vec<T>) {
        if self.error.is_some() {
            return;
        }
        let Some((name, per_point, size, count, range)) = self.saved.fields.get(self.next) else {
            self.error = Some(format!("no saved array for field {}", field.name));
            return;
        };
        self.next += 1;
        if name != field.name
            || *per_point != field.per_point
            || *size != T::BYTES
            || *count != values.len()
        {
            self.error = Some(format!(
                "saved array {name} ({count} values of {size} bytes, {per_point} per point) does not fit field {} ({} values of {} bytes, {} per point)",
                field.name,
                values.len(),
                T::BYTES,
                field.per_point
            ));
            return;
        }
        let bits = &self.saved.bytes[range.clone()];
        for (v, b) in values.iter_mut().zip(bits.chunks_exact(T::BYTES)) {
            match T::from_bits(b) {
                Some(x) => *v = x,
                None => {
                    self.error = Some(format!("a value of {name} that is not one"));
                    return;
                }
            }
        }
    }
}

impl Saved {
    /// Overwrites every per-point array of `p` with the saved one.
    pub fn load_particles<R: Real>(&self, p: &mut Particles<R>) -> Result<(), CheckpointError> {
        let mut load = Load {
            saved: self,
            next: 0,
            error: None,
        };
        p.visit_fields(&mut load);
        let error = load.error.or_else(|| {
            (load.next != self.fields.len())
                .then(|| format!("{} saved arrays, {} fields", self.fields.len(), load.next))
        });
        match error {
            None => Ok(()),
            Some(what) => Err(self.corrupt(what)),
        }
    }

    /// A [`CheckpointError::Corrupt`] naming this file.
    pub fn corrupt(&self, what: String) -> CheckpointError {
        CheckpointError::Corrupt {
            path: self.path.clone(),
            what,
        }
    }

    /// True when the run had reached its end time.
    pub fn finished(&self, outputs: usize) -> bool {
        self.driver.next_output >= outputs
    }
}

/// The advisory lock on an output folder, held while a run writes into it.
#[derive(Debug)]
pub struct FolderLock {
    _file: std::fs::File,
}

/// Creates `dir` if missing and takes its lock (`dir/.lock`), refusing a folder another run
/// holds.
pub fn lock(dir: &Path) -> Result<FolderLock, CheckpointError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let p = dir.join(LOCK);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&p)
        .map_err(io(&p))?;
    match fs4::fs_std::FileExt::try_lock_exclusive(&file) {
        Ok(true) => Ok(FolderLock { _file: file }),
        Ok(false) => Err(CheckpointError::Busy {
            dir: dir.to_path_buf(),
        }),
        Err(e) => Err(io(&p)(e)),
    }
}

/// What an existing output folder holds (its lock file aside).
#[derive(Debug)]
pub enum Holds {
    /// Nothing.
    Nothing,
    /// A run of this case and options that ended (its checkpoint at the end time, or a guard
    /// rail stopped it).
    SameFinished,
    /// A run of this case stopped before its end time (a checkpoint to resume from).
    SameUnfinished,
    /// A run of another case or other options: what differs.
    Other(String),
    /// Files that are no run this build wrote (or a checkpoint it cannot read).
    Unknown,
}

/// Names in `dir` other than the lock file.
fn entries(dir: &Path) -> Result<Vec<PathBuf>, CheckpointError> {
    let mut out = Vec::new();
    let rd = match std::fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(out),
        Err(e) => return Err(io(dir)(e)),
    };
    for e in rd {
        let e = e.map_err(io(dir))?;
        if e.file_name() != LOCK {
            out.push(e.path());
        }
    }
    Ok(out)
}

/// What `dir` holds, against the fingerprint of the run about to start and its output count.
pub fn holds(dir: &Path, now: &Fingerprint, outputs: usize) -> Result<Holds, CheckpointError> {
    if entries(dir)?.is_empty() {
        return Ok(Holds::Nothing);
    }
    let saved = match read(dir) {
        Ok(Some(s)) => s,
        Ok(None) | Err(CheckpointError::Corrupt { .. }) => return Ok(Holds::Unknown),
        Err(e) => return Err(e),
    };
    // A run stopped by a guard rail ended too: resuming it would diverge again.
    let diverged = std::fs::read(dir.join("run.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .is_some_and(|j| j["status"] == "diverged");
    Ok(match saved.fingerprint.difference(now) {
        Some(d) => Holds::Other(d),
        None if saved.finished(outputs) || diverged => Holds::SameFinished,
        None => Holds::SameUnfinished,
    })
}

/// Empties `dir` but for its lock file.
pub fn clear(dir: &Path) -> Result<(), CheckpointError> {
    for p in entries(dir)? {
        let r = if p.is_dir() && !p.is_symlink() {
            std::fs::remove_dir_all(&p)
        } else {
            std::fs::remove_file(&p)
        };
        r.map_err(io(&p))?;
    }
    Ok(())
}

/// Before a resume from `series`: removes what a killed run left that the checkpoint does not
/// account for (temporary files, particle files written after it, a stale `run.json`).
pub fn tidy(dir: &Path, series: &Series, finished: bool) -> Result<(), CheckpointError> {
    for p in entries(dir)? {
        let Some(name) = p.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        let stale = name.starts_with(".tmp-")
            || (name == "run.json" && !finished)
            || (name.starts_with("particles_")
                && name.ends_with(".vtu")
                && !series.pvd.iter().any(|(_, f)| f == name));
        if stale {
            std::fs::remove_file(&p).map_err(io(&p))?;
        }
    }
    let tmp = dir.join(FOLDER).join(format!("{FILE}.tmp"));
    if tmp.exists() {
        std::fs::remove_file(&tmp).map_err(io(&tmp))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_damaged_checkpoint_is_refused_not_trusted() {
        let dir = tempfile::tempdir().unwrap();
        let fp = Fingerprint(vec![Item {
            name: "x".into(),
            hash: 1,
            shown: "1".into(),
        }]);
        let mut p = Particles::<f64> {
            x: vec![[1.0, 2.0, 3.0]],
            u: vec![[0.0; 3]],
            v: vec![[0.5; 3]],
            mass: vec![2.0],
            volume: vec![1.0],
            stress: vec![[0.0; 6]],
            element: vec![0],
            material: vec![1],
            id: vec![1],
            active: vec![true],
            ..Default::default()
        };
        let series = Series {
            pvd: vec![(0.5, "particles_00000.vtu".into())],
            history: "h\n".into(),
            energy: "e\n".into(),
            reaction: "r\n".into(),
        };
        let state = State {
            fingerprint: &fp,
            driver: Driver::default(),
            scalars: &[("time", 0.25f64.to_bits())],
            particles: &p,
            series: &series,
            observer: b"obs",
        };
        write(dir.path(), &state).unwrap();
        let s = read(dir.path()).unwrap().unwrap();
        assert_eq!(s.fingerprint, fp);
        assert_eq!(s.series, series);
        assert_eq!(s.observer, b"obs");
        p.x[0] = [9.0; 3];
        s.load_particles(&mut p).unwrap();
        assert_eq!(p.x[0], [1.0, 2.0, 3.0]);
        // Every truncation and every flipped byte is caught.
        let bytes = std::fs::read(path(dir.path())).unwrap();
        for cut in [0, 5, 12, bytes.len() / 2, bytes.len() - 1] {
            std::fs::write(path(dir.path()), &bytes[..cut]).unwrap();
            assert!(matches!(
                read(dir.path()),
                Err(CheckpointError::Corrupt { .. })
            ));
        }
        for at in (0..bytes.len()).step_by(7) {
            let mut b = bytes.clone();
            b[at] ^= 0x10;
            std::fs::write(path(dir.path()), &b).unwrap();
            assert!(read(dir.path()).is_err(), "flip at {at}");
        }
    }
}
