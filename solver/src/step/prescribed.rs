//! Prescribed velocity on material points (Anura3D's `$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME`
//! and `..._SURFACE`, scaled by the CPS `$$PRESCRIBED_VELOCITY` multiplier).
//!
//! Each row of the GOM section names an element, the velocity components it prescribes and their
//! values. At set-up, the points in the listed elements are marked: they carry the prescribed
//! velocity from then on, wherever they go. In every step the velocity is imposed three times, as
//! Anura3D does:
//!
//! 1. after the grid update, the prescribed components of the marked points are set to the
//!    prescribed value, and the nodal accelerations of the *masked* components are zeroed (the
//!    masked components are those the rows prescribe, at all four corners of every listed
//!    element), so that the FLIP update cannot change them;
//! 2. after the MUSL re-mapping, the marked points are set again and the masked nodal velocities
//!    are replaced by the mass-weighted mean velocity of the marked points in the listed elements
//!    (zero at a masked component no such point reaches), before strains, stresses and positions
//!    are updated from the nodal velocities.
//!
//! The override ignores fixities: a fixed component of a masked node moves with the prescribed
//! velocity (Anura3D's rule). Everything here runs on the calling thread over the short lists of
//! marked points and masked nodes, in a fixed order, so the results do not depend on the number
//! of threads, and the work per step is proportional to the number of marked points.

use mpm_shared::model::Body;
use mpm_shared::Model;

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::parallel::partition::Partition;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::constraint::{Constraint, Hook};
use crate::step::load_curve::LoadCurve;

/// One row `entity fx fy fz vx vy vz` of an Anura3D prescribed-velocity section (material
/// points or nodes), `entity fx fy vx vy` in a 2D model (`dim` 2): the 0-based entity (checked
/// against `count`, named `what` in messages), the direction flags and the velocity (z free and
/// zero in 2D). The error says what is wrong with the row.
pub(crate) fn entity_flags_velocity(
    r: &[mpm_shared::model::Token],
    count: usize,
    what: &str,
    dim: usize,
) -> Result<(u32, [bool; 3], [f64; 3]), String> {
    if r.len() < 1 + 2 * dim {
        return Err("too few values".into());
    }
    let entity = r[0].as_int().unwrap_or(0);
    if entity < 1 || entity as usize > count {
        return Err(format!(
            "{what} {} is not in the mesh (1..={count})",
            r[0].as_f64().unwrap_or(f64::NAN)
        ));
    }
    let mut directions = [false; 3];
    for (d, flag) in directions.iter_mut().enumerate().take(dim) {
        *flag = match r[1 + d].as_int() {
            Some(0) => false,
            Some(1) => true,
            _ => return Err("direction flags must be 0 or 1".into()),
        };
    }
    let mut velocity = [0.0; 3];
    for (d, v) in velocity.iter_mut().enumerate().take(dim) {
        *v = r[1 + dim + d]
            .as_f64()
            .filter(|v| v.is_finite())
            .ok_or_else(|| "velocities must be numbers".to_string())?;
    }
    Ok((entity as u32 - 1, directions, velocity))
}

/// One row of a prescribed-velocity section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrescribedElement {
    /// The element (0-based, in the case's element order).
    pub element: u32,
    /// The components the row prescribes (x, y, z).
    pub directions: [bool; 3],
    /// The prescribed velocity (m/s) at multiplier 1; only the prescribed components are used.
    pub velocity: [f64; 3],
}

/// The prescribed velocities of a case.
#[derive(Debug, Clone, PartialEq)]
pub struct PrescribedVelocity {
    /// The set's name in `reaction.csv` (the GOM section's keyword, or the scene entry's name).
    pub name: String,
    /// The rows, in the input's order (a later row for the same element wins).
    pub rows: Vec<PrescribedElement>,
    /// Multiplier value at full load.
    pub scale: f64,
    /// How the multiplier grows with time.
    pub curve: LoadCurve,
}

impl PrescribedVelocity {
    /// The multiplier at time `t`.
    pub fn multiplier(&self, t: f64) -> f64 {
        self.scale * self.curve.at(t)
    }

    /// The components every row prescribes (all rows prescribe the same ones, see
    /// [`read_rows`]).
    pub fn directions(&self) -> [bool; 3] {
        self.rows.first().map_or([false; 3], |r| r.directions)
    }

