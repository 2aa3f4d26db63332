//! Finding every point's element after the points moved, and keeping them sorted by element.

use crate::element::locate::{locate_width, merge, relocate, run_inside, Found, NOTHING_FOUND};
use crate::element::Element;
use crate::parallel::team::Shared;
use crate::real::Real;

use super::{Check, Divergence, Engine, Lost, StepError};

impl<R: Real, E: Element> Engine<R, E> {
    /// Whether the points are located in the stress pass as they move (docs/design.md §4.10):
    /// unless something between the two passes bears on their elements, the mesh moving, a
    /// second body, or lost points dropped (deactivated before the mixed rule's averages and
    /// the guards read them).
    pub fn locates_in_stress_pass(&self) -> bool {
        !self.constraints.move_mesh() && self.structure.is_none() && !self.drop_lost
    }

    /// Finds every point's element (each thread walks its own points), stops at the first
    /// point (by index) that left the mesh unless such points are dropped, and keeps the points
    /// sorted by element.
    pub(super) fn locate(&mut self, dt: f64) -> Result<(), StepError> {
        self.walk_points();
        self.settle_located(dt)
    }

    /// Walks every active point from its element to the one holding it now, in chunks,
    /// recording per thread what [`locate`](Self::locate) needs ([`Outcome`]).
    pub(super) fn walk_points(&mut self) {
        let mesh = &self.mesh;
        let layout = &self.layout;
        let p = &mut self.particles;
        let elements = Shared::new(&mut p.element);
        let actives = Shared::new(&mut p.active);
        let x = &p.x;
        // Per thread: the first point it found outside (index, element), how many, and whether
        // a point changed element, over the chunks it walked.
        for o in &mut self.locate_outcome {
            *o = NOTHING_FOUND;
        }
        let outcomes = Shared::new(&mut self.locate_outcome);
        let drop_lost = self.drop_lost;
        // In chunks handed out while the walk runs (a thread slowed by its core leaves the rest
        // of its chunks to the others): the lowest lost point, the count and the moved flag
        // are the same whichever thread walks a chunk.
        self.team.run_chunks(layout.thread_chunks(), |t, c| {
            let r = layout.chunk_particles(c);
            // SAFETY: the particle ranges of the chunks are disjoint, and each chunk runs once.
            let (el, active) = unsafe { (elements.range(r.clone()), actives.range(r.clone())) };
            let mut o = NOTHING_FOUND;
            let w = locate_width::<E, R>();
            let mut skip = 0;
            for (j, i) in r.clone().enumerate() {
                if skip > 0 {
                    skip -= 1;
                    continue;
                }
                // A batch of `w` active points of one element that are all still inside it
                // (most points, most steps) is checked at once; the rest walk one by one.
                if w > 1 && j + w <= el.len() {
                    let e = el[j];
                    if (0..w).all(|q| active[j + q] && el[j + q] == e) {
                        let inside = match w {
                            4 => run_inside::<E, R, 4>(mesh, e as usize, &x[i..i + 4]),
                            3 => run_inside::<E, R, 3>(mesh, e as usize, &x[i..i + 3]),
                            _ => run_inside::<E, R, 2>(mesh, e as usize, &x[i..i + 2]),
                        };
                        if inside {
                            skip = w - 1;
                            continue;
                        }
                    }
                }
                if !active[j] {
                    continue;
                }
                match relocate(mesh, &mut o, i, &mut el[j], &x[i]) {
                    Found::In(_) => {}
                    Found::Outside(_) if drop_lost => active[j] = false,
                    Found::Outside(_) | Found::Beyond(_) => break,
                }
            }
            // SAFETY: slot t is this thread's only (a thread runs its chunks one after another).
            let mine = unsafe { &mut outcomes.range(t..t + 1)[0] };
            merge(mine, o);
        });
    }

