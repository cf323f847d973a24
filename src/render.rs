//! A scene through a calibrated lens, by either of seed 000's two paths:
//!
//! * **vertex** (Sec. 3.2): Alg. 1 per vertex, triangle discard, optional tessellation; every
//!   output exact for its data type (colour, IDs, flow, depth);
//! * **warp** (Sec. 3.3): a pinhole render of the overscanned frustum (so barrel lenses get
//!   their borders), then the compute warp — bilinear for colour, nearest for IDs and depth.
//!   Flow cannot be warped honestly (its vectors live in the pinhole image), so the warp path
//!   refuses it (Table 1).
//!
//! Supersampling renders colour at `s×` the resolution with the scaled camera (the lens is
//! the same: distortion acts on normalized coordinates) and box-filters down: anti-aliased
//! edges for calibration, where corner positions must be sub-pixel exact. IDs, flow and depth
//! are rendered at 1× (they must not be averaged).

use crate::gpu::{Context, GpuError, Result};
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::{Depth, Pixels, Raster};
use crate::model::overscan::overscan;
use crate::model::warp::WarpGeometry;
use crate::model::{Intrinsics, InverseMethod, OpenCvCamera, OpenCvDistortion};
use crate::pass::geometry::{render, ColorFormat, GeometryDesc, Outputs, Projection, Rendered};
use crate::pass::warp::{run_warp, Coordinates, PixelFormat, WarpDesc};
use crate::scene::tessellate::tessellate;
use crate::scene::{Pose, Scene};

/// Which path renders the lens.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RenderPath {
    /// Alg. 1 with discard tolerance δ.
    Vertex { delta: f64 },
    /// Pinhole render of the overscanned frustum, then the compute warp with `method`.
    Warp { method: InverseMethod },
}

/// What to render.
#[derive(Debug, Clone)]
pub struct RenderRequest {
    pub camera: OpenCvCamera,
    pub pose: Pose,
    /// The pose flow is measured from.
    pub previous_pose: Pose,
    pub path: RenderPath,
    pub outputs: Outputs,
    /// Colour supersampling factor per axis (1 = none).
    pub supersample: u32,
    /// Split mesh edges longer than this many pixels first (vertex path).
    pub tessellate: Option<f64>,
    pub background: [f32; 4],
}

/// The camera rendering `camera`'s image at `s×` its resolution.
pub fn scaled_camera(camera: &OpenCvCamera, s: u32) -> std::result::Result<OpenCvCamera, String> {
    let k = camera.intrinsics;
    let f = s as f64;
    OpenCvCamera::new(
        camera.width * s,
        camera.height * s,
        Intrinsics {
            fx: k.fx * f,
            fy: k.fy * f,
            // Pixel edges scale, not centres: pixel i spans [i − 0.5, i + 0.5].
            cx: (k.cx + 0.5) * f - 0.5,
            cy: (k.cy + 0.5) * f - 0.5,
        },
        camera.distortion,
    )
    .map_err(|e| e.to_string())
}

/// Box-filters an image by `s` per axis (its size must be a multiple of `s`).
pub fn downsample(image: &Raster, s: u32) -> Raster {
    if s == 1 {
        return image.clone();
    }
    let (w, h) = (image.width / s, image.height / s);
    let n = (s * s) as f32;
    let mut sums = vec![[0f32; 4]; (w * h) as usize];
    for y in 0..h * s {
        for x in 0..w * s {
            let v = image.rgba_f32((y * image.width + x) as usize);
            let o = &mut sums[((y / s) * w + x / s) as usize];
            for c in 0..4 {
                o[c] += v[c];
            }
        }
    }
    let pixels = match image.pixels {
        Pixels::Rgba8(_) => Pixels::Rgba8(
            sums.iter()
                .map(|p| p.map(|c| (c / n * 255.0).round().clamp(0.0, 255.0) as u8))
                .collect(),
        ),
        _ => Pixels::Rgba32F(sums.iter().map(|p| p.map(|c| c / n)).collect()),
    };
    Raster {
        width: w,
        height: h,
        pixels,
        depth: image.depth,
    }
}

fn invalid(e: impl ToString) -> GpuError {
    GpuError::Invalid(e.to_string())
}

/// Renders `scene` as `request` asks; `progress` hears each step.
pub fn render_scene(
    ctx: &Context,
    scene: &Scene,
    request: &RenderRequest,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    let s = request.supersample.clamp(1, 16);
    match request.path {
        RenderPath::Vertex { delta } => {
            let mesh = match request.tessellate {
                Some(l) => {
                    progress(&format!("tessellating to {l} px edges"));
                    let m = tessellate(&scene.mesh, &request.pose, &request.camera.intrinsics, l)
                        .map_err(invalid)?;
                    progress(&format!("{} triangles", m.triangle_count()));
                    m
                }
                None => scene.mesh.clone(),
            };
            let projection = Projection::Lens { delta };
            let o = request.outputs;
            let data = Outputs { color: None, ..o };
            let run = |camera: OpenCvCamera, outputs: Outputs| {
                let mut desc = GeometryDesc::new(camera, projection, outputs);
                desc.background = request.background;
                render(
                    ctx,
                    desc,
                    &mesh,
                    scene.texture.as_ref(),
                    &request.pose,
                    &request.previous_pose,
                )
            };
            if s == 1 || o.color.is_none() {
                progress("rendering (vertex path)");
                return run(request.camera.clone(), o);
            }
            progress(&format!("rendering colour at {s}× (vertex path)"));
            let big = run(
                scaled_camera(&request.camera, s).map_err(invalid)?,
                Outputs {
                    color: o.color,
                    ids: false,
                    flow: false,
                    depth: false,
                },
            )?;
            let mut out = if data.ids || data.flow || data.depth {
                progress("rendering data outputs at 1×");
                run(request.camera.clone(), data)?
            } else {
                Rendered {
                    width: request.camera.width,
                    height: request.camera.height,
                    ..Default::default()
                }
            };
            out.color = big.color.map(|c| downsample(&c, s));
            Ok(out)
        }
        RenderPath::Warp { method } => render_warp_path(ctx, scene, request, method, s, progress),
    }
}

