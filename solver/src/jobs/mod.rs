//! Jobs built on the driver: consolidation against Terzaghi, comparisons with Anura3D's reported
//! points, and the closed forms of Cam Clay's element tests.

pub mod anura3d_compare;
pub mod cam_clay;
pub mod consolidation;
pub mod terzaghi;
