//! First-order (paraxial) analysis of a prescription by 2×2 ray-transfer matrices on
//! (height y, reduced angle n·u): refraction at a surface of curvature c between indices n
//! and n' is `[[1, 0], [−(n'−n)c, 1]]`, a gap t in index n is `[[1, t/n], [0, 1]]`. Both have
//! determinant 1, which the pupil magnifications below use.
//!
//! All axial positions are in mm from the front (first) vertex, positive towards the image.

use super::prescription::Prescription;

/// A 2×2 ray-transfer matrix `[[a, b], [c, d]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Abcd {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
}

impl Abcd {
    pub const IDENTITY: Abcd = Abcd {
        a: 1.0,
        b: 0.0,
        c: 0.0,
        d: 1.0,
    };

    /// `self` after `first` (the matrix of applying `first`, then `self`).
    pub fn after(self, first: Abcd) -> Abcd {
        Abcd {
            a: self.a * first.a + self.b * first.c,
            b: self.a * first.b + self.b * first.d,
            c: self.c * first.a + self.d * first.c,
            d: self.c * first.b + self.d * first.d,
        }
    }

    fn refraction(n_before: f64, n_after: f64, radius: f64) -> Abcd {
        let curvature = if radius == 0.0 { 0.0 } else { 1.0 / radius };
        Abcd {
            c: -(n_after - n_before) * curvature,
            ..Abcd::IDENTITY
        }
    }

    fn gap(thickness: f64, n: f64) -> Abcd {
        Abcd {
            b: thickness / n,
            ..Abcd::IDENTITY
        }
    }
}

/// The matrix from just before surface `from` to just after surface `to - 1` (refractions at
/// `from..to`, with the gaps between them; `with_last_gap` adds the gap after `to - 1`), at
/// wavelength `lambda_um`.
pub fn transfer(
    p: &Prescription,
    from: usize,
    to: usize,
    with_last_gap: bool,
    lambda_um: f64,
) -> Abcd {
    let mut m = Abcd::IDENTITY;
    let index_before = |i: usize| {
        if i == 0 {
            1.0
        } else {
            p.surfaces[i - 1].ior_at(lambda_um)
        }
    };
    for i in from..to {
        let s = &p.surfaces[i];
        let n_after = s.ior_at(lambda_um);
        m = Abcd::refraction(index_before(i), n_after, s.radius).after(m);
        if i + 1 < to || with_last_gap {
            m = Abcd::gap(s.thickness, n_after).after(m);
        }
    }
    m
}

/// First-order properties of a lens in air.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paraxial {
    /// Effective focal length (mm); `None` for an afocal system (e.g. a flat window).
    pub efl: Option<f64>,
    /// Back focal length: rear vertex → rear focal point (mm).
    pub bfl: Option<f64>,
    /// Front focal length: front focal point → front vertex (mm).
    pub ffl: Option<f64>,
    /// Principal planes (from the front vertex).
    pub front_principal_z: Option<f64>,
    pub rear_principal_z: Option<f64>,
    /// Entrance and exit pupils: position (from the front vertex) and diameter.
    pub entrance_pupil_z: f64,
    pub entrance_pupil_diameter: f64,
    pub exit_pupil_z: f64,
    pub exit_pupil_diameter: f64,
    /// EFL / entrance-pupil diameter.
    pub f_number: Option<f64>,
    /// Front vertex → rear vertex (mm).
    pub rear_vertex_z: f64,
}

/// First-order analysis at `lambda_um`.
pub fn analyse(p: &Prescription, lambda_um: f64) -> Paraxial {
    let n = p.surfaces.len();
    let s = transfer(p, 0, n, false, lambda_um);
    let rear_vertex_z = p.vertex_positions()[n - 1];
    let focal = (s.c.abs() > 1e-15).then_some(());
    let efl = focal.map(|_| -1.0 / s.c);
    let bfl = focal.map(|_| -s.a / s.c);
    let ffl = focal.map(|_| -s.d / s.c);
    let stop = p.stop_index();
    let stop_diameter = p.surfaces[stop].aperture;
    // Entrance pupil: the object-space plane the front group images onto the stop.
    let front = transfer(p, 0, stop, stop > 0, lambda_um);
    let (entrance_pupil_z, entrance_pupil_diameter) = if stop == 0 {
        (0.0, stop_diameter)
    } else {
        (front.b / front.a, stop_diameter / front.a.abs())
    };
    // Exit pupil: the image of the stop through the rear group.
    let rear = if stop + 1 < n {
        transfer(p, stop + 1, n, false, lambda_um).after(Abcd::gap(
            p.surfaces[stop].thickness,
            p.surfaces[stop].ior_at(lambda_um),
        ))
    } else {
        Abcd::IDENTITY
    };
    let (exit_pupil_z, exit_pupil_diameter) = if stop + 1 < n {
        (
            rear_vertex_z - rear.b / rear.d,
            stop_diameter / rear.d.abs(),
        )
    } else {
        (rear_vertex_z, stop_diameter)
    };
    Paraxial {
        efl,
        bfl,
        ffl,
        front_principal_z: focal.map(|_| (s.d - 1.0) / s.c),
        rear_principal_z: focal.map(|_| rear_vertex_z + (1.0 - s.a) / s.c),
        entrance_pupil_z,
        entrance_pupil_diameter,
        exit_pupil_z,
        exit_pupil_diameter,
        f_number: efl.map(|f| f / entrance_pupil_diameter),
        rear_vertex_z,
    }
}

/// Paraxial image distance behind the rear vertex of an on-axis object `object_mm` in front
/// of the front vertex (the film distance that focuses it); `None` if it images at infinity.
pub fn focus(p: &Prescription, object_mm: f64, lambda_um: f64) -> Option<f64> {
    let s = transfer(p, 0, p.surfaces.len(), false, lambda_um);
    let den = s.c * object_mm + s.d;
    (den.abs() > 1e-15).then(|| -(s.a * object_mm + s.b) / den)
}
