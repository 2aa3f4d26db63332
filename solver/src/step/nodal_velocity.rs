//! Prescribed velocity on nodes: a rigid footing, platen or pile modelled as mesh nodes
//! (Anura3D's `$$PRESCRIBED_NODAL_VELOCITY_*` sections, scaled by the CPS
//! `$$PRESCRIBED_VELOCITY` multiplier, and scenes' `[[velocity]]` on surfaces and planes).
//!
//! A prescribed component behaves as a fixity with a value: after the grid update its
//! acceleration is the prescribed velocity's rate over the step, value × (multiplier at the
//! step's end - multiplier at its start) / Δt, and after the MUSL re-mapping its nodal velocity
//! is value × the multiplier at the step's end. This is what Anura3D does: its acceleration
//! multiplier is the velocity multiplier's rate, the slope of a `linear` load and 0 for a
//! `step` one, whose multiplier is already at its value at t = 0 (so a sudden velocity gives
//! the points next to the nodes no jump: only the nodes move at once; a ramp from 0 carries
//! them along). The prescription overrides a fixity of the same component (Anura3D's
//! rule too); components a row does not prescribe stay free, or fixed where a fixity says so.
//! Where two rows prescribe the same component of a node, the later wins.
//!
//! The work is a loop over the short list of prescribed components on the calling thread, in
//! a fixed order, with no allocation: the results and the reaction sums
//! ([`crate::step::reaction`]) do not depend on the number of threads.

use mpm_shared::model::Body;
use mpm_shared::Model;

use crate::element::Element;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::step::constraint::{Constraint, Hook};
use crate::step::load_curve::LoadCurve;
use crate::step::moment::Moment;
use crate::step::reaction::Reaction;

/// One prescribed node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrescribedNode {
    /// The model node (0-based, in the case's node order).
    pub node: u32,
    /// The components prescribed (x, y, z).
    pub directions: [bool; 3],
    /// The velocity (m/s) at multiplier 1; only the prescribed components are used.
    pub velocity: [f64; 3],
}

/// A set of prescribed nodes with one multiplier, and one reaction.
#[derive(Debug, Clone, PartialEq)]
pub struct NodalVelocitySet {
    /// The set's name in `reaction.csv`.
    pub name: String,
    /// The rows, in the input's order (a later row for the same node and component wins).
    pub rows: Vec<PrescribedNode>,
    /// Multiplier value at full load.
    pub scale: f64,
    /// How the multiplier grows with time.
    pub curve: LoadCurve,
}

impl NodalVelocitySet {
    /// The rows with their nodes renumbered: `node_new[n]` is node n's new index.
    pub fn renumbered(mut self, node_new: &[u32]) -> Self {
        for r in &mut self.rows {
            r.node = node_new[r.node as usize];
        }
        self
    }

    /// The set's entry in the reaction list (velocity and components of its first row).
    pub fn reaction(&self) -> Reaction {
        let (v, d) = self
            .rows
            .first()
            .map_or(([0.0; 3], [false; 3]), |r| (r.velocity, r.directions));
        Reaction::new(&self.name, v, d, self.scale, self.curve.clone())
    }
}

/// The GOM sections read here (Anura3D accepts one of them per case).
pub const SECTIONS: [&str; 4] = [
    "PRESCRIBED_NODAL_VELOCITY_VOLUME",
    "PRESCRIBED_NODAL_VELOCITY_SURFACE",
    "PRESCRIBED_NODAL_VELOCITY_LINE",
    "PRESCRIBED_NODAL_VELOCITY_POINT",
];

/// A GOM section's keyword and its rows.
pub type NodalSection = (String, Vec<PrescribedNode>);

/// Reads the prescribed nodal velocities of `model`: rows `node fx fy fz vx vy vz` (node ids
/// 1-based, flags 1 for prescribed and 0 for free). Returns the section's keyword and its rows
/// (`None` when there is no section or it is empty), or the section and what is wrong with it.
/// Two sections at once are refused, as Anura3D refuses them.
pub fn read_rows(model: &Model) -> Result<Option<NodalSection>, (String, String)> {
    let present: Vec<&mpm_shared::model::Section> = model
        .sections
        .iter()
        .filter(|s| SECTIONS.contains(&s.keyword.as_str()))
        .collect();
    let Some(section) = present.first() else {
        return Ok(None);
    };
    let item = format!("$${}", section.keyword);
    if present.len() > 1 {
        return Err((
            item,
            format!(
                "prescribed nodal velocities are given in more than one section (also $${}); Anura3D accepts one of volumes, surfaces, lines or points",
                present[1].keyword
            ),
        ));
    }
    let Body::Table { rows, .. } = &section.body else {
        return Err((item, "expected a count and rows".into()));
    };
    let nodes = model.node_count();
    let mut out = Vec::with_capacity(rows.len());
    for (k, r) in rows.rows().enumerate() {
        let bad = |what: &str| {
            (
                item.clone(),
                format!(
                    "row {}: {what} (expected '{}')",
                    k + 1,
                    if model.dimension.coords() == 2 {
                        "node fx fy vx vy"
                    } else {
                        "node fx fy fz vx vy vz"
                    }
                ),
            )
        };
        let (node, directions, velocity) = crate::step::prescribed::entity_flags_velocity(
            r,
            nodes,
            "node",
            model.dimension.coords(),
        )
        .map_err(|m| bad(&m))?;
        out.push(PrescribedNode {
            node,
            directions,
            velocity,
        });
    }
    Ok((!out.is_empty()).then(|| (section.keyword.clone(), out)))
}

