//! Jobs built on the driver: consolidation against Terzaghi, and comparisons with Anura3D's reported points.

pub mod anura3d_compare;
pub mod consolidation;
pub mod terzaghi;
