//! The Anura3D compatibility matrix, generated, never kept by hand.
//!
//! `cargo run --release -p mpm-solve --example anura3d_compat -- ROOT OUT.md [--check PREVIOUS.md]`
//!
//! Walks every case folder under `ROOT/Benchmarks` and `ROOT/Workshop` that holds a GOM
//! (`*.GOM`, `*.GOM_stage0`) and a `*.CPS_001`. Each case is loaded with
//! `mpm_solve::input::anura3d::load`: a refusal is recorded with the loader's message. An accepted case
//! is run and, when an `*_expected.BMS` lists material points, compared with it point by point
//! (`mpm_solve::jobs::anura3d_compare`): reproduced when the worst deviation is at most 1 %, else
//! differs. Panics are caught per case. OUT.md gets a summary, a table per case, the refusals
//! grouped by reason, and every GOM section, GOM material key and CPS key of the suite with the
//! number of cases using it and what the loader does with it (`mpm_solve::input::anura3d_keys`).
//!
//! With `--check PREVIOUS.md`, exits with status 1, listing them, when a case that is
//! reproduced in PREVIOUS.md is not reproduced now (OUT.md is written either way).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use mpm_shared::bms::Bms;
use mpm_shared::cps::{Cps, Method};
use mpm_shared::model::is_material_key;
use mpm_solve::driver::dispatch::{dispatch, Generic};
use mpm_solve::driver::run::{run, RunError};
use mpm_solve::element::Element;
use mpm_solve::input::anura3d::CaseError;
use mpm_solve::input::anura3d_keys::{self, KeyKind};
use mpm_solve::input::case::Drag;
use mpm_solve::jobs::anura3d_compare::{compare, Comparison};
use mpm_solve::real::Real;

/// Largest deviation for "reproduced" (1 %).
const TOLERANCE: f64 = 0.01;

/// One case: a `.CPS_001` and the GOM beside it.
struct Input {
    /// Name in the table: the folder relative to ROOT (plus the CPS stem when a folder holds
    /// several cases).
    name: String,
    /// The case folder.
    dir: PathBuf,
    gom: PathBuf,
    cps: PathBuf,
    bms: Option<PathBuf>,
}

/// What happened to a case.
enum Status {
    /// Every reported point within the tolerance.
    Reproduced(String),
    /// Ran, but not within the tolerance.
    Differs(String),
    /// Ran; nothing to compare with.
    Ran(String),
    /// The loader refused it: its message.
    Refused(String),
    /// The loader could not read the files.
    Unreadable(String),
    /// The run (or the comparison) failed or panicked.
    Failed(String),
}

impl Status {
    fn label(&self) -> &'static str {
        match self {
            Status::Reproduced(_) => "reproduced",
            Status::Differs(_) => "differs",
            Status::Ran(_) => "ran",
            Status::Refused(_) => "refused",
            Status::Unreadable(_) => "unreadable",
            Status::Failed(_) => "failed",
        }
    }

    fn detail(&self) -> &str {
        match self {
            Status::Reproduced(s)
            | Status::Differs(s)
            | Status::Ran(s)
            | Status::Refused(s)
            | Status::Unreadable(s)
            | Status::Failed(s) => s,
        }
    }
}