    /// The set's entry in the reaction list (velocity of its first row).
    pub fn reaction(&self) -> crate::step::reaction::Reaction {
        let v = self.rows.first().map_or([0.0; 3], |r| r.velocity);
        crate::step::reaction::Reaction::new(
            &self.name,
            v,
            self.directions(),
            self.scale,
            self.curve.clone(),
        )
    }

    /// The rows of the elements `partition` owns, numbered locally (all of them, unchanged, on
    /// one process).
    pub fn owned_by(mut self, partition: &Partition) -> Self {
        if !partition.is_whole() {
            self.rows.retain_mut(|r| {
                partition
                    .local_element(r.element as usize)
                    .map(|l| r.element = l as u32)
                    .is_some()
            });
        }
        self
    }

    /// The rows with their elements renumbered: `new_of_old[e]` is element e's new index.
    pub fn renumbered(mut self, new_of_old: &[u32]) -> Self {
        for r in &mut self.rows {
            r.element = new_of_old[r.element as usize];
        }
        self
    }
}

/// The GOM sections read here.
pub const SECTIONS: [&str; 2] = [
    "PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME",
    "PRESCRIBED_MATERIAL_POINT_VELOCITY_SURFACE",
];

/// Reads the prescribed-velocity rows of `model` (`element fx fy fz vx vy vz`, element ids
/// 1-based, flags 1 for prescribed and 0 for free). Returns the rows (none when neither section
/// is present), or the section and what is wrong with it.
///
/// Refused, each for a reason Anura3D gives or would hide:
/// * both sections at once (Anura3D refuses this too);
/// * rows that prescribe different components: Anura3D gives the points of each row the
///   components of that row *and of all rows before it* (its flags accumulate), with that row's
///   values, which this solver does not reproduce.
pub fn read_rows(model: &Model) -> Result<Vec<PrescribedElement>, (String, String)> {
    let present: Vec<&mpm_shared::model::Section> = model
        .sections
        .iter()
        .filter(|s| SECTIONS.contains(&s.keyword.as_str()))
        .collect();
    let Some(section) = present.first() else {
        return Ok(Vec::new());
    };
    let item = format!("$${}", section.keyword);
    if present.len() > 1 {
        return Err((
            item,
            "prescribed material-point velocities are given more than once (on volumes and surfaces); give them in one section, as Anura3D requires".into(),
        ));
    }
    let Body::Table { rows, .. } = &section.body else {
        return Err((item, "expected a count and rows".into()));
    };
    let elements = model.element_count();
    let mut out = Vec::with_capacity(rows.len());
    for (k, r) in rows.rows().enumerate() {
        let bad = |what: &str| {
            (
                item.clone(),
                format!(
                    "row {}: {what} (expected '{}')",
                    k + 1,
                    if model.dimension.coords() == 2 {
                        "element fx fy vx vy"
                    } else {
                        "element fx fy fz vx vy vz"
                    }
                ),
            )
        };
        let (element, directions, velocity) =
            entity_flags_velocity(r, elements, "element", model.dimension.coords())
                .map_err(|m| bad(&m))?;
        out.push(PrescribedElement {
            element,
            directions,
            velocity,
        });
    }
    if let Some(k) = out.iter().position(|r| r.directions != out[0].directions) {
        return Err((
            item,
            format!(
                "row {} prescribes other components than row 1; Anura3D would also impose the earlier rows' components on its points, which is not reproduced here: give every row the same direction flags",
                k + 1
            ),
        ));
    }
    Ok(out)
}

/// The engine's side: marked points, masked nodes and the scratch of the nodal mean, all
/// allocated at set-up.
#[derive(Debug, Clone)]
pub struct Prescribed<R: Real> {
    /// The multiplier: scale × curve (Anura3D's `PRESCRIBED_VELOCITY`).
    scale: f64,
    curve: LoadCurve,
    /// Prescribed components.
    directions: [bool; 3],
    /// Listed elements, ascending, without repeats.
    elements: Vec<u32>,
    /// Corner nodes of the listed elements (the masked nodes), ascending, without repeats.
    nodes: Vec<u32>,
    /// Marked points: current index and prescribed velocity at multiplier 1, by ascending index.
    points: Vec<(u32, V3<R>)>,
    /// Per masked node: whether a point contributed yet, Σ m N, the first contributing
    /// velocity, and Σ m N (v - first).
    seen: Vec<bool>,
    mass: Vec<R>,
    first: Vec<V3<R>>,
    sum: Vec<V3<R>>,
}

