//! Elements: the interface every element type implements ([`Element`]), the types there are
//! ([`tet4::Tet4`] for 3D models, [`tri3::Tri3`] and [`tri3::Tri3Axi`] for plane-strain and
//! axisymmetric 2D sections), the mesh built from them ([`mesh::Mesh`]) and point location
//! ([`locate`]).
//!
//! The phases of the step are generic over the element type, so a new element is a new file
//! here, not a change to the kernels. Element data live in 3-vectors whatever the element's
//! dimension: a 2D element lies in z = 0 with zero z-gradients, so the kernels' 3D strain and
//! stress give plane strain unchanged; axisymmetry adds its hoop terms where the kernels ask
//! [`Element::AXISYMMETRIC`] (docs/design.md §7.7).

pub mod locate;
pub mod mesh;
pub mod tet4;
pub mod tri3;

use std::fmt::Debug;

use mpm_shared::{Dimension, ElementType};

use crate::four::Lanes;
use crate::real::{Real, V3};
use tet4::Tet4;
use tri3::{Tri3, Tri3Axi};

/// Values per element node or per element face: `[T; N]` for the element's N.
pub trait PerNode<T>: Copy + Debug + Send + Sync + AsRef<[T]> + AsMut<[T]> + 'static {}

impl<T: Copy + Debug + Send + Sync + 'static, const N: usize> PerNode<T> for [T; N] {}

/// What an element type precomputes per element from its node coordinates.
#[derive(Debug, Clone, Copy)]
pub struct Geometry<E: Element, R: Real> {
    /// The map from global to local coordinates that [`Element::shape`] evaluates.
    pub map: E::Map<R>,
    /// Shape-function gradients of the nodes (constant over a linear element).
    pub grad: E::Nodes<V3<R>>,
    /// Volume (area for 2D elements).
    pub volume: R,
    /// Smallest altitude, the length in the Courant time step.
    pub min_altitude: R,
}

/// An element type: node and face counts as associated constants, shape values and gradients,
/// where material points are placed in it, which of them carry a face load, and how a point
/// walks out of it.
pub trait Element: Copy + Debug + Default + Send + Sync + 'static {
    /// Name in messages, plural ("4-node tetrahedra").
    const NAME: &'static str;
    /// Spatial dimension of the element (its coordinates are stored as 3-vectors regardless).
    const DIM: usize;
    /// Nodes per element.
    const NODES: usize;
    /// Faces per element.
    const FACES: usize;
    /// An axisymmetric section (x the radius): the kernels add the hoop strain u_r/r and its
    /// force, and points carry their mass and volume per radian. Constant, so the terms cost
    /// nothing where it is false.
    const AXISYMMETRIC: bool = false;
    /// `[T; NODES]`.
    type Nodes<T: Copy + Debug + Send + Sync + 'static>: PerNode<T>;
    /// `[T; FACES]`.
    type Faces<T: Copy + Debug + Send + Sync + 'static>: PerNode<T>;
    /// The per-element data [`Element::shape`] needs besides the first node's position.
    type Map<R: Real>: Copy + Debug + Send + Sync + 'static;

    /// Whether a model of this dimension and element type is computed with this element (its
    /// first [`Element::NODES`] nodes being the element's nodes in this element's order).
    fn computes(dimension: Dimension, element: ElementType) -> bool;
    /// Per-node values from a function of the local node index.
    fn nodes<T: Copy + Debug + Send + Sync + 'static>(f: impl FnMut(usize) -> T) -> Self::Nodes<T>;
    /// Per-face values from a function of the face index.
    fn faces<T: Copy + Debug + Send + Sync + 'static>(f: impl FnMut(usize) -> T) -> Self::Faces<T>;
    /// Local nodes of face `k`.
    fn face(k: usize) -> &'static [usize];
    /// Geometry of an element with nodes at `x`; `Err(signed volume)` if inverted, flat or not
    /// finite.
    fn geometry<R: Real>(x: &Self::Nodes<[f64; 3]>) -> Result<Geometry<Self, R>, f64>;
    /// Shape-function values at `p` of the element with map `map` and first node at `first`.
    fn shape<R: Real>(map: &Self::Map<R>, first: &V3<R>, p: &V3<R>) -> Self::Nodes<R>;
    /// Shape values at `W` points at once, `x[a][q]` being coordinate a of point q: `[k][q]` is
    /// node k's value at point q, nodes past [`Element::NODES`] zero. Each lane's arithmetic is
    /// [`Element::shape`]'s, in the same order, so the values are the same bits; written value by
    /// value across the points, so that the compiler turns each operation into vector
    /// instructions.
    fn shape_lanes<R: Real, const W: usize>(
        map: &Self::Map<R>,
        first: &V3<R>,
        x: &[[R; W]; 3],
    ) -> [[R; W]; 4];
    /// [`Element::shape_lanes`] in lanes of any kind ([`crate::four::Lanes`]: explicit four-lane
    /// vectors in the passes' four-lane copies, plain arrays in their portable ones; `x[a]`:
    /// coordinate a, one lane per point; `[k]`: node k's values, zero past
    /// [`Element::NODES`]): the same operations in the same order, so the same bits.
    fn shape_four<R: Real, F: Lanes<R>>(
        t: F::Token,
        map: &Self::Map<R>,
        first: &V3<R>,
        x: &[F; 3],
    ) -> [F; 4];
    /// The face a point with shape values `n` lies beyond (the most negative one), or `None`
    /// when it is inside, within `tol` (a small negative number).
    fn exit_face<R: Real>(n: &Self::Nodes<R>, tol: R) -> Option<usize>;
    /// Shape values (local coordinates) of `n` material points placed in one element, in
    /// Anura3D's order, or `None` when `n` points per element are not supported.
    fn point_placement(n: u32) -> Option<Vec<Self::Nodes<f64>>>;
    /// Which of the `n` points placed in an element (by [`Element::point_placement`]) carry a load
    /// on its face `face`: indices into the element's points.
    fn face_load_points(n: usize, face: usize) -> Vec<usize>;
    /// Point counts [`Element::point_placement`] supports, for messages ("1, 4 or 10").
    fn supported_point_counts() -> &'static str;
}

