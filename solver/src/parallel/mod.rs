//! The thread team and the deterministic parallel sums: who computes what.

pub mod avx2;
pub mod comm;
pub mod exact;
pub mod gather;
pub mod halo;
pub mod huge_pages;
pub mod machine;
#[cfg(feature = "mpi")]
pub mod mpi_comm;
pub mod partition;
pub mod placement;
pub mod pool;
pub mod reach;
pub mod sort;
pub mod team;
