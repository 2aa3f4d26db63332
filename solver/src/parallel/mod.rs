//! The thread team and the deterministic parallel sums: who computes what.

pub mod comm;
pub mod gather;
pub mod machine;
pub mod partition;
pub mod team;
