//! Morton (Z-order) keys on a 2^N grid over the mesh's bounding cube (docs/design.md §3).

/// Spreads the low 21 bits of `v` so that bit i moves to bit 3i.
#[inline]
pub fn spread3(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Spreads the low 31 bits of `v` so that bit i moves to bit 2i.
#[inline]
pub fn spread2(v: u64) -> u64 {
    let mut x = v & 0x7fff_ffff;
    x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
    x = (x | (x << 8)) & 0x00ff_00ff_00ff_00ff;
    x = (x | (x << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
    x = (x | (x << 2)) & 0x3333_3333_3333_3333;
    x = (x | (x << 1)) & 0x5555_5555_5555_5555;
    x
}

/// Axis names for messages.
const AXES: [char; 3] = ['x', 'y', 'z'];

/// Why no curve grid can be laid over a set of points.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BoundsError {
    /// A coordinate is NaN or infinite.
    #[error("node {node} has {axis} = {value}; coordinates must be finite numbers")]
    Coordinate {
        /// The node, 1-based (the GOM's node number).
        node: usize,
        /// The axis.
        axis: char,
        /// The value.
        value: f64,
    },
    /// An axis's extent (max − min) overflows to infinity.
    #[error(
        "the {axis} extent of the mesh (max {max:e} − min {min:e}) is not a finite number; \
         coordinates that far apart cannot be ordered (scale or shift the mesh)"
    )]
    Extent {
        /// The axis.
        axis: char,
        /// Smallest coordinate along it.
        min: f64,
        /// Largest coordinate along it.
        max: f64,
    },
}

/// The first NaN or infinite coordinate of `coords` as an error (cold: only after a failed
/// check).
#[cold]
fn first_non_finite(coords: &[f64], dim: usize) -> BoundsError {
    let i = coords
        .iter()
        .position(|v| !v.is_finite())
        .expect("called only when a coordinate is not finite");
    BoundsError::Coordinate {
        node: i / dim + 1,
        axis: AXES[i % dim],
        value: coords[i],
    }
}

/// The quantisation grid: per-axis origin and scale so that q = floor((c - lo) * scale).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Lower corner.
    pub lo: [f64; 3],
    /// Cube side (or per-axis extent with `--no-cubic`); 0 collapses the axis to cell 0.
    pub side: [f64; 3],
    /// Levels N (cells per axis 2^N).
    pub levels: u32,
    /// Number of axes used (2 or 3).
    pub dim: usize,
}

impl Grid {
    /// The grid over points `coords` (`dim` per point): lo = per-axis minimum, side = the largest
    /// extent for every axis (`cubic`), or each axis's own extent.
    ///
    /// Refuses a NaN or infinite coordinate (naming the first such node, 1-based) and an axis
    /// whose extent max − min overflows: either would send every centroid to the same cell.
    pub fn bounding(
        coords: &[f64],
        dim: usize,
        levels: u32,
        cubic: bool,
    ) -> Result<Grid, BoundsError> {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        // One pass: a flag rather than a branch per value keeps the loop as fast as before;
        // the offending node is looked for only when the flag is set.
        let mut all_finite = true;
        for p in coords.chunks_exact(dim) {
            for a in 0..dim {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
                all_finite &= p[a].is_finite();
            }
        }
        if !all_finite {
            return Err(first_non_finite(coords, dim));
        }
        let mut side = [0.0; 3];
        for a in 0..dim {
            side[a] = if hi[a] > lo[a] { hi[a] - lo[a] } else { 0.0 };
            if !side[a].is_finite() {
                return Err(BoundsError::Extent {
                    axis: AXES[a],
                    min: lo[a],
                    max: hi[a],
                });
            }
        }
        if cubic {
            let s = side.iter().copied().fold(0.0, f64::max);
            side = [s; 3];
        }
        for a in dim..3 {
            lo[a] = 0.0;
            side[a] = 0.0;
        }
        Ok(Grid {
            lo,
            side,
            levels,
            dim,
        })
    }

    /// Position of `c` along axis `a` scaled to [0, 1] (0 when the axis has no extent).
    #[inline]
    pub fn unit(&self, c: f64, a: usize) -> f64 {
        if self.side[a] > 0.0 {
            (c - self.lo[a]) / self.side[a]
        } else {
            0.0
        }
    }

    /// The cell index q of `c` along axis `a`: min(floor(t 2^N), 2^N - 1).
    #[inline]
    pub fn cell(&self, c: f64, a: usize) -> u64 {
        let n = (1u64 << self.levels) as f64;
        let t = self.unit(c, a) * n; // exact scaling by a power of two
        let max = (1u64 << self.levels) - 1;
        if t <= 0.0 {
            0
        } else {
            (t.floor() as u64).min(max)
        }
    }

