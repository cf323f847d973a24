//! Writes `vklens.pc` beside the built library (`target/<profile>/vklens.pc`), so that
//! `PKG_CONFIG_PATH=target/release pkg-config --cflags --libs vklens` finds this checkout's
//! header and library.

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let (Some(out), Some(manifest)) = (
        std::env::var_os("OUT_DIR").map(PathBuf::from),
        std::env::var_os("CARGO_MANIFEST_DIR").map(PathBuf::from),
    ) else {
        return;
    };
    // OUT_DIR is target/<profile>/build/<package>-<hash>/out.
    let Some(libdir) = out.ancestors().nth(3) else {
        return;
    };
    let version = std::env::var("CARGO_PKG_VERSION").unwrap_or_default();
    let pc = format!(
        "libdir={}\nincludedir={}\n\nName: vklens\nDescription: Calibrated camera-lens distortion on Vulkan (C API)\nVersion: {version}\nRequires.private: vulkan\nLibs: -L${{libdir}} -lvklens\nLibs.private: -lpthread -ldl -lm\nCflags: -I${{includedir}}\n",
        libdir.display(),
        manifest.join("include").display(),
    );
    // A failure here only loses the convenience file; the build itself does not need it.
    let _ = std::fs::write(libdir.join("vklens.pc"), pc);
}
