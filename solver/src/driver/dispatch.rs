//! The one place where a run's types are chosen: the precision from the case's setting and the
//! element from its model (3D tetrahedra, plane-strain or axisymmetric triangles). Code generic
//! over both implements [`Generic`]; [`dispatch`] calls it with the engine monomorphized for the
//! case, so every combination shares one code path.

use crate::element::tet4::Tet4;
use crate::element::tri3::{Tri3, Tri3Axi};
use crate::element::{Element, ElementKind};
use crate::input::case::{Case, Precision};
use crate::real::Real;

/// Code generic over the precision and the element type.
pub trait Generic {
    /// What it returns.
    type Output;
    /// Runs it with precision `R` and element `E`.
    fn call<R: Real, E: Element>(self) -> Self::Output;
}

/// Why a case has no engine.
#[derive(Debug, thiserror::Error)]
#[error("{dimension} models of {element} are not computed (3D-cartesian tetrahedra, 2D-plane_strain and 2D-axisymmetric triangles are)")]
pub struct NoEngine {
    /// The model's dimension keyword.
    pub dimension: &'static str,
    /// The model's elements.
    pub element: &'static str,
}

/// Calls `g` with the precision and element type `case` asks for.
pub fn dispatch<G: Generic>(case: &Case, g: G) -> Result<G::Output, NoEngine> {
    let (dimension, element) = (case.model.dimension, case.model.element_type);
    let kind = ElementKind::of(dimension, element).ok_or(NoEngine {
        dimension: dimension.keyword(),
        element: element.describe(),
    })?;
    Ok(match (case.numerics.precision, kind) {
        (Precision::F64, ElementKind::Tet4) => g.call::<f64, Tet4>(),
        (Precision::F64, ElementKind::Tri3) => g.call::<f64, Tri3>(),
        (Precision::F64, ElementKind::Tri3Axi) => g.call::<f64, Tri3Axi>(),
        (Precision::F32, ElementKind::Tet4) => g.call::<f32, Tet4>(),
        (Precision::F32, ElementKind::Tri3) => g.call::<f32, Tri3>(),
        (Precision::F32, ElementKind::Tri3Axi) => g.call::<f32, Tri3Axi>(),
    })
}
