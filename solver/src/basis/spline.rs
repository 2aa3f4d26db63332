//! The one-dimensional functions of the background grid's bases ([`super::grid`]), one per
//! node of a uniform lattice of `cells` cells of unit length (coordinates in cells), and their
//! treatment at the lattice's two ends.
//!
//! - [`Shape::Linear`]: the hat function, support one cell either side of its node (2 nodes
//!   touch a point);
//! - [`Shape::Gimp`]: the uniform GIMP function (Bardenhagen & Kober 2004), the hat convolved
//!   with a point's characteristic function of half-width `a` cells, support 1 + a (up to 3
//!   nodes);
//! - [`Shape::Bspline2`]: the quadratic B-spline, C¹, support 1.5 cells either side (3 nodes).
//!
//! The wider functions reach past the lattice's ends: a point within 1.5 cells (quadratic) or
//! `a` cells (GIMP) of an end touches a node one cell outside it. Those *ghost* nodes are not
//! kept: their value is taken as the linear extrapolation of the two nodes inside,
//! v₋₁ = 2 v₀ − v₁ (and the same at the far end), so each ghost's function is folded into its
//! neighbours' (N₀ += 2 N₋₁, N₁ −= N₋₁). The folded set still sums to one and still
//! reproduces linear fields exactly (the extrapolation is exact for them); at the end itself
//! only the end node's function is non-zero (for the quadratic spline, N₀ = 1 − ξ and N₁ = ξ
//! on the first half cell, joining the interior splines with a continuous slope), so a fixity
//! on the end node holds exactly on the boundary plane, and no function is negative. These are
//! the *modified boundary splines* of docs/design.md §4.20.

/// A one-dimensional function of the background grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// The hat function (trilinear cells in 3D).
    Linear,
    /// Uniform GIMP with a point half-width of `a` cells (0 < a ≤ 0.5).
    Gimp {
        /// The point's half-width, in cells.
        a: f64,
    },
    /// The quadratic B-spline.
    Bspline2,
}

/// Most nodes one point touches along one axis.
pub const MOST_PER_AXIS: usize = 3;

/// The nodes a point touches along one axis (lattice indices, the first of `len`
/// consecutive ones), with each one's value and derivative (per cell).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Along {
    /// The first node's index.
    pub first: usize,
    /// How many nodes.
    pub len: usize,
    /// The values.
    pub n: [f64; MOST_PER_AXIS],
    /// The derivatives along the axis, per cell.
    pub dn: [f64; MOST_PER_AXIS],
}

impl Shape {
    /// The function of the node at 0 at offset `r` (in cells) and its derivative.
    fn at(self, r: f64) -> (f64, f64) {
        let (q, sign) = (r.abs(), if r < 0.0 { -1.0 } else { 1.0 });
        match self {
            Shape::Linear => {
                if q < 1.0 {
                    (1.0 - q, -sign)
                } else {
                    (0.0, 0.0)
                }
            }
            Shape::Gimp { a } => {
                if q < a {
                    (1.0 - (r * r + a * a) / (2.0 * a), -r / a)
                } else if q < 1.0 - a {
                    (1.0 - q, -sign)
                } else if q < 1.0 + a {
                    let d = 1.0 + a - q;
                    (d * d / (4.0 * a), -sign * d / (2.0 * a))
                } else {
                    (0.0, 0.0)
                }
            }
            Shape::Bspline2 => {
                if q < 0.5 {
                    (0.75 - r * r, -2.0 * r)
                } else if q < 1.5 {
                    let d = 1.5 - q;
                    (0.5 * d * d, -sign * d)
                } else {
                    (0.0, 0.0)
                }
            }
        }
    }

    /// How far (in cells) a node's function reaches.
    pub fn reach(self) -> f64 {
        match self {
            Shape::Linear => 1.0,
            Shape::Gimp { a } => 1.0 + a,
            Shape::Bspline2 => 1.5,
        }
    }

