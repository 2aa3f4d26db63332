//! Mixed integration (Anura3D's `MPM-MIXED`): in a full element the internal force is
//! integrated at the element's Gauss point (weight: the element volume, stress and pore
//! pressure: the volume-weighted means of its points') and the points take the element's mean
//! values; elsewhere the points integrate. Which elements are full, and when the points take
//! the means, follows the case's [`MixedRule`].
//!
//! With linear tetrahedra the strain increment is uniform in an element, so the Gauss point's
//! update equals the mean of the points' updates: storing the stress at the points only and
//! averaging it each step is exact, and needs no Gauss-point state that would have to follow
//! elements as they fill and empty. The element sums are formed in
//! [`crate::step::particle_to_grid::particle_to_grid`].

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::input::case::MixedRule;
use crate::parallel::gather::Layout;
use crate::parallel::team::{Shared, Team};
use crate::real::Real;
use crate::state::particles::Particles;

/// Per-element state, allocated once.
#[derive(Debug, Clone)]
pub struct Mixed<R: Real> {
    /// Degree of filling: the share of an element's volume its points must fill to be full.
    pub filling: f64,
    /// Which elements are full and when points take the means.
    pub rule: MixedRule,
    /// Under [`MixedRule::Anura3d`], per point id: whether the point started beside a face
    /// shared with an element that started empty (Anura3D's boundary particle).
    pub boundary: Vec<bool>,
    /// Mean stress of each full element (set by particle to grid).
    pub stress: Vec<[R; 6]>,
    /// Mean pore pressure of each full element (set by particle to grid; two-phase cases).
    pub pressure: Vec<R>,
    /// Whether each element is full this step.
    pub full: Vec<bool>,
}

impl<R: Real> Mixed<R> {
    /// Buffers for `elements` elements; `boundary`: under [`MixedRule::Anura3d`], the
    /// boundary points by id ([`boundary_points`]).
    pub fn new(elements: usize, filling: f64, rule: MixedRule, boundary: Vec<bool>) -> Self {
        Mixed {
            filling,
            rule,
            boundary,
            stress: vec![[R::ZERO; 6]; elements],
            pressure: vec![R::ZERO; elements],
            full: vec![false; elements],
        }
    }

    /// After the stress update, under [`MixedRule::FullAtStart`]: every point of an element
    /// that was full at the start of the step takes the element's volume-weighted mean stress
    /// (the Gauss-point stress), and its mean pore pressure in two-phase cases (Anura3D keeps
    /// one pore pressure per Gauss point too).
    pub fn after_stress<E: Element>(
        &self,
        team: &Team,
        layout: &Layout<R, E>,
        p: &mut Particles<R>,
    ) {
        if self.rule == MixedRule::FullAtStart {
            average_all(team, layout, p, Select::Full(&self.full));
        }
    }

    /// After the points are located anew, under [`MixedRule::Anura3d`]: every point of every
    /// element whose active points are of one material takes the element's volume-weighted
    /// mean stress, pore pressure and state (Anura3D's StressAndPorePressureSmoothening and
    /// StateParametersSmoothening).
    pub fn after_locate<E: Element>(
        &self,
        team: &Team,
        layout: &Layout<R, E>,
        p: &mut Particles<R>,
    ) {
        if self.rule == MixedRule::Anura3d {
            average_all(team, layout, p, Select::OneMaterial);
        }
    }
}

/// Whether an element whose active points, `points` of `p`, fill `filled` of its volume
/// `volume` is full under `rule` (`filling`: the degree of filling; `boundary`: Anura3D's
/// boundary points by id).
#[inline]
pub fn is_full<R: Real>(
    rule: MixedRule,
    boundary: &[bool],
    filling: R,
    p: &Particles<R>,
    points: std::ops::Range<usize>,
    filled: R,
    volume: R,
) -> bool {
    if filled <= R::ZERO {
        return false;
    }
    let limit = filling * volume;
    match rule {
        MixedRule::FullAtStart => filled >= limit,
        MixedRule::Anura3d => {
            let beside = points
                .clone()
                .any(|i| p.active[i] && boundary[p.id[i] as usize]);
            one_material(&p.active, &p.material, points) && !(beside && filled <= limit)
        }
    }
}

/// Whether the active points among `points` are all of one material.
fn one_material(active: &[bool], material: &[u32], points: std::ops::Range<usize>) -> bool {
    let mut m = points.filter(|&i| active[i]).map(|i| material[i]);
    let first = m.next();
    m.all(|x| Some(x) == first)
}

/// The elements whose points take their means.
enum Select<'a> {
    /// Those marked full.
    Full(&'a [bool]),
    /// Those whose active points are of one material.
    OneMaterial,
}

