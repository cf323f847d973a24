//! The committed `include/vklens.h` is exactly what cbindgen generates from `src/lib.rs`:
//! a change to the API that forgets the header fails here. `VKLENS_BLESS=1` rewrites it.

use std::path::Path;

#[test]
fn the_committed_header_is_what_cbindgen_generates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen generates the header");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).expect("UTF-8 header");
    let path = dir.join("include/vklens.h");
    if std::env::var_os("VKLENS_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write include/vklens.h");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != generated {
        let first = committed
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(committed.lines().count().min(generated.lines().count()));
        panic!(
            "include/vklens.h differs from what cbindgen generates (first at line {}); run \
             `VKLENS_BLESS=1 cargo test --release -p vklens-capi --test header` and commit it",
            first + 1
        );
    }
    for name in [
        "vkl_warper_record",
        "VKL_API_VERSION",
        "VKL_ERROR_INPUT",
        "vkl_vulkan",
        "vkl_scene_render",
        "VKL_OUTPUT_FLOW",
    ] {
        assert!(generated.contains(name), "{name} missing from the header");
    }
}