/// One row of the case table.
struct Row {
    name: String,
    dimension: String,
    element: String,
    method: String,
    materials: String,
    expected: String,
    status: Status,
    /// For refusals, the group in the "by reason" table.
    reason: Option<String>,
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut positional, mut check) = (Vec::new(), None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--check" {
            match it.next() {
                Some(p) => check = Some(PathBuf::from(p)),
                None => return usage("--check needs a file"),
            }
        } else if a.starts_with('-') {
            return usage(&format!("unknown option {a}"));
        } else {
            positional.push(a.clone());
        }
    }
    let [root, out] = positional.as_slice() else {
        return usage("expected ROOT and OUT.md");
    };
    let (root, out) = (PathBuf::from(root), PathBuf::from(out));
    let previous = match &check {
        None => None,
        Some(p) => match std::fs::read_to_string(p)
            .map_err(|e| e.to_string())
            .and_then(|t| {
                previous_statuses(&t)
                    .filter(|m| !m.is_empty())
                    .ok_or_else(|| "no '## Cases' table with rows found".to_string())
            }) {
            Ok(m) => Some(m),
            Err(e) => {
                eprintln!("anura3d_compat: {}: {e}", p.display());
                return ExitCode::from(2);
            }
        },
    };
    if !root.join("Benchmarks").is_dir() {
        eprintln!(
            "anura3d_compat: {} has no Benchmarks folder (is it the Anura3D suite?)",
            root.display()
        );
        return ExitCode::from(2);
    }
    let inputs = find_cases(&root);
    let started = Instant::now();
    let mut rows = Vec::new();
    let mut keys: BTreeMap<(KeyKind, String), BTreeSet<String>> = BTreeMap::new();
    for input in &inputs {
        let t0 = Instant::now();
        let row = evaluate(&root, input, &mut keys);
        eprintln!(
            "{:>7.2} s  {:<10} {}",
            t0.elapsed().as_secs_f64(),
            row.status.label(),
            row.name
        );
        rows.push(row);
    }
    eprintln!(
        "{} cases in {:.1} s",
        rows.len(),
        started.elapsed().as_secs_f64()
    );
    let command = format!(
        "cargo run --release -p mpm-solve --example anura3d_compat -- {} {}",
        root.display(),
        out.display()
    );
    let doc = document(&command, &rows, &keys);
    if let Err(e) = mpm_shared::io::write_output(&out, doc.as_bytes()) {
        eprintln!("anura3d_compat: {e}");
        return ExitCode::from(2);
    }
    eprintln!("wrote {}", out.display());
    let Some(previous) = previous else {
        return ExitCode::SUCCESS;
    };
    let now: BTreeMap<&str, &str> = rows
        .iter()
        .map(|r| (r.name.as_str(), r.status.label()))
        .collect();
    let mut lost = Vec::new();
    for (name, status) in &previous {
        if status == "reproduced" && now.get(name.as_str()) != Some(&"reproduced") {
            lost.push(format!(
                "{name}: reproduced before, now {}",
                now.get(name.as_str()).copied().unwrap_or("absent")
            ));
        }
    }
    for (name, status) in &now {
        if *status == "reproduced" && previous.get(*name).map(String::as_str) != Some("reproduced")
        {
            eprintln!("newly reproduced: {name}");
        }
    }
    if lost.is_empty() {
        eprintln!(
            "check: all {} cases reproduced in {} are still reproduced",
            previous.values().filter(|s| *s == "reproduced").count(),
            check.as_deref().unwrap_or(Path::new("")).display()
        );
        ExitCode::SUCCESS
    } else {
        eprintln!("check FAILED: {} case(s) no longer reproduced:", lost.len());
        for l in &lost {
            eprintln!("  {l}");
        }
        ExitCode::FAILURE
    }
}

fn usage(problem: &str) -> ExitCode {
    eprintln!("anura3d_compat: {problem}");
    eprintln!(
        "usage: cargo run --release -p mpm-solve --example anura3d_compat -- ROOT OUT.md [--check PREVIOUS.md]"
    );
    ExitCode::from(2)
}