    /// The nodes of a lattice of `cells` cells that a point at `s` (in cells from the first
    /// node, 0 ≤ s ≤ cells) touches, with the ghosts past either end folded in (the module's
    /// doc). A point on or past an end is taken at the end.
    #[inline]
    pub fn along(self, s: f64, cells: usize) -> Along {
        let s = s.clamp(0.0, cells as f64);
        if self == Shape::Linear {
            // The hat's slope jumps at its node: a point on a node takes the cell above it
            // (the cell below at the far end), both nodes of one cell.
            let first = (s.floor() as usize).min(cells - 1);
            let r = s - first as f64;
            return Along {
                first,
                len: 2,
                n: [1.0 - r, r, 0.0],
                dn: [-1.0, 1.0, 0.0],
            };
        }
        if self == Shape::Bspline2 {
            // Inside, in closed form: the nearest node i, the point at r = s − i ∈ [−½, ½].
            let i = s.round();
            if i >= 1.0 && i + 1.0 <= cells as f64 {
                let r = s - i;
                let (below, above) = (0.5 - r, 0.5 + r);
                return Along {
                    first: i as usize - 1,
                    len: 3,
                    n: [0.5 * below * below, 0.75 - r * r, 0.5 * above * above],
                    dn: [-below, -2.0 * r, above],
                };
            }
        }
        let reach = self.reach();
        // Every node within reach, ghosts included: indices from `lo` (may be −1) to `hi`
        // (may be cells + 1).
        let lo = (s - reach).floor() as i64 + 1;
        let hi = (s + reach).ceil() as i64 - 1;
        let (last, mut first) = (cells as i64, i64::MAX);
        if lo >= 0 && hi <= last {
            return self.inside(s, lo, hi);
        }
        let mut n = [0.0; MOST_PER_AXIS + 2];
        let mut dn = [0.0; MOST_PER_AXIS + 2];
        let mut touched = [false; MOST_PER_AXIS + 2];
        let lowest = lo.max(0);
        let mut add = |k: i64, v: f64, d: f64, touched: &mut [bool]| {
            let slot = (k - lowest) as usize;
            n[slot] += v;
            dn[slot] += d;
            touched[slot] = true;
        };
        for k in lo..=hi {
            let (v, d) = self.at(s - k as f64);
            if v == 0.0 && d == 0.0 {
                continue;
            }
            if k < 0 {
                // v₋₁ = 2 v₀ − v₁ (a ghost one cell out; a lattice of one cell folds into
                // its two nodes).
                add(0, 2.0 * v, 2.0 * d, &mut touched);
                add(1, -v, -d, &mut touched);
            } else if k > last {
                add(last, 2.0 * v, 2.0 * d, &mut touched);
                add(last - 1, -v, -d, &mut touched);
            } else {
                add(k, v, d, &mut touched);
            }
        }
        // The touched nodes are consecutive; keep them (at most three).
        let mut out = Along {
            first: 0,
            len: 0,
            n: [0.0; MOST_PER_AXIS],
            dn: [0.0; MOST_PER_AXIS],
        };
        for slot in 0..touched.len() {
            if !touched[slot] {
                continue;
            }
            let k = lowest + slot as i64;
            first = first.min(k);
            let at = (k - first) as usize;
            assert!(
                at < MOST_PER_AXIS,
                "a 1D stencil past {MOST_PER_AXIS} nodes"
            );
            out.n[at] = n[slot];
            out.dn[at] = dn[slot];
            out.len = out.len.max(at + 1);
        }
        out.first = first as usize;
        out
    }

