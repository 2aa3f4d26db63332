//! Coverage-guided fuzzing of the gom reader (see docs/design.md §7.5, "Fuzzing").
#![no_main]

#[path = "../../shared/tests/fuzz_support/readers.rs"]
#[allow(dead_code)] // each target uses one of them
mod readers;

libfuzzer_sys::fuzz_target!(|data: &[u8]| readers::read_gom(data));
