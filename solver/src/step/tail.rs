//! A wave front's numerical precursor cut where the precision cannot carry it: nodal values far
//! below the field's largest set to zero (docs/design.md §9, "Subnormal tails").
//!
//! An explicit step carries a disturbance one element further per step, and ahead of a front the
//! scheme leaves values that fall by orders of magnitude per element down to exact zero. In
//! single precision the products of two such values (a spin with a stress, a velocity with
//! itself) fall below the smallest normal number, 1.2e-38, and the processor takes each of those
//! operations through its slow subnormal path: a two-phase f32 column ran 1.6× slower than f64.
//! Cutting the nodal accelerations and re-mapped velocities below [`Real::TAIL`] of the field's
//! largest (2⁻⁴⁰ in f32, 2¹⁶ below its resolution; none in f64) keeps the products normal. The
//! largest is a maximum, the same whatever order the threads and processes find it in, so the
//! cut is the same for any thread or rank count.

use crate::parallel::comm::Communicator;
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::step::grid_update::{GridScratch, NODE_BLOCK};

/// Which nodal vectors of a grid [`cut_grid`] cuts (the solid's and, in a two-phase grid, the
/// liquid's, against one largest).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Nodal {
    /// The accelerations of the grid update.
    Acceleration,
    /// The velocities re-mapped from the points.
    Velocity,
}

/// [`cut`] of a grid's accelerations or re-mapped velocities, both phases together, with the
/// per-block values of the grid's scratch.
pub fn cut_grid<R: Real>(
    team: &Team,
    comm: &dyn Communicator,
    scratch: &mut GridScratch<R>,
    g: &mut Grid<R>,
    which: Nodal,
) {
    let blocks = &mut scratch.per_block;
    let solid = match which {
        Nodal::Acceleration => &mut g.acc,
        Nodal::Velocity => &mut g.vel,
    };
    match (&mut g.liquid, which) {
        (Some(l), Nodal::Acceleration) => cut(team, comm, blocks, &mut [solid, &mut l.acc]),
        (Some(l), Nodal::Velocity) => cut(team, comm, blocks, &mut [solid, &mut l.vel]),
        (None, _) => cut(team, comm, blocks, &mut [solid]),
    }
}

/// Sets to zero every component of `fields` (nodal vectors over the mesh's nodes, all of one
/// length, at most two fields) whose magnitude is below [`Real::TAIL`] times the largest finite
/// magnitude among them all, over every process's nodes, on the team. Does nothing where the
/// precision keeps every value (`TAIL` 0) or the fields are all zero. `blocks` holds at least
/// one value per [`NODE_BLOCK`] nodes (preallocated: a step allocates nothing).
pub fn cut<R: Real>(
    team: &Team,
    comm: &dyn Communicator,
    blocks: &mut [R],
    fields: &mut [&mut [V3<R>]],
) {
    if R::TAIL == 0.0 {
        return;
    }
    let n = fields.first().map_or(0, |f| f.len());
    assert!(
        fields.iter().all(|f| f.len() == n),
        "nodal fields of different lengths"
    );
    // One pass over the nodes for the largest of every field, one for the cut: each a single
    // run of the team.
    {
        let fields: &[&mut [V3<R>]] = fields;
        team.for_blocks(n, NODE_BLOCK, blocks, |r| {
            // A non-finite value (a diverging run, which the guards report) sets no scale.
            fields.iter().fold(R::ZERO, |m, field| {
                m.max(R::largest_finite_magnitude(field[r.clone()].as_flattened()))
            })
        });
    }
    let largest = blocks[..n.div_ceil(NODE_BLOCK)]
        .iter()
        .fold(R::ZERO, |a, &b| a.max(b));
    // A node shared by ranks holds its whole value on each after the exchange, so the largest
    // over the ranks is the mesh's.
    let below = R::of(comm.max(largest.f64()) * R::TAIL);
    if below == R::ZERO {
        return;
    }
    let out: [Option<Shared<'_, V3<R>>>; MAX_FIELDS] = {
        assert!(
            fields.len() <= MAX_FIELDS,
            "more nodal fields than a cut takes"
        );
        let mut it = fields.iter_mut();
        std::array::from_fn(|_| it.next().map(|f| Shared::new(f)))
    };
    team.for_blocks(n, NODE_BLOCK, blocks, |r| {
        for field in out.iter().flatten() {
            // SAFETY: the nodes of block r are this call's only.
            let nodes = unsafe { field.range(r.clone()) };
            // (Every value stored, cut or kept: a select the compiler makes vector
            // operations, where a store only of the cut ones stayed a branch per value.)
            for x in nodes.as_flattened_mut() {
                *x = if x.abs() < below { R::ZERO } else { *x };
            }
        }
        R::ZERO
    });
}

