#![no_main]
//! Every camera format vklens reads (vklens JSON of each model, OpenCV FileStorage, ROS,
//! Kalibr, COLMAP, Basalt, camodocal, NCore, OCamCalib, the SLAM systems' configs, DSO and
//! LSD-SLAM/PTAM text, Gyroflow, OpenCV stereo files), through the one entry point that
//! detects them: every camera of the listing, with and without a size, picked by index and
//! by name, written back in every format.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        vklens::io::camera::exercise(text);
    }
});
