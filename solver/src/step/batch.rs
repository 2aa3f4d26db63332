//! Batches of an element's points for the passes that hold each value across several points
//! (`[c][q]`: value c of point q), so that each operation is one over the batch, which the
//! compiler emits as vector instructions (docs/design.md §5.3). Each point's arithmetic stays
//! the one a point-by-point loop does, in the same order, so the bits do not depend on the
//! width.

use crate::element::Element;
use crate::four::Four;
use crate::real::{Real, V3};

/// The lanes of the point passes' portable copies: plain arrays, which the compiler vectorizes
/// for the baseline instruction set; in a build that assumes AVX2, the precision's four-lane
/// vectors (the AVX2 copies' own: there is no other copy to take them).
#[cfg(not(target_feature = "avx2"))]
pub type Portable<R> = crate::four::Lanes4<R>;

/// The lanes of the point passes' portable copies, in a build that assumes AVX2: the
/// precision's four-lane vectors.
#[cfg(target_feature = "avx2")]
pub type Portable<R> = <R as Real>::Four;

/// Points per batch of particle to grid's shape values, of grid to particle and of the
/// pore-pressure rate's sums in tetrahedra (triangles go point by point), measured on one
/// thread against batches of 1 to 3 (docs/design.md §5.3). A literal, not a function of the
/// element type: the passes expand their element closure once per width.
pub const TETRAHEDRA: usize = 4;

/// Up to `W` consecutive points of one element, from index `start`: which lanes hold a point
/// that takes part (`on`), and the point each lane reads (`at`: its own, or the first taking
/// part for a lane past the batch's points or of a point that does not take part, whose values
/// are computed and never stored).
#[derive(Debug, Clone, Copy)]
pub struct Batch<const W: usize> {
    /// Index of the batch's first point.
    pub start: usize,
    /// Points in the batch (the lanes past them are padding).
    pub len: usize,
    /// Whether lane q's point takes part.
    pub on: [bool; W],
    /// The point lane q reads.
    pub at: [usize; W],
}

impl<const W: usize> Batch<W> {
    /// The batch of the points from `start` up to `end` (at most `W`), those with `takes_part`
    /// on; `Err(len)` (the points to skip) when none of them takes part.
    #[inline(always)]
    pub fn new(
        start: usize,
        end: usize,
        takes_part: impl Fn(usize) -> bool,
    ) -> Result<Self, usize> {
        let len = (end - start).min(W);
        let on: [bool; W] = std::array::from_fn(|q| q < len && takes_part(start + q));
        let Some(lead) = on.iter().position(|&o| o) else {
            return Err(len);
        };
        let at = std::array::from_fn(|q| start + if on[q] { q } else { lead });
        Ok(Batch { start, len, on, at })
    }

    /// The indices of the points that take part, in order.
    #[inline(always)]
    pub fn points(&self) -> impl Iterator<Item = usize> + '_ {
        (self.start..self.start + self.len).filter(|&i| self.on[i - self.start])
    }

    /// Each lane's point's `C` values of `v`, value by value.
    #[inline(always)]
    pub fn gather<T: Copy, const C: usize>(&self, v: &[[T; C]]) -> [[T; W]; C] {
        std::array::from_fn(|c| self.at.map(|i| v[i][c]))
    }
}

/// The shape values of points `j..j + live` of `x` (one to four of an element whose map and
/// first corner are `map`, `first`), one node-lane vector per point: formed four points at a
/// time, one lane per point, and turned by a transpose (each point's own bits; the lanes past
/// `live` repeat the last point, computed and never used).
#[inline(always)]
pub fn node_lane_shapes<E: Element, R: Real, F: Four<R>>(
    t: F::Token,
    map: &E::Map<R>,
    first: &V3<R>,
    x: &[V3<R>],
    j: usize,
    live: usize,
) -> [F; 4] {
    let xl = point_lanes3::<R, F>(t, x, j, live);
    F::transpose(t, E::shape_four(t, map, first, &xl))
}

/// Points `j..j + live`' values of `a` as lanes (lane q: point j + q; the lanes past `live` the
/// last of them again): four points' by one load.
#[inline(always)]
pub fn point_lanes<R: Real, F: Four<R>>(t: F::Token, a: &[R], j: usize, live: usize) -> F {
    if live == 4 {
        return F::load(t, a[j..j + 4].try_into().expect("four points"));
    }
    F::load(t, &[0, 1, 2, 3].map(|q: usize| a[j + q.min(live - 1)]))
}

