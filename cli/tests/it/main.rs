//! The integration tests: the command line, the public API and the cross-checks against
//! OpenCV's own calibration and remap. One binary for all of them, because each binary links
//! the whole library: a binary per file cost the test command minutes of linking on two
//! cores.

mod common;

mod calibration;
mod camera_files;
mod cli;
mod cli_cameras;
mod cli_labels;
mod cli_lens;
mod cli_new_camera;
mod cli_points;
mod cli_render;
mod cli_stereo_rectify;
mod cli_warp;
mod facade;
mod frame_compiles;
mod hostile;
mod opencv;
mod outputs;
