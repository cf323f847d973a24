//! Replays every input under `tests/corpus/TARGET/` through the parser its fuzz target
//! (`fuzz/fuzz_targets/TARGET.rs`) drives, on stable: what the fuzzers found once (and the
//! seeds they started from) stays fixed. Each input must be refused or accepted, never panic.

use std::path::Path;

fn inputs(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = crate::repo_root().join("tests/corpus").join(target);
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| {
            let p = e.unwrap().path();
            (p.display().to_string(), std::fs::read(&p).unwrap())
        })
        .collect();
    v.sort();
    assert!(!v.is_empty(), "{}: no inputs", dir.display());
    v
}

/// Runs `f` on every input of `target`, failing on the first panic with the input's name.
fn replay(target: &str, f: impl Fn(&[u8])) {
    for (name, data) in inputs(target) {
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&data)));
        assert!(r.is_ok(), "{target}: {name} panics");
    }
}

fn temp_file(tag: &str, ext: &str, body: &[u8]) -> std::path::PathBuf {
    let p = std::env::temp_dir().join(format!("vklens-corpus-{tag}-{}.{ext}", std::process::id()));
    std::fs::write(&p, body).unwrap();
    p
}

#[test]
fn camera_corpus() {
    replay("camera", |d| {
        if let Ok(text) = std::str::from_utf8(d) {
            vklens::io::camera::exercise(text);
        }
    });
}

#[test]
fn lens_corpus() {
    replay("lens", |d| {
        if let Ok(text) = std::str::from_utf8(d) {
            let _ = vklens::lens::prescription::Prescription::parse(text, "corpus");
        }
    });
}

#[test]
fn scene_toml_corpus() {
    replay("scene_toml", |d| {
        if let Ok(text) = std::str::from_utf8(d) {
            let _ = vklens::plan::SceneFile::parse(text, Path::new("/corpus/scene.toml"));
        }
    });
}

#[test]
fn points_corpus() {
    replay("points", |d| {
        if let Ok(text) = std::str::from_utf8(d) {
            let _ = crate::commands::parse_point_rows(text, true);
        }
    });
}

#[test]
fn mesh_corpus() {
    replay("mesh", |d| {
        let Some((&kind, body)) = d.split_first() else {
            return;
        };
        let ext = ["obj", "gltf", "glb"][kind as usize % 3];
        let _ = vklens::scene::load::load_file(&temp_file("mesh", ext, body));
    });
}

#[test]
fn image_corpus() {
    replay("image", |d| {
        let Some((&kind, body)) = d.split_first() else {
            return;
        };
        let ext = ["png", "exr"][kind as usize % 2];
        let _ = vklens::imaging::file::load(&temp_file("image", ext, body));
    });
}

/// The image fuzzer's one finding: a 1 KiB file whose header claims an image of 2 GiB made
/// the decoder allocate the claimed size before it found the data missing. Refused from the
/// header now, at once.
#[test]
fn an_image_header_claiming_more_than_its_file_can_hold_is_refused_before_decoding() {
    let data = std::fs::read(crate::repo_root().join("tests/corpus/image/oom-header-claims-2gib"))
        .unwrap();
    let (&kind, body) = data.split_first().unwrap();
    let ext = ["png", "exr"][kind as usize % 2];
    let start = std::time::Instant::now();
    let e = vklens::imaging::file::load(&temp_file("oom", ext, body))
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot hold") || e.contains("budget"), "{e}");
    assert!(start.elapsed().as_secs_f64() < 1.0);
}