/// Every folder under ROOT/Benchmarks and ROOT/Workshop with a `.CPS_001` and a GOM, sorted.
fn find_cases(root: &Path) -> Vec<Input> {
    let mut dirs = Vec::new();
    for top in ["Benchmarks", "Workshop"] {
        collect_dirs(&root.join(top), &mut dirs);
    }
    dirs.sort();
    let mut out = Vec::new();
    for dir in dirs {
        let mut files: Vec<String> = match std::fs::read_dir(&dir) {
            Ok(rd) => rd
                .filter_map(|e| e.ok())
                .filter(|e| e.path().is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect(),
            Err(_) => continue,
        };
        files.sort();
        let goms: Vec<String> = files
            .iter()
            .filter(|f| f.ends_with(".GOM") || f.ends_with(".GOM_stage0"))
            .cloned()
            .collect();
        let cpss: Vec<String> = files
            .iter()
            .filter(|f| f.ends_with(".CPS_001"))
            .cloned()
            .collect();
        let rel = dir
            .strip_prefix(root)
            .unwrap_or(&dir)
            .to_string_lossy()
            .replace('\\', "/");
        for cps in &cpss {
            let stem = cps.trim_end_matches(".CPS_001");
            // The GOM of the same project; else one that starts with its name; else the only
            // one that is not an expected result.
            let exact = [format!("{stem}.GOM"), format!("{stem}.GOM_stage0")];
            let inputs: Vec<&String> = goms.iter().filter(|g| !g.contains("_expected")).collect();
            let gom = goms
                .iter()
                .find(|g| exact.contains(g))
                .or_else(|| goms.iter().find(|g| g.starts_with(&format!("{stem}."))))
                .or_else(|| (inputs.len() == 1).then(|| inputs[0]));
            let Some(gom) = gom else { continue };
            let expected: Vec<&String> = files
                .iter()
                .filter(|f| f.ends_with("_expected.BMS"))
                .collect();
            let own = format!("{stem}_expected.BMS");
            let bms = expected
                .iter()
                .find(|f| ***f == own)
                .or_else(|| (expected.len() == 1).then(|| &expected[0]))
                .map(|f| dir.join(f));
            out.push(Input {
                name: if cpss.len() > 1 {
                    format!("{rel}:{stem}")
                } else {
                    rel.clone()
                },
                dir: dir.clone(),
                gom: dir.join(gom),
                cps: dir.join(cps),
                bms,
            });
        }
    }
    out
}

fn collect_dirs(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    out.push(dir.to_path_buf());
    for e in rd.filter_map(|e| e.ok()) {
        if e.path().is_dir() {
            collect_dirs(&e.path(), out);
        }
    }
}

/// A message with the suite's paths shortened to file names, on one line, safe in a table.
fn clean(msg: &str, root: &Path, dir: &Path) -> String {
    let mut s = msg.replace(&format!("{}/", dir.display()), "");
    s = s.replace(&format!("{}/", root.display()), "");
    cell(&s)
}

/// Text safe inside a Markdown table cell.
fn cell(s: &str) -> String {
    s.replace(['\n', '\r'], " ").replace('|', "\\|")
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".to_string()
    }
}

