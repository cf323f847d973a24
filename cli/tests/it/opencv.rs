//! Runs `tests/opencv_crosscheck.py`: vklens against OpenCV itself (undistort vs
//! initUndistortRectifyMap + remap; the distort → OpenCV-undistort round trip). `scripts/bootstrap`
//! installs opencv-python-headless.

use crate::common;

use std::process::Command;

#[test]
fn vklens_agrees_with_opencv_remap_and_round_trips_through_opencv() {
    let root = crate::common::root().display().to_string();
    let have_cv2 = Command::new("python3")
        .args(["-c", "import cv2, numpy"])
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    assert!(have_cv2, "python3 with cv2 and numpy is needed: run scripts/bootstrap (it pip-installs opencv-python-headless)");
    let out = Command::new("python3")
        .arg(format!("{root}/tests/opencv_crosscheck.py"))
        .arg(env!("CARGO_BIN_EXE_vklens"))
        .arg(common::shared_dir())
        .env("VKLENS_VALIDATION", "1")
        .output()
        .expect("run python3");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    assert!(out.status.success(), "OpenCV cross-check failed:\n{text}");
}