fn render_warp_path(
    ctx: &Context,
    scene: &Scene,
    request: &RenderRequest,
    method: InverseMethod,
    s: u32,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    let o = request.outputs;
    if o.flow {
        return Err(invalid(
            "flow needs the vertex path: its vectors live in the pinhole image and a warp cannot carry them (seed 000 Table 1); use --path vertex",
        ));
    }
    let cam = &request.camera;
    let ov = overscan(cam, 1.0).map_err(invalid)?;
    let pinhole = OpenCvCamera::new(ov.width, ov.height, ov.intrinsics, OpenCvDistortion::default())
        .map_err(invalid)?;
    let geometry = WarpGeometry::distort(cam.clone(), method)
        .with_ideal(ov.intrinsics, (ov.width, ov.height))
        .map_err(invalid)?;
    let pinhole_render = |camera: OpenCvCamera, outputs: Outputs| {
        let mut desc = GeometryDesc::new(camera, Projection::Pinhole, outputs);
        desc.background = request.background;
        render(ctx, desc, &scene.mesh, scene.texture.as_ref(), &request.pose, &request.pose)
    };
    let warp = |source: &Raster, format: PixelFormat, sampling: Sampling, fill: [f32; 4]| {
        run_warp(
            ctx,
            WarpDesc {
                geometry: geometry.clone(),
                coordinates: Coordinates::Analytic,
                sampling,
                format,
                fill,
                write_mask: false,
            },
            source,
        )
        .map(|(r, _)| r)
    };
    let mut out = Rendered {
        width: cam.width,
        height: cam.height,
        ..Default::default()
    };
    if let Some(format) = o.color {
        progress(&format!(
            "rendering the pinhole source {}×{} at {s}× (warp path)",
            ov.width, ov.height
        ));
        let big = pinhole_render(
            scaled_camera(&pinhole, s).map_err(invalid)?,
            Outputs {
                color: Some(format),
                ids: false,
                flow: false,
                depth: false,
            },
        )?;
        let source = downsample(big.color.as_ref().ok_or_else(|| invalid("no colour"))?, s);
        progress("warping colour (bilinear)");
        let pixel_format = match format {
            ColorFormat::Rgba8 => PixelFormat::Rgba8,
            ColorFormat::Rgba16F => PixelFormat::Rgba32F,
        };
        out.color = Some(warp(&source, pixel_format, Sampling::Bilinear, request.background)?);
    }
    if o.ids || o.depth {
        progress("rendering pinhole IDs/depth at 1× (warp path)");
        let data = pinhole_render(
            pinhole.clone(),
            Outputs {
                color: None,
                ids: o.ids,
                flow: false,
                depth: o.depth,
            },
        )?;
        let raster = |pixels: Pixels| Raster {
            width: ov.width,
            height: ov.height,
            pixels,
            depth: Depth::F32,
        };
        if let Some(ids) = data.ids {
            progress("warping IDs (nearest)");
            let r = warp(&raster(Pixels::R32Uint(ids)), PixelFormat::R32Uint, Sampling::Nearest, [0.0; 4])?;
            if let Pixels::R32Uint(p) = r.pixels {
                out.ids = Some(p);
            }
        }
        if let Some(depth) = data.depth {
            progress("warping depth (nearest)");
            let r = warp(
                &raster(Pixels::Rgba32F(depth.iter().map(|&z| [z, z, z, 1.0]).collect())),
                PixelFormat::Rgba32F,
                Sampling::Nearest,
                [f32::INFINITY; 4],
            )?;
            out.depth = Some((0..r.len()).map(|i| r.rgba_f32(i)[0]).collect());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_camera_keeps_pixel_edges() {
        let cam = OpenCvCamera::from_coeffs(
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
        .unwrap();
        let big = scaled_camera(&cam, 4).unwrap();
        // The image's left edge (pixel −0.5) is at the same normalized x in both.
        let edge = |c: &OpenCvCamera| (-0.5 - c.intrinsics.cx) / c.intrinsics.fx;
        assert!((edge(&cam) - edge(&big)).abs() < 1e-15);
        assert_eq!((big.width, big.height), (3200, 2400));
        let img = Raster {
            width: 4,
            height: 2,
            pixels: Pixels::Rgba8(vec![
                [0; 4], [255; 4], [10; 4], [10; 4], [255; 4], [0; 4], [10; 4], [10; 4],
            ]),
            depth: Depth::U8,
        };
        let small = downsample(&img, 2);
        assert_eq!(small.pixels, Pixels::Rgba8(vec![[128; 4], [10; 4]]));
    }
}
