//! Particle to grid against the point-by-point equations, in both copies.

use super::*;
use crate::element::mesh::TetMesh;
use crate::parallel::comm::SingleProcess;
use crate::parallel::gather::Layout;
use crate::parallel::team::{Pin, Team};
use crate::state::grid::LiquidNodes;
use crate::state::particles::LiquidPoints;
use mpm_shared::{generate, ElementType};

/// Points of 0 to 6 per element, inside it, with masses, velocities, stresses and pore
/// pressures of magnitudes that differ from point to point; every third element with a
/// point of material 1 (dry, its own gravity) among those of material 0 (saturated).
fn points(mesh: &TetMesh<f64>) -> Particles<f64> {
    let mut rng = crate::test_rng::uniform(11);
    let element: Vec<u32> = (0..mesh.elements() as u32)
        .flat_map(|e| std::iter::repeat_n(e, (e as usize * 5 + 3) % 7))
        .collect();
    let mut p = Particles::<f64>::at_rest(element);
    let n = p.len();
    for i in 0..n {
        let e = p.element[i] as usize;
        let corners = mesh.corners[e];
        // A point inside: barycentric weights from 0.05 up, normalised.
        let w: [f64; 4] = std::array::from_fn(|_| 0.05 + rng());
        let total: f64 = w.iter().sum();
        p.x[i] = std::array::from_fn(|a| {
            (0..4)
                .map(|k| w[k] / total * mesh.x[corners[k] as usize][a])
                .sum()
        });
        p.mass[i] = 0.5 + rng();
        p.volume[i] = 1e-3 * (0.5 + rng());
        p.v[i] = std::array::from_fn(|_| rng() - 0.5);
        p.stress[i] = std::array::from_fn(|_| 1e3 * (rng() - 0.5));
        if e % 3 == 0 && i % 2 == 1 {
            p.material[i] = 1;
        }
    }
    p.liquid = Some(LiquidPoints {
        w: (0..n)
            .map(|_| std::array::from_fn(|_| rng() - 0.5))
            .collect(),
        p: (0..n).map(|_| -1e2 * rng()).collect(),
        volume0: None,
    });
    p
}

/// Each node's mass, momentum, internal and external force, then the liquid's mass,
/// porosity-weighted mass, drag, momentum and force, summed point by point as the
/// equations of docs/design.md §4.2 write them: V (σ' + p I) ∇N for each point, and each
/// point's weight with its own material's gravity.
fn reference(
    mesh: &TetMesh<f64>,
    p: &Particles<f64>,
    gravity: &[V3<f64>],
    fluids: &[Option<Fluid<f64>>],
    liquid_gravity: V3<f64>,
) -> Vec<Vec<f64>> {
    let nodes = mesh.x.len();
    let mut out = vec![vec![0.0; nodes]; 19];
    let l = p.liquid.as_ref().unwrap();
    for i in 0..p.len() {
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let (grad, corners) = (&mesh.grad[e], &mesh.corners[e]);
        let material = p.material[i] as usize;
        let fluid = fluids[material];
        // (A dry material's points carry pore pressure 0 in a run; here they do not, and
        // their total stress takes it as the pass does.)
        let mut s = p.stress[i];
        for c in s.iter_mut().take(3) {
            *c += l.p[i];
        }
        const ROWS: [[usize; 3]; 3] = [[0, 3, 5], [3, 1, 4], [5, 4, 2]];
        for k in 0..4 {
            let node = corners[k] as usize;
            let w = p.mass[i] * n[k];
            out[0][node] += w;
            for a in 0..3 {
                let traction: f64 = (0..3).map(|b| s[ROWS[a][b]] * grad[k][b]).sum();
                out[1 + a][node] += w * p.v[i][a];
                out[4 + a][node] -= p.volume[i] * traction;
                out[7 + a][node] += w * gravity[material][a];
            }
            let Some(f) = fluid else { continue };
            let mw = f.rho_w * p.volume[i];
            out[10][node] += mw * n[k];
            out[11][node] += f.n * mw * n[k];
            out[12][node] += f.drag * p.volume[i] * n[k];
            for a in 0..3 {
                out[13 + a][node] += mw * n[k] * l.w[i][a];
                let pressure = p.volume[i] * l.p[i] * grad[k][a];
                out[16 + a][node] += mw * n[k] * liquid_gravity[a] - pressure;
                // The liquid's weight, on the mixture's external force.
                out[7 + a][node] += f.n * mw * n[k] * liquid_gravity[a];
            }
        }
    }
    out
}