    /// Morton key of point `c`: bits of q interleaved, x lowest.
    #[inline]
    pub fn key(&self, c: &[f64]) -> u64 {
        if self.dim == 3 {
            spread3(self.cell(c[0], 0))
                | spread3(self.cell(c[1], 1)) << 1
                | spread3(self.cell(c[2], 2)) << 2
        } else {
            spread2(self.cell(c[0], 0)) | spread2(self.cell(c[1], 1)) << 1
        }
    }

    /// The literature study's Algorithm 3, level by level: halve the cell, add 1 (x), 2 (y),
    /// 4 (z) when the point lies in the upper half (a point on the boundary goes up), shift.
    /// Slow; kept as the reference the fast key is tested against.
    pub fn key_by_levels(&self, c: &[f64]) -> u64 {
        let mut key = 0u64;
        let mut lo = [0.0f64; 3];
        let mut size = 1.0f64;
        for _ in 0..self.levels {
            size *= 0.5;
            let mut digit = 0u64;
            for a in 0..self.dim {
                let mid = lo[a] + size;
                if self.unit(c[a], a) >= mid {
                    digit |= 1 << a;
                    lo[a] = mid;
                }
            }
            key = (key << self.dim) | digit;
        }
        key
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_matches_bit_loop() {
        for v in [0u64, 1, 2, 3, 0x1f_ffff, 0x15_5555, 123_456] {
            let mut s3 = 0;
            let mut s2 = 0;
            for b in 0..31 {
                if b < 21 {
                    s3 |= ((v >> b) & 1) << (3 * b);
                }
                s2 |= ((v >> b) & 1) << (2 * b);
            }
            assert_eq!(spread3(v), s3);
            assert_eq!(spread2(v), s2);
        }
    }

    /// Deterministic pseudo-random numbers (SplitMix64), to avoid a dependency.
    fn rng(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *seed;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn fast_key_equals_level_by_level_on_random_and_boundary_points() {
        let mut seed = 7;
        for (dim, levels) in [(3usize, 21u32), (3, 1), (3, 5), (2, 31), (2, 3), (2, 16)] {
            let pts: Vec<f64> = [-3.5, 2.0, 0.25, 10.0, 7.0, 1.0][..2 * dim].to_vec();
            for cubic in [true, false] {
                let g = Grid::bounding(&pts, dim, levels, cubic).unwrap();
                for i in 0..20_000 {
                    let mut c = [0.0; 3];
                    for (a, ca) in c.iter_mut().enumerate().take(dim) {
                        let r = rng(&mut seed);
                        *ca = if i % 2 == 0 {
                            g.lo[a] + r * g.side[a]
                        } else {
                            // Exactly on a cell boundary of some level.
                            let lv = (rng(&mut seed) * levels as f64) as u32;
                            let m = (r * (1u64 << lv) as f64).floor();
                            g.lo[a] + g.side[a] * m / (1u64 << lv) as f64
                        };
                    }
                    assert_eq!(
                        g.key(&c),
                        g.key_by_levels(&c),
                        "dim {dim} levels {levels} point {c:?}"
                    );
                }
                // The upper corner clamps to the last cell.
                let hi: Vec<f64> = (0..dim).map(|a| g.lo[a] + g.side[a]).collect();
                assert_eq!(g.key(&hi), g.key_by_levels(&hi));
            }
        }
    }

    #[test]
    fn non_finite_coordinates_and_extents_are_refused() {
        // ±1e308 are finite, but their distance is not.
        let far = [0.0, -1e308, 0.0, 1.0, 1e308, 1.0];
        for cubic in [true, false] {
            assert_eq!(
                Grid::bounding(&far, 3, 21, cubic),
                Err(BoundsError::Extent {
                    axis: 'y',
                    min: -1e308,
                    max: 1e308
                })
            );
        }
        // The first bad value is named by its node (1-based) and axis.
        let bad = [0.0, 0.0, 1.0, 1.0, f64::NAN, f64::INFINITY];
        let e = Grid::bounding(&bad, 2, 31, true).unwrap_err();
        assert!(
            matches!(e, BoundsError::Coordinate { node: 3, axis: 'x', value } if value.is_nan()),
            "{e:?}"
        );
        assert!(e.to_string().contains("node 3 has x = NaN"), "{e}");
        let inf = [0.0, 0.0, 0.0, 1.0, 1.0, f64::NEG_INFINITY];
        assert_eq!(
            Grid::bounding(&inf, 3, 21, true),
            Err(BoundsError::Coordinate {
                node: 2,
                axis: 'z',
                value: f64::NEG_INFINITY
            })
        );
        // Large but representable extents are fine.
        assert!(Grid::bounding(&[-4e307, 0.0, 0.0, 4e307, 1.0, 1.0], 3, 21, true).is_ok());
    }

    #[test]
    fn boundary_goes_to_the_upper_half() {
        let g = Grid::bounding(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], 3, 1, true).unwrap();
        assert_eq!(g.key(&[0.5, 0.0, 0.0]), 1);
        assert_eq!(g.key(&[0.0, 0.5, 0.0]), 2);
        assert_eq!(g.key(&[0.4999, 0.5, 0.5]), 6);
    }
}
