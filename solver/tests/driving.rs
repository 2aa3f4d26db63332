//! The pile-driving report (`jobs::driving`): the monopile job's scene (testdata/monopile.toml)
//! cut to two short blows writes `driving.csv`, a trace per blow and `driving.png`; the
//! records agree with the hammer's closed form and with each other; the report is the same
//! for any thread count and after a run killed mid-blow is resumed.

mod common;

use std::path::{Path, PathBuf};

use mpm_solve::step::load_curve::Blow;

/// The hammer of testdata/monopile.toml.
const RAM: f64 = 8.0;
const V0: f64 = 5.0;
const Z: f64 = 55800.0;
const CUSHION: f64 = 2.0e7;

/// The monopile scene with two blows 20 ms apart, the first at 10 ms, to 50 ms.
fn short_monopile(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(common::testdata("monopile.toml")).unwrap();
    let hammer = format!(
        "hammer = {{ ram_mass = {RAM:?}, velocity = {V0:?}, impedance = {Z:?}, cushion = {CUSHION:e}, blows = 10, interval = 0.1, first = 0.1 }}"
    );
    assert!(text.contains(&hammer), "the job's hammer changed:\n{text}");
    let text = text
        .replace(
            &hammer,
            &hammer
                .replace(
                    "interval = 0.1, first = 0.1",
                    "interval = 0.02, first = 0.01",
                )
                .replace("blows = 10", "blows = 2"),
        )
        .replace("end = 1.1", "end = 0.05")
        .replace("output_interval = 0.1", "output_interval = 0.05")
        .replace(
            "monopile_tri3.msh",
            &common::testdata("monopile_tri3.msh").display().to_string(),
        );
    assert!(text.contains("end = 0.05"), "the job's end time changed");
    let p = dir.join("monopile.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// The rows of a CSV file under its header, as numbers (an empty field as NaN).
fn rows(path: &Path, header: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header), "{}", path.display());
    lines
        .map(|l| {
            l.split(',')
                .map(|v| {
                    if v.is_empty() {
                        f64::NAN
                    } else {
                        v.parse().unwrap()
                    }
                })
                .collect()
        })
        .collect()
}

