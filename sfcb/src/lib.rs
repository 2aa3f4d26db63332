//! The space-filling-curve blackbox as a library: curve keys, element ordering, vertex
//! renumbering and partitions (docs/design.md §3). The `sfcb` binary is a thin front end.
#![warn(missing_docs)]

pub mod hilbert;
pub mod metrics;
pub mod morton;
pub mod order;
