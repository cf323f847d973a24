//! The GPU warp against the f64 reference warp (same coordinates, same sampling) on the
//! shared cameras, with the validation layer on. Differences are stated and bounded.

use crate::host::warp::run_warp;
use crate::host::warp_raster::run_raster_warp;
use crate::imaging::cpu_warp::{self, Border, Sampling};
use crate::imaging::{BitDepth, Pixels, Raster};
use crate::io::reference::load_reference;
use crate::model::warp::WarpGeometry;
use crate::model::InverseMethod;
use crate::pass::warp::{Coordinates, MapInterpolation, PixelFormat, WarpDesc};

/// A test image with edges and smooth gradients in every channel.
fn test_image(w: u32, h: u32) -> Raster {
    let mut p = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32, y as f32);
            let checker = (((x / 32) + (y / 32)) % 2) as f32;
            p.push([
                0.5 + 0.5 * (fx / 9.0).sin() * (fy / 13.0).cos(),
                0.2 + 0.6 * checker,
                fx / w as f32,
                1.0,
            ]);
        }
    }
    Raster {
        width: w,
        height: h,
        pixels: Pixels::Rgba32F(p),
        bit_depth: BitDepth::F32,
    }
}

struct Diff {
    mean: f64,
    max: f64,
    mask_mismatch: usize,
    valid: usize,
}

fn compare(a: &Raster, am: &[u8], b: &Raster, bm: &[u8]) -> Diff {
    let (mut sum, mut max, mut n, mut mismatch) = (0.0, 0.0f64, 0usize, 0usize);
    for i in 0..a.len() {
        let (va, vb) = (am[i] > 127, bm[i] > 127);
        if va != vb {
            mismatch += 1;
            continue;
        }
        if !va {
            continue;
        }
        let (pa, pb) = (a.rgba_f32(i), b.rgba_f32(i));
        for c in 0..4 {
            let d = (pa[c] - pb[c]).abs() as f64;
            sum += d;
            max = max.max(d);
        }
        n += 1;
    }
    Diff {
        mean: sum / (4 * n.max(1)) as f64,
        max,
        mask_mismatch: mismatch,
        valid: n,
    }
}

fn check(
    name: &str,
    geometry: WarpGeometry,
    coordinates: Coordinates,
    format: PixelFormat,
    ctx: &crate::host::Context,
) -> Diff {
    let filter = (Sampling::Bilinear, Border::Constant);
    check_filtered(name, geometry, coordinates, format, filter, ctx)
}

/// As [`check`] with an interpolation and a border of its own.
fn check_filtered(
    name: &str,
    geometry: WarpGeometry,
    coordinates: Coordinates,
    format: PixelFormat,
    (sampling, border): (Sampling, Border),
    ctx: &crate::host::Context,
) -> Diff {
    let (w, h) = geometry.source_size;
    let mut source = test_image(w, h);
    if format == PixelFormat::Rgba8 {
        let Pixels::Rgba32F(p) = &source.pixels else {
            unreachable!()
        };
        source.pixels = Pixels::Rgba8(
            p.iter()
                .map(|v| v.map(|c| (c * 255.0).round() as u8))
                .collect(),
        );
        source.bit_depth = BitDepth::U8;
    }
    let fill = [0.0; 4];
    let (cpu, cpu_mask) = cpu_warp::warp(&geometry, &source, sampling, border, fill);
    let desc = WarpDesc {
        geometry,
        coordinates,
        sampling,
        border,
        format,
        fill,
        write_mask: true,
    };
    let (gpu, gpu_mask) = run_warp(ctx, desc, &source).expect("gpu warp");
    let d = compare(&cpu, &cpu_mask, &gpu, &gpu_mask);
    println!(
        "{name}: mean {:.2e}, max {:.2e} over {} valid px; {} px differ in validity",
        d.mean, d.max, d.valid, d.mask_mismatch
    );
    d
}