#[test]
fn two_blows_on_the_monopile_give_the_driving_record() {
    use mpm_solve::jobs::driving::{BLOW_HEADER, TRACE_HEADER};
    let tmp = tempfile::tempdir().unwrap();
    let input = short_monopile(tmp.path());
    let out = tmp.path().join("out");
    let o = common::solve(&input, &out, &["--threads", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let blows = rows(&out.join("driving.csv"), BLOW_HEADER);
    assert_eq!(blows.len(), 2, "two blows");
    let col = |name: &str| BLOW_HEADER.split(',').position(|c| c == name).unwrap();
    // The hammer's peak, Z v0 times the cushion blow's largest multiplier (the report's rows
    // are 0.1 ms means: a little below it).
    let blow = Blow::new(RAM, Z, Some(CUSHION));
    let peak = Z
        * V0
        * (0..10_000)
            .map(|i| blow.at(i as f64 * 1e-6))
            .fold(0.0, f64::max);
    for (k, b) in blows.iter().enumerate() {
        assert_eq!(b[col("blow")], (k + 1) as f64);
        let force = b[col("max_head_force")];
        assert!(
            force < peak && force > 0.98 * peak,
            "blow {}: {force} vs {peak}",
            k + 1
        );
        // A stress wave in the pile: at the hammer's peak the head moves at about F / Z (the
        // toe's reflection comes back after 2 L / c = 2.3 ms); a toe that gives way sends back
        // a wave that at most doubles it, on top of what rings on from a blow 20 ms before.
        let v = b[col("max_head_velocity")];
        assert!(
            v < 2.5 * force / Z,
            "blow {}: head {v} m/s, F/Z {}",
            k + 1,
            force / Z
        );
        // The pile takes part of the ram's energy (the cushion keeps the rest).
        let energy = b[col("energy")];
        assert!(
            energy > 0.0 && energy < 0.5 * RAM * V0 * V0,
            "blow {}: {energy} kJ",
            k + 1
        );
        assert!(b[col("set")] > 0.0, "blow {} drove the pile down", k + 1);
        assert!(b[col("max_base_resistance")] > 0.0 && b[col("max_shaft_resistance")] > 0.0);
        assert!(
            b[col("max_tip_excess_pore_pressure")] > 0.0,
            "the blow loads the water"
        );
        assert!(
            b[col("plug_length")] > 1.5 && b[col("plug_length")] < 2.5,
            "{}",
            b[col("plug_length")]
        );
        assert_eq!(b[col("blows_per_metre")], 1.0 / b[col("set")]);
    }
    // The tip goes down by each blow's set.
    let (a, b) = (&blows[0], &blows[1]);
    let step = b[col("tip_depth")] - a[col("tip_depth")];
    assert!(
        (step - b[col("set")]).abs() < 1e-12,
        "{step} vs {}",
        b[col("set")]
    );
    assert!(a[col("tip_depth")] > 2.0, "the tip starts 2 m deep");
    for k in 1..=2 {
        let trace = rows(&out.join(format!("blows/blow_{k:03}.csv")), TRACE_HEADER);
        assert!(trace.len() > 150, "blow {k}: a row per 0.1 ms of its 20 ms");
        let last = trace.last().unwrap();
        assert!(
            (last[0] - 0.02).abs() < 1e-4,
            "blow {k} ends after its interval: {}",
            last[0]
        );
        let at_peak = trace.iter().max_by(|a, b| a[1].total_cmp(&b[1])).unwrap();
        // The first blow strikes a pile near rest (the second one rings on from the first).
        let ratio = at_peak[2] / (at_peak[1] / Z);
        if k == 1 {
            assert!(
                (ratio - 1.0).abs() < 0.2,
                "blow 1: v / (F / Z) = {ratio} at the peak"
            );
        }
    }
    assert!(out.join("driving.png").metadata().unwrap().len() > 10_000);
}

#[test]
fn the_report_is_the_same_for_any_thread_count_and_after_a_resume_mid_blow() {
    let tmp = tempfile::tempdir().unwrap();
    let input = short_monopile(tmp.path());
    // Step 1,300 is at about 18 ms, in the first blow (10 to 30 ms).
    common::killed_and_resumed_match(&input, tmp.path(), &[("1300", "7")], "1");
}

#[test]
fn the_mesh_limits_are_reported_before_the_run() {
    // The job's moving mesh: 7 m of compressed box below the pile at Courant 0.5 take 3.5 m
    // of travel; the 0.5 m box above, 0.25 m the other way.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_mpm-solve"))
        .arg(common::testdata("monopile.toml"))
        .arg("--check")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    assert!(
        text.contains("may travel 0.250 m into the box from y = 14.5 to 15.0 m; or 3.500 m into the box from y = 0.0 to 7.0 m"),
        "{text}"
    );
}

#[test]
fn absorbing_planes_through_the_empty_cells_act_as_the_sands_own_groups() {
    // The planes x = 6 and y = 0 hold the empty cells' faces above the ground too; those take
    // no dashpot, so the planes give the groups' boundary exactly (with them, a point that
    // strayed into the far side's top cells was crushed in the job's third blow).
    let tmp = tempfile::tempdir().unwrap();
    let groups = short_monopile(tmp.path());
    let text = std::fs::read_to_string(&groups).unwrap();
    let planes = tmp.path().join("planes.toml");
    let edited = text
        .replace("physical = \"far\"", "plane = \"x = 6\"")
        .replace("physical = \"base\"", "plane = \"y = 0\"");
    assert_ne!(edited, text);
    std::fs::write(&planes, edited).unwrap();
    let (a, b) = (tmp.path().join("groups"), tmp.path().join("planes"));
    for (input, out) in [(&groups, &a), (&planes, &b)] {
        let o = common::solve(input, out, &["--threads", "2"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    for f in [
        "driving.csv",
        "particles_00000.vtu",
        "reaction.csv",
        "blows/blow_002.csv",
    ] {
        assert!(
            std::fs::read(a.join(f)).unwrap() == std::fs::read(b.join(f)).unwrap(),
            "{f} differs"
        );
    }
    // A plane of empty cells' faces only absorbs nothing: refused.
    let top = tmp.path().join("top.toml");
    std::fs::write(
        &top,
        text.replace("physical = \"base\"", "plane = \"y = 15\""),
    )
    .unwrap();
    let o = common::solve(&top, &tmp.path().join("top"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("selects only faces of elements without material points"),
        "{err}"
    );
}
