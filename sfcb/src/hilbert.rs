//! Hilbert curve keys on the same 2^N grid as the Morton keys, table driven.
//!
//! The curve is the one of Hamilton's "Compact Hilbert Indices" (2006): at each level the cell's
//! octant bits l are transformed by the current state (entry corner e, direction d), the Gray-code
//! inverse of the result is the level's digit, and the state moves on. With 2^n octants and
//! n·2^n states the whole step fits a small table, built once from those rules, so a key costs one
//! table look-up per level instead of the per-bit arithmetic.

use std::sync::OnceLock;

/// Rotates the low `n` bits of `x` right by `r`.
fn rotr(x: u32, r: u32, n: u32) -> u32 {
    let r = r % n;
    let mask = (1 << n) - 1;
    ((x >> r) | (x << (n - r))) & mask
}

/// Rotates the low `n` bits of `x` left by `r`.
fn rotl(x: u32, r: u32, n: u32) -> u32 {
    rotr(x, n - r % n, n)
}

fn gray(i: u32) -> u32 {
    i ^ (i >> 1)
}

fn gray_inverse(g: u32) -> u32 {
    let mut i = g;
    let mut s = 1;
    while (g >> s) > 0 {
        i ^= g >> s;
        s += 1;
    }
    i
}

/// Entry corner of sub-cell `i`.
fn entry(i: u32) -> u32 {
    if i == 0 {
        0
    } else {
        gray(2 * ((i - 1) / 2))
    }
}

/// Intra-cell direction of sub-cell `i` in `n` dimensions.
fn direction(i: u32, n: u32) -> u32 {
    if i == 0 {
        0
    } else if i % 2 == 0 {
        (i - 1).trailing_ones() % n
    } else {
        i.trailing_ones() % n
    }
}

/// One level of the encoder: from state (e, d) and octant bits `l` (x in bit 0) to the digit and
/// the next state.
fn step(e: u32, d: u32, l: u32, n: u32) -> (u32, u32, u32) {
    let t = rotr(l ^ e, d + 1, n);
    let w = gray_inverse(t);
    let e2 = e ^ rotl(entry(w), d + 1, n);
    let d2 = (d + direction(w, n) + 1) % n;
    (w, e2, d2)
}

/// Transition table for `n` dimensions: index `state << n | l` gives `next_state << n | digit`,
/// with state = e·n + d.
fn table(n: u32) -> Vec<u16> {
    let states = (1u32 << n) * n;
    let mut t = vec![0u16; (states << n) as usize];
    for s in 0..states {
        let (e, d) = (s / n, s % n);
        for l in 0..(1u32 << n) {
            let (w, e2, d2) = step(e, d, l, n);
            t[((s << n) | l) as usize] = (((e2 * n + d2) << n) | w) as u16;
        }
    }
    t
}

fn table3() -> &'static [u16] {
    static T: OnceLock<Vec<u16>> = OnceLock::new();
    T.get_or_init(|| table(3))
}

fn table2() -> &'static [u16] {
    static T: OnceLock<Vec<u16>> = OnceLock::new();
    T.get_or_init(|| table(2))
}

/// Hilbert index of cell `q` (one coordinate per axis, `levels` bits each) in 2 or 3 dimensions.
#[inline]
pub fn key(q: &[u64], levels: u32) -> u64 {
    let n = q.len() as u32;
    let t = if n == 3 { table3() } else { table2() };
    let mut state: u32 = 0;
    let mut h: u64 = 0;
    for i in (0..levels).rev() {
        let mut l = 0u32;
        for (a, &c) in q.iter().enumerate() {
            l |= (((c >> i) & 1) as u32) << a;
        }
        let v = t[((state << n) | l) as usize] as u32;
        h = (h << n) | u64::from(v & ((1 << n) - 1));
        state = v >> n;
    }
    h
}

/// The same index computed level by level from the rules, without the table (reference).
pub fn key_by_rules(q: &[u64], levels: u32) -> u64 {
    let n = q.len() as u32;
    let (mut e, mut d, mut h) = (0u32, 0u32, 0u64);
    for i in (0..levels).rev() {
        let mut l = 0u32;
        for (a, &c) in q.iter().enumerate() {
            l |= (((c >> i) & 1) as u32) << a;
        }
        let (w, e2, d2) = step(e, d, l, n);
        h = (h << n) | u64::from(w);
        e = e2;
        d = d2;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_curve(n: usize, levels: u32) {
        let side = 1u64 << levels;
        let cells = side.pow(n as u32);
        let mut at = vec![u64::MAX; cells as usize];
        for c in 0..cells {
            let q: Vec<u64> = (0..n).map(|a| (c / side.pow(a as u32)) % side).collect();
            let h = key(&q, levels);
            assert_eq!(h, key_by_rules(&q, levels));
            assert!(h < cells, "index out of range");
            assert_eq!(at[h as usize], u64::MAX, "index {h} used twice");
            at[h as usize] = c;
        }
        for w in at.windows(2) {
            let (a, b) = (w[0], w[1]);
            let dist: u64 = (0..n)
                .map(|ax| {
                    let (x, y) = (
                        (a / side.pow(ax as u32)) % side,
                        (b / side.pow(ax as u32)) % side,
                    );
                    x.abs_diff(y)
                })
                .sum();
            assert_eq!(
                dist, 1,
                "consecutive cells {a} and {b} are not face neighbours"
            );
        }
        // The curve starts at the origin cell.
        assert_eq!(at[0], 0);
    }

    #[test]
    fn consecutive_cells_are_face_adjacent_3d() {
        for levels in 1..=4 {
            check_curve(3, levels);
        }
    }

    #[test]
    fn consecutive_cells_are_face_adjacent_2d() {
        for levels in 1..=6 {
            check_curve(2, levels);
        }
    }
}
