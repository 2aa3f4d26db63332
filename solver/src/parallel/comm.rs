//! The global reductions of a run, made explicit: every value that needs all of the mesh (sums
//! of energies, work and force norms, the smallest time step, counts of lost points) passes
//! through one [`Communicator`]. One process computes everything, so [`SingleProcess`] returns
//! its argument; a distributed run (MPI ranks along the curve partitions) implements the same
//! trait with collective calls, and the engine does not change.

/// Reductions over every process of a run. Each call is collective: every process calls it,
/// in the same order, with its own part.
pub trait Communicator: Send + Sync {
    /// This process's number, 0-based.
    fn rank(&self) -> usize;
    /// Number of processes.
    fn ranks(&self) -> usize;
    /// Sum of every process's `local` (in rank order, so the result is the same everywhere).
    fn sum(&self, local: f64) -> f64;
    /// Smallest of every process's `local`.
    fn min(&self, local: f64) -> f64;
    /// Largest of every process's `local`.
    fn max(&self, local: f64) -> f64;
    /// Sum of counts.
    fn sum_count(&self, local: u64) -> u64;
}

/// One process: every reduction is its own value.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SingleProcess;

impl Communicator for SingleProcess {
    fn rank(&self) -> usize {
        0
    }

    fn ranks(&self) -> usize {
        1
    }

    fn sum(&self, local: f64) -> f64 {
        local
    }

    fn min(&self, local: f64) -> f64 {
        local
    }

    fn max(&self, local: f64) -> f64 {
        local
    }

    fn sum_count(&self, local: u64) -> u64 {
        local
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_process_reduces_to_its_own_values() {
        let c: &dyn Communicator = &SingleProcess;
        assert_eq!((c.rank(), c.ranks()), (0, 1));
        assert_eq!(c.sum(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(c.min(3.5), 3.5);
        assert_eq!(c.max(f64::INFINITY), f64::INFINITY);
        assert_eq!(c.sum_count(7), 7);
    }
}