impl<R: Real> Prescribed<R> {
    /// Marks the points of the listed elements (`p` as placed, before any step).
    pub fn new<E: Element>(spec: &PrescribedVelocity, mesh: &Mesh<E, R>, p: &Particles<R>) -> Self {
        // By element; a later row for the same element wins, as in Anura3D.
        let mut velocity_of: Vec<(u32, [f64; 3])> =
            spec.rows.iter().map(|r| (r.element, r.velocity)).collect();
        velocity_of.sort_by_key(|&(e, _)| e);
        let mut k = 0;
        for j in 0..velocity_of.len() {
            if k > 0 && velocity_of[k - 1].0 == velocity_of[j].0 {
                velocity_of[k - 1] = velocity_of[j];
            } else {
                velocity_of[k] = velocity_of[j];
                k += 1;
            }
        }
        velocity_of.truncate(k);
        let elements: Vec<u32> = velocity_of.iter().map(|&(e, _)| e).collect();
        let mut nodes: Vec<u32> = elements
            .iter()
            .flat_map(|&e| mesh.corners[e as usize].as_ref().iter().copied())
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        let points = (0..p.len())
            .filter_map(|i| {
                let k = elements.binary_search(&p.element[i]).ok()?;
                Some((i as u32, velocity_of[k].1.map(R::of)))
            })
            .collect();
        let n = nodes.len();
        Prescribed {
            scale: spec.scale,
            curve: spec.curve.clone(),
            directions: spec.directions(),
            elements,
            nodes,
            points,
            seen: vec![false; n],
            mass: vec![R::ZERO; n],
            first: vec![[R::ZERO; 3]; n],
            sum: vec![[R::ZERO; 3]; n],
        }
    }

    /// The multiplier at time `t` (as [`PrescribedVelocity::multiplier`]).
    pub fn multiplier(&self, t: f64) -> f64 {
        self.scale * self.curve.at(t)
    }

    /// Number of marked points.
    pub fn marked_points(&self) -> usize {
        self.points.len()
    }

    /// The masked nodes (computational node ids, ascending).
    pub fn masked_nodes(&self) -> &[u32] {
        &self.nodes
    }

    /// Sets the prescribed components of the marked points to `scale` times their value.
    fn impose_on_points(&self, p: &mut Particles<R>, scale: R) {
        for &(i, v) in &self.points {
            let i = i as usize;
            if !p.active[i] {
                continue;
            }
            for d in 0..3 {
                if self.directions[d] {
                    p.v[i][d] = scale * v[d];
                }
            }
        }
    }

    /// After the grid update: the marked points take the prescribed velocity (`scale`: the
    /// multiplier now) and the masked components have zero acceleration.
    pub fn override_accelerations(&self, g: &mut Grid<R>, p: &mut Particles<R>, scale: R) {
        self.impose_on_points(p, scale);
        for &n in &self.nodes {
            for d in 0..3 {
                if self.directions[d] {
                    g.acc[n as usize][d] = R::ZERO;
                }
            }
        }
    }

    /// The prescribed components.
    pub fn directions(&self) -> [bool; 3] {
        self.directions
    }

    /// The reaction after the grid update: the masked components' accelerations are zeroed,
    /// so it is -Σ f over them (f = f_int + f_ext + `traction` × `tm`), by ascending node, at
    /// nodes that are not empty.
    pub fn reaction(&self, g: &Grid<R>, traction: &[V3<R>], tm: R) -> [f64; 3] {
        let mut out = [0.0; 3];
        for &n in &self.nodes {
            let n = n as usize;
            if g.mass[n] <= g.empty_below {
                continue;
            }
            for d in 0..3 {
                if self.directions[d] {
                    out[d] -=
                        g.f_int[n][d].f64() + g.f_ext[n][d].f64() + tm.f64() * traction[n][d].f64();
                }
            }
        }
        out
    }