/// Points per batch of the stress update (`step::stress`), chosen per element type and
/// precision by measurement (one thread, batches of 1, 2 and 4 on each case, docs/design.md
/// §5.3): four f32 values fill one 16-byte vector register of the baseline x86-64 instruction
/// set, and a tetrahedron's four points fill the batch; everywhere else (f64, whose four values
/// take two registers and spill; the triangle's three points) point by point was the fastest.
/// The results do not depend on it: a batch does each point's arithmetic as a point-by-point
/// loop does. (Grid to particle and the locate check have widths of their own, measured the
/// same way.)
pub const fn batch_width<E: Element, R: Real>() -> usize {
    if R::BYTES == 4 && E::DIM == 3 {
        4
    } else {
        1
    }
}

/// The element type a model is computed with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ElementKind {
    /// 4-node tetrahedra (10-node models computed with their corners), 3D.
    Tet4,
    /// 3-node triangles in plane strain.
    Tri3,
    /// 3-node triangles of an axisymmetric section.
    Tri3Axi,
}

impl ElementKind {
    /// The element for a model's dimension and element type; `None` for a combination no
    /// engine computes (3D triangles, 2D tetrahedra, cylindrical coordinates).
    pub fn of(dimension: Dimension, element: ElementType) -> Option<Self> {
        [ElementKind::Tet4, ElementKind::Tri3, ElementKind::Tri3Axi]
            .into_iter()
            .find(|k| k.computes(dimension, element))
    }

    fn computes(self, dimension: Dimension, element: ElementType) -> bool {
        match self {
            ElementKind::Tet4 => Tet4::computes(dimension, element),
            ElementKind::Tri3 => Tri3::computes(dimension, element),
            ElementKind::Tri3Axi => Tri3Axi::computes(dimension, element),
        }
    }

    /// The element's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Tet4 => Tet4::NAME,
            ElementKind::Tri3 => Tri3::NAME,
            ElementKind::Tri3Axi => Tri3Axi::NAME,
        }
    }
}

/// Uniform samples in [0, 1) from a xorshift sequence: reproducible points for the element
/// tests.
#[cfg(test)]
pub(crate) fn samples(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}
