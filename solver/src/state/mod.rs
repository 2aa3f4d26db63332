//! The state of a run: material points and nodal arrays.

pub mod grid;
pub mod particles;
