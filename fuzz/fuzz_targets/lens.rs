#![no_main]
//! Lens prescription files (Heidrich et al.'s lens systems).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = vklens::lens::prescription::Prescription::parse(text, "fuzz.dat");
    }
});
