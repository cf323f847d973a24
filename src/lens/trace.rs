//! Exact sequential ray tracing through a prescription (f64): ray–sphere (or plane)
//! intersection on the cap nearest each vertex, clipping at every clear aperture and at the
//! stop, vector Snell refraction, total internal reflection as a blocked ray.
//!
//! Coordinates: mm, z along the optical axis from the front vertex towards the image.

use glam::DVec3;

use super::prescription::Prescription;

/// A ray: origin and unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub direction: DVec3,
}

/// Why a ray did not get through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blocked {
    /// Misses the sphere of surface `i` altogether.
    Missed(usize),
    /// Hits surface `i` outside its clear aperture (or the stop outside its opening).
    Aperture(usize),
    /// Total internal reflection at surface `i`.
    TotalInternalReflection(usize),
}

/// Vector Snell's law: refracts unit `d` at unit normal `n` (facing against `d`) from index
/// `n1` into `n2`; `None` on total internal reflection.
pub fn refract(d: DVec3, n: DVec3, n1: f64, n2: f64) -> Option<DVec3> {
    let eta = n1 / n2;
    let cos_i = -n.dot(d);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

/// Traces `ray` (travelling towards +z) from object space through every surface at
/// `lambda_um`; returns the ray leaving the last surface.
pub fn trace(p: &Prescription, ray: Ray, lambda_um: f64) -> Result<Ray, Blocked> {
    let vertices = p.vertex_positions();
    let mut r = ray;
    let mut n_before = 1.0;
    for (i, s) in p.surfaces.iter().enumerate() {
        let z = vertices[i];
        let (hit, normal) = if s.radius == 0.0 {
            if r.direction.z <= 0.0 {
                return Err(Blocked::Missed(i));
            }
            let t = (z - r.origin.z) / r.direction.z;
            (r.origin + t * r.direction, DVec3::NEG_Z)
        } else {
            let centre = DVec3::new(0.0, 0.0, z + s.radius);
            let oc = r.origin - centre;
            let b = oc.dot(r.direction);
            let disc = b * b - (oc.length_squared() - s.radius * s.radius);
            if disc < 0.0 {
                return Err(Blocked::Missed(i));
            }
            // The cap at the vertex: the nearer intersection for a centre behind the vertex
            // (convex towards the light), the farther one otherwise.
            let t = if s.radius > 0.0 {
                -b - disc.sqrt()
            } else {
                -b + disc.sqrt()
            };
            let hit = r.origin + t * r.direction;
            let mut normal = (hit - centre) / s.radius.abs();
            if normal.dot(r.direction) > 0.0 {
                normal = -normal;
            }
            (hit, normal)
        };
        if hit.x * hit.x + hit.y * hit.y > 0.25 * s.aperture * s.aperture {
            return Err(Blocked::Aperture(i));
        }
        let n_after = s.ior_at(lambda_um);
        let direction = if s.stop || n_after == n_before {
            r.direction
        } else {
            refract(r.direction, normal, n_before, n_after)
                .ok_or(Blocked::TotalInternalReflection(i))?
        };
        r = Ray {
            origin: hit,
            direction,
        };
        n_before = n_after;
    }
    Ok(r)
}

/// Height (y) at which `ray` crosses the plane `z`.
pub fn height_at(ray: &Ray, z: f64) -> f64 {
    let t = (z - ray.origin.z) / ray.direction.z;
    ray.origin.y + t * ray.direction.y
}

/// The chief ray of field angle `theta` (radians, object at infinity, in the y–z plane): the
/// ray through the centre of the stop, found by bisection on its entrance height.
pub fn chief_ray(p: &Prescription, theta: f64, lambda_um: f64) -> Option<Ray> {
    let stop = p.stop_index();
    let stop_z = p.vertex_positions()[stop];
    let direction = DVec3::new(0.0, theta.sin(), theta.cos());
    let start_z = -1.0;
    // Height at the stop of the ray entering at height h (traced up to the stop only).
    let front = Prescription {
        name: String::new(),
        surfaces: p.surfaces[..stop].to_vec(),
    };
    let at_stop = |h: f64| -> Option<f64> {
        let ray = Ray {
            origin: DVec3::new(0.0, h, start_z),
            direction,
        };
        let out = if stop == 0 {
            ray
        } else {
            trace(&front, ray, lambda_um).ok()?
        };
        Some(height_at(&out, stop_z))
    };
    // Bracket the root over the front aperture (the height at the stop is monotonic in the
    // entrance height where rays pass), then bisect: robust where vignetting cuts the range.
    let reach = p.surfaces[0].aperture / 2.0 + (1.0 + 1.0) * theta.tan().abs();
    let samples = 400;
    let mut bracket = None;
    let mut previous: Option<(f64, f64)> = None;
    for k in 0..=samples {
        let h = -reach + 2.0 * reach * k as f64 / samples as f64;
        let Some(y) = at_stop(h) else {
            previous = None;
            continue;
        };
        if let Some((hp, yp)) = previous {
            if yp.signum() != y.signum() {
                bracket = Some((hp, yp, h));
                break;
            }
        }
        previous = Some((h, y));
    }
    let (mut lo, y_lo, mut hi) = bracket?;
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        match at_stop(mid) {
            Some(y) if y.signum() == y_lo.signum() => lo = mid,
            Some(_) => hi = mid,
            None => return None,
        }
    }
    let h1 = 0.5 * (lo + hi);
    let ray = Ray {
        origin: DVec3::new(0.0, h1, start_z),
        direction,
    };
    // The whole lens must pass it.
    trace(p, ray, lambda_um).ok().map(|_| ray)
}
