#![no_main]
//! PNG and OpenEXR loading through the project's own loader (the first byte picks the
//! extension; the loader goes by content).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, body)) = data.split_first() else { return };
    let ext = ["png", "exr"][kind as usize % 2];
    let path = std::env::temp_dir().join(format!("vklens-fuzz-image-{}.{ext}", std::process::id()));
    if std::fs::write(&path, body).is_ok() {
        let _ = vklens::imaging::file::load(&path);
    }
});
