//! The law's update of a batch of the general loop ([`update_batch`]): a batch of one
//! linear-elastic or Mohr-Coulomb material across its points, any other law point by point.

use crate::element::Element;
use crate::four::Plain;
use crate::material::law::Law;
use crate::material::mohr_coulomb::MohrCoulomb;
use crate::real::Real;
use crate::step::batch::Batch;

use super::{plastic_lanes_avx2, ChunkPoints, Pass};

/// The stresses `s1` of batch `b`'s points updated by their laws for the strain increments
/// `de` (each lane a point; the state of the points that take part updated with them).
#[inline(always)]
pub(super) fn update_batch<E: Element, R: Real, const W: usize, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    p: &mut ChunkPoints<'_, R>,
    b: &Batch<W>,
    s1: &mut [Plain<R, W>; 6],
    de: &[Plain<R, W>; 6],
) {
    let mut s: [[R; W]; 6] = std::array::from_fn(|c| s1[c].0);
    let d: [[R; W]; 6] = std::array::from_fn(|c| de[c].0);
    let material = p.material;
    let lead = material[b.at[0]];
    let one = b.points().all(|i| material[i] == lead);
    match &cx.laws[lead as usize] {
        Law::LinearElastic(le) if one => le.update_lanes(&mut s, &d),
        // (A lone point goes by the scalar update: the same bits.)
        Law::MohrCoulomb(mc) if one && W > 1 => plastic_lanes::<R, W, WIDE>(mc, &mut s, &d, &b.on),
        _ => {
            let k = p.k;
            for i in b.points() {
                let q = i - b.start;
                let mut si: [R; 6] = std::array::from_fn(|c| s[c][q]);
                let di: [R; 6] = std::array::from_fn(|c| d[c][q]);
                cx.laws[material[i] as usize].update(&mut si, &di, &mut p.state[k * i..k * i + k]);
                for c in 0..6 {
                    s[c][q] = si[c];
                }
            }
        }
    }
    *s1 = std::array::from_fn(|c| Plain(s[c]));
}

/// [`MohrCoulomb::update_lanes`] in a function of its own, so that the long return does not
/// crowd the registers of the chunk's loop that every other law runs through; with `WIDE`
/// (the chunk's AVX2 copy's) compiled with AVX2.
#[inline(never)]
fn plastic_lanes<R: Real, const W: usize, const WIDE: bool>(
    mc: &MohrCoulomb<R>,
    s: &mut [[R; W]; 6],
    de: &[[R; W]; 6],
    on: &[bool; W],
) {
    if WIDE {
        debug_assert!(crate::parallel::avx2::present());
        // SAFETY: `WIDE` only in the chunk's AVX2 copy, which runs where the processor has
        // AVX2.
        unsafe { plastic_lanes_avx2(mc, s, de, on) }
    } else {
        mc.update_lanes(s, de, on)
    }
}