/// The most nodal fields one [`cut`] takes (a two-phase grid's two).
const MAX_FIELDS: usize = 2;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::comm::SingleProcess;
    use crate::parallel::team::{Pin, Team};

    /// A field decaying by 10× per node from 1e3, and a second field's values.
    fn fields<R: Real>(n: usize) -> (Vec<V3<R>>, Vec<V3<R>>) {
        let a = (0..n)
            .map(|i| {
                let v = 1e3 * 10f64.powi(-(i as i32 % 40));
                [R::of(v), R::of(-v), R::ZERO]
            })
            .collect();
        let b = (0..n)
            .map(|i| [R::ZERO, R::of(1e-14 * i as f64), R::ONE])
            .collect();
        (a, b)
    }

    fn cut_with<R: Real>(threads: usize, n: usize) -> (Vec<V3<R>>, Vec<V3<R>>) {
        let team = Team::new(threads, Pin::None).unwrap();
        let (mut a, mut b) = fields::<R>(n);
        let mut blocks = vec![R::ZERO; n.div_ceil(NODE_BLOCK)];
        cut(&team, &SingleProcess, &mut blocks, &mut [&mut a, &mut b]);
        (a, b)
    }

    #[test]
    fn single_precision_cuts_below_its_tail_of_the_largest_and_keeps_the_rest() {
        let n = 3 * NODE_BLOCK + 17;
        let (a, b) = cut_with::<f32>(1, n);
        let (a0, b0) = fields::<f32>(n);
        // The largest is 1e3 (the first field's): cut below 1e3 · 2⁻⁴⁰ ≈ 9.1e-10.
        let below = 1e3 * f32::TAIL;
        for (x, x0) in a.iter().flatten().zip(a0.iter().flatten()) {
            let expect = if (x0.abs() as f64) < below { 0.0 } else { *x0 };
            assert_eq!(x.to_bits(), expect.to_bits(), "{x0}");
        }
        for (x, x0) in b.iter().flatten().zip(b0.iter().flatten()) {
            let expect = if (x0.abs() as f64) < below { 0.0 } else { *x0 };
            assert_eq!(x.to_bits(), expect.to_bits(), "{x0}");
        }
        // Something was cut and something small was kept.
        assert!(a.iter().zip(&a0).any(|(x, x0)| x[0] == 0.0 && x0[0] != 0.0));
        assert!(a.iter().any(|x| x[0] > 0.0 && (x[0] as f64) < 1e-8));
    }

    #[test]
    fn the_cut_is_the_same_for_any_thread_count() {
        let n = 5 * NODE_BLOCK + 3;
        let one = cut_with::<f32>(1, n);
        for threads in [2, 3] {
            assert_eq!(cut_with::<f32>(threads, n), one, "{threads} threads");
        }
    }

    #[test]
    fn double_precision_keeps_every_value() {
        let n = NODE_BLOCK + 5;
        assert_eq!(cut_with::<f64>(2, n), fields::<f64>(n));
    }

    #[test]
    fn a_non_finite_value_sets_no_scale() {
        let team = Team::new(1, Pin::None).unwrap();
        let mut a = vec![[f32::INFINITY, 1.0, 1e-13]; 4];
        let mut blocks = vec![0.0f32; 1];
        cut(&team, &SingleProcess, &mut blocks, &mut [&mut a]);
        // The largest finite magnitude is 1: 1e-13 is below 2⁻⁴⁰, infinity stays.
        assert_eq!(a[0], [f32::INFINITY, 1.0, 0.0]);
    }
}
