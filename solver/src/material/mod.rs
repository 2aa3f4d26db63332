//! Constitutive laws of the solid and the pore liquid's constants.

pub mod conformance;
pub mod definition;
pub mod element_test;
pub mod error;
pub mod hypoplastic;
pub mod law;
pub mod linear_elastic;
pub mod liquid;
pub mod modified_cam_clay;
pub mod mohr_coulomb;
pub mod principal;
pub mod strain_softening_mohr_coulomb;
pub mod strength;