    /// [`Shape::along`] where no ghost is within reach (`0 ≤ lo ≤ hi ≤ cells`): the same
    /// values, without the fold (most points: the step's hottest function on a grid).
    #[inline]
    fn inside(self, s: f64, lo: i64, hi: i64) -> Along {
        let mut out = Along {
            first: lo as usize,
            len: 0,
            n: [0.0; MOST_PER_AXIS],
            dn: [0.0; MOST_PER_AXIS],
        };
        let mut first = None;
        for k in lo..=hi {
            let (v, d) = self.at(s - k as f64);
            if v == 0.0 && d == 0.0 {
                continue;
            }
            let f = *first.get_or_insert(k);
            let at = (k - f) as usize;
            // (0 + v: the fold's sums start from zero, and so never give −0.)
            out.n[at] = 0.0 + v;
            out.dn[at] = 0.0 + d;
            out.len = at + 1;
        }
        out.first = first.unwrap_or(lo) as usize;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHAPES: [Shape; 4] = [
        Shape::Linear,
        Shape::Gimp { a: 0.25 },
        Shape::Gimp { a: 0.5 },
        Shape::Bspline2,
    ];

    fn samples(cells: usize) -> impl Iterator<Item = f64> {
        (0..=400 * cells).map(move |k| k as f64 / 400.0)
    }

    /// Each point's values sum to one and reproduce its position; the derivatives sum to zero
    /// and reproduce the position's slope (1): constants and linear fields are exact, up to the
    /// lattice's ends.
    #[test]
    fn partition_of_unity_and_linear_fields_to_the_ends() {
        for shape in SHAPES {
            for cells in [1usize, 2, 3, 7] {
                for s in samples(cells) {
                    let a = shape.along(s, cells);
                    let nodes = a.first..a.first + a.len;
                    assert!(nodes.end <= cells + 1, "{shape:?} {cells} {s}");
                    let sum: f64 = a.n[..a.len].iter().sum();
                    let x: f64 = nodes.clone().zip(&a.n).map(|(k, n)| k as f64 * n).sum();
                    let dsum: f64 = a.dn[..a.len].iter().sum();
                    let dx: f64 = nodes.zip(&a.dn).map(|(k, d)| k as f64 * d).sum();
                    assert!((sum - 1.0).abs() < 1e-13, "{shape:?} {cells} {s}: {sum}");
                    assert!((x - s).abs() < 1e-13, "{shape:?} {cells} {s}: {x}");
                    assert!(dsum.abs() < 1e-13, "{shape:?} {cells} {s}: {dsum}");
                    assert!((dx - 1.0).abs() < 1e-13, "{shape:?} {cells} {s}: {dx}");
                }
            }
        }
    }

    /// Inside the lattice the quadratic spline's closed form is the spline: every node's value
    /// and slope is its function at the point's offset from it.
    #[test]
    fn the_closed_form_inside_is_the_spline() {
        let cells = 9;
        for step in 0..=9000 {
            let s = 1.5 + step as f64 * 6.0 / 9000.0;
            let a = Shape::Bspline2.along(s, cells);
            for k in 0..=cells {
                let (v, d) = Shape::Bspline2.at(s - k as f64);
                let (n, dn) = match k.checked_sub(a.first).filter(|&j| j < a.len) {
                    Some(j) => (a.n[j], a.dn[j]),
                    None => (0.0, 0.0),
                };
                assert!(
                    (n - v).abs() < 1e-14 && (dn - d).abs() < 1e-14,
                    "{s} node {k}"
                );
            }
        }
    }

    /// On each end of the lattice only the end node's function is non-zero (a fixity there
    /// holds on the boundary), and no function is negative.
    #[test]
    fn interpolating_at_the_ends_and_never_negative() {
        for shape in SHAPES {
            for cells in [2usize, 5] {
                for (s, node) in [(0.0, 0), (cells as f64, cells)] {
                    let a = shape.along(s, cells);
                    for k in 0..a.len {
                        let expect = if a.first + k == node { 1.0 } else { 0.0 };
                        assert!((a.n[k] - expect).abs() < 1e-14, "{shape:?} at {s}: {a:?}");
                    }
                }
                for s in samples(cells) {
                    let a = shape.along(s, cells);
                    assert!(a.n[..a.len].iter().all(|&n| n >= -1e-15), "{shape:?} {s}");
                }
            }
        }
    }

    /// The derivatives are the values' slopes (central differences away from the kinks).
    #[test]
    fn derivatives_are_the_slopes() {
        let value = |shape: Shape, s: f64, cells: usize, node: usize| {
            let a = shape.along(s, cells);
            (a.first..a.first + a.len)
                .position(|k| k == node)
                .map_or(0.0, |k| a.n[k])
        };
        let eps = 1e-6;
        for shape in SHAPES {
            let cells = 6;
            for s in samples(cells).filter(|s| *s > eps && *s < cells as f64 - eps) {
                let a = shape.along(s, cells);
                for k in 0..a.len {
                    let node = a.first + k;
                    let slope = (value(shape, s + eps, cells, node)
                        - value(shape, s - eps, cells, node))
                        / (2.0 * eps);
                    // The hat's kinks (at the nodes) make a central difference a mean of
                    // two slopes there; GIMP and the spline have none.
                    let kink = shape == Shape::Linear && (s - s.round()).abs() < 2.0 * eps;
                    assert!(
                        (slope - a.dn[k]).abs() < 1e-4 || kink,
                        "{shape:?} node {node} at {s}: {slope} against {}",
                        a.dn[k]
                    );
                }
            }
        }
    }

    /// The quadratic spline's folded end: 1 − ξ and ξ on the first half cell.
    #[test]
    fn quadratic_end_is_linear_on_the_first_half_cell() {
        for s in [0.0, 0.1, 0.3, 0.49] {
            let a = Shape::Bspline2.along(s, 4);
            assert_eq!(a.first, 0);
            assert!((a.n[0] - (1.0 - s)).abs() < 1e-14);
            assert!((a.n[1] - s).abs() < 1e-14);
            assert!(a.len == 2 || a.n[2].abs() < 1e-14);
        }
    }
}
