//! Why a material's properties are refused: the one error type of material input, whichever
//! file (Anura3D case or scene) they come from; the readers add the file and item.

use crate::material::law::LawError;

/// A material property out of its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaterialError {
    /// A property that must be positive and finite is not.
    #[error("{what} must be positive, got {value}")]
    NotPositive {
        /// The property, in words ("density").
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A porosity outside its range.
    #[error("porosity must be in {range}, got {value}")]
    Porosity {
        /// The accepted range, written as an interval ("(0, 1)").
        range: &'static str,
        /// The value given.
        value: f64,
    },
    /// The constitutive law's parameters.
    #[error(transparent)]
    Law(#[from] LawError),
}
