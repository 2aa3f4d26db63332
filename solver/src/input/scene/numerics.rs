//! The scene's top-level numerical choices: precision, integration, and the share of PIC in
//! the points' velocity update.

use super::{refuse, Refusal};
use crate::input::case::{Gradient, Integration, MixedRule, Precision};

/// Refuses a PIC share outside [0, 1], and any PIC share with prescribed velocities.
pub(super) fn check_pic_blend(pic_blend: f64, has_velocities: bool) -> Result<(), Refusal> {
    if !(0.0..=1.0).contains(&pic_blend) {
        return Err(refuse(
            "pic_blend",
            format!("must be in [0, 1], got {pic_blend}"),
        ));
    }
    if pic_blend > 0.0 && has_velocities {
        // The PIC part would read a prescribed component as a fixed one (zero).
        return Err(refuse(
            "pic_blend",
            "is not modelled together with [[velocity]] prescriptions; leave it 0 (FLIP)",
        ));
    }
    Ok(())
}

/// The precision `precision` names (f64 by default).
pub(super) fn precision(precision: Option<&str>) -> Result<Precision, Refusal> {
    match precision {
        None => Ok(Precision::F64),
        Some(s) => Precision::parse(s).ok_or_else(|| {
            refuse(
                "precision",
                format!("{s:?} is not a precision; use \"f64\" or \"f32\""),
            )
        }),
    }
}

/// The integration `integration` names (material points by default).
pub(super) fn integration(integration: Option<&str>) -> Result<Integration, Refusal> {
    match integration {
        None | Some("points") => Ok(Integration::MaterialPoints),
        // Anura3D's default degree of filling (CPS `DEGREE_OF_FILLING`).
        Some("mixed") => Ok(Integration::Mixed {
            filling: 0.9,
            rule: MixedRule::FullAtStart,
        }),
        Some(s) => Err(refuse(
            "integration",
            format!("{s:?} is not an integration; use \"points\" or \"mixed\""),
        )),
    }
}

/// The gradients `gradient` names on the mesh's elements (their own by default).
pub(super) fn gradient(gradient: Option<&str>, on_grid: bool) -> Result<Gradient, Refusal> {
    let g = match gradient {
        None | Some("element") => Gradient::Element,
        Some("ddmp") => Gradient::Ddmp,
        Some("ddmp_blended") => Gradient::DdmpBlended,
        Some(s) => {
            return Err(refuse(
                "gradient",
                format!("{s:?} is not a gradient; use \"element\", \"ddmp\" or \"ddmp_blended\""),
            ))
        }
    };
    if on_grid && g != Gradient::Element {
        return Err(refuse(
            "gradient",
            "the dual-domain gradients are the mesh's elements'; a [grid] takes its basis's own",
        ));
    }
    Ok(g)
}