/// Sets the stress, pore pressure and state of the active points of every element `select`
/// takes to their volume-weighted means.
fn average_all<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    p: &mut Particles<R>,
    select: Select<'_>,
) {
    let (active, volume, material) = (&p.active, &p.volume, &p.material);
    let include = |e: usize, range: std::ops::Range<usize>| match select {
        Select::Full(full) => full[e],
        Select::OneMaterial => one_material(active, material, range),
    };
    let averages = Averages {
        team,
        layout,
        active,
        volume,
        include: &include,
    };
    if let Some(l) = &mut p.liquid {
        let add = |m: &mut [R; 1], w: R, v: &[R]| m[0] += w * v[0];
        averages.average((&mut l.p, 1), add);
    }
    let add = |m: &mut [R; 6], w: R, v: &[R]| {
        for c in 0..6 {
            m[c] += w * v[c];
        }
    };
    averages.average((p.stress.as_flattened_mut(), 6), add);
    // Anura3D averages the state too; the scenes' rule never did.
    let k = p.state_len;
    if k > 0 && matches!(select, Select::OneMaterial) {
        assert!(k <= 8, "state averaging holds up to 8 values a point");
        let add = |m: &mut [R; 8], w: R, v: &[R]| {
            for (c, v) in v.iter().enumerate() {
                m[c] += w * *v;
            }
        };
        averages.average((&mut p.state, k), add);
    }
}

/// What every set of values' averages reads: the team, the elements' points, which are
/// active and their volumes (the weights), and which elements take the means (`include`, of
/// the element's index and its points).
struct Averages<'a, E: Element, R: Real> {
    team: &'a Team,
    layout: &'a Layout<R, E>,
    active: &'a [bool],
    volume: &'a [R],
    include: &'a (dyn Fn(usize, std::ops::Range<usize>) -> bool + Sync),
}

impl<E: Element, R: Real> Averages<'_, E, R> {
    /// Sets the `width` values of each active point (`values`, `width` a point) of every
    /// element `include` selects to their volume-weighted mean; `add(sum, weight, values)`
    /// accumulates one point into a sum of `N ≥ width` values. Each thread treats its own
    /// elements.
    fn average<const N: usize>(
        &self,
        (values, width): (&mut [R], usize),
        add: impl Fn(&mut [R; N], R, &[R]) + Sync,
    ) {
        let (active, volume, layout) = (self.active, self.volume, self.layout);
        debug_assert!(width <= N && values.len() == width * volume.len());
        let values = Shared::new(values);
        self.team.run(|k| {
            for e in layout.element_range(k) {
                let range = layout.particles_of(e);
                if range.is_empty() || !(self.include)(e, range.clone()) {
                    continue;
                }
                // SAFETY: the particles of element e belong to this thread only.
                let x = unsafe { values.range(width * range.start..width * range.end) };
                let (mut v, mut mean) = (R::ZERO, [R::ZERO; N]);
                for (j, i) in range.clone().enumerate() {
                    if active[i] {
                        v += volume[i];
                        add(&mut mean, volume[i], &x[width * j..width * j + width]);
                    }
                }
                if v > R::ZERO {
                    for m in mean.iter_mut().take(width) {
                        *m /= v;
                    }
                    for (j, i) in range.enumerate() {
                        if active[i] {
                            x[width * j..width * j + width].copy_from_slice(&mean[..width]);
                        }
                    }
                }
            }
        });
    }
}

/// Anura3D's boundary particles, by point id: in every element that has points, the points
/// placed beside a face whose neighbour has none (not a face on the mesh's boundary). With one
/// point an element's point; with three in a triangle or four in a tetrahedron (point k nearest
/// corner k) those of the face's corners; with ten also the three on the face's edges (edges in
/// Anura3D's order 0–1, 0–2, 0–3, 1–2, 1–3, 2–3). `p` must be as placed: each element's points
/// together, in placement order.
pub fn boundary_points<E: Element, R: Real>(mesh: &Mesh<E, R>, p: &Particles<R>) -> Vec<bool> {
    const EDGES: [[usize; 2]; 6] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];
    let mut filled = vec![false; mesh.elements()];
    for &e in &p.element {
        filled[e as usize] = true;
    }
    let mut out = vec![false; p.id.iter().map(|&i| i as usize + 1).max().unwrap_or(0)];
    let mut start = 0;
    while start < p.len() {
        let e = p.element[start] as usize;
        let end = start
            + p.element[start..]
                .iter()
                .take_while(|&&x| x as usize == e)
                .count();
        let n = end - start;
        for (f, &across) in mesh.neighbour[e].as_ref().iter().enumerate() {
            if across == u32::MAX || filled[across as usize] {
                continue;
            }
            // Face f is the one opposite corner f.
            for k in 0..n {
                let beside = match n {
                    1 => true,
                    // Anura3D's side tables of triangles (DetermineAdjacentParticlesTRI_MP3)
                    // and tetrahedra name the points of the face's corners.
                    3 | 4 => k != f,
                    10 => match k {
                        0..=3 => k != f,
                        _ => !EDGES[k - 4].contains(&f),
                    },
                    _ => false,
                };
                if beside {
                    out[p.id[start + k] as usize] = true;
                }
            }
        }
        start = end;
    }
    out
}
