//! A test basis whose points touch more nodes than their element's corners ([`Spread`]), and
//! the tests that drive particle to grid and grid to particle through the stencil passes with
//! it: the seam of [`crate::basis`] proven on a basis the element kernels cannot take.

use crate::basis::linear::Linear;
use crate::basis::{Basis, Stencil};
use crate::element::mesh::{Mesh, TetMesh};
use crate::element::Element;
use crate::material::liquid::{Fluid, LiquidSpec};
use crate::parallel::comm::SingleProcess;
use crate::parallel::gather::Layout;
use crate::parallel::reach::Reach;
use crate::parallel::team::{Pin, Team};
use crate::real::V3;
use crate::state::grid::{Grid, LiquidNodes};
use crate::state::particles::{LiquidPoints, Particles};
use crate::step::grid_to_particle::{grid_to_particle, LiquidRemap, Remap};
use crate::step::particle_to_grid::{particle_to_grid, LiquidLoads, MapToGrid};
use crate::step::passes::Passes;
use mpm_shared::{generate, ElementType};

/// A partition of unity over an element's corners and its face neighbours' (at most 8 nodes for
/// a tetrahedron inside the mesh): half the element's own shape function at its corners, plus
/// an even share of the other half at every node of the set. Its gradients are half the
/// element's at its corners and zero elsewhere, so they sum to zero as a partition of unity's
/// must. Not a basis to compute with (its gradients are not its weights'), but one whose
/// points reach past their element, which the stencil passes must take.
pub struct Spread {
    /// Per element, its corners and then its neighbours' other nodes, once each.
    nodes: Vec<Vec<u32>>,
}

impl Spread {
    /// The node sets of `mesh`'s elements.
    pub fn new<E: Element, R: crate::real::Real>(mesh: &Mesh<E, R>) -> Self {
        let nodes = (0..mesh.elements())
            .map(|e| {
                let mut set: Vec<u32> = mesh.corners[e].as_ref().to_vec();
                for &across in mesh.neighbour[e].as_ref() {
                    if (across as usize) < mesh.elements() {
                        for &n in mesh.corners[across as usize].as_ref() {
                            if !set.contains(&n) {
                                set.push(n);
                            }
                        }
                    }
                }
                set
            })
            .collect();
        Spread { nodes }
    }
}

impl<E: Element, R: crate::real::Real> Basis<E, R> for Spread {
    const LINEAR: bool = false;

    fn stencil(&self, mesh: &Mesh<E, R>, e: usize, x: &V3<R>, out: &mut Stencil<R>) {
        out.clear();
        let (n, grad) = (mesh.shape(e, x), mesh.grad[e].as_ref());
        let set = &self.nodes[e];
        let half = R::of(0.5);
        let even = half / R::of(set.len() as f64);
        for (k, &node) in set.iter().enumerate() {
            if k < E::NODES {
                let g = grad[k].map(|c| half * c);
                out.push(node, half * n.as_ref()[k] + even, g);
            } else {
                out.push(node, even, [R::ZERO; 3]);
            }
        }
    }

    fn reach(&self, _mesh: &Mesh<E, R>, e: usize, out: &mut Vec<u32>) {
        out.clear();
        out.extend_from_slice(&self.nodes[e]);
    }
}

/// The linear element through the stencil passes: its stencils, without its element kernels.
struct LinearStencils;

impl<E: Element, R: crate::real::Real> Basis<E, R> for LinearStencils {
    const LINEAR: bool = false;

    fn stencil(&self, mesh: &Mesh<E, R>, e: usize, x: &V3<R>, out: &mut Stencil<R>) {
        Linear.stencil(mesh, e, x, out);
    }

    fn reach(&self, mesh: &Mesh<E, R>, e: usize, out: &mut Vec<u32>) {
        Linear.reach(mesh, e, out);
    }
}