#[test]
fn gpu_warp_matches_the_f64_reference_on_every_shared_camera() {
    let ctx = crate::testing::validated_context();
    let reference = load_reference().unwrap();
    for case in &reference.cases {
        let cam = case.camera().unwrap();
        let total = (cam.width * cam.height) as usize;
        for (label, coords) in [
            ("analytic", Coordinates::Analytic),
            ("map", Coordinates::Map),
        ] {
            let d = check(
                &format!("{} distort {label}", case.name),
                WarpGeometry::distort(cam.clone(), InverseMethod::Newton),
                coords,
                PixelFormat::Rgba32F,
                ctx,
            );
            // f32 coordinates are within ~1e-3 px of f64 (up to 7e-3 px near folds); on this
            // image a 1e-3 px shift changes a value by at most ~1e-3 at the sharpest edge.
            // Measured: mean ≤ 7.6e-7, max ≤ 4.3e-4 (rational_wide, next to its fold).
            assert!(d.mean < 5e-6, "{}: mean {}", case.name, d.mean);
            assert!(d.max < 2e-3, "{}: max {}", case.name, d.max);
            // Validity may differ only for pixels on the domain or frame boundary.
            assert!(
                d.mask_mismatch * 1000 <= total,
                "{}: {} mask mismatches",
                case.name,
                d.mask_mismatch
            );
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn chromatic_undistort_and_8bit_variants_match_the_reference() {
    let ctx = crate::testing::validated_context();
    let fig2 = crate::testing::reference_camera("seed_fig2");
    let total = (fig2.width * fig2.height) as usize;
    let chroma = WarpGeometry::distort(fig2.clone(), InverseMethod::Newton)
        .with_chromatic([1.01, 1.0, 0.99])
        .unwrap();
    for coords in [Coordinates::Analytic, Coordinates::Map] {
        let d = check(
            "seed_fig2 chromatic",
            chroma.clone(),
            coords,
            PixelFormat::Rgba32F,
            ctx,
        );
        assert!(d.mean < 5e-6 && d.max < 2e-3 && d.mask_mismatch * 1000 <= total);
    }
    let und = check(
        "seed_fig2 undistort",
        WarpGeometry::undistort(fig2.clone()),
        Coordinates::Analytic,
        PixelFormat::Rgba32F,
        ctx,
    );
    assert!(und.mean < 5e-6 && und.max < 2e-3 && und.mask_mismatch * 1000 <= total);
    // 8-bit: the GPU stores rgba8, so rounding to 1/255 (≤ 0.00196) comes on top.
    let d8 = check(
        "seed_fig2 rgba8",
        WarpGeometry::distort(fig2.clone(), InverseMethod::Newton),
        Coordinates::Analytic,
        PixelFormat::Rgba8,
        ctx,
    );
    assert!(d8.mean < 1e-3 && d8.max < 2.5e-3 && d8.mask_mismatch * 1000 <= total);
    for method in [InverseMethod::Heikkila, InverseMethod::FixedPoint(5)] {
        let d = check(
            &format!("seed_fig2 {method}"),
            WarpGeometry::distort(fig2.clone(), method),
            Coordinates::Analytic,
            PixelFormat::Rgba32F,
            ctx,
        );
        assert!(
            d.mean < 5e-6 && d.max < 2e-3 && d.mask_mismatch * 1000 <= total,
            "{method}"
        );
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn every_interpolation_and_border_matches_the_reference() {
    let ctx = crate::testing::validated_context();
    // Barrel distortion: the distorted image's corners see past the pinhole source's frame,
    // where the borders differ.
    let fig2 = crate::testing::reference_camera("seed_fig2");
    let total = (fig2.width * fig2.height) as usize;
    let geometry = WarpGeometry::distort(fig2.clone(), InverseMethod::Newton);
    let mut filled = Vec::new();
    for sampling in [Sampling::Nearest, Sampling::Bilinear, Sampling::Bicubic] {
        for border in [Border::Constant, Border::Replicate, Border::Reflect] {
            for coords in [Coordinates::Analytic, Coordinates::Map] {
                let name = format!("seed_fig2 {} {} {coords:?}", sampling.name(), border.name());
                let filter = (sampling, border);
                let d = check_filtered(
                    &name,
                    geometry.clone(),
                    coords,
                    PixelFormat::Rgba32F,
                    filter,
                    ctx,
                );
                // Nearest flips to the neighbouring pixel where f32 and f64 coordinates sit on
                // either side of a half-pixel: a step of the test image on a few pixels.
                // Measured: nearest mean ≤ 3.1e-7, max 5.5e-2; bilinear and bicubic mean
                // ≤ 3.4e-7, max ≤ 1.3e-4 (reflect's mirrored taps lie farther out).
                let (mean, max) = match sampling {
                    Sampling::Nearest => (5e-6, 0.1),
                    _ => (5e-6, 1e-3),
                };
                assert!(d.mean < mean && d.max < max, "{name}: {} {}", d.mean, d.max);
                assert!(d.mask_mismatch * 1000 <= total, "{name}");
                filled.push((border, total - d.valid - d.mask_mismatch));
            }
        }
    }
    // Only the constant border leaves off-frame pixels without a value (barrel corners).
    for (border, n) in filled {
        match border {
            Border::Constant => assert!(n > total / 100, "constant: {n} filled"),
            _ => assert_eq!(n, 0, "{}: pixels filled", border.name()),
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn coarse_maps_trade_bounded_error_and_conservative_validity_for_speed() {
    use crate::host::warp::read_maps;
    use crate::model::CameraModel;
    use glam::DVec2;
    let ctx = crate::testing::validated_context();
    for name in ["prism_tilt", "rational_wide"] {
        let cam = crate::testing::reference_camera(name);
        let g = WarpGeometry::distort(cam.clone(), InverseMethod::Newton);
        let exact = &read_maps(ctx, &g, Coordinates::Map).unwrap()[0];
        for (coords, bound) in [
            (
                Coordinates::CoarseMap {
                    stride: 4,
                    refine: 0,
                    interpolation: MapInterpolation::Bilinear,
                },
                3e-3,
            ),
            (
                Coordinates::CoarseMap {
                    stride: 8,
                    refine: 0,
                    interpolation: MapInterpolation::Cubic,
                },
                1e-3,
            ),
            (
                Coordinates::CoarseMap {
                    stride: 16,
                    refine: 1,
                    interpolation: MapInterpolation::Bilinear,
                },
                2e-3,
            ),
        ] {
            let coarse = &read_maps(ctx, &g, coords).unwrap()[0];
            let (mut worst, mut residual, mut lost, mut gained) = (0.0f64, 0.0f64, 0usize, 0usize);
            for (i, (e, c)) in exact.iter().zip(coarse).enumerate() {
                let p = DVec2::new(
                    (i % cam.width as usize) as f64,
                    (i / cam.width as usize) as f64,
                );
                match (e[0].is_nan(), c[0].is_nan()) {
                    (false, false) => {
                        // Against the f64 model, not the f32 exact map.
                        if let Some(t) = g.model_coordinate(p, 1) {
                            worst = worst.max((DVec2::new(c[0] as f64, c[1] as f64) - t).length());
                        }
                        // Forward residual: where the model sends the coarse map's answer.
                        let x = cam
                            .intrinsics
                            .to_normalized(DVec2::new(c[0] as f64, c[1] as f64));
                        if let Some(back) = cam.distort_pixel(cam.intrinsics.to_pixel(x)) {
                            residual = residual.max((back - p).length());
                        }
                    }
                    (false, true) => lost += 1,
                    (true, false) => gained += 1,
                    (true, true) => {}
                }
            }
            println!(
                "{name} {coords:?}: max {worst:.1e} px from the f64 model, forward residual ≤ {residual:.1e} px; \
                 {lost} px conservatively invalid, {gained} wrongly valid"
            );
            assert_eq!(
                gained, 0,
                "a coarse map must never call an invalid pixel valid"
            );
            // Every valid pixel passed the shader's forward check (0.05 px, f32).
            assert!(residual < 0.06, "{name} {coords:?}: residual {residual}");
            if name == "prism_tilt" {
                // No fold inside this image: the error bound holds everywhere, nothing is lost.
                assert!(worst < bound, "{name} {coords:?}: {worst}");
                assert_eq!(lost, 0);
            }
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn a_full_camera_per_channel_matches_the_reference() {
    // The general form of lateral colour: each channel its own calibrated camera (here the
    // Lambers et al.'s Fig. 2 lens with slightly different k1 and focal length for R and B).
    let ctx = crate::testing::validated_context();
    let g_cam = crate::testing::reference_camera("seed_fig2");
    let variant = |dk1: f64, df: f64| {
        let mut d = g_cam.distortion();
        d.k1 += dk1;
        let mut k = g_cam.intrinsics;
        k.fx *= 1.0 + df;
        k.fy *= 1.0 + df;
        crate::model::Camera::new(g_cam.width, g_cam.height, k, d).unwrap()
    };
    let mut geometry = WarpGeometry::distort(g_cam.clone(), InverseMethod::Newton);
    geometry.channel_cameras = Some(Box::new([
        variant(0.004, 0.003),
        g_cam.clone(),
        variant(-0.004, -0.003),
    ]));
    let total = (g_cam.width * g_cam.height) as usize;
    let d = check(
        "seed_fig2 per-channel cameras",
        geometry.clone(),
        Coordinates::Map,
        PixelFormat::Rgba32F,
        ctx,
    );
    assert!(d.mean < 5e-6 && d.max < 2e-3 && d.mask_mismatch * 1000 <= total);
    // Analytic mode refuses (three full models per pixel belong in a map).
    let desc = WarpDesc {
        geometry,
        coordinates: Coordinates::Analytic,
        sampling: Sampling::Bilinear,
        border: crate::Border::Constant,
        format: PixelFormat::Rgba32F,
        fill: [0.0; 4],
        write_mask: true,
    };
    assert!(crate::pass::warp::WarpPass::new(ctx.gpu(), desc).is_err());
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn coarse_maps_cover_images_that_are_not_a_multiple_of_the_stride() {
    // One invocation per coarse cell writes its pixels: the cells cut by the right and bottom
    // edges, the cells past a multiple of the workgroup size, and images smaller than one cell
    // must all get every pixel, within the accuracy of the interpolation of the f64 model.
    // Each map is of another camera (principal point moved by a third of a pixel), so that a
    // pixel left unwritten cannot pass on what an earlier map left in reused memory.
    use crate::host::warp::read_maps;
    use crate::model::{Camera, Intrinsics};
    use glam::DVec2;
    let ctx = crate::testing::validated_context();
    let mut variant = 0.0;
    for (w, h) in [(1, 1), (17, 9), (33, 20), (70, 9)] {
        for (stride, interpolation) in [
            (4, MapInterpolation::Bilinear),
            (8, MapInterpolation::Cubic),
            (16, MapInterpolation::Cubic),
        ] {
            variant += 1.0;
            // A mild lens, so that interpolation is accurate even across a whole tiny image.
            let f = 2.0 * w.max(h) as f64 + 2.0;
            let cam = Camera::from_coeffs(
                w,
                h,
                Intrinsics {
                    fx: f,
                    fy: f,
                    cx: (w as f64 - 1.0) / 2.0 + variant / 3.0,
                    cy: (h as f64 - 1.0) / 2.0,
                },
                &[-0.05, 0.01, 0.001, -0.001, 0.002],
            )
            .unwrap();
            let g = WarpGeometry::distort(cam, InverseMethod::Newton);
            let coords = Coordinates::CoarseMap {
                stride,
                refine: 0,
                interpolation,
            };
            // The host's f64 estimate of this interpolation (at cell centres, where it peaks).
            let estimate = g.coarse_interpolation_error(stride, interpolation).unwrap();
            let coarse = &read_maps(ctx, &g, coords).unwrap()[0];
            assert_eq!(coarse.len(), (w * h) as usize);
            for (i, c) in coarse.iter().enumerate() {
                let p = DVec2::new((i as u32 % w) as f64, (i as u32 / w) as f64);
                let exact = g.model_coordinate(p, 1).unwrap();
                let d = (DVec2::new(c[0] as f64, c[1] as f64) - exact).length();
                assert!(
                    d <= 1.5 * estimate + 1e-3,
                    "{w}×{h} {coords:?} pixel {p}: {d} px, estimate {estimate} px"
                );
            }
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn the_coarse_map_check_is_compiled_out_only_where_the_f64_estimate_allows() {
    use crate::pass::warp::WarpPass;
    let ctx = crate::testing::validated_context();
    let interpolations = [MapInterpolation::Bilinear, MapInterpolation::Cubic];
    for ((name, expect_check), interpolation) in [
        ("prism_tilt", false),
        ("seed_fig2", false),
        ("rational_wide", true),
    ]
    .into_iter()
    .flat_map(|case| interpolations.map(|i| (case, i)))
    {
        let cam = crate::testing::reference_camera(name);
        let g = WarpGeometry::distort(cam, InverseMethod::Newton);
        let estimate = g.coarse_interpolation_error(8, interpolation);
        if interpolation == MapInterpolation::Cubic && !expect_check {
            // The cubic stencil's error is O(h⁴): far under the bilinear one at stride 8.
            let bilinear = g.coarse_interpolation_error(8, MapInterpolation::Bilinear);
            assert!(estimate.unwrap() < 0.1 * bilinear.unwrap(), "{name}");
        }
        let desc = WarpDesc {
            geometry: g,
            coordinates: Coordinates::CoarseMap {
                stride: 8,
                refine: 0,
                interpolation,
            },
            sampling: Sampling::Bilinear,
            border: crate::Border::Constant,
            format: PixelFormat::Rgba8,
            fill: [0.0; 4],
            write_mask: false,
        };
        let pass = WarpPass::new(ctx.gpu(), desc).unwrap();
        println!(
            "{name} {interpolation:?}: f64 interpolation estimate {estimate:?} px; per-pixel check {:?}",
            pass.coarse_map_checked()
        );
        assert_eq!(
            pass.coarse_map_checked(),
            Some(expect_check),
            "{name} {interpolation:?}"
        );
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn the_fragment_shader_warp_matches_the_compute_warp() {
    // The same maps, the same sampling arithmetic, another way of walking the pixels: the two
    // outputs may differ only by the rounding of one store (bitwise equal in practice), with
    // and without chromatic aberration, float and 8-bit, fill where there is no source.
    let ctx = crate::testing::validated_context();
    let cam = crate::testing::reference_camera("rational_wide");
    let plain = WarpGeometry::distort(cam.clone(), InverseMethod::Newton);
    let chroma = plain.clone().with_chromatic([1.01, 1.0, 0.99]).unwrap();
    let float_source = test_image(cam.width, cam.height);
    let Pixels::Rgba32F(float_pixels) = &float_source.pixels else {
        unreachable!("test_image is float")
    };
    let byte_source = Raster {
        width: cam.width,
        height: cam.height,
        pixels: Pixels::Rgba8(
            float_pixels
                .iter()
                .map(|p| p.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
                .collect(),
        ),
        bit_depth: BitDepth::U8,
    };
    for (geometry, name) in [(plain, "plain"), (chroma, "chromatic")] {
        for (format, source) in [
            (PixelFormat::Rgba32F, &float_source),
            (PixelFormat::Rgba8, &byte_source),
        ] {
            let desc = WarpDesc {
                geometry: geometry.clone(),
                coordinates: Coordinates::Map,
                sampling: Sampling::Bilinear,
                border: crate::Border::Constant,
                format,
                fill: [0.25, 0.0, 0.0, 0.0],
                write_mask: true,
            };
            let (compute, mask) = run_warp(ctx, desc.clone(), source).expect("compute warp");
            let raster = run_raster_warp(ctx, desc, source).expect("fragment warp");
            let (a, b) = (rgba(&compute), rgba(&raster));
            assert_eq!(a.len(), b.len());
            let worst = a
                .iter()
                .zip(&b)
                .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()))
                .fold(0.0f32, f32::max);
            let lsb = if format == PixelFormat::Rgba8 {
                1.0 / 255.0
            } else {
                1e-6
            };
            assert!(worst <= lsb, "{name} {format:?}: differs by {worst}");
            // Pixels without a source carry the fill in both (rational_wide folds in view).
            let filled = mask.iter().filter(|&&m| m == 0).count();
            assert!(
                filled > 0,
                "rational_wide should leave pixels without a source"
            );
            for (i, _) in mask.iter().enumerate().filter(|(_, &m)| m == 0) {
                assert!(
                    (b[i][0] - 0.25).abs() <= lsb && b[i][3] == 0.0,
                    "{name}: fill at {i}"
                );
            }
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

fn rgba(r: &Raster) -> Vec<[f32; 4]> {
    match &r.pixels {
        Pixels::Rgba32F(p) => p.clone(),
        Pixels::Rgba8(p) => p.iter().map(|q| q.map(|c| c as f32 / 255.0)).collect(),
        Pixels::R32Uint(_) => panic!("colour expected"),
    }
}

#[test]
fn the_warp_reads_the_domain_table_only_where_it_can_say_more_than_the_inner_radius() {
    use crate::pass::warp::WarpPass;
    let ctx = crate::testing::validated_context();
    // The DOMAIN_TABLE constant the analytic warp of `geometry` is built with.
    let table = |geometry: &WarpGeometry| {
        let desc = WarpDesc {
            geometry: geometry.clone(),
            coordinates: Coordinates::Analytic,
            sampling: Sampling::Bilinear,
            border: Border::Constant,
            format: PixelFormat::Rgba32F,
            fill: [0.0; 4],
            write_mask: true,
        };
        let pass = WarpPass::new(ctx.gpu(), desc).unwrap();
        pass.pipeline()
            .constants
            .get(crate::pass::spec::DOMAIN_TABLE)
    };
    let (mut seen, mut rounds) = ([false; 2], [false; 2]);
    // A mild lens (`vklens bench startup`'s), whose whole frame lies inside its domain's
    // inner radius, and the shared cameras, whose corners pass it.
    let mild = crate::model::Camera::from_coeffs(
        640,
        360,
        crate::model::Intrinsics {
            fx: 333.3,
            fy: 333.3,
            cx: 319.5,
            cy: 179.5,
        },
        &[-0.12, 0.03, 0.001, -0.0005],
    )
    .unwrap();
    let mut cases: Vec<(&str, WarpGeometry)> = [("mild", mild)]
        .into_iter()
        .chain(
            ["seed_fig2", "prism_tilt", "rational_wide"]
                .map(|n| (n, crate::testing::reference_camera(n))),
        )
        .map(|(n, cam)| (n, WarpGeometry::undistort(cam)))
        .collect();
    // rational_wide undistorted into a pinhole of a third of its focal length: the output's
    // corners reach past the fold, where the table decides.
    let wide = crate::testing::reference_camera("rational_wide");
    let mut k = wide.intrinsics;
    (k.fx, k.fy) = (k.fx / 3.0, k.fy / 3.0);
    let size = (wide.width, wide.height);
    cases.push((
        "rational_wide, wider output",
        WarpGeometry::undistort(wide).with_ideal(k, size).unwrap(),
    ));
    for (name, g) in cases {
        let inner = g.camera.shader_domain().min_ideal_radius();
        let k = g.ideal;
        let cam = &g.camera;
        let (w, h) = ((cam.width - 1) as f64, (cam.height - 1) as f64);
        let corner = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
            .map(|(u, v)| ((u - k.cx) / k.fx).hypot((v - k.cy) / k.fy))
            .into_iter()
            .fold(0.0, f64::max);
        let round = g.camera.shader_domain().is_round();
        rounds[usize::from(round)] = true;
        let reads = !round && corner > inner * (1.0 - 1e-4);
        seen[usize::from(reads)] = true;
        // The distort direction tests every Newton iterate: the table goes only with a round
        // domain, and the image is still the f64 reference's.
        let distort = WarpGeometry::distort(g.camera.clone(), InverseMethod::Newton);
        assert_eq!(table(&distort), Some(u32::from(!round)), "{name} distort");
        let d = check(
            &format!("{name} distort"),
            distort,
            Coordinates::Analytic,
            PixelFormat::Rgba32F,
            ctx,
        );
        assert!(
            d.mean < 5e-6 && d.max < 2e-3,
            "{name} distort: mean {} max {}",
            d.mean,
            d.max
        );
        assert_eq!(
            table(&g),
            Some(u32::from(reads)),
            "{name}: corner {corner}, inner {inner}"
        );
        // Either way, every pixel as the f64 reference warp has it.
        let d = check(
            &format!("{name} undistort"),
            g,
            Coordinates::Analytic,
            PixelFormat::Rgba32F,
            ctx,
        );
        assert!(
            d.mean < 5e-6 && d.max < 2e-3,
            "{name}: mean {} max {}",
            d.mean,
            d.max
        );
        assert_eq!(d.mask_mismatch, 0, "{name}");
    }
    assert_eq!(seen, [true, true], "an undistort warp of each kind");
    assert_eq!(rounds, [true, true], "a round domain and one that is not");
    crate::testing::assert_no_validation_messages(ctx);
}
