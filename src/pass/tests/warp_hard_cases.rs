//! The warp where it is easy to go wrong: folding lenses (a clean masked border, no streaks),
//! 1×1 and very large images, object IDs (never blended), sizes a device cannot hold.

use crate::host::warp::run_warp;
use crate::imaging::cpu_warp::Sampling;
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::model::warp::WarpGeometry;
use crate::model::{Camera, Intrinsics, InverseMethod};
use crate::pass::warp::{Coordinates, PixelFormat, WarpDesc};
use glam::DVec2;

fn flat(w: u32, h: u32, v: u8) -> Raster {
    Raster {
        width: w,
        height: h,
        pixels: Pixels::Rgba8(vec![[v, v, v, 255]; (w * h) as usize]),
        bit_depth: BitDepth::U8,
    }
}

fn desc(
    geometry: WarpGeometry,
    format: PixelFormat,
    sampling: Sampling,
    fill: [f32; 4],
) -> WarpDesc {
    WarpDesc {
        geometry,
        coordinates: Coordinates::Analytic,
        sampling,
        border: crate::Border::Constant,
        format,
        fill,
        write_mask: true,
    }
}

#[test]
fn folding_lenses_get_a_clean_masked_border_not_streaks() {
    let ctx = crate::testing::validated_context();
    for name in ["rational_wide", "strong_pincushion"] {
        let cam = crate::testing::reference_camera(name);
        // Overscanned source, so every pixel without a source is one the lens cannot invert.
        let o = crate::model::overscan::overscan(&cam, 1.0).unwrap();
        let g = WarpGeometry::distort(cam.clone(), InverseMethod::Newton)
            .with_ideal(o.intrinsics, (o.width, o.height))
            .unwrap();
        let source = flat(o.width, o.height, 200);
        let fill = [1.0, 0.0, 1.0, 1.0];
        let (out, mask) = run_warp(
            ctx,
            desc(g, PixelFormat::Rgba8, Sampling::Bilinear, fill),
            &source,
        )
        .unwrap();
        let Pixels::Rgba8(px) = &out.pixels else {
            panic!()
        };
        let (mut masked, mut wrong) = (0, 0);
        for (i, (&m, p)) in mask.iter().zip(px).enumerate() {
            let q = DVec2::new(
                (i % cam.width as usize) as f64,
                (i / cam.width as usize) as f64,
            );
            let invertible = cam
                .undistort_normalized(cam.intrinsics.to_normalized(q), InverseMethod::Newton)
                .is_some();
            if m == 0 {
                masked += 1;
                // A masked pixel is exactly the fill, and the lens really cannot invert it
                // (a pixel right on the boundary may go either way in f32).
                assert_eq!(
                    *p,
                    [255, 0, 255, 255],
                    "{name}: masked pixel {q} is not the fill"
                );
                if invertible {
                    wrong += 1;
                }
            } else {
                // Valid pixels are clean source samples: no streaks of edge pixels.
                assert_eq!(
                    *p,
                    [200, 200, 200, 255],
                    "{name}: valid pixel {q} is not a source sample"
                );
                if !invertible {
                    wrong += 1;
                }
            }
        }
        println!(
            "{name}: {masked} px masked; {wrong} disagree with the f64 domain (boundary pixels)"
        );
        assert!(
            wrong * 10_000 <= mask.len(),
            "{name}: {wrong} pixels on the wrong side of the domain"
        );
        if name == "rational_wide" {
            assert!(masked > 100_000, "the fold-over corners are masked");
        } else {
            assert_eq!(
                masked, 0,
                "strong_pincushion does not fold inside the image"
            );
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn a_one_pixel_image_and_a_large_one() {
    let ctx = crate::testing::validated_context();
    let tiny = Camera::from_coeffs(
        1,
        1,
        Intrinsics {
            fx: 1.0,
            fy: 1.0,
            cx: 0.0,
            cy: 0.0,
        },
        &[-0.1, 0.0, 0.0, 0.0],
    )
    .unwrap();
    let (out, mask) = run_warp(
        ctx,
        desc(
            WarpGeometry::distort(tiny, InverseMethod::Newton),
            PixelFormat::Rgba8,
            Sampling::Bilinear,
            [0.0; 4],
        ),
        &flat(1, 1, 77),
    )
    .unwrap();
    assert_eq!((out.width, out.height, mask.clone()), (1, 1, vec![255]));
    assert_eq!(out.pixels, Pixels::Rgba8(vec![[77, 77, 77, 255]]));
    let big = Camera::from_coeffs(
        4096,
        4096,
        Intrinsics {
            fx: 3000.0,
            fy: 3000.0,
            cx: 2047.5,
            cy: 2047.5,
        },
        &[-0.05, 0.01, 0.0, 0.0],
    )
    .unwrap();
    let (out, mask) = run_warp(
        ctx,
        desc(
            WarpGeometry::distort(big, InverseMethod::Newton),
            PixelFormat::Rgba8,
            Sampling::Bilinear,
            [0.0; 4],
        ),
        &flat(4096, 4096, 9),
    )
    .unwrap();
    assert_eq!((out.width, out.height), (4096, 4096));
    assert_eq!(mask[2048 * 4096 + 2048], 255);
    // Larger than the device can hold: a clear error, not a Vulkan failure.
    let max = ctx.gpu().max_image_side();
    if max < 65536 {
        let huge = Camera::from_coeffs(
            max + 1,
            8,
            Intrinsics {
                fx: 1.0,
                fy: 1.0,
                cx: 0.0,
                cy: 0.0,
            },
            &[0.0; 4],
        )
        .unwrap();
        let e = run_warp(
            ctx,
            desc(
                WarpGeometry::distort(huge, InverseMethod::Newton),
                PixelFormat::Rgba8,
                Sampling::Bilinear,
                [0.0; 4],
            ),
            &flat(max + 1, 8, 0),
        )
        .expect_err("refused");
        assert!(e.to_string().contains("larger than"), "{e}");
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn object_ids_are_never_blended_but_bilinear_colour_is() {
    // Lambers et al. Table 1: post-processing breaks data that cannot be interpolated. Nearest
    // sampling of R32_UINT keeps every ID exact; bilinear on the same numbers mixes them.
    let ctx = crate::testing::validated_context();
    let cam = Camera::from_coeffs(
        320,
        240,
        Intrinsics {
            fx: 200.0,
            fy: 200.0,
            cx: 159.5,
            cy: 119.5,
        },
        &[-0.2, 0.05, 0.0, 0.0],
    )
    .unwrap();
    let ids: Vec<u32> = (0..240u32)
        .flat_map(|y| (0..320u32).map(move |x| 1 + (x / 16) + 100 * (y / 16)))
        .collect();
    let id_set: std::collections::HashSet<u32> = ids.iter().copied().collect();
    let source = Raster {
        width: 320,
        height: 240,
        pixels: Pixels::R32Uint(ids.clone()),
        bit_depth: BitDepth::F32,
    };
    let g = WarpGeometry::distort(cam, InverseMethod::Newton);
    let (out, mask) = run_warp(
        ctx,
        desc(g.clone(), PixelFormat::R32Uint, Sampling::Nearest, [0.0; 4]),
        &source,
    )
    .unwrap();
    let Pixels::R32Uint(got) = &out.pixels else {
        panic!()
    };
    for (i, (&id, &m)) in got.iter().zip(&mask).enumerate() {
        if m > 0 {
            assert!(id_set.contains(&id), "pixel {i}: {id} is not a source ID");
        } else {
            assert_eq!(id, 0, "filled with the fill ID");
        }
    }
    let as_float = Raster {
        width: 320,
        height: 240,
        pixels: Pixels::Rgba32F(ids.iter().map(|&i| [i as f32, 0.0, 0.0, 1.0]).collect()),
        bit_depth: BitDepth::F32,
    };
    let (blended, _) = run_warp(
        ctx,
        desc(g, PixelFormat::Rgba32F, Sampling::Bilinear, [0.0; 4]),
        &as_float,
    )
    .unwrap();
    let Pixels::Rgba32F(b) = &blended.pixels else {
        panic!()
    };
    let mixed = b
        .iter()
        .filter(|v| v[0] != 0.0 && (v[0].fract() != 0.0 || !id_set.contains(&(v[0] as u32))))
        .count();
    println!("bilinear produced {mixed} pixels whose 'ID' exists nowhere in the source; nearest produced none");
    assert!(mixed > 1000);
    // R32_UINT refuses bilinear outright.
    let e = crate::pass::warp::WarpPass::new(
        ctx.gpu(),
        desc(
            WarpGeometry::distort(
                Camera::from_coeffs(
                    8,
                    8,
                    Intrinsics {
                        fx: 8.0,
                        fy: 8.0,
                        cx: 3.5,
                        cy: 3.5,
                    },
                    &[0.0; 4],
                )
                .unwrap(),
                InverseMethod::Newton,
            ),
            PixelFormat::R32Uint,
            Sampling::Bilinear,
            [0.0; 4],
        ),
    );
    assert!(e.is_err());
    crate::testing::assert_no_validation_messages(ctx);
}
