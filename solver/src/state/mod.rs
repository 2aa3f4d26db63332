//! The state of a run: material points, nodal arrays and per-element sums one pass leaves for
//! a later one.

pub mod grid;
pub mod particles;
pub mod pore_weights;
