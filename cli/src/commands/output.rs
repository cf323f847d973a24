//! Where a rendered frame's outputs go: checked before any work, written atomically.

use std::path::Path;

use super::CliError;
use vklens::imaging::{file as image_io, BitDepth, Pixels, Raster};
use vklens::pass::geometry::Rendered;

pub(crate) fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
}

pub(crate) fn check_output(path: &Path, what: &str, allowed: &[&str]) -> Result<String, CliError> {
    let ext = extension(path).unwrap_or_default();
    if !allowed.contains(&ext.as_str()) {
        return Err(CliError::input(format!(
            "{}: the {what} output must be {}",
            path.display(),
            allowed
                .iter()
                .map(|e| format!(".{e}"))
                .collect::<Vec<_>>()
                .join(" or ")
        )));
    }
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
    image_io::check_writable(path)?;
    Ok(ext)
}

/// Refuses two outputs naming the same file (one would silently overwrite the other), before
/// any work is done. Paths are compared made absolute, with symlinks resolved where they exist.
pub(crate) fn distinct_outputs(outputs: &[(&str, &Path)]) -> Result<(), CliError> {
    let key = |p: &Path| {
        std::fs::canonicalize(p)
            .or_else(|_| std::path::absolute(p))
            .unwrap_or_else(|_| p.to_path_buf())
    };
    for (i, (flag_a, a)) in outputs.iter().enumerate() {
        for (flag_b, b) in &outputs[i + 1..] {
            if key(a) == key(b) {
                return Err(CliError::input(format!(
                    "{flag_a} and {flag_b} both name {}: give each output its own file",
                    a.display()
                )));
            }
        }
    }
    Ok(())
}

/// Where each output of a frame goes.
#[derive(Default)]
pub(crate) struct Targets<'a> {
    pub color: Option<&'a Path>,
    pub ids: Option<&'a Path>,
    pub flow: Option<&'a Path>,
    pub depth: Option<&'a Path>,
    pub range: Option<&'a Path>,
    pub classes: Option<&'a Path>,
    pub boxes: Option<&'a Path>,
    pub keypoints: Option<&'a Path>,
    /// The object list (`objects.json`), with the frame's outputs.
    pub objects: Option<(&'a Path, &'a [vklens::labels::ObjectLabel])>,
}

/// `value` as indented JSON with a final newline.
pub(crate) fn json_text(value: &impl serde::Serialize) -> Result<String, CliError> {
    serde_json::to_string_pretty(value)
        .map(|s| s + "\n")
        .map_err(|e| CliError::internal(format!("cannot write JSON: {e}")))
}

/// Writes every output of a frame, or none: each is staged (written to its temporary file),
/// and only when all are is each put in place.
///
/// With `written`, the outputs join that run's list as they are put in place (a run that
/// fails or is interrupted later removes them).
pub(crate) fn write_outputs(
    args: &Targets,
    r: &Rendered,
    labels: &vklens::labels::FrameLabels,
    ids_ext: Option<&str>,
    mut written: Option<&mut image_io::RunOutputs>,
) -> Result<(), CliError> {
    let staged = std::cell::RefCell::new(Vec::new());
    let save = |raster: &Raster, path: &Path| -> Result<(), vklens::Error> {
        staged
            .borrow_mut()
            .push(image_io::save_staged(raster, path, image_io::Channels(4))?);
        Ok(())
    };
    let float_image = |pixels: Vec<[f32; 4]>| Raster {
        width: r.width,
        height: r.height,
        pixels: Pixels::Rgba32F(pixels),
        bit_depth: BitDepth::F32,
    };
    if let (Some(path), Some(c)) = (args.color, &r.color) {
        save(c, path)?;
    }
    let sixteen_bit = |values: &[u32]| Raster {
        width: r.width,
        height: r.height,
        pixels: Pixels::R32Uint(values.to_vec()),
        bit_depth: BitDepth::U16,
    };
    if let (Some(path), Some(ids)) = (args.ids, &r.ids) {
        if ids_ext == Some("png") {
            if let Some(&big) = ids.iter().find(|&&i| i > u16::MAX as u32) {
                return Err(CliError::input(format!(
                    "{}: object ID {big} does not fit a 16-bit PNG; write the IDs to .exr",
                    path.display()
                )));
            }
            save(&sixteen_bit(ids), path)?;
        } else {
            save(
                &float_image(
                    ids.iter()
                        .map(|&i| [i as f32, i as f32, i as f32, 1.0])
                        .collect(),
                ),
                path,
            )?;
        }
    }
    if let (Some(path), Some(flow)) = (args.flow, &r.flow) {
        let pixels = flow
            .iter()
            .map(|f| {
                let known = f[0].is_finite() && f[1].is_finite();
                [f[0], f[1], 0.0, if known { 1.0 } else { 0.0 }]
            })
            .collect();
        save(&float_image(pixels), path)?;
    }
    for (path, values) in [(args.depth, &r.depth), (args.range, &r.range)] {
        if let (Some(path), Some(values)) = (path, values) {
            save(
                &float_image(values.iter().map(|&z| [z, z, z, 1.0]).collect()),
                path,
            )?;
        }
    }
    if let (Some(path), Some(classes)) = (args.classes, &labels.classes) {
        save(&sixteen_bit(classes), path)?;
    }
    let json = |path: &Path, text: String| -> Result<(), CliError> {
        staged
            .borrow_mut()
            .push(image_io::stage(path, |tmp| std::fs::write(tmp, &text))?);
        Ok(())
    };
    if let (Some(path), Some(boxes)) = (args.boxes, &labels.boxes) {
        json(path, json_text(boxes)?)?;
    }
    if let (Some(path), Some(keypoints)) = (args.keypoints, &labels.keypoints) {
        json(path, json_text(keypoints)?)?;
    }
    if let Some((path, objects)) = args.objects {
        json(path, json_text(&objects)?)?;
    }
    for s in staged.into_inner() {
        match written.as_deref_mut() {
            Some(w) => s.commit_into(w)?,
            None => s.commit()?,
        }
    }
    Ok(())
}