/// Points `j..j + live`' 3-vectors of `a` one vector per component (lane q: point j + q; the
/// lanes past `live` the last of them again): four points' by [`Four::load_points3`], from
/// their twelve consecutive values.
#[inline(always)]
pub fn point_lanes3<R: Real, F: Four<R>>(
    t: F::Token,
    a: &[V3<R>],
    j: usize,
    live: usize,
) -> [F; 3] {
    if live == 4 {
        let four: &[V3<R>; 4] = a[j..j + 4].try_into().expect("four points");
        return F::load_points3(t, four);
    }
    let at = [0, 1, 2, 3].map(|q: usize| j + q.min(live - 1));
    // (A loop, not `from_fn`: the intrinsics in its closure would become calls.)
    let mut v = [F::splat(t, R::ZERO); 3];
    for (c, vc) in v.iter_mut().enumerate() {
        *vc = F::load(t, &at.map(|i| a[i][c]));
    }
    v
}

/// The points an element usually holds (Anura3D's usual placements): a tetrahedron's four, a
/// triangle's three. The point passes take an element of exactly this count, all taking part,
/// in straight code outside their batch loops (docs/design.md §9).
pub const fn usual_count<E: Element>() -> usize {
    if E::NODES == 4 {
        4
    } else {
        3
    }
}

/// Whether the points `j..end` are an element's [`usual_count`], all active and of material
/// `lead` (four by [`four_of`]).
#[inline(always)]
pub fn usual_of<E: Element>(
    active: &[bool],
    material: &[u32],
    j: usize,
    end: usize,
    lead: u32,
) -> bool {
    if end - j != usual_count::<E>() {
        return false;
    }
    if usual_count::<E>() == 4 {
        four_of(active, material, j, lead)
    } else {
        active[j..end].iter().all(|&a| a) && material[j..end].iter().all(|&m| m == lead)
    }
}

/// Whether the four points `j..j + 4` are all active and of material `lead`: one compare of
/// each array's four (checked point by point, the point passes ran 13 instructions per point
/// for it).
#[inline(always)]
pub fn four_of(active: &[bool], material: &[u32], j: usize, lead: u32) -> bool {
    active[j..j + 4] == [true; 4] && material[j..j + 4] == [lead; 4]
}

/// Stores an element's sums held as lanes (`sums[c]`: value c of each node, lane k node k; a
/// triangle's fourth lane never stored) into the scatter's buffer: the `W` values of each node's
/// `stride` from `offset` on, four values at a time turned from value lanes into node lanes by
/// a transpose and stored whole, the last one to three value by value (values moved, not
/// computed: the same bits). Callers pass the pass's width and offset as constants of the
/// element and phases (not a field read at run time), so that the buffer's node rows are
/// found without a division (`chunks_exact` of a width known at run time divided per element)
/// and the checks fold away.
///
/// # Panics
/// If `four` does not hold exactly [`Element::NODES`] rows of `stride` values, or the `W`
/// values from `offset` do not fit in a row.
#[inline(always)]
pub fn store_nodes<E: Element, R: Real, F: Four<R>, const W: usize>(
    t: F::Token,
    sums: &[F; W],
    four: &mut [R],
    stride: usize,
    offset: usize,
) {
    const { assert!(E::NODES == 3 || E::NODES == 4) };
    assert!(
        four.len() == E::NODES * stride && offset + W <= stride,
        "a slot width other than the scatter's"
    );
    // (Indexed, not `array::from_fn` or an array's iterator: the AVX2 copies must not call
    // the library's array helpers, `scripts/check-avx2-copies`.) With the width and offset
    // constants, every index below is one and its check folds away.
    let mut c = 0;
    while c + 4 <= W {
        let lanes = F::transpose(t, [sums[c], sums[c + 1], sums[c + 2], sums[c + 3]]);
        for (k, node) in lanes.iter().enumerate() {
            if k == E::NODES {
                break;
            }
            let at = k * stride + offset + c;
            let to: &mut [R; 4] = (&mut four[at..at + 4]).try_into().expect("four values");
            *to = node.to_array();
        }
        c += 4;
    }
    while c < W {
        let lanes = sums[c].to_array();
        for (k, &v) in lanes.iter().enumerate() {
            if k == E::NODES {
                break;
            }
            four[k * stride + offset + c] = v;
        }
        c += 1;
    }
}

