//! From input files to a resolved [`case::Case`]: TOML scenes, Anura3D GOM + CPS (with the key table), the initial stresses, the critical time step, the pre-flight plan, scenes written back as Anura3D cases, and the command line's overrides of a case.

pub mod anura3d;
pub mod anura3d_keys;
pub mod case;
pub mod export_anura3d;
pub mod faces;
pub mod initial_stress;
pub mod overrides;
pub mod preflight;
pub mod scene;
pub mod time_step;
