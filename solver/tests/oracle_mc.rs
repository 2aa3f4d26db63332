//! Mohr–Coulomb against Anura3D itself (issue 16, validation 2): scenes of our own (a block
//! slumping under its weight, a rough strip footing pushed into the soil) exported
//! with `--export-anura3d`, run by the Anura3D binary that `ANURA3D_ORACLE` names and by
//! `mpm-solve` on the same files, every material point compared by id at every load step.
//! While no point has reached the yield surface the two codes must agree to round-off; once
//! yielding spreads they may part by the order of the return algorithms' round-off growing
//! through the collapse, and the final geometry must agree within 1 %. Skipped, visibly, when
//! the variable is unset.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use mpm_shared::anura3d_vtk::read_step;

mod common;
use common::{run_oracle, testdata};

/// The Anura3D binary, or `None` (skipped, visibly) when `ANURA3D_ORACLE` is unset.
fn oracle() -> Option<PathBuf> {
    common::oracle("Mohr-Coulomb comparison with Anura3D")
}

/// One load step of one code: per point id, position and stress.
type Points = HashMap<u32, ([f64; 3], [f64; 6])>;

/// Principal stresses of a symmetric tensor (xx yy zz xy yz zx), ascending (closed form).
fn principal(s: &[f64; 6]) -> [f64; 3] {
    let [xx, yy, zz, xy, yz, zx] = *s;
    let p = (xx + yy + zz) / 3.0;
    let (a, b, c) = (xx - p, yy - p, zz - p);
    let j2 = (a * a + b * b + c * c) / 2.0 + xy * xy + yz * yz + zx * zx;
    if j2 <= 1e-30 {
        return [p; 3];
    }
    let j3 = a * (b * c - yz * yz) - xy * (xy * c - yz * zx) + zx * (xy * yz - b * zx);
    let r = (j2 / 3.0).sqrt();
    let cos3 = (j3 / 2.0 / r.powi(3)).clamp(-1.0, 1.0);
    let t = cos3.acos() / 3.0;
    let third = 2.0 * std::f64::consts::PI / 3.0;
    let mut v = [0.0, 1.0, 2.0].map(|k| p + 2.0 * r * (t - k * third).cos());
    v.sort_by(|x, y| x.partial_cmp(y).unwrap());
    v
}

/// The Mohr–Coulomb yield function (tension positive, σ1 ≤ σ2 ≤ σ3), as Anura3D writes it.
fn yield_mc(s: &[f64; 6], phi_deg: f64, c: f64) -> f64 {
    let [s1, _, s3] = principal(s);
    let sp = phi_deg.to_radians().sin();
    0.5 * (s3 - s1) + 0.5 * (s3 + s1) * sp - c * phi_deg.to_radians().cos()
}

/// Runs `mpm-solve` on the exported case; per load step, the points.
fn run_ours(gom: &Path, cps: &Path, out: &Path) -> Vec<Points> {
    let (case, _) = mpm_solve::input::anura3d::load(gom, cps).unwrap();
    let mut steps = Vec::new();
    mpm_solve::driver::run::run_observed::<f64>(&case, out, &Default::default(), &mut |e| {
        let p = &e.particles;
        steps.push(
            (0..p.len())
                .map(|i| (p.id[i], (p.x[i], p.stress[i])))
                .collect::<Points>(),
        );
    })
    .unwrap();
    steps
}

fn anura3d_steps(dir: &Path, name: &str, n: usize) -> Vec<Points> {
    (1..=n as u32)
        .map(|k| {
            read_step(dir, name, k)
                .unwrap()
                .iter()
                .map(|m| (m.id, (m.position, m.eff_stress_solid)))
                .collect()
        })
        .collect()
}

/// Per load step: largest position difference over `length`, largest stress difference over
/// the largest Anura3D stress, and the number of our points on the yield surface.
fn differences(
    a: &[Points],
    b: &[Points],
    length: f64,
    phi: f64,
    c: f64,
) -> Vec<(f64, f64, usize)> {
    a.iter()
        .zip(b)
        .map(|(a, b)| {
            assert_eq!(a.len(), b.len(), "different point counts");
            let scale = a
                .values()
                .flat_map(|(_, s)| s.iter().map(|v| v.abs()))
                .fold(0.0, f64::max);
            let (mut dx, mut ds, mut plastic) = (0.0f64, 0.0f64, 0);
            let mut worst = (0u32, [0.0; 6], [0.0; 6]);
            for (id, (xa, sa)) in a {
                let (xb, sb) = b.get(id).unwrap_or_else(|| panic!("point {id} missing"));
                for k in 0..3 {
                    dx = dx.max((xa[k] - xb[k]).abs());
                }
                for k in 0..6 {
                    if (sa[k] - sb[k]).abs() > ds {
                        ds = (sa[k] - sb[k]).abs();
                        worst = (*id, *sa, *sb);
                    }
                }
                // On the surface (to round-off of the stress scale): yielded.
                if yield_mc(sb, phi, c) > -1e-9 * scale {
                    plastic += 1;
                }
            }
            eprintln!(
                "worst stress at point {}: Anura3D {:?}, ours {:?}",
                worst.0, worst.1, worst.2
            );
            (dx / length, ds / scale, plastic)
        })
        .collect()
}

