//! Outputs are written safely: never half-written, never replacing what is at the path when
//! that is not a regular file (that concurrent writers never mix their bytes is a unit test of
//! `imaging::file`).

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vklens-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("vklens-tmp"))
        .collect()
}

#[test]
fn a_symlink_is_followed_a_device_written_through_a_folder_refused() {
    let dir = temp_dir("targets");
    let vklens = env!("CARGO_BIN_EXE_vklens");
    let demo = |out: &Path| {
        Command::new(vklens)
            .args(["demo", "--output", out.to_str().unwrap()])
            .output()
            .unwrap()
    };
    // A symlink: its target gets the image, the link stays a link.
    let real = dir.join("real.png");
    let link = dir.join("link.png");
    std::fs::write(&real, b"old").unwrap();
    std::os::unix::fs::symlink("real.png", &link).unwrap();
    let o = demo(&link);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(image::open(&real).unwrap().width(), 800);
    // A character device (a second /dev/null): written through, still a device.
    let null = dir.join("null.png");
    let made = Command::new("mknod")
        .args([null.to_str().unwrap(), "c", "1", "3"])
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if made {
        let o = demo(&null);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(std::fs::metadata(&null)
            .unwrap()
            .file_type()
            .is_char_device());
    } else {
        eprintln!("mknod is not allowed here: the device case is not checked");
    }
    // A folder: refused, exit 2, and it stays a folder.
    let folder = dir.join("folder.png");
    std::fs::create_dir(&folder).unwrap();
    let o = demo(&folder);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("is a folder"));
    assert!(folder.is_dir());
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_outputs_naming_one_file_are_refused_before_any_work() {
    let dir = temp_dir("same");
    let cam = crate::common::root().join("examples/cameras/barrel_k1k2.json");
    let c = dir.join("c.png");
    let vklens = env!("CARGO_BIN_EXE_vklens");
    let o = Command::new(vklens)
        .args([
            "render",
            "--camera",
            cam.to_str().unwrap(),
            "--scene",
            "boxes",
        ])
        .args([
            "--output",
            c.to_str().unwrap(),
            "--ids",
            c.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--output and --ids"), "{err}");
    assert!(!c.exists());
    let input = dir.join("in.png");
    image::RgbaImage::new(800, 600).save(&input).unwrap();
    let o = Command::new(vklens)
        .args(["distort", "--camera", cam.to_str().unwrap()])
        .args([
            "--input",
            input.to_str().unwrap(),
            "--output",
            c.to_str().unwrap(),
        ])
        .args(["--mask", dir.join(".").join("c.png").to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--output and --mask"), "{err}");
    assert!(!c.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A glTF file whose accessor index points nowhere (the glTF crate panics on it) is one line,
/// exit 2, naming the file: the panic is caught and not printed.
#[test]
fn a_malformed_gltf_is_one_line_exit_2() {
    let dir = temp_dir("gltf");
    let bad = dir.join("bad.gltf");
    std::fs::write(&bad, r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#).unwrap();
    let cam = crate::common::root().join("examples/cameras/barrel_k1k2.json");
    let o = Command::new(env!("CARGO_BIN_EXE_vklens"))
        .args(["render", "--camera", cam.to_str().unwrap()])
        .args(["--scene", bad.to_str().unwrap()])
        .args(["--output", dir.join("c.png").to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bad.gltf") && !err.contains("panicked"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
