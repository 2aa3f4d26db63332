//! Per element, the weights of the smoothed pore-pressure rate, which particle to grid sums
//! from the points it reads anyway so that the rate's own pass need not read them again.
//!
//! The smoothed rate at a node is Σ_e Σ_p V_p N_k(x_p) r_p / Σ_e Σ_p V_p N_k(x_p) over the
//! saturated points of the node's elements (docs/design.md §4). In a linear element the rate
//! r_p of its points of one material is one value per element, r_e, so an element's part is
//! r_e W_ek with W_ek = Σ_p V_p N_k(x_p): the shape values, volumes and positions the sum
//! needs are those particle to grid has in hand a few passes earlier (the points neither move
//! nor change volume in between).

use crate::real::Real;

/// The element holds no active saturated point.
pub const NO_POINTS: u32 = u32::MAX;
/// The element's active saturated points are of more than one material.
pub const MIXED: u32 = u32::MAX - 1;

/// Per element: W_ek, and which material its saturated points share.
#[derive(Debug, Clone)]
pub struct PoreWeights<R: Real> {
    /// Σ_p V_p N_k(x_p) over the element's active saturated points, point by point in order
    /// from zero, one value per node (zeros past the element's nodes).
    pub weights: Vec<[R; 4]>,
    /// The material of those points where they share one, [`NO_POINTS`] or [`MIXED`].
    pub material: Vec<u32>,
    /// Whether particle to grid wrote them this step (the rate's pass takes them only then,
    /// and marks them used).
    pub fresh: bool,
}

impl<R: Real> PoreWeights<R> {
    /// Room for `elements` elements.
    pub fn new(elements: usize) -> Self {
        PoreWeights {
            weights: vec![[R::ZERO; 4]; elements],
            material: vec![NO_POINTS; elements],
            fresh: false,
        }
    }

    /// The same room for `elements` elements (a rank's elements after a new cut of the curve);
    /// allocates only when the count changes.
    pub fn fit(&mut self, elements: usize) {
        self.weights.resize(elements, [R::ZERO; 4]);
        self.material.resize(elements, NO_POINTS);
    }
}

/// The material a set of points shares, `so_far` with one more point of `material` added.
#[inline(always)]
pub fn with_point(so_far: u32, material: u32) -> u32 {
    if so_far == NO_POINTS || so_far == material {
        material
    } else {
        MIXED
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_share_a_material_until_another_comes() {
        assert_eq!(with_point(NO_POINTS, 3), 3);
        assert_eq!(with_point(3, 3), 3);
        assert_eq!(with_point(3, 4), MIXED);
        assert_eq!(with_point(MIXED, 3), MIXED);
        assert_eq!(with_point(MIXED, MIXED), MIXED);
    }
}