/// The pass's node values in [`reference`]'s order.
fn of_grid(g: &Grid<f64>) -> Vec<Vec<f64>> {
    let l = g.liquid.as_ref().unwrap();
    let v3 = |v: &[V3<f64>], a: usize| v.iter().map(|x| x[a]).collect::<Vec<_>>();
    let mut out = vec![g.mass.clone()];
    for field in [&g.momentum, &g.f_int, &g.f_ext] {
        out.extend((0..3).map(|a| v3(field, a)));
    }
    out.extend([l.mass.clone(), l.mass_n.clone(), l.drag.clone()]);
    for field in [&l.momentum, &l.force] {
        out.extend((0..3).map(|a| v3(field, a)));
    }
    out
}

/// An element's points of every array are the arrays' runs over its range, liquid ones
/// included; a range past the arrays and arrays of different lengths are refused.
#[test]
fn point_arrays_slice_every_array_alike_and_refuse_what_does_not_fit() {
    let mesh =
        TetMesh::<f64>::new(&generate::box_mesh([2, 2, 2], [1.0; 3], ElementType::Tet4)).unwrap();
    let mut p = points(&mesh);
    let n = p.len();
    let arrays = PointArrays::new(&p, true);
    for r in [0..0, 0..n, 3..7, n - 1..n] {
        let e = arrays.element(r.clone());
        assert_eq!(e.x, &p.x[r.clone()]);
        assert_eq!(e.stress, &p.stress[r.clone()]);
        assert_eq!(e.material, &p.material[r.clone()]);
        let l = p.liquid.as_ref().unwrap();
        assert_eq!(e.pore.unwrap(), &l.p[r.clone()]);
        assert_eq!(e.w.unwrap(), &l.w[r.clone()]);
    }
    // Without the liquid's pass, no liquid velocities.
    assert!(PointArrays::new(&p, false).element(0..n).w.is_none());
    let past =
        std::panic::catch_unwind(|| PointArrays::new(&p, true).element(n - 1..n + 1).x.len());
    assert!(past.is_err());
    p.volume.pop();
    let uneven = std::panic::catch_unwind(|| PointArrays::new(&p, true).len);
    assert!(uneven.is_err());
}

/// The element totals (the stress, pore-pressure and mass sums formed once per element)
/// give the nodal values of the point-by-point equations to round-off, with several
/// points per element and two materials in some elements (one saturated, one dry, with
/// different gravity), on one and two threads, in the AVX2 and the portable copies, which
/// agree bit for bit.
#[test]
fn element_totals_give_the_point_by_point_sums() {
    let mesh = TetMesh::new(&generate::box_mesh([3, 4, 3], [1.0; 3], ElementType::Tet4)).unwrap();
    let p = points(&mesh);
    let gravity = vec![[0.0, -9.81, 0.0], [1.5, -4.0, 0.5]];
    let spec = crate::material::liquid::LiquidSpec::new(0.4, 1000.0, 2e6, 1e-12, 1e-6).unwrap();
    let fluids = vec![Some(Fluid::new(&spec)), None];
    let liquid_gravity = [0.0, -9.81, 0.0];
    let want = reference(&mesh, &p, &gravity, &fluids, liquid_gravity);
    let mut first: Option<Vec<Vec<u64>>> = None;
    for (threads, portable) in [(1, true), (1, false), (2, false), (2, true)] {
        let team = Team::new(threads, Pin::None).unwrap();
        let layout = Layout::new(&mesh, &p, threads);
        let mut slots = layout.new_slots();
        let mut g = Grid::<f64>::new(mesh.x.len());
        g.liquid = Some(LiquidNodes::new(mesh.x.len()));
        let loads = LiquidLoads {
            fluids: &fluids,
            gravity: liquid_gravity,
        };
        crate::parallel::avx2::with_portable(portable, || {
            let passes = Passes::new(&team, &layout, &mesh, &SingleProcess);
            let to = MapToGrid {
                particles: &p,
                gravity: &gravity,
                grid: &mut g,
                body: None,
                mixed: None,
                liquid: Some(loads),
                pore_weights: None,
            };
            particle_to_grid(&passes, &mut slots, to)
        });
        let got = of_grid(&g);
        for (field, (w, v)) in want.iter().zip(&got).enumerate() {
            let scale = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (node, (a, b)) in w.iter().zip(v).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-12 * scale,
                    "field {field} node {node}: {b} against {a} ({threads} threads, \
                     portable {portable})"
                );
            }
        }
        let bits: Vec<Vec<u64>> = got
            .iter()
            .map(|f| f.iter().map(|x| x.to_bits()).collect())
            .collect();
        match &first {
            None => first = Some(bits),
            Some(b) => assert!(
                *b == bits,
                "{threads} threads, portable {portable}: other bits"
            ),
        }
    }
}
