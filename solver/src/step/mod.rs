//! The phases of one explicit MUSL step, in the order they run, and what they read from the configuration (load curves, damping rule, drag, prescribed velocities).

pub mod absorbing;
pub mod absorbing_anura3d;
pub mod batch;
pub mod bulk_viscosity;
pub mod constraint;
pub mod contact;
pub mod grid_to_particle;
pub mod grid_update;
pub mod load_curve;
pub mod mixed;
pub mod moment;
pub mod moving_mesh;
pub mod nodal_energy;
pub mod nodal_velocity;
pub mod particle_to_grid;
pub mod passes;
pub mod prescribed;
pub mod reaction;
pub mod semi_implicit;
pub mod smoothing;
pub mod stress;
pub mod tail;
pub mod time_step;
pub mod wall_friction;
