#![no_main]
//! Every camera format (vklens JSON of each model, OpenCV FileStorage YAML/XML/JSON, ROS,
//! Kalibr, COLMAP), through the one entry point that detects them; also with a camera index.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        for index in [None, Some(1)] {
            if let Ok(camera) = vklens::internal::io::camera::parse_camera_at(text, "fuzz.json", index) {
                // A camera that loads must be usable: its model answers without panicking.
                let _ = camera.to_json();
                let _ = camera.unproject_points(&[[1.0, 2.0], [f64::MAX, -0.0]]);
            }
        }
    }
});
