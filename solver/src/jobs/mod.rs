//! Jobs built on the driver: consolidation against Terzaghi, comparisons with Anura3D's reported
//! points, the closed forms of Cam Clay's element tests and the hypoplastic law's peak and
//! critical states; the pile-driving report of a hammer on a structure in contact with the soil.

pub mod anura3d_compare;
pub mod cam_clay;
pub mod consolidation;
pub mod driving;
pub mod hypoplastic;
pub mod plot;
pub mod terzaghi;