/// Describes, loads, runs and compares one case; records the keys its files use in `keys`.
fn evaluate(
    root: &Path,
    input: &Input,
    keys: &mut BTreeMap<(KeyKind, String), BTreeSet<String>>,
) -> Row {
    let mut row = Row {
        name: input.name.clone(),
        dimension: "?".into(),
        element: "?".into(),
        method: "?".into(),
        materials: "?".into(),
        expected: "no".into(),
        status: Status::Failed(String::new()),
        reason: None,
    };
    let mut use_key = |kind: KeyKind, key: &str| {
        keys.entry((kind, key.to_string()))
            .or_default()
            .insert(input.name.clone());
    };
    // What the files say, read independently of the loader.
    if let Ok(model) = mpm_shared::read_model(&input.gom) {
        row.dimension = model.dimension.keyword().to_string();
        row.element = model.element_type.keyword().to_string();
        let mut kinds: Vec<String> = Vec::new();
        for m in model.materials() {
            let law = m.get("MATERIAL_MODEL_SOLID").unwrap_or("?");
            let k = format!("{} ({law})", m.kind);
            if !kinds.contains(&k) {
                kinds.push(k);
            }
            for (key, _) in &m.properties {
                use_key(KeyKind::MaterialKey, key);
            }
        }
        row.materials = kinds.join(", ");
        for s in &model.sections {
            if !is_material_key(&s.keyword) {
                use_key(KeyKind::GomSection, &s.keyword);
            }
        }
    }
    if let Ok(data) = std::fs::read(&input.cps) {
        if let Ok((cps, _)) = Cps::read(&data, &input.cps.display().to_string()) {
            row.method = match cps.settings().map(|s| s.method) {
                Ok(Method::MpmMp) => "MPM-MP".into(),
                Ok(Method::MpmMixed) => "MPM-MIXED".into(),
                Ok(Method::Other(m)) => m,
                Err(_) => "?".into(),
            };
            for e in &cps.entries {
                use_key(KeyKind::CpsKey, &e.keyword);
            }
        }
    }
    let expected = match &input.bms {
        None => None,
        Some(p) => {
            let read = std::fs::read(p).map_err(|e| e.to_string()).and_then(|d| {
                mpm_shared::bms::read_bms(&d, &p.display().to_string()).map_err(|e| e.to_string())
            });
            match read {
                Ok(b) if b.material_points.is_empty() => {
                    row.expected = "no points".into();
                    None
                }
                Ok(b) => {
                    row.expected = "yes".into();
                    Some(b)
                }
                Err(e) => {
                    row.expected = "unreadable".into();
                    row.status =
                        Status::Failed(format!("expected BMS: {}", clean(&e, root, &input.dir)));
                    return row;
                }
            }
        }
    };
    // The loader.
    let loaded = catch_unwind(AssertUnwindSafe(|| {
        mpm_solve::input::anura3d::load(&input.gom, &input.cps)
    }));
    let case = match loaded {
        Err(p) => {
            row.status =
                Status::Failed(cell(&format!("panic while loading: {}", panic_message(p))));
            return row;
        }
        Ok(Err(e)) => {
            let msg = clean(&e.to_string(), root, &input.dir);
            match &e {
                CaseError::Unsupported { item, message, .. } => {
                    row.reason = Some(refusal_reason(item, message));
                    row.status = Status::Refused(msg);
                }
                CaseError::Key(r) => {
                    row.reason = Some(refusal_reason(&format!("$${}", r.key), &r.what));
                    row.status = Status::Refused(msg);
                }
                _ => row.status = Status::Unreadable(msg),
            }
            return row;
        }
        Ok(Ok((case, _))) => case,
    };
    // The run, with the case's own element type; the comparison while the engine is at hand.
    struct RunAndCompare<'a> {
        case: &'a mpm_solve::input::case::Case,
        dir: &'a Path,
        expected: Option<&'a Bms>,
    }
    impl Generic for RunAndCompare<'_> {
        type Output = Result<(u64, f64, Option<Comparison>), RunError>;
        fn call<R: Real, E: Element>(self) -> Self::Output {
            let engine = run::<R, E>(self.case, self.dir, &Default::default())?;
            let c = self.expected.map(|bms| compare(&engine, bms));
            Ok((engine.steps, engine.time, c))
        }
    }
    let run_with = |case: &mpm_solve::input::case::Case| {
        let tmp = tempfile::tempdir().map_err(|e| cell(&format!("temporary folder: {e}")))?;
        let ran = catch_unwind(AssertUnwindSafe(|| {
            dispatch(
                case,
                RunAndCompare {
                    case,
                    dir: tmp.path(),
                    expected: expected.as_ref(),
                },
            )
        }));
        match ran {
            Err(p) => Err(cell(&format!("panic: {}", panic_message(p)))),
            Ok(Err(e)) => Err(clean(&e.to_string(), root, &input.dir)),
            Ok(Ok(Err(e))) => Err(clean(&e.to_string(), root, &input.dir)),
            Ok(Ok(Ok(r))) => Ok(r),
        }
    };
    // Two-phase cases are judged with Anura3D's own drag discretisation (explicit); the
    // default implicit drag's deviation is noted beside it.
    let two_phase = case.has_liquid();
    let mut judged = case.clone();
    if two_phase {
        judged.numerics.drag = Drag::Explicit;
    }
    let (steps, time, comparison) = match run_with(&judged) {
        Ok(r) => r,
        Err(message) => {
            row.status = Status::Failed(message);
            return row;
        }
    };
    row.status = match comparison {
        None => Status::Ran(format!(
            "{steps} steps to t = {time:.4e} s; no expected material points to compare"
        )),
        Some(c) => judge(&c),
    };
    if let (true, Status::Reproduced(s) | Status::Differs(s)) = (two_phase, &mut row.status) {
        let implicit = match run_with(&case) {
            Ok((_, _, Some(c))) => format!("{:.3} %", 100.0 * c.worst),
            Ok(_) => "not compared".into(),
            Err(m) => format!("failed: {m}"),
        };
        let _ = write!(
            s,
            "; with --drag explicit (the default implicit drag: worst {implicit})"
        );
    }
    row
}

