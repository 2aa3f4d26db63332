//! The computational mesh: linear tetrahedra, their geometry and neighbours, and locating points in them.

pub mod locate;
pub mod mesh;
