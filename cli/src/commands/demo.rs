//! `vklens demo`: a procedural grid seen through a lens, written as a PNG.

use std::path::PathBuf;

use clap::Args;

use super::{context, finish, load_camera, CliError};
use vklens::model::{Camera, Intrinsics};

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Camera file; default: Lambers et al.'s Fig. 2 camera (800×600, fx = fy = 400,
    /// cx = 399.5, cy = 299.5, k1 = -0.05, k2 = 0.01, p1 = 0.03, p2 = -0.01).
    #[arg(long, value_name = "CAM")]
    camera: Option<PathBuf>,
    /// Output PNG.
    #[arg(long, default_value = "grid.png")]
    output: PathBuf,
    /// Grid spacing in pinhole pixels.
    #[arg(long, default_value_t = 50)]
    grid: u32,
}

/// Lambers et al.'s Fig. 2 camera.
pub fn seed_fig2() -> Camera {
    Camera::from_coeffs(
        800,
        600,
        Intrinsics {
            fx: 400.0,
            fy: 400.0,
            cx: 399.5,
            cy: 299.5,
        },
        &[-0.05, 0.01, 0.03, -0.01],
    )
    .expect("Lambers et al.'s Fig. 2 camera is valid: its parameters are constants")
}

pub fn run(args: DemoArgs) -> Result<(), CliError> {
    let camera = match &args.camera {
        Some(path) => load_camera(path)?,
        None => seed_fig2(),
    };
    super::output::check_output(&args.output, "demo", &["png"])?;
    let ctx = context()?;
    eprintln!(
        "rendering {}×{} through the lens on {}",
        camera.width,
        camera.height,
        ctx.gpu().device_name()
    );
    let pixels = vklens::host::grid_demo::render_grid(&ctx, &camera, args.grid)?;
    finish(&ctx)?;
    let image = image::RgbaImage::from_raw(camera.width, camera.height, pixels)
        .ok_or_else(|| CliError::internal("pixel count does not match the image size"))?;
    vklens::imaging::file::write_atomically(&args.output, |tmp| {
        image
            .save_with_format(tmp, image::ImageFormat::Png)
            .map_err(std::io::Error::other)
    })?;
    let invalid = image.pixels().filter(|p| p[3] == 0).count();
    eprintln!(
        "wrote {} ({} px outside the lens's valid domain, left transparent)",
        args.output.display(),
        invalid
    );
    Ok(())
}