/// Reproduced or differs, with the worst deviation.
fn judge(c: &Comparison) -> Status {
    let mut s = match &c.worst_at {
        Some(w) => format!(
            "worst {:.3} % (point {} {}: {:.4e} vs {:.4e})",
            100.0 * c.worst,
            w.id,
            w.column,
            w.ours,
            w.expected
        ),
        None => "nothing compared".to_string(),
    };
    let _ = write!(s, ", {} points at t = {:.4e} s", c.points, c.expected_time);
    if !c.time_matches() {
        let _ = write!(s, "; the run ended at t = {:.4e} s", c.time);
    }
    if !c.missing.is_empty() {
        let _ = write!(s, "; reported points missing: {:?}", c.missing);
    }
    if c.reproduced(TOLERANCE) {
        Status::Reproduced(s)
    } else {
        Status::Differs(s)
    }
}

/// The group of a refusal: the refused item, or for materials the refused type or law.
fn refusal_reason(item: &str, message: &str) -> String {
    if item.starts_with("material ") {
        match message.split_once(" is not supported") {
            Some((what, _)) => what.to_string(),
            None => format!("material: {message}"),
        }
    } else if item == "$$ELEMENTTYPE" || item == "$$COMPUTATION_METHOD" {
        format!("{item}: {message}")
    } else {
        item.to_string()
    }
}

/// Status per case from a previous document's "## Cases" table.
fn previous_statuses(doc: &str) -> Option<BTreeMap<String, String>> {
    let mut lines = doc.lines().skip_while(|l| l.trim() != "## Cases");
    lines.next()?;
    let mut table = lines
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'));
    let header = split_row(table.next()?);
    let case_col = header.iter().position(|h| h == "Case")?;
    let status_col = header.iter().position(|h| h == "Status")?;
    let mut out = BTreeMap::new();
    for l in table.skip(1) {
        let cells = split_row(l);
        let (Some(name), Some(status)) = (cells.get(case_col), cells.get(status_col)) else {
            continue;
        };
        let status = status.trim_matches('*').to_string();
        out.insert(name.trim_matches('`').to_string(), status);
    }
    Some(out)
}

/// The cells of a Markdown table row (`\|` is not a separator).
fn split_row(line: &str) -> Vec<String> {
    let mut cells = Vec::new();
    let mut cur = String::new();
    let mut chars = line.trim().trim_start_matches('|').chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                cur.push('|');
                chars.next();
            }
            '|' => cells.push(std::mem::take(&mut cur).trim().to_string()),
            _ => cur.push(c),
        }
    }
    if !cur.trim().is_empty() {
        cells.push(cur.trim().to_string());
    }
    cells
}

/// The cases using a key (or the keys of one pattern), and the keys seen.
type KeyGroup<'a> = (BTreeSet<String>, BTreeSet<&'a str>);

