//! Reading what users bring: camera files, the shared reference data.

pub mod camera;
pub mod catalog;
pub mod dso;
pub mod gyroflow;
pub mod models;
pub mod reference;
pub mod slam;
pub mod stereo;
#[cfg(test)]
mod tests;
pub mod writers;

pub use camera::{load_camera, parse_camera};

use std::io::Read;
use std::path::Path;

/// Largest text input vklens reads (camera, lens and scene files), in MiB, unless
/// `VKLENS_MAX_FILE_MB` says otherwise: real ones are a few KiB, and a limit keeps a mistaken
/// path (`/dev/zero`, a video) from filling memory before the parser can object.
pub const DEFAULT_MAX_FILE_MB: u64 = 16;

/// The limit in force, in bytes.
pub fn max_file_bytes() -> u64 {
    std::env::var("VKLENS_MAX_FILE_MB")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .unwrap_or(DEFAULT_MAX_FILE_MB)
        .saturating_mul(1 << 20)
}

/// Reads a text file of at most [`max_file_bytes`]; a larger one is an error of kind
/// `FileTooLarge` naming the limit and how to raise it, read no further than the limit.
pub fn read_text(path: &Path) -> std::io::Result<String> {
    let limit = max_file_bytes();
    let mut text = String::new();
    std::fs::File::open(path)?
        .take(limit.saturating_add(1))
        .read_to_string(&mut text)?;
    if text.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!(
                "larger than {} MiB, the limit for a text input (set VKLENS_MAX_FILE_MB to raise it)",
                limit >> 20
            ),
        ));
    }
    Ok(text)
}
