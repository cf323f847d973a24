//! Every model of the table in the shaders (`glsl/include/camera_model.glsl` and
//! `glsl/include/models/`), f32 and f64, against the f64 model, under validation: the forward
//! map within 2e-3 px, the inverse within 1e-3 px reprojected, and invalid exactly where the
//! f64 model says (away from the domain's edge, where f32 rounding may decide either way).

use crate::host::points::{run_project, run_unproject};
use crate::model::samples::{fitted_inverse_cameras, sample_cameras};
use crate::model::Camera;
use crate::pass::Precision;
use glam::{DVec2, DVec3};

/// Directions all around, from the axis to past the domain's edge.
fn directions() -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for i in 0..=36 {
        let theta = std::f64::consts::PI * i as f64 / 36.0;
        for j in 0..12 {
            let phi = std::f64::consts::TAU * j as f64 / 12.0 + 0.05;
            out.push([
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]);
        }
    }
    out
}

/// Whether a ray is far enough from the domain's edge that f32 and f64 must agree on it.
fn clear_of_the_edge(camera: &Camera, p: DVec3) -> bool {
    let off = |q: DVec3| camera.project(q).is_some();
    let n = p.normalize();
    let side = n.any_orthonormal_vector();
    [1e-3, -1e-3]
        .iter()
        .all(|&t| off((n + side * t).normalize()) == off(n))
        && off((n + n.cross(side) * 1e-3).normalize()) == off(n)
}

fn precisions(ctx: &crate::host::Context) -> Vec<Precision> {
    let mut v = vec![Precision::F32];
    if ctx.gpu().supports_float64() {
        v.push(Precision::F64);
    }
    v
}

#[test]
fn every_model_projects_on_the_gpu_as_on_the_cpu() {
    let ctx = crate::testing::validated_context();
    let points = directions();
    let fitted = fitted_inverse_cameras().expect("fitted samples");
    for (name, camera) in sample_cameras().expect("samples").into_iter().chain(fitted) {
        for precision in precisions(ctx) {
            let got = run_project(ctx, &camera, precision, &points).expect("gpu run");
            let mut worst = 0.0f64;
            for (p, g) in points.iter().zip(&got) {
                let p = DVec3::from(*p);
                let want = camera.project(p);
                // The standard model projects past its fold as cv2.projectPoints does (pixels
                // 1e5 off the image): its domain is the pinhole-side table.
                let in_pinhole_domain = p.z > 0.0
                    && camera
                        .domain()
                        .contains_ideal(DVec2::new(p.x / p.z, p.y / p.z));
                if !camera.model().is_ray_model() && !in_pinhole_domain {
                    continue;
                }
                match (want, g) {
                    (Some(w), Some(g)) => {
                        // The bound is for pixels on the image. Far off it f32 is as good as
                        // the model's conditioning allows: next to a unified model's edge
                        // z + ξ|p| cancels, and a pixel 40 image widths out moves by tenths.
                        let (iw, ih) = (camera.width as f64, camera.height as f64);
                        if w.x >= -0.5 && w.y >= -0.5 && w.x <= iw - 0.5 && w.y <= ih - 0.5 {
                            worst = worst.max((DVec2::from(*g) - w).length());
                        }
                    }
                    (None, None) => {}
                    (w, g) if clear_of_the_edge(&camera, p) => {
                        panic!("{name} {precision} {p:?}: CPU {w:?}, GPU {g:?}")
                    }
                    _ => {}
                }
            }
            println!("{name} {precision}: forward max error {worst:.2e} px");
            let bound = if precision == Precision::F32 {
                2e-3
            } else {
                1e-6
            };
            assert!(worst <= bound, "{name} {precision}: {worst} px");
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}

#[test]
fn every_model_unprojects_on_the_gpu_within_1e_3_px() {
    let ctx = crate::testing::validated_context();
    let fitted = fitted_inverse_cameras().expect("fitted samples");
    for (name, camera) in sample_cameras().expect("samples").into_iter().chain(fitted) {
        let (w, h) = (camera.width as f64, camera.height as f64);
        let mut pixels = Vec::new();
        for j in 0..=24 {
            for i in 0..=32 {
                pixels.push([i as f64 / 32.0 * (w - 1.0), j as f64 / 24.0 * (h - 1.0)]);
            }
        }
        for precision in precisions(ctx) {
            let rays = run_unproject(ctx, &camera, precision, &pixels).expect("gpu run");
            let (mut worst, mut valid) = (0.0f64, 0);
            for (p, g) in pixels.iter().zip(&rays) {
                let px = DVec2::from(*p);
                match (camera.unproject(px), g) {
                    (Some(ray), Some(g)) => {
                        valid += 1;
                        // The f64 pixel of the GPU's ray against the CPU ray's (the pixel
                        // itself, but where the camera evaluates a fit of its inverse): next
                        // to a fold an angle error is magnified, the pixel error is not.
                        let back = camera.project(DVec3::from(*g)).unwrap_or_else(|| {
                            panic!("{name} {precision} {p:?}: GPU ray {g:?} outside the domain")
                        });
                        let want = camera.project(ray).expect("the CPU ray projects");
                        worst = worst.max((back - want).length());
                    }
                    (None, None) => {}
                    (want, got) => {
                        // Only a pixel whose neighbours disagree (the domain's edge) may differ.
                        let edge = [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]
                            .iter()
                            .any(|d| {
                                camera.unproject(px + DVec2::from(*d)).is_some() != want.is_some()
                            });
                        assert!(edge, "{name} {precision} {p:?}: CPU {want:?}, GPU {got:?}");
                    }
                }
            }
            println!("{name} {precision}: {valid} pixels, inverse max error {worst:.2e} px");
            assert!(valid > 0, "{name}: no pixel valid");
            let bound = if precision == Precision::F32 {
                1e-3
            } else {
                1e-6
            };
            assert!(worst <= bound, "{name} {precision}: {worst} px");
        }
    }
    crate::testing::assert_no_validation_messages(ctx);
}
