//! Jobs built on the driver: consolidation against Terzaghi, comparisons with Anura3D's reported
//! points, the closed forms of Cam Clay's element tests and the hypoplastic law's peak and
//! critical states.

pub mod anura3d_compare;
pub mod cam_clay;
pub mod consolidation;
pub mod hypoplastic;
pub mod terzaghi;
