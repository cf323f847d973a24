#![no_main]
//! Meshes: the first byte picks OBJ, glTF (JSON) or GLB; the rest is the file, loaded
//! through the project's own loader (which reads files).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, body)) = data.split_first() else { return };
    let ext = ["obj", "gltf", "glb"][kind as usize % 3];
    let path = std::env::temp_dir().join(format!("vklens-fuzz-mesh-{}.{ext}", std::process::id()));
    if std::fs::write(&path, body).is_ok() {
        let _ = vklens::scene::load::load_file(&path);
    }
});