    /// After the MUSL re-mapping: the marked points take the prescribed velocity again, and the
    /// masked nodal velocities become the mass-weighted mean of the marked points in the listed
    /// elements (zero where none contributes). The mean is taken relative to the first
    /// contributing point's velocity, so that a uniform prescribed velocity is reproduced exactly.
    pub fn override_velocities<E: Element>(
        &mut self,
        mesh: &Mesh<E, R>,
        g: &mut Grid<R>,
        p: &mut Particles<R>,
        scale: R,
    ) {
        self.impose_on_points(p, scale);
        self.mean_of_marked(mesh, p);
        for (s, &n) in self.nodes.iter().enumerate() {
            let v = self.mean(s);
            for d in 0..3 {
                if self.directions[d] {
                    g.vel[n as usize][d] = v[d];
                }
            }
        }
    }

    /// The masked nodes' mean velocity of the marked points in the listed elements, as they
    /// move now (Σ m N v / Σ m N per node, relative to the first contributing point's velocity),
    /// for [`Prescribed::masked`].
    pub fn mean_of_marked<E: Element>(&mut self, mesh: &Mesh<E, R>, p: &Particles<R>) {
        self.seen.fill(false);
        self.mass.fill(R::ZERO);
        for &(i, _) in &self.points {
            let i = i as usize;
            let e = p.element[i];
            if !p.active[i] || self.elements.binary_search(&e).is_err() {
                continue;
            }
            let e = e as usize;
            let n = mesh.shape(e, &p.x[i]);
            let n = n.as_ref();
            let v = p.v[i];
            for k in 0..E::NODES {
                let Ok(s) = self.nodes.binary_search(&mesh.corners[e].as_ref()[k]) else {
                    continue;
                };
                let w = p.mass[i] * n[k];
                if !self.seen[s] {
                    self.seen[s] = true;
                    self.first[s] = v;
                    self.sum[s] = [R::ZERO; 3];
                }
                self.mass[s] += w;
                for d in 0..3 {
                    self.sum[s][d] += w * (v[d] - self.first[s][d]);
                }
            }
        }
    }

    /// Masked node `s`'s (index into [`Prescribed::masked_nodes`]) mean velocity from the last
    /// [`Prescribed::mean_of_marked`] (zero where no marked point contributes).
    fn mean(&self, s: usize) -> V3<R> {
        let m = self.mass[s];
        if self.seen[s] && m != R::ZERO {
            [0, 1, 2].map(|d| self.first[s][d] + self.sum[s][d] / m)
        } else {
            [R::ZERO; 3]
        }
    }

    /// At a masked node (computational id), the prescribed components and the marked points'
    /// mean velocity from the last [`Prescribed::mean_of_marked`]; `None` elsewhere.
    pub fn masked(&self, node: u32) -> Option<([bool; 3], V3<R>)> {
        let s = self.nodes.binary_search(&node).ok()?;
        Some((self.directions, self.mean(s)))
    }

    /// Follows a re-sort of the points: `new_of_old[i]` is point i's new index.
    pub fn follow(&mut self, new_of_old: &[u32]) {
        for pt in &mut self.points {
            pt.0 = new_of_old[pt.0 as usize];
        }
        self.points.sort_unstable_by_key(|pt| pt.0);
    }
}

impl<R: Real, E: Element> Constraint<R, E> for Prescribed<R> {
    fn name(&self) -> &'static str {
        "prescribed velocity"
    }

    /// The marked points take the prescribed velocity, the masked components no acceleration,
    /// and the first reaction is their force.
    fn after_grid_update(&mut self, cx: &mut Hook<'_, R, E>) {
        let pm = R::of(self.multiplier(cx.at.end()));
        self.override_accelerations(cx.soil, cx.particles, pm);
        cx.reactions[0].force = self.reaction(cx.soil, cx.traction, cx.at.traction);
    }

    fn after_remap(&mut self, cx: &mut Hook<'_, R, E>) {
        let pm = R::of(self.multiplier(cx.at.end()));
        self.override_velocities(cx.mesh, cx.soil, cx.particles, pm);
    }

    fn holds_points(&self) -> bool {
        true
    }

    fn follow(&mut self, new_of_old: &[u32]) {
        Prescribed::follow(self, new_of_old);
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}
