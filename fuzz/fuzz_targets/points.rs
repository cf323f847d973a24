#![no_main]
//! The JSON points of `vklens points` (rows of two or three numbers).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = vklens_cli::commands::parse_point_rows(text, true);
    }
});