/// A mesh of 4 × 3 × 3 cells of tetrahedra with 0 to 5 points per element, inside it, with
/// masses, velocities, stresses, liquid velocities and pore pressures that differ from point
/// to point (every fourth element's points dry).
fn scene() -> (TetMesh<f64>, Particles<f64>) {
    let mesh = TetMesh::new(&generate::box_mesh([4, 3, 3], [1.0; 3], ElementType::Tet4)).unwrap();
    let mut rng = crate::test_rng::uniform(23);
    let element: Vec<u32> = (0..mesh.elements() as u32)
        .flat_map(|e| std::iter::repeat_n(e, (e as usize * 3 + 1) % 6))
        .collect();
    let mut p = Particles::<f64>::at_rest(element);
    let n = p.len();
    for i in 0..n {
        let e = p.element[i] as usize;
        let corners = mesh.corners[e];
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
        if e % 4 == 3 {
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
    (mesh, p)
}

/// Material 0 saturated, material 1 dry.
fn fluids() -> Vec<Option<Fluid<f64>>> {
    let spec = LiquidSpec::new(0.4, 1000.0, 2e6, 1e-12, 1e-6).unwrap();
    vec![Some(Fluid::new(&spec)), None]
}

/// The gravity of each material, and the liquid's.
const GRAVITY: [V3<f64>; 2] = [[0.0, -9.81, 0.0], [0.5, -4.0, 0.25]];

/// Particle to grid of `p` with `basis` (both phases).
fn mapped<B: Basis<crate::element::tet4::Tet4, f64>>(
    mesh: &TetMesh<f64>,
    p: &Particles<f64>,
    basis: &B,
) -> Grid<f64> {
    // Three threads: the stencil passes' sums split by node ranges (`Reach`).
    let team = Team::new(3, Pin::None).unwrap();
    let layout = Layout::new(mesh, p, 3);
    let reach = Reach::new(basis, mesh, &layout, 3);
    let mut slots = layout.new_slots();
    let mut g = Grid::<f64>::new(mesh.x.len());
    g.liquid = Some(LiquidNodes::new(mesh.x.len()));
    let fluids = fluids();
    let passes = Passes::new(&team, &layout, mesh, &SingleProcess).with_basis(basis, &reach);
    let to = MapToGrid {
        particles: p,
        gravity: &GRAVITY,
        grid: &mut g,
        body: None,
        mixed: None,
        liquid: Some(LiquidLoads {
            fluids: &fluids,
            gravity: GRAVITY[0],
        }),
        pore_weights: None,
    };
    particle_to_grid(&passes, &mut slots, to);
    g
}

/// Grid to particle of `p` from `g` with `basis` (FLIP, or blended with `pic`), both phases.
fn remapped<B: Basis<crate::element::tet4::Tet4, f64>>(
    mesh: &TetMesh<f64>,
    (p, g): (&mut Particles<f64>, &mut Grid<f64>),
    basis: &B,
    pic: f64,
) {
    // Three threads: the stencil passes' sums split by node ranges (`Reach`).
    let team = Team::new(3, Pin::None).unwrap();
    let layout = Layout::new(mesh, p, 3);
    let reach = Reach::new(basis, mesh, &layout, 3);
    let mut slots = layout.new_slots();
    let fluids = fluids();
    let fixed = vec![[false; 3]; mesh.x.len()];
    let passes = Passes::new(&team, &layout, mesh, &SingleProcess).with_basis(basis, &reach);
    let remap = Remap {
        particles: p,
        grid: g,
        fixed: &fixed,
        dt: 1e-3,
        pic,
        guard: None,
        body: None,
        begin: true,
        liquid: Some(LiquidRemap {
            fluids: &fluids,
            fixed: &fixed,
        }),
    };
    grid_to_particle(&passes, &mut slots, remap);
}

/// `a` and `b` within `tolerance` of the largest magnitude of `a`, value by value.
fn close(what: &str, a: &[f64], b: &[f64], tolerance: f64) {
    assert_eq!(a.len(), b.len(), "{what}");
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tolerance * scale,
            "{what} {i}: {y} against {x}"
        );
    }
}

/// Every nodal field of particle to grid, flattened.
fn fields(g: &Grid<f64>) -> Vec<(&'static str, Vec<f64>)> {
    let l = g.liquid.as_ref().unwrap();
    let flat = |v: &[V3<f64>]| v.as_flattened().to_vec();
    vec![
        ("mass", g.mass.clone()),
        ("momentum", flat(&g.momentum)),
        ("internal force", flat(&g.f_int)),
        ("external force", flat(&g.f_ext)),
        ("liquid mass", l.mass.clone()),
        ("porosity-weighted liquid mass", l.mass_n.clone()),
        ("drag", l.drag.clone()),
        ("liquid momentum", flat(&l.momentum)),
        ("liquid force", flat(&l.force)),
    ]
}

/// The stencil passes with the linear element's stencils give the element kernels' nodal sums
/// and updated velocities, to round-off (the kernels form the internal force and the weight
/// once per element, the stencils point by point): both phases, two materials.
#[test]
fn the_stencil_passes_give_the_element_kernels_sums() {
    let (mesh, p) = scene();
    let kernels = mapped(&mesh, &p, &Linear);
    let stencils = mapped(&mesh, &p, &LinearStencils);
    for ((what, a), (_, b)) in fields(&kernels).iter().zip(&fields(&stencils)) {
        close(what, a, b, 1e-12);
    }
    let (mut pk, mut ps) = (p.clone(), p.clone());
    let (mut gk, mut gs) = (kernels.clone(), kernels);
    for g in [&mut gk, &mut gs] {
        g.empty_below = 1e-12;
        for (n, a) in g.acc.iter_mut().enumerate() {
            *a = [0.1 * n as f64, -1.0, 0.5];
        }
        let l = g.liquid.as_mut().unwrap();
        for (n, a) in l.acc.iter_mut().enumerate() {
            *a = [0.5, -0.02 * n as f64, 0.25];
        }
    }
    for pic in [0.0, 0.3] {
        remapped(&mesh, (&mut pk, &mut gk), &Linear, pic);
        remapped(&mesh, (&mut ps, &mut gs), &LinearStencils, pic);
        close(
            "velocities",
            pk.v.as_flattened(),
            ps.v.as_flattened(),
            1e-14,
        );
        let (lk, ls) = (pk.liquid.as_ref().unwrap(), ps.liquid.as_ref().unwrap());
        close(
            "liquid velocities",
            lk.w.as_flattened(),
            ls.w.as_flattened(),
            1e-14,
        );
        close(
            "nodal velocities",
            gk.vel.as_flattened(),
            gs.vel.as_flattened(),
            1e-12,
        );
        let (lk, ls) = (gk.liquid.as_ref().unwrap(), gs.liquid.as_ref().unwrap());
        close(
            "liquid nodal velocities",
            lk.vel.as_flattened(),
            ls.vel.as_flattened(),
            1e-12,
        );
    }
}