/// The Markdown document.
fn document(
    command: &str,
    rows: &[Row],
    keys: &BTreeMap<(KeyKind, String), BTreeSet<String>>,
) -> String {
    let mut d = String::new();
    let count = |l: &str| rows.iter().filter(|r| r.status.label() == l).count();
    let _ = writeln!(d, "# Anura3D compatibility matrix\n");
    let _ = writeln!(
        d,
        "Generated, not edited by hand: `scripts/anura3d-compat` runs\n`{command}`\n(`scripts/anura3d-compat --check` compares a fresh run with this file).\n"
    );
    let _ = writeln!(
        d,
        "Every case folder of the Anura3D benchmark suite (`Benchmarks/`, `Workshop/`) with a GOM \
and a `.CPS_001` is loaded with `mpm_solve::input::anura3d::load`. A case it refuses is listed with \
the loader's message, which names the feature. An accepted case is run; where its \
`*_expected.BMS` lists material points, every reported point is compared at the reported time \
(position, displacement, the six stresses, pore pressure; each difference relative to the \
value, or for near-zero values to 1e-3 of the largest |value| of the field's columns (position, displacement or stress)): **reproduced** when \
the worst deviation is at most 1 % and the run ends at the reported time, else **differs**. \
**ran**: accepted and run, with no expected material points to compare; **unreadable**: the \
files could not be read; **failed**: the run stopped with an error or a panic.\n"
    );
    let _ = writeln!(d, "## Summary\n");
    let _ = writeln!(
        d,
        "{} cases: {} reproduced, {} differ, {} ran without expected points, {} refused, {} unreadable, {} failed.\n",
        rows.len(),
        count("reproduced"),
        count("differs"),
        count("ran"),
        count("refused"),
        count("unreadable"),
        count("failed")
    );
    let _ = writeln!(d, "## Cases\n");
    let _ = writeln!(
        d,
        "| Case | Dimension | Element | Method | Materials (law) | Expected BMS | Status | Worst deviation, or why |"
    );
    let _ = writeln!(d, "|---|---|---|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            d,
            "| `{}` | {} | {} | {} | {} | {} | {} | {} |",
            r.name,
            cell(&r.dimension),
            cell(&r.element),
            cell(&r.method),
            cell(&r.materials),
            r.expected,
            r.status.label(),
            r.status.detail()
        );
    }
    let mut reasons: BTreeMap<&str, usize> = BTreeMap::new();
    for r in rows {
        if let Some(reason) = &r.reason {
            *reasons.entry(reason.as_str()).or_default() += 1;
        }
    }
    let mut reasons: Vec<(&str, usize)> = reasons.into_iter().collect();
    reasons.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    let _ = writeln!(d, "\n## Refusals by reason\n");
    let _ = writeln!(
        d,
        "The first thing the loader refuses in each refused case (a case may use more).\n"
    );
    let _ = writeln!(d, "| Refused | Cases |");
    let _ = writeln!(d, "|---|---|");
    for (reason, n) in reasons {
        let _ = writeln!(d, "| {} | {n} |", cell(reason));
    }
    // Keys, grouped by their table entry where it is a pattern.
    let mut groups: BTreeMap<(KeyKind, String), KeyGroup<'_>> = BTreeMap::new();
    for ((kind, key), cases) in keys {
        let name = match anura3d_keys::lookup(*kind, key) {
            Some((pattern, _)) if pattern.contains('*') => pattern.to_string(),
            _ => key.clone(),
        };
        let g = groups.entry((*kind, name)).or_default();
        g.0.extend(cases.iter().cloned());
        g.1.insert(key.as_str());
    }
    let _ = writeln!(d, "\n## Keys\n");
    let _ = writeln!(
        d,
        "Every GOM section, GOM material key and CPS key the suite uses, with the number of \
cases whose files hold it (whatever its value) and what the loader does with it, from \
`mpm_solve::input::anura3d_keys` (`*` stands for any text). **NOT CHECKED** marks keys the loader \
neither models nor refuses although they can change results.\n"
    );
    let _ = writeln!(d, "| Kind | Key | Cases | Support |");
    let _ = writeln!(d, "|---|---|---|---|");
    for ((kind, name), (cases, seen)) in &groups {
        let status = if name.contains('*') {
            anura3d_keys::lookup(*kind, seen.iter().next().copied().unwrap_or(""))
                .map_or(anura3d_keys::KeyStatus::Unknown, |e| e.1)
        } else {
            anura3d_keys::status(*kind, name)
        };
        let shown = if seen.len() > 1 {
            format!("`{name}` ({} keys)", seen.len())
        } else if name.contains('*') {
            format!("`{name}` (`{}`)", seen.iter().next().copied().unwrap_or(""))
        } else {
            format!("`{name}`")
        };
        let _ = writeln!(
            d,
            "| {} | {} | {} | {} |",
            kind.label(),
            cell(&shown),
            cases.len(),
            cell(&status.to_string())
        );
    }
    d
}
