//! A frame compiles no shader: every pipeline is compiled when it is made, never again at a
//! draw or a dispatch, however many frames follow.
//!
//! lavapipe, the device these tests run on, compiles a shader again at every draw or dispatch
//! where an `if` reads uniform values alone and inlining them folds half the shader away
//! (`VKL_RUNTIME` in glsl/include/rolling_shutter.glsl): milliseconds per frame that no result
//! shows. Its compiler is LLVM, which starts a module per compile, so a small library put in
//! front of LLVM (tests/frame_compiles/count_compiles.c) counts the compiles of a run: three
//! frames must compile what one frame does. Skipped, saying why, where the Vulkan driver is not
//! lavapipe on LLVM.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common;

use common::{scratch, stderr};

/// LLVM's shared library as lavapipe links it, or why there is none to count compiles in.
fn lavapipe_llvm() -> Result<PathBuf, String> {
    let icd = std::fs::read_dir("/usr/share/vulkan/icd.d")
        .map_err(|e| format!("no Vulkan drivers listed: {e}"))?
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("lvp_icd"))
        })
        .ok_or("lavapipe is not installed")?;
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&icd).map_err(|e| format!("{}: {e}", icd.display()))?,
    )
    .map_err(|e| format!("{}: {e}", icd.display()))?;
    let library = json["ICD"]["library_path"]
        .as_str()
        .ok_or_else(|| format!("{}: no ICD.library_path", icd.display()))?;
    let ldd = Command::new("ldd")
        .arg(library)
        .output()
        .map_err(|e| format!("ldd: {e}"))?;
    String::from_utf8_lossy(&ldd.stdout)
        .lines()
        .filter(|l| l.contains("libLLVM"))
        .find_map(|l| {
            l.split("=>")
                .nth(1)?
                .split_whitespace()
                .next()
                .map(PathBuf::from)
        })
        .ok_or_else(|| format!("{library} does not link LLVM"))
}

/// Builds the counting library against `llvm`.
fn counter(llvm: &Path) -> PathBuf {
    let out = scratch("framecompiles", "count_compiles.so");
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let built = Command::new(&compiler)
        .args(["-shared", "-fPIC", "-O2", "-Wall", "-Werror"])
        .arg(crate::common::root().join("tests/frame_compiles/count_compiles.c"))
        // The library finds LLVM's function by dlsym alone: it must still load LLVM first.
        .arg("-Wl,--no-as-needed")
        .arg(llvm)
        .arg("-ldl")
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap_or_else(|e| panic!("{compiler}: {e}"));
    assert!(built.status.success(), "{compiler}: {}", stderr(&built));
    out
}

/// The shader compiles of `vklens render --scene scene --frames frames` (module names).
fn compiles(counter: &Path, scene: &Path, frames: &str) -> Vec<String> {
    let out = scratch("framecompiles", &format!("out{frames}"));
    let o = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(["render", "--scene"])
        .arg(scene)
        .arg("--out")
        .arg(&out)
        .args(["--frames", frames])
        .env("VKLENS_VALIDATION", "1")
        .env("LD_PRELOAD", counter)
        .output()
        .unwrap();
    let said = stderr(&o);
    assert!(o.status.success(), "{}: {said}", scene.display());
    said.lines()
        .filter_map(|l| l.strip_prefix("vklens-compile: "))
        .map(str::to_owned)
        .collect()
}

/// examples/scenes/rolling_shutter.toml (a camera that moves during the readout) with its one
/// pose three times.
fn moving_rolling_shutter() -> PathBuf {
    let examples = crate::common::root().join("examples/scenes");
    let text = std::fs::read_to_string(examples.join("rolling_shutter.toml")).unwrap();
    let camera = examples.join("../cameras/barrel_k1k2.json");
    let text = text.replace("\"../cameras/barrel_k1k2.json\"", &format!("{camera:?}"));
    let pose = &text[text.find("[[poses]]").expect("the example has a pose")..];
    let path = scratch("framecompiles", "rolling_shutter.toml");
    std::fs::write(&path, format!("{text}\n{pose}\n{pose}")).unwrap();
    path
}

#[test]
fn three_frames_compile_what_one_frame_does() {
    let llvm = match lavapipe_llvm() {
        Ok(l) => l,
        Err(why) => {
            eprintln!("skipped: {why}");
            return;
        }
    };
    let counter = counter(&llvm);
    let flow = crate::common::root().join("examples/scenes/ids_and_flow.toml");
    for scene in [moving_rolling_shutter(), flow] {
        let one = compiles(&counter, &scene, "0..1");
        let three = compiles(&counter, &scene, "0..3");
        assert!(!one.is_empty(), "{}: no compile counted", scene.display());
        assert_eq!(
            one.len(),
            three.len(),
            "{}: one frame compiled {one:?}, three frames {three:?}",
            scene.display()
        );
    }
}