    /// After the walk (its own pass, or fused into the stress pass): stops the run on a point
    /// that left the mesh (unless lost points are dropped), exchanges the points that crossed
    /// to other ranks, and re-sorts the points by element where any moved.
    pub(super) fn settle_located(&mut self, dt: f64) -> Result<(), StepError> {
        let drop_lost = self.drop_lost;
        let outside = self.locate_outcome.iter().map(|o| o.1).sum::<u64>();
        let outside_anywhere = self.comm.sum_count(outside);
        if !drop_lost && outside_anywhere > 0 {
            return Err(self.lost_point(dt));
        }
        self.lost += outside_anywhere;
        let mut moved = self.locate_outcome.iter().any(|o| o.2);
        if !self.partition.is_whole() {
            moved |= self.migrate();
        }
        // `moved` even when the order holds: a point moving into the next element stays in
        // order, but its element's point range must follow it (design.md §5.2).
        let permuted = self.layout.resort(
            &self.team,
            &mut self.particles,
            moved,
            &mut self.sort_scratch,
        );
        if permuted {
            // Point loads and prescribed points follow their points: old index → new index.
            if !self.point_loads.is_empty() || self.constraints.hold_points() {
                let sc = &mut self.sort_scratch;
                sc.inverse.resize(sc.order.len(), 0);
                for (new, &old) in sc.order.iter().enumerate() {
                    sc.inverse[old as usize] = new as u32;
                }
                for load in &mut self.point_loads {
                    load.0 = sc.inverse[load.0 as usize];
                }
                self.constraints.follow(&sc.inverse);
            }
        }
        Ok(())
    }

    /// The first rank's first point that left the mesh in a step of `dt`, as the error every
    /// rank stops with: a lost point, or the instability it shows, where the run was forced
    /// past Courant 1 or the point moved more than its element's size in the step (an
    /// explicit step that blew up flings points out of the mesh; a body that leaves a mesh too
    /// small for it crosses its boundary at the speed it has). Collective.
    fn lost_point(&self, dt: f64) -> StepError {
        let (mesh, p) = (&self.mesh, &self.particles);
        let mine = self
            .locate_outcome
            .iter()
            .filter(|o| o.1 > 0)
            .min()
            .map(|&((i, e), _, _)| {
                let g = mesh.global(&p.x[i]);
                let speed = p.v[i].iter().map(|v| v.f64() * v.f64()).sum::<f64>().sqrt();
                vec![
                    f64::from(p.id[i]),
                    g[0],
                    g[1],
                    g[2],
                    f64::from(self.input_element[e as usize] + 1),
                    speed * dt,
                    mesh.min_altitude[e as usize].f64(),
                ]
            })
            .unwrap_or_default();
        let mut all = Vec::new();
        self.comm.all_gather(&mine, &mut all);
        let lost = Lost {
            id: all[0] as u32,
            step: self.steps,
            time: self.time,
            x: all[1],
            y: all[2],
            z: all[3],
            element: all[4] as u32,
        };
        let (moved, size) = (all[5], all[6]);
        let courant = self.courant.0;
        if courant <= 1.0 && moved <= size {
            return lost.into();
        }
        let why = if courant > 1.0 {
            format!(
                "the run was forced past Courant 1 (Courant number {courant}): the explicit step is unstable"
            )
        } else {
            format!(
                "the point moved {:.3} times its element's size in one step (Courant number {courant}): the velocities blew up",
                moved / size
            )
        };
        StepError::Diverged(Box::new(Divergence {
            check: Check::Escaped,
            step: lost.step,
            time: lost.time,
            point: Some(lost.id),
            element: Some(lost.element),
            node: None,
            field: "step_displacement",
            value: moved,
            cause: format!(
                "{why}; material point {} left the mesh at ({}, {}, {}) having moved {moved} m in its last step (its element's smallest height: {size} m)",
                lost.id, lost.x, lost.y, lost.z
            ),
        }))
    }
}
