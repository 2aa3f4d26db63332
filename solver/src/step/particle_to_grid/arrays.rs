//! The points particle to grid reads: the per-point arrays, all of one length ([`PointArrays`]),
//! and an element's points with what the point sums read beside them ([`Points`]).

use crate::element::Element;
use crate::real::{Real, V3};
use crate::state::particles::Particles;
use crate::step::contact::OneBody;

use super::LiquidLoads;

/// The per-point arrays particle to grid reads, all of one length (checked once, when they are
/// taken), so that an element's points are sliced out of every one of them with one check of
/// their range ([`PointArrays::element`]) rather than one per array: per element, those checks
/// were about a tenth of a triangle's instructions in this pass.
#[derive(Clone, Copy)]
pub(super) struct PointArrays<'a, R: Real> {
    pub len: usize,
    pub active: &'a [bool],
    pub material: &'a [u32],
    pub x: &'a [V3<R>],
    pub mass: &'a [R],
    pub vel: &'a [V3<R>],
    pub volume: &'a [R],
    pub stress: &'a [[R; 6]],
    pub pore: Option<&'a [R]>,
    /// The points' bulk viscous pressures, where the case has bulk viscosity.
    pub bulk: Option<&'a [R]>,
    pub w: Option<&'a [V3<R>]>,
    pub volume0: Option<&'a [R]>,
}

impl<'a, R: Real> PointArrays<'a, R> {
    /// The arrays of `p` (its liquid's with `liquid`).
    ///
    /// # Panics
    /// If they are not all of one length (a [`Particles`] whose arrays were resized apart).
    pub fn new(p: &'a Particles<R>, liquid: bool) -> Self {
        let len = p.x.len();
        let lp = p.liquid.as_ref();
        let a = PointArrays {
            len,
            active: &p.active,
            material: &p.material,
            x: &p.x,
            mass: &p.mass,
            vel: &p.v,
            volume: &p.volume,
            stress: &p.stress,
            pore: lp.map(|l| &l.p[..]),
            bulk: p.bulk.as_ref().map(|b| &b.pressure[..]),
            w: lp.filter(|_| liquid).map(|l| &l.w[..]),
            volume0: lp.filter(|_| liquid).and_then(|l| l.volume0.as_deref()),
        };
        let lens = [
            a.active.len(),
            a.material.len(),
            a.mass.len(),
            a.vel.len(),
            a.volume.len(),
            a.stress.len(),
            a.pore.map_or(len, <[R]>::len),
            a.bulk.map_or(len, <[R]>::len),
            a.w.map_or(len, <[V3<R>]>::len),
            a.volume0.map_or(len, <[R]>::len),
        ];
        assert!(
            lens.iter().all(|&l| l == len),
            "particle arrays of different lengths"
        );
        a
    }

    /// Every array cut to the first `len` values (all of them: a no-op on the values), by
    /// slicing the compiler sees, so that the loops over an element's points index without
    /// bounds checks.
    #[inline(always)]
    pub fn cut(&self) -> Self {
        let n = self.len;
        PointArrays {
            len: n,
            active: &self.active[..n],
            material: &self.material[..n],
            x: &self.x[..n],
            mass: &self.mass[..n],
            vel: &self.vel[..n],
            volume: &self.volume[..n],
            stress: &self.stress[..n],
            pore: self.pore.map(|a| &a[..n]),
            bulk: self.bulk.map(|a| &a[..n]),
            w: self.w.map(|a| &a[..n]),
            volume0: self.volume0.map(|a| &a[..n]),
        }
    }

    /// The points `r` of every array (arrays of `r`'s length).
    ///
    /// # Panics
    /// If `r` is not a range within the arrays (one check for all of them).
    #[inline(always)]
    pub fn element(&self, r: std::ops::Range<usize>) -> Self {
        assert!(
            r.start <= r.end && r.end <= self.len,
            "points past the arrays"
        );
        /// `a[r]`.
        #[inline(always)]
        fn sub<T>(a: &[T], r: std::ops::Range<usize>) -> &[T] {
            debug_assert!(r.start <= r.end && r.end <= a.len());
            // SAFETY: every array is `len` long (checked in `new`, and the fields are this
            // type's own), and `r` lies within `len` (checked above).
            unsafe { a.get_unchecked(r) }
        }
        PointArrays {
            len: r.len(),
            active: sub(self.active, r.clone()),
            material: sub(self.material, r.clone()),
            x: sub(self.x, r.clone()),
            mass: sub(self.mass, r.clone()),
            vel: sub(self.vel, r.clone()),
            volume: sub(self.volume, r.clone()),
            stress: sub(self.stress, r.clone()),
            pore: self.pore.map(|a| sub(a, r.clone())),
            bulk: self.bulk.map(|a| sub(a, r.clone())),
            w: self.w.map(|a| sub(a, r.clone())),
            volume0: self.volume0.map(|a| sub(a, r.clone())),
        }
    }
}

/// The liquid's loads, and an element's points' liquid velocities and (where the liquid mass is
/// held fixed) initial volumes.
pub(super) type LiquidSlices<'a, R> = (LiquidLoads<'a, R>, &'a [V3<R>], Option<&'a [R]>);

/// An element's points ([`PointArrays::element`]), and what the point sums read beside them:
/// in the liquid's pass the liquid's loads with the points' liquid arrays (one value, so that a
/// point asks once whether there is a liquid), the element's map and first corner, each
/// material's gravity, the body mapped, and whether the element is full (mixed integration).
pub(super) struct Points<'a, E: Element, R: Real> {
    /// The points' arrays.
    pub arrays: PointArrays<'a, R>,
    /// The liquid's loads and arrays, in the liquid's pass.
    pub liquid: Option<LiquidSlices<'a, R>>,
    /// The element's map to local coordinates.
    pub map: &'a E::Map<R>,
    /// Its first corner.
    pub first: &'a V3<R>,
    /// Per material, the acceleration that gives its points' weight.
    pub gravity: &'a [V3<R>],
    /// The points mapped (all for `None`).
    pub body: Option<OneBody>,
    /// Whether the element is full (mixed integration): its Gauss point takes its points'
    /// stresses.
    pub full: bool,
}

impl<E: Element, R: Real> Points<'_, E, R> {
    /// The same points with every array cut to their count again (one length), so that the
    /// point sums index them without bounds checks.
    #[inline(always)]
    pub fn cut(&self) -> Self {
        let arrays = self.arrays.cut();
        let count = arrays.len;
        Points {
            arrays,
            liquid: self
                .liquid
                .map(|(l, w, v0)| (l, &w[..count], v0.map(|v| &v[..count]))),
            ..*self
        }
    }
}
