//! Real lens systems (Heidrich et al.): prescriptions of spherical surfaces and
//! glasses, an exact sequential ray tracer, and first-order analysis — pure f64, no Vulkan.
//!
//! Built so far: the lens-file format ([`prescription`]), paraxial analysis ([`paraxial`]:
//! focal lengths, principal planes, pupils, f-number, focusing), the exact tracer
//! ([`trace`]), the distortion curve from chief rays ([`distortion_curve`]) and the OpenCV
//! model fitted to a traced lens ([`fit`]), and Heidrich et al.'s image-based model
//! ([`image_model`]: virtual centres of projection, quad-tree, vignetting, radiometric
//! weights) that the GPU renderer draws.

use crate::Result;

pub mod fit;
pub mod image_model;
pub mod paraxial;
pub mod prescription;
pub mod reference;
pub mod trace;

pub use fit::{fit_opencv, OpenCvFit};
pub use paraxial::{analyse, focus, Paraxial};
pub use prescription::{Prescription, PrescriptionError, Surface, LAMBDA_D};

/// Frames `scene` for a render through `lens`: the pose (given, or the scene centred in the
/// lens's first-order camera) and the optics focused at `focus_m` (given, or the distance of
/// the scene's centre).
pub fn frame_scene(
    lens: &Prescription,
    pixels: (u32, u32),
    pitch_mm: f64,
    f_number: Option<f64>,
    focus_m: Option<f64>,
    pose: Option<crate::scene::Pose>,
    scene: &crate::scene::Scene,
) -> Result<(image_model::Optics, crate::scene::Pose)> {
    let framing = image_model::Optics::new(lens, pixels, pitch_mm, f64::INFINITY, f_number)?;
    let pose = match pose {
        Some(p) => p,
        None => scene.default_pose(&framing.equivalent_camera()?),
    };
    let focus = focus_m.unwrap_or_else(|| {
        let (lo, hi) = scene.mesh.bounds();
        let z = pose.apply(0.5 * (lo + hi)).z;
        if z > 0.0 {
            z
        } else {
            f64::INFINITY
        }
    });
    let optics = image_model::Optics::new(lens, pixels, pitch_mm, focus, f_number)?;
    Ok((optics, pose))
}

/// One point of a distortion curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistortionPoint {
    /// Field angle (degrees).
    pub field_deg: f64,
    /// Real chief-ray image height on the paraxial focal plane (mm, positive).
    pub image_height_mm: f64,
    /// Paraxial (ideal) height EFL · tan θ (mm).
    pub paraxial_height_mm: f64,
    /// (real − paraxial) / paraxial, percent: negative is barrel.
    pub distortion_percent: f64,
}

/// Distortion of a lens focused at infinity, at `steps` field angles up to `max_field_deg`
/// (stopping where the chief ray is vignetted).
pub fn distortion_curve(
    p: &Prescription,
    max_field_deg: f64,
    steps: u32,
    lambda_um: f64,
) -> Vec<DistortionPoint> {
    let par = analyse(p, lambda_um);
    let (Some(efl), Some(bfl)) = (par.efl, par.bfl) else {
        return Vec::new();
    };
    let focal_plane = par.rear_vertex_z + bfl;
    let mut out = Vec::new();
    for k in 1..=steps {
        let field = max_field_deg * k as f64 / steps as f64;
        let theta = field.to_radians();
        let Some(ray) = trace::chief_ray(p, theta, lambda_um) else {
            break;
        };
        let Ok(exit) = trace::trace(p, ray, lambda_um) else {
            break;
        };
        let real = trace::height_at(&exit, focal_plane).abs();
        let ideal = efl.abs() * theta.tan();
        out.push(DistortionPoint {
            field_deg: field,
            image_height_mm: real,
            paraxial_height_mm: ideal,
            distortion_percent: 100.0 * (real - ideal) / ideal,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::trace::{trace, Ray};
    use super::*;
    use glam::DVec3;

    mod lens_systems;

    fn lens(text: &str) -> Prescription {
        Prescription::parse(text, "test").unwrap()
    }

    #[test]
    fn thin_lens_limit_obeys_the_lensmaker_and_gauss_equations() {
        // Biconvex, R = ±100 mm, n = 1.5, 1 µm thick: f = 1 / ((n − 1)(2/R)) = 100 mm. The
        // aperture is 0.6 mm: wider, the two surfaces would cross (0.32 mm from the axis).
        let p = lens("100 0.001 1.5 0.6\n-100 100 1 0.6\n");
        let par = analyse(&p, LAMBDA_D);
        assert!((par.efl.unwrap() - 100.0).abs() < 1e-3, "{par:?}");
        // 1/s + 1/s' = 1/f: an object 300 mm away images 150 mm behind.
        let s_img = focus(&p, 300.0, LAMBDA_D).unwrap();
        assert!((s_img - 150.0).abs() < 1e-2, "{s_img}");
        // The exact trace of a near-axis ray agrees with the paraxial focus.
        let out = trace(
            &p,
            Ray {
                origin: DVec3::new(0.0, 0.01, -1.0),
                direction: DVec3::Z,
            },
            LAMBDA_D,
        )
        .unwrap();
        let z_cross = out.origin.z - out.origin.y * out.direction.z / out.direction.y;
        assert!((z_cross - (par.rear_vertex_z + par.bfl.unwrap())).abs() < 1e-3);
    }

    #[test]
    fn a_flat_window_shifts_rays_but_does_not_bend_them() {
        let p = lens("0 10 1.5 50\n0 5 1 50\n");
        assert!(analyse(&p, LAMBDA_D).efl.is_none(), "afocal");
        let d = DVec3::new(0.0, 0.3f64.sin(), 0.3f64.cos());
        let out = trace(
            &p,
            Ray {
                origin: DVec3::new(0.0, 0.0, -1.0),
                direction: d,
            },
            LAMBDA_D,
        )
        .unwrap();
        assert!((out.direction - d).length() < 1e-12);
        // Lateral shift t·sin(θ − θ')/cos θ' for a plate of thickness t.
        let theta_t = (0.3f64.sin() / 1.5).asin();
        let shift = 10.0 * (0.3 - theta_t).sin() / theta_t.cos();
        let straight = (out.origin.z + 1.0) * 0.3f64.tan();
        let actual_perp = (straight - out.origin.y) * 0.3f64.cos();
        assert!(
            (actual_perp - shift).abs() < 1e-9,
            "{actual_perp} vs {shift}"
        );
    }

    #[test]
    fn total_internal_reflection_and_apertures_block_rays() {
        // Leaving glass (n = 1.5) through a flat face at 60° exceeds the critical angle.
        let d = super::trace::refract(
            DVec3::new(0.0, 60f64.to_radians().sin(), 60f64.to_radians().cos()),
            DVec3::NEG_Z,
            1.5,
            1.0,
        );
        assert!(d.is_none());
        let p = lens("100 2 1.5 10\n-100 50 1 10\n");
        let r = trace(
            &p,
            Ray {
                origin: DVec3::new(0.0, 6.0, -1.0),
                direction: DVec3::Z,
            },
            LAMBDA_D,
        );
        assert_eq!(r, Err(trace::Blocked::Aperture(0)));
    }
}