/// One prescribed component: computational node, component, set, value at multiplier 1.
#[derive(Debug, Clone, Copy)]
struct Entry<R> {
    node: u32,
    component: u8,
    set: u16,
    value: R,
}

/// The engine's side: the prescribed components and the per-set multipliers of the step, all
/// allocated at set-up.
#[derive(Debug, Clone)]
pub struct NodalVelocity<R: Real> {
    /// Ascending by node, then component; one entry per prescribed component.
    entries: Vec<Entry<R>>,
    /// Index of the first set in the engine's reaction list.
    first: usize,
    /// Per set: multiplier at the step's end and its rate over the step.
    now: Vec<R>,
    rate: Vec<R>,
}

impl<R: Real> NodalVelocity<R> {
    /// The prescribed components of `sets` (model nodes mapped by `node_of_model`; a node that
    /// is not a computational node, such as a mid-edge node, is left out); their reactions are
    /// entries `first..` of the engine's reaction list.
    pub fn new(sets: &[NodalVelocitySet], node_of_model: &[u32], first: usize) -> Self {
        // (node, component) → (order given, set, value); the latest given wins.
        let mut all: Vec<(u32, u8, usize, u16, f64)> = Vec::new();
        let mut order = 0;
        for (s, set) in sets.iter().enumerate() {
            for r in &set.rows {
                let n = node_of_model
                    .get(r.node as usize)
                    .copied()
                    .unwrap_or(u32::MAX);
                for d in 0..3 {
                    if r.directions[d] && n != u32::MAX {
                        all.push((n, d as u8, order, s as u16, r.velocity[d]));
                    }
                    order += 1;
                }
            }
        }
        all.sort_unstable_by_key(|e| (e.0, e.1, e.2));
        let mut entries: Vec<Entry<R>> = Vec::with_capacity(all.len());
        for (node, component, _, set, v) in all {
            let e = Entry {
                node,
                component,
                set,
                value: R::of(v),
            };
            match entries.last_mut() {
                Some(l) if l.node == node && l.component == component => *l = e,
                _ => entries.push(e),
            }
        }
        NodalVelocity {
            entries,
            first,
            now: vec![R::ZERO; sets.len()],
            rate: vec![R::ZERO; sets.len()],
        }
    }

    /// Number of prescribed nodal components.
    pub fn components(&self) -> usize {
        self.entries.len()
    }

    /// Marks the prescribed components in `fixed`, so that the grid update leaves them out of
    /// its sums and the re-mapping does not compute them (both are then overridden here).
    pub fn constrain(&self, fixed: &mut [[bool; 3]]) {
        for e in &self.entries {
            fixed[e.node as usize][e.component as usize] = true;
        }
    }

    /// After the grid update of the step `at` on the nodes `g`: the prescribed components
    /// take their acceleration, and each set's reaction becomes Σ (m a - f) over its
    /// components (`traction` × the step's multiplier: the face loads; empty nodes add
    /// nothing).
    pub fn set_accelerations(
        &mut self,
        g: &mut Grid<R>,
        traction: &[V3<R>],
        reactions: &mut [Reaction],
        at: &Moment<R>,
    ) {
        let (tm, t, dt) = (at.traction, at.time, at.dt);
        for (k, r) in reactions[self.first..self.first + self.now.len()]
            .iter_mut()
            .enumerate()
        {
            self.now[k] = R::of(r.multiplier(t + dt));
            self.rate[k] = R::of(r.rate(t, dt));
            r.force = [0.0; 3];
        }
        for e in &self.entries {
            let (n, c) = (e.node as usize, e.component as usize);
            let a = e.value * self.rate[e.set as usize];
            g.acc[n][c] = a;
            let m = g.mass[n];
            if m <= g.empty_below {
                continue;
            }
            let f = g.f_int[n][c].f64() + g.f_ext[n][c].f64() + tm.f64() * traction[n][c].f64();
            reactions[self.first + e.set as usize].force[c] += m.f64() * a.f64() - f;
        }
    }

