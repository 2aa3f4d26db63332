//! `mpm-solve` as a library: an explicit material point method (MUSL, FLIP velocity update,
//! lumped masses, local damping) on linear tetrahedra, generic over the precision.
//!
//! One module per stage: [`particle_to_grid`], [`grid_update`], [`grid_to_particle`],
//! [`stress`], [`locate`]; the law in [`linear_elastic`]; set-up in [`mesh`], [`particles`],
//! [`case`] and [`scene`]; files in [`output`]; the driver in [`run`]; scenes written as
//! Anura3D cases in [`export_anura3d`]; two runs' outputs compared field by field in [`compare`].
#![warn(missing_docs)]
// Kernels index several arrays (shape values, gradients, components) in lockstep, which reads
// better as index loops; and `!(x > 0.0)` is deliberate where NaN must be rejected too.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod anura3d;
pub mod anura3d_compare;
pub mod anura3d_keys;
pub mod case;
pub mod compare;
pub mod consolidation;
pub mod engine;
pub mod export_anura3d;
pub mod gather;
pub mod grid;
pub mod grid_to_particle;
pub mod grid_update;
pub mod linear_elastic;
pub mod liquid;
pub mod load_curve;
pub mod locate;
pub mod mesh;
pub mod mixed;
pub mod output;
pub mod particle_to_grid;
pub mod particles;
pub mod preflight;
pub mod prescribed;
pub mod real;
pub mod run;
pub mod scene;
pub mod smoothing;
pub mod stress;
pub mod team;
pub mod terzaghi;
pub mod time_step;
pub mod units;
