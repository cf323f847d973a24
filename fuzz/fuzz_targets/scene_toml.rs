#![no_main]
//! Scene files (TOML) as the planner reads them.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = vklens::plan::SceneFile::parse(text, std::path::Path::new("/fuzz/scene.toml"));
    }
});
