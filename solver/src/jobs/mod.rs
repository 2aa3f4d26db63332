//! Jobs built on the driver: consolidation against Terzaghi, comparisons with Anura3D's reported
//! points, the closed forms of Cam Clay's element tests and the hypoplastic law's peak and
//! critical states; the pile-driving report of a hammer on a structure in contact with the soil.

pub mod anura3d_compare;
pub mod cam_clay;
pub mod consolidation;
pub mod driving;
pub mod hypoplastic;
pub mod plot;
pub mod terzaghi;

/// An observer's state of f64 values as the bytes of a checkpoint (little-endian bits).
pub(crate) fn state_bytes(values: &[f64]) -> Vec<u8> {
    values
        .iter()
        .flat_map(|x| x.to_bits().to_le_bytes())
        .collect()
}

/// The f64 values of [`state_bytes`]; refused, naming `what`, when the length is not whole
/// values.
pub(crate) fn state_values(state: &[u8], what: &str) -> Result<Vec<f64>, String> {
    if state.len() % 8 != 0 {
        return Err(format!("{what} of a ragged length"));
    }
    Ok(state
        .chunks_exact(8)
        .map(|c| f64::from_bits(u64::from_le_bytes(c.try_into().unwrap_or_default())))
        .collect())
}