/// A tetrahedron's slots in the scatter's buffer (`four`: four nodes of `W` values each, one
/// node after another) as four rows of `W` values.
///
/// # Panics
/// If `four` does not hold exactly four rows of `W` values.
#[inline(always)]
pub fn node_rows<R, const W: usize>(four: &mut [R]) -> &mut [[R; W]; 4] {
    assert_eq!(four.len(), 4 * W, "a slot width other than the scatter's");
    // SAFETY: `four` holds exactly 4 W values, one after another (checked above), and
    // [[R; W]; 4] is 4 W values of R one after another, without padding (an array's layout):
    // the same memory, borrowed mutably once, for as long as `four` is.
    unsafe { &mut *four.as_mut_ptr().cast::<[[R; W]; 4]>() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;

    /// Row k, value c of [`node_rows`] is value c of node k's slot, written through to the
    /// buffer; a buffer of another width is refused.
    #[test]
    fn node_rows_are_the_nodes_slots() {
        let mut four: Vec<f64> = (0..24).map(f64::from).collect();
        let rows = node_rows::<f64, 6>(&mut four);
        for (k, row) in rows.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                assert_eq!(v, (6 * k + c) as f64);
            }
        }
        rows[2][5] = -1.0;
        assert_eq!(four[17], -1.0);
        let wrong = std::panic::catch_unwind(|| {
            let mut short = vec![0.0f32; 11];
            node_rows::<f32, 3>(&mut short)[0][0]
        });
        assert!(wrong.is_err());
    }

    /// Node by node, value by value: the `W` values of `sums` (value c of node k: lane k of
    /// `sums[c]`) into each node's `stride` from `offset` on, the nodes past the element's
    /// untouched.
    fn store_reference<E: Element, R: Real, const W: usize>(
        sums: &[[R; 4]; W],
        four: &mut [R],
        stride: usize,
        offset: usize,
    ) {
        for k in 0..E::NODES {
            for c in 0..W {
                four[k * stride + offset + c] = sums[c][k];
            }
        }
    }

    /// [`store_nodes`] writes the values of the node-by-node store, where it writes them, and
    /// leaves the rest of the buffer alone: the solid's values and the liquid's after them, of
    /// a two-phase pass (a tetrahedron's 10 + 12, a triangle's 7 + 9), in both precisions, in
    /// lanes `F`.
    fn stores_as_store<E: Element, R: Real, F: Four<R>, const S: usize, const L: usize>() {
        let Some(t) = F::token() else {
            eprintln!("skipped: this processor lacks the four-lane type's instructions");
            return;
        };
        let width = S + L;
        let mut rng = crate::test_rng::uniform(5);
        let mut value = || R::of(rng() * 2e3 - 1e3);
        let solid: [[R; 4]; S] = std::array::from_fn(|_| std::array::from_fn(|_| value()));
        let liquid: [[R; 4]; L] = std::array::from_fn(|_| std::array::from_fn(|_| value()));
        let marker = R::of(-7.5);
        let nodes = E::NODES;
        let (mut want, mut got) = (vec![marker; nodes * width], vec![marker; nodes * width]);
        store_reference::<E, R, S>(&solid, &mut want, width, 0);
        store_reference::<E, R, L>(&liquid, &mut want, width, S);
        let s4: [F; S] = std::array::from_fn(|c| F::load(t, &solid[c]));
        let w4: [F; L] = std::array::from_fn(|c| F::load(t, &liquid[c]));
        store_nodes::<E, R, F, S>(t, &s4, &mut got, width, 0);
        store_nodes::<E, R, F, L>(t, &w4, &mut got, width, S);
        let bits = |v: &[R]| v.iter().map(|x| x.f64().to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&got), bits(&want));
        // Only the solid's: the liquid's places keep their marker.
        let mut dry = vec![marker; nodes * width];
        store_nodes::<E, R, F, S>(t, &s4, &mut dry, width, 0);
        for (k, node) in dry.chunks_exact(width).enumerate() {
            assert!(node[S..].iter().all(|&x| x == marker), "node {k}");
            assert_eq!(bits(&node[..S]), bits(&want[width * k..width * k + S]));
        }
        // A buffer of another width is refused.
        let refused = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut short = vec![marker; nodes * width - 1];
            store_nodes::<E, R, F, S>(t, &s4, &mut short, width, 0);
        }));
        assert!(refused.is_err());
    }

    #[test]
    fn an_element_s_vectors_store_as_its_lanes() {
        use crate::element::tri3::Tri3;
        use crate::four::Lanes4;
        stores_as_store::<Tet4, f64, <f64 as Real>::Four, 10, 12>();
        stores_as_store::<Tet4, f32, <f32 as Real>::Four, 10, 12>();
        stores_as_store::<Tri3, f64, <f64 as Real>::Four, 7, 9>();
        stores_as_store::<Tri3, f32, <f32 as Real>::Four, 7, 9>();
        stores_as_store::<Tet4, f64, Lanes4<f64>, 10, 12>();
        stores_as_store::<Tri3, f32, Lanes4<f32>, 7, 9>();
    }
}
