//! `mpm-solve` as a library: an explicit material point method (MUSL, FLIP velocity update,
//! lumped masses, local damping) on linear tetrahedra, generic over the precision.
//!
//! The folders, from the bottom up (each uses only those above it in this list, see
//! docs/design.md §7.4), on the ground the precision ([`real`]) and its four-lane vectors
//! ([`four`]); then [`element`] (mesh, locating points), [`basis`] (what the points map
//! with), [`material`] (laws), [`state`]
//! (points, nodes), [`parallel`] (thread team, deterministic sums), [`step`] (the phases of a
//! step), [`input`] (scenes and Anura3D cases resolved into a [`input::case::Case`]),
//! [`driver`] (the engine, the loop over output times, output files) and [`jobs`]
//! (consolidation against Terzaghi, comparisons with Anura3D); beside them, [`compare`] (two
//! runs' outputs, or a run and Anura3D's, compared field by field for golden files).
#![warn(missing_docs)]
// Kernels index several arrays (shape values, gradients, components) in lockstep, which reads
// better as index loops; and `!(x > 0.0)` is deliberate where NaN must be rejected too.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod four;
pub mod real;

pub mod basis;
pub mod element;
pub mod material;
pub mod state;

pub mod parallel;

pub mod step;

pub mod input;

pub mod driver;

pub mod jobs;

pub mod compare;

#[cfg(test)]
mod test_rng;