/// A basis whose points touch up to eight nodes: particle to grid keeps the points' mass and
/// momentum (and the liquid's), their internal forces balance, their weight is the points';
/// a rigid translation maps to the nodes as itself, and grid to particle moves the points
/// and the nodes with a uniform acceleration as a rigid body.
#[test]
fn a_basis_past_the_element_keeps_mass_momentum_and_a_rigid_translation() {
    let (mesh, mut p) = scene();
    let spread = Spread::new(&mesh);
    let mut s = Stencil::default();
    let centre = (0..mesh.elements())
        .max_by_key(|&e| spread.nodes[e].len())
        .unwrap();
    Basis::<_, f64>::stencil(&spread, &mesh, centre, &mesh.x[0], &mut s);
    assert_eq!(
        s.len(),
        8,
        "an inner tetrahedron's and its neighbours' nodes"
    );
    let g = mapped(&mesh, &p, &spread);
    let fluids = fluids();
    let l = p.liquid.as_ref().unwrap();
    let total = |v: &[f64]| v.iter().sum::<f64>();
    let sum3 = |v: &[V3<f64>], a: usize| v.iter().map(|x| x[a]).sum::<f64>();
    let mass: f64 = total(&p.mass);
    let liquid_mass: f64 = (0..p.len())
        .filter_map(|i| fluids[p.material[i] as usize].map(|f| f.rho_w * p.volume[i]))
        .sum();
    assert!((total(&g.mass) - mass).abs() < 1e-12 * mass);
    let gl = g.liquid.as_ref().unwrap();
    assert!((total(&gl.mass) - liquid_mass).abs() < 1e-12 * liquid_mass);
    for a in 0..3 {
        let momentum: f64 = (0..p.len()).map(|i| p.mass[i] * p.v[i][a]).sum();
        assert!((sum3(&g.momentum, a) - momentum).abs() < 1e-12 * mass);
        let weight: f64 = (0..p.len())
            .map(|i| {
                let m = p.material[i] as usize;
                let liquid = fluids[m].map_or(0.0, |f| f.n * f.rho_w * p.volume[i]);
                (p.mass[i] + liquid) * GRAVITY[m][a]
            })
            .sum();
        assert!((sum3(&g.f_ext, a) - weight).abs() < 1e-12 * mass * 10.0);
        let stress: f64 = (0..p.len())
            .map(|i| p.stress[i][0].abs() * p.volume[i])
            .sum();
        assert!(
            sum3(&g.f_int, a).abs() < 1e-12 * stress,
            "internal forces balance"
        );
        let momentum_w: f64 = (0..p.len())
            .filter_map(|i| {
                fluids[p.material[i] as usize].map(|f| f.rho_w * p.volume[i] * l.w[i][a])
            })
            .sum();
        assert!((sum3(&gl.momentum, a) - momentum_w).abs() < 1e-12 * liquid_mass);
    }
    // A rigid translation: every point at one velocity, the nodes at it too.
    let (v0, acc) = ([0.3, -0.2, 0.1], [1.5, -9.81, 0.5]);
    p.v.iter_mut().for_each(|v| *v = v0);
    let mut g = mapped(&mesh, &p, &spread);
    g.empty_below = 1e-12;
    for (n, m) in g.mass.iter().enumerate() {
        if *m > g.empty_below {
            close("nodal velocity", &v0, &g.momentum[n].map(|c| c / m), 1e-13);
        }
    }
    g.acc.iter_mut().for_each(|a| *a = acc);
    g.liquid
        .as_mut()
        .unwrap()
        .acc
        .iter_mut()
        .for_each(|a| *a = acc);
    remapped(&mesh, (&mut p, &mut g), &spread, 0.0);
    let v1: V3<f64> = std::array::from_fn(|a| v0[a] + 1e-3 * acc[a]);
    for v in &p.v {
        close("point velocity", &v1, v, 1e-13);
    }
    for (n, v) in g.vel.iter().enumerate() {
        if g.mass[n] > g.empty_below {
            close("nodal velocity after", &v1, v, 1e-13);
        }
    }
}
