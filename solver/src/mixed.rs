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
//! [`crate::particle_to_grid::particle_to_grid`].

use crate::gather::Layout;
use crate::particles::Particles;
use crate::real::Real;
use crate::team::{Shared, Team};

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
    pub fn smooth_stresses(&self, team: &Team, layout: &Layout<R>, p: &mut Particles<R>) {
        if let Some(l) = &mut p.liquid {
            let pressure = Shared::new(&mut l.p);
            let (active, volume) = (&p.active, &p.volume);
            team.run(|k| {
                for e in layout.element_ranges[k].clone() {
                    if !self.full[e] {
                        continue;
                    }
                    let range = layout.particles_of(e);
                    // SAFETY: the particles of element e belong to this thread only.
                    let pe = unsafe { pressure.range(range.clone()) };
                    let (mut v, mut mean) = (R::ZERO, R::ZERO);
                    for (j, i) in range.clone().enumerate() {
                        if active[i] {
                            v += volume[i];
                            mean += volume[i] * pe[j];
                        }
                    }
                    if v > R::ZERO {
                        mean /= v;
                        for (j, i) in range.enumerate() {
                            if active[i] {
                                pe[j] = mean;
                            }
                        }
                    }
                }
            });
        }
        let stress = Shared::new(&mut p.stress);
        let (active, volume) = (&p.active, &p.volume);
        team.run(|k| {
            for e in layout.element_ranges[k].clone() {
                if !self.full[e] {
                    continue;
                }
                let range = layout.particles_of(e);
                // SAFETY: the particles of element e belong to this thread only.
                let s = unsafe { stress.range(range.clone()) };
                let (mut v, mut mean) = (R::ZERO, [R::ZERO; 6]);
                for (j, i) in range.clone().enumerate() {
                    if active[i] {
                        v += volume[i];
                        for c in 0..6 {
                            mean[c] += volume[i] * s[j][c];
                        }
                    }
                }
                if v > R::ZERO {
                    for c in mean.iter_mut() {
                        *c /= v;
                    }
                    for (j, i) in range.enumerate() {
                        if active[i] {
                            s[j] = mean;
                        }
                    }
                }
            }
        });
    }
}