    /// After the MUSL re-mapping: the prescribed components take their velocity.
    pub fn set_velocities(&self, g: &mut Grid<R>) {
        for e in &self.entries {
            g.vel[e.node as usize][e.component as usize] = e.value * self.now[e.set as usize];
        }
    }
}

impl<R: Real, E: Element> Constraint<R, E> for NodalVelocity<R> {
    fn name(&self) -> &'static str {
        "nodal velocity"
    }

    fn after_grid_update(&mut self, cx: &mut Hook<'_, R, E>) {
        self.set_accelerations(cx.soil, cx.traction, cx.reactions, cx.at);
    }

    fn after_remap(&mut self, cx: &mut Hook<'_, R, E>) {
        self.set_velocities(cx.soil);
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step of `dt` from `t` with face loads at multiplier `tm`.
    fn moment(tm: f64, t: f64, dt: f64) -> Moment<f64> {
        Moment {
            time: t,
            dt,
            gravity: [0.0; 3],
            traction: tm,
            liquid: 0.0,
            damping: 0.0,
            damping_rule: crate::step::grid_update::DampingRule::Anura3d,
            drag: crate::step::grid_update::Drag::Implicit,
        }
    }

    fn set(name: &str, rows: &[(u32, [bool; 3], [f64; 3])], curve: LoadCurve) -> NodalVelocitySet {
        NodalVelocitySet {
            name: name.into(),
            rows: rows
                .iter()
                .map(|&(node, directions, velocity)| PrescribedNode {
                    node,
                    directions,
                    velocity,
                })
                .collect(),
            scale: 1.0,
            curve,
        }
    }

    #[test]
    fn components_are_imposed_like_fixities_with_a_value_and_the_reaction_balances_them() {
        let sets = [
            set(
                "a",
                &[
                    (2, [false, true, false], [0.0, -1.0, 0.0]),
                    (0, [true; 3], [1.0, 2.0, 3.0]),
                ],
                LoadCurve::Step,
            ),
            // Node 0's y by the later set wins; node 3 is no computational node.
            set(
                "b",
                &[
                    (0, [false, true, false], [0.0, 5.0, 0.0]),
                    (3, [true; 3], [9.0; 3]),
                ],
                LoadCurve::ramp(1.0),
            ),
        ];
        let node_of_model = [0, 1, 2, u32::MAX];
        let mut nv = NodalVelocity::<f64>::new(&sets, &node_of_model, 1);
        assert_eq!(nv.components(), 4);
        let mut fixed = vec![[false; 3]; 3];
        nv.constrain(&mut fixed);
        assert_eq!(fixed, vec![[true; 3], [false; 3], [false, true, false]]);
        let mut g = Grid::<f64>::new(3);
        g.mass = vec![2.0, 1.0, 0.0];
        g.f_int = vec![[1.0, 1.0, 1.0], [7.0; 3], [4.0; 3]];
        g.f_ext = vec![[0.0, -0.5, 0.0], [0.0; 3], [0.0; 3]];
        let traction = vec![[0.0, 0.0, 0.25], [0.0; 3], [0.0; 3]];
        let mut reactions = vec![Reaction::new(
            "mp",
            [0.0; 3],
            [false; 3],
            1.0,
            LoadCurve::Step,
        )];
        reactions.extend(sets.iter().map(|s| s.reaction()));
        // 0.5 s from t = 0: set a is at full speed from the start (no acceleration), set b
        // ramps to half.
        nv.set_accelerations(&mut g, &traction, &mut reactions, &moment(2.0, 0.0, 0.5));
        assert_eq!(g.acc[0], [0.0, 5.0, 0.0]);
        assert_eq!(g.acc[2], [0.0, 0.0, 0.0]);
        assert_eq!(g.acc[1], [0.0; 3]);
        // m a - (f_int + f_ext + 2 traction) at node 0; node 2 is empty.
        assert_eq!(reactions[1].force, [-1.0, 0.0, -1.5]);
        assert_eq!(reactions[2].force, [0.0, 2.0 * 5.0 - 0.5, 0.0]);
        assert_eq!(reactions[0].force, [0.0; 3]);
        nv.set_velocities(&mut g);
        assert_eq!(g.vel[0], [1.0, 2.5, 3.0]);
        assert_eq!(g.vel[2], [0.0, -1.0, 0.0]);
        // Past the ramp's end, 0.5 s to 1.5 s: set b reaches full speed at 1 s.
        nv.set_accelerations(&mut g, &traction, &mut reactions, &moment(2.0, 0.5, 1.0));
        assert_eq!(g.acc[0], [0.0, 2.5, 0.0]);
        nv.set_velocities(&mut g);
        assert_eq!(g.vel[0], [1.0, 5.0, 3.0]);
    }
}
