//! Writing images without leaving half-written files behind: write to a temporary file in
//! the same folder, then rename over the target.

use std::path::Path;

use crate::cli::CliError;

/// Saves `image` as PNG at `path` atomically.
pub fn save_atomically(image: &image::RgbaImage, path: &Path) -> Result<(), CliError> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(CliError::input(format!(
            "{}: folder {} does not exist",
            path.display(),
            dir.display()
        )));
    }
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("output");
    let tmp = dir.join(format!(".{name}.vklens-tmp"));
    let result = image
        .save_with_format(&tmp, image::ImageFormat::Png)
        .map_err(|e| CliError::runtime(format!("{}: cannot write: {e}", path.display())))
        .and_then(|_| {
            std::fs::rename(&tmp, path)
                .map_err(|e| CliError::runtime(format!("{}: cannot write: {e}", path.display())))
        });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