/// The block's extent: largest x and largest y over the points.
fn extent(p: &Points) -> (f64, f64) {
    p.values().fold((f64::MIN, f64::MIN), |(x, y), (q, _)| {
        (x.max(q[0]), y.max(q[1]))
    })
}

/// Exports `scene`, runs it in both codes and prints the per-load-step table: Anura3D's and
/// our points per load step, and the differences (positions over `length`).
fn both(bin: &Path, scene: &str, length: f64, phi: f64, c: f64) -> Compared {
    let dir = tempfile::tempdir().unwrap();
    let files =
        mpm_solve::input::export_anura3d::export_scene(&testdata(scene), dir.path()).unwrap();
    let name = files.gom.file_stem().unwrap().to_string_lossy().to_string();
    run_oracle(bin, dir.path(), &name);
    let out = tempfile::tempdir().unwrap();
    let ours = run_ours(&files.gom, &files.cps, out.path());
    let theirs = anura3d_steps(dir.path(), &name, ours.len());
    let d = differences(&theirs, &ours, length, phi, c);
    eprintln!("{scene}:");
    eprintln!(
        "| load step | position / {length} m | stress / max | our points on the yield surface |"
    );
    eprintln!("|---:|---:|---:|---:|");
    for (k, (dx, ds, n)) in d.iter().enumerate() {
        eprintln!("| {} | {dx:.1e} | {ds:.1e} | {n} |", k + 1);
    }
    Compared { theirs, ours, d }
}

/// Both codes' points per load step and their differences ([`differences`]).
struct Compared {
    theirs: Vec<Points>,
    ours: Vec<Points>,
    d: Vec<(f64, f64, usize)>,
}

/// While no point has yielded, the two codes agree to round-off.
fn elastic_steps_agree(d: &[(f64, f64, usize)]) {
    for (k, (dx, ds, n)) in d.iter().enumerate() {
        if *n == 0 {
            assert!(
                *dx <= 1e-9 && *ds <= 1e-9,
                "load step {}: elastic everywhere but position differs by {dx:.1e} and stress by {ds:.1e}",
                k + 1
            );
        }
    }
}

#[test]
fn mohr_coulomb_footing_matches_anura3d() {
    let Some(bin) = oracle() else { return };
    let (phi, c) = (20.0, 5.0);
    // Lengths over the strip's half-width.
    let Compared { theirs, ours, d } = both(&bin, "oracle_mc_footing.toml", 0.1, phi, c);
    elastic_steps_agree(&d);
    let last = d.last().unwrap();
    assert!(last.2 > 50, "only {} points yielded", last.2);
    // The footing's settlement is prescribed; the soil beside it heaves: the highest point
    // and the deepest, in both codes.
    let top = |p: &Points| p.values().map(|(x, _)| x[1]).fold(f64::MIN, f64::max);
    let low = |p: &Points| {
        p.values()
            .filter(|(x, _)| x[0] < 0.1 && x[1] > 0.3)
            .map(|(x, _)| x[1])
            .fold(f64::MAX, f64::min)
    };
    let (ta, tb) = (top(theirs.last().unwrap()), top(ours.last().unwrap()));
    let (la, lb) = (low(theirs.last().unwrap()), low(ours.last().unwrap()));
    eprintln!("final: heave top Anura3D {ta:.6} ours {tb:.6}; under the footing Anura3D {la:.6} ours {lb:.6}");
    assert!(
        last.0 <= 0.01,
        "final positions differ by {:.2} % of the half-width",
        100.0 * last.0
    );
}

#[test]
fn mohr_coulomb_block_collapse_matches_anura3d() {
    let Some(bin) = oracle() else { return };
    let (phi, c) = (20.0, 0.5);
    let Compared { theirs, ours, d } = both(&bin, "oracle_mc_block.toml", 0.3, phi, c);
    let (xa, ya) = extent(theirs.last().unwrap());
    let (xb, yb) = extent(ours.last().unwrap());
    eprintln!("final extent: Anura3D x {xa:.5} y {ya:.5}; mpm-solve x {xb:.5} y {yb:.5}");
    // The block must have yielded and slumped, or the test proves nothing about plasticity.
    let last = d.last().unwrap();
    assert!(last.2 > 0, "no point yielded");
    assert!(
        xa > 0.25,
        "the block did not slump: it reaches x = {xa} (from 0.2)"
    );
    elastic_steps_agree(&d);
    assert!(
        last.0 <= 0.01,
        "final positions differ by {:.2} % of the block height",
        100.0 * last.0
    );
    assert!((xa - xb).abs() <= 0.01 * xa, "run-out {xb} against {xa}");
    assert!((ya - yb).abs() <= 0.01 * ya, "height {yb} against {ya}");
}
