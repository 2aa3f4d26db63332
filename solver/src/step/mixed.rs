//! Mixed integration (Anura3D's `MPM-MIXED`): in an element whose material points fill at least
//! a given fraction of its volume, the internal force is integrated at the element's Gauss point
//! (weight: the element volume, stress and pore pressure: the volume-weighted means of its
//! points') and the points take the Gauss-point values back after the update; elsewhere the
//! points integrate.
//!
//! With linear tetrahedra the strain increment is uniform in an element, so the Gauss point's
//! update equals the mean of the points' updates: storing the stress at the points only and
//! averaging it each step is exact, and needs no Gauss-point state that would have to follow
//! elements as they fill and empty. The element sums are formed in
//! [`crate::step::particle_to_grid::particle_to_grid`].

use crate::element::Element;
use crate::parallel::gather::Layout;
use crate::parallel::team::{Shared, Team};
use crate::real::Real;
use crate::state::particles::Particles;

/// Per-element state, allocated once.
#[derive(Debug, Clone)]
pub struct Mixed<R: Real> {
    /// Degree of filling from which an element is full.
    pub filling: f64,
    /// Mean stress of each full element (set by particle to grid).
    pub stress: Vec<[R; 6]>,
    /// Mean pore pressure of each full element (set by particle to grid; two-phase cases).
    pub pressure: Vec<R>,
    /// Whether each element is full this step.
    pub full: Vec<bool>,
}

impl<R: Real> Mixed<R> {
    /// Buffers for `elements` elements.
    pub fn new(elements: usize, filling: f64) -> Self {
        Mixed {
            filling,
            stress: vec![[R::ZERO; 6]; elements],
            pressure: vec![R::ZERO; elements],
            full: vec![false; elements],
        }
    }

    /// After the stress update: every point of an element that was full at the start of the
    /// step takes the element's volume-weighted mean stress (the Gauss-point stress), and its
    /// mean pore pressure in two-phase cases (Anura3D keeps one pore pressure per Gauss point
    /// too).
    pub fn smooth_stresses<E: Element>(
        &self,
        team: &Team,
        layout: &Layout<R, E>,
        p: &mut Particles<R>,
    ) {
        let (active, volume) = (&p.active, &p.volume);
        if let Some(l) = &mut p.liquid {
            let (add, div) = (
                |m: &mut R, w: R, v: &R| *m += w * *v,
                |m: &mut R, v: R| *m /= v,
            );
            self.average(team, layout, active, volume, &mut l.p, add, div);
        }
        let add = |m: &mut [R; 6], w: R, v: &[R; 6]| {
            for c in 0..6 {
                m[c] += w * v[c];
            }
        };
        let div = |m: &mut [R; 6], v: R| {
            for c in m.iter_mut() {
                *c /= v;
            }
        };
        self.average(team, layout, active, volume, &mut p.stress, add, div);
    }

    /// Sets the values of the active points of every full element to their volume-weighted
    /// mean; `add(sum, weight, value)` accumulates one point, `div(sum, total)` divides by the
    /// total volume. Each thread treats its own elements.
    #[allow(clippy::too_many_arguments)]
    fn average<E: Element, T: Copy + Default + Send + Sync>(
        &self,
        team: &Team,
        layout: &Layout<R, E>,
        active: &[bool],
        volume: &[R],
        values: &mut [T],
        add: impl Fn(&mut T, R, &T) + Sync,
        div: impl Fn(&mut T, R) + Sync,
    ) {
        let values = Shared::new(values);
        team.run(|k| {
            for e in layout.element_range(k) {
                if !self.full[e] {
                    continue;
                }
                let range = layout.particles_of(e);
                // SAFETY: the particles of element e belong to this thread only.
                let x = unsafe { values.range(range.clone()) };
                let (mut v, mut mean) = (R::ZERO, T::default());
                for (j, i) in range.clone().enumerate() {
                    if active[i] {
                        v += volume[i];
                        add(&mut mean, volume[i], &x[j]);
                    }
                }
                if v > R::ZERO {
                    div(&mut mean, v);
                    for (j, i) in range.enumerate() {
                        if active[i] {
                            x[j] = mean;
                        }
                    }
                }
            }
        });
    }
}
