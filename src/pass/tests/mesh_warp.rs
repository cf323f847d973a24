//! The Durham radial-correction paper's Sec. II-B's mesh warp against the exact (f64) warp coordinates and the compute
//! warp, validated.

use crate::host::mesh_warp::run_mesh_warp;
use crate::host::warp::run_warp;
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::warp::WarpGeometry;
use crate::model::InverseMethod;
use crate::pass::mesh_warp::MeshWarpOutput;
use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc};
use crate::testing::{assert_no_validation_messages, reference_camera, validated_context};
use glam::DVec2;

#[test]
fn mesh_error_shrinks_with_n_and_the_image_matches_the_compute_warp() {
    let ctx = validated_context();
    let camera = reference_camera("seed_fig2");
    let g = WarpGeometry::distort(camera, InverseMethod::Newton);
    let (w, h) = g.output_size;
    let source = Raster {
        width: w,
        height: h,
        pixels: Pixels::Rgba8(
            (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    [
                        (x * 255 / w) as u8,
                        (y * 255 / h) as u8,
                        (((x / 8) + (y / 8)) % 2 * 255) as u8,
                        255,
                    ]
                })
                .collect(),
        ),
        bit_depth: BitDepth::U8,
    };
    let error = |n: u32| {
        let m = run_mesh_warp(ctx, &g, n, MeshWarpOutput::Coordinates, &source).unwrap();
        let (mut worst, mut covered, mut sourced) = (0f64, 0, 0);
        for y in (0..h).step_by(5) {
            for x in (0..w).step_by(5) {
                // None: no source pixel there (the border a same-size pinhole source lacks).
                let Some(exact) = g.source_coordinate(DVec2::new(x as f64, y as f64), 1) else {
                    continue;
                };
                sourced += 1;
                let c = m.rgba_f32((y * w + x) as usize);
                if c[3] == 1.0 {
                    covered += 1;
                    worst = worst.max(DVec2::new(c[0] as f64, c[1] as f64).distance(exact));
                }
            }
        }
        // Cells with a sourceless corner are dropped: a thin band at the border only.
        assert!(
            covered as f64 > 0.9 * sourced as f64,
            "{covered} of {sourced}"
        );
        worst
    };
    let (coarse, fine) = (error(16), error(128));
    // Linear interpolation: error ∝ cell size² (8× finer → ~64× smaller).
    assert!(
        coarse > 0.05 && fine < coarse / 30.0,
        "16: {coarse}, 128: {fine}"
    );
    // Measured 0.012 px at 128×128 on this camera (the bench table has more).
    assert!(fine < 0.02, "{fine}");

    let mesh = run_mesh_warp(ctx, &g, 128, MeshWarpOutput::Image, &source).unwrap();
    let (compute, _) = run_warp(
        ctx,
        WarpDesc {
            geometry: g.clone(),
            coordinates: Coordinates::Analytic,
            sampling: Sampling::Bilinear,
            border: crate::Border::Constant,
            format: PixelFormat::Rgba8,
            fill: [0.0; 4],
            write_mask: false,
        },
        &source,
    )
    .unwrap();
    let mut sum = 0f64;
    for i in 0..mesh.len() {
        let (a, b) = (mesh.rgba_f32(i), compute.rgba_f32(i));
        sum += (0..4).map(|c| (a[c] - b[c]).abs() as f64).sum::<f64>() / 4.0;
    }
    let mean = sum / mesh.len() as f64;
    // The sampler's 8-bit sub-texel weights against the compute warp's f32 bilinear.
    assert!(mean < 0.01, "mean difference {mean}");
    assert_no_validation_messages(ctx);
}
