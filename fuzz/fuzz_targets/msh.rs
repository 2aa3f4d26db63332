//! Coverage-guided fuzzing of the msh reader (see docs/design.md §7.6).
#![no_main]

#[path = "../../shared/tests/fuzz_support/readers.rs"]
mod readers;

libfuzzer_sys::fuzz_target!(|data: &[u8]| readers::read_msh(data));
