//! Mixed integration (Anura3D's `MPM-MIXED`): in an element whose material points fill at least
//! a given fraction of its volume, the internal force is integrated at the element's Gauss point
//! (weight: the element volume, stress: the volume-weighted mean of its points' stresses) and the
//! points take that Gauss-point stress back after the update; elsewhere the points integrate.
//!
//! With linear tetrahedra the strain increment is uniform in an element, so the Gauss point's
//! update equals the mean of the points' updates: storing the stress at the points only and
//! averaging it each step is exact, and needs no Gauss-point state that would have to follow
//! elements as they fill and empty.

use crate::grid::Grid;
use crate::mesh::TetMesh;
use crate::particles::Particles;
use crate::real::Real;

/// Per-element sums, allocated once.
#[derive(Debug, Clone)]
pub struct Mixed<R: Real> {
    /// Degree of filling from which an element is full.
    pub filling: f64,
    /// Sum of the points' volumes per element.
    pub volume: Vec<R>,
    /// Volume-weighted sum of the points' stresses per element (then the mean, for full ones).
    pub stress: Vec<[R; 6]>,
    /// Whether each element is full this step.
    pub full: Vec<bool>,
}

impl<R: Real> Mixed<R> {
    /// Buffers for `elements` elements.
    pub fn new(elements: usize, filling: f64) -> Self {
        Mixed {
            filling,
            volume: vec![R::ZERO; elements],
            stress: vec![[R::ZERO; 6]; elements],
            full: vec![false; elements],
        }
    }

    /// Sums the points' volumes and stresses per element, marks the full elements and turns
    /// their sums into mean stresses.
    pub fn gather(&mut self, mesh: &TetMesh<R>, p: &Particles<R>) {
        self.sum(p);
        let fill = R::of(self.filling);
        for e in 0..self.full.len() {
            let v = self.volume[e];
            self.full[e] = v > R::ZERO && v >= fill * mesh.volume[e];
        }
        self.mean();
    }

    fn sum(&mut self, p: &Particles<R>) {
        self.volume.fill(R::ZERO);
        self.stress.fill([R::ZERO; 6]);
        for i in 0..p.len() {
            if !p.active[i] {
                continue;
            }
            let e = p.element[i] as usize;
            let v = p.volume[i];
            self.volume[e] += v;
            for c in 0..6 {
                self.stress[e][c] += v * p.stress[i][c];
            }
        }
    }

    fn mean(&mut self) {
        for e in 0..self.full.len() {
            let v = self.volume[e];
            if self.full[e] {
                for c in 0..6 {
                    self.stress[e][c] /= v;
                }
            }
        }
    }

    /// Adds the Gauss-point internal forces of the full elements, -V_e σ_e ∇N.
    pub fn internal_forces(&self, mesh: &TetMesh<R>, g: &mut Grid<R>) {
        for e in 0..self.full.len() {
            if !self.full[e] {
                continue;
            }
            let s = self.stress[e];
            let vol = mesh.volume[e];
            for k in 0..4 {
                let node = mesh.corners[e][k] as usize;
                let dn = mesh.grad[e][k];
                let f = [
                    s[0] * dn[0] + s[3] * dn[1] + s[5] * dn[2],
                    s[3] * dn[0] + s[1] * dn[1] + s[4] * dn[2],
                    s[5] * dn[0] + s[4] * dn[1] + s[2] * dn[2],
                ];
                for a in 0..3 {
                    g.f_int[node][a] -= vol * f[a];
                }
            }
        }
    }

    /// After the stress update: every point of an element that was full at the start of the
    /// step takes the element's volume-weighted mean stress (the Gauss-point stress).
    pub fn smooth_stresses(&mut self, p: &mut Particles<R>) {
        self.sum(p);
        self.mean();
        for i in 0..p.len() {
            if !p.active[i] {
                continue;
            }
            let e = p.element[i] as usize;
            if self.full[e] {
                p.stress[i] = self.stress[e];
            }
        }
    }
}
