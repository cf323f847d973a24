//! The camera-model table (after COLMAP's `sensor/models.h`): what every model of the table
//! offers, written once, and the generic code every model inherits from it.
//!
//! A model of the table maps a camera-frame point (OpenCV's frame: x right, y down, z ahead)
//! to its *distorted normalized* point `m`, from which the pixel follows by the camera's
//! `fx fy cx cy` (`u = fx·m.x + cx`, `v = fy·m.y + cy`), and back from `m` to the unit ray. A
//! model gives, in one place:
//!
//! * its parameters ([`RayModel::param_names`], [`RayModel::params`], and
//!   [`RayModel::from_params`] where they are named numbers); its name and everything else
//!   the list of models holds is its row in `list.rs`;
//! * its forward map, written once generic over [`Scalar`] ([`RayModel::project_generic`]):
//!   the same code gives the value and, through [`Jet`], the exact analytic Jacobian;
//! * its valid domain ([`RayModel::contains_ray`]), the explicit "invalid" of vklens: a point
//!   outside it has no pixel;
//! * its inverse ([`RayModel::unproject`]): closed form where the model has one, else Newton,
//!   `None` outside the domain.
//!
//! Everything else (the pixel, the pinhole-side maps a warp needs, the Jacobians) is generic:
//! [`project`], [`project_jacobian`], [`distort_normalized`].

use glam::{DMat2, DVec2, DVec3};

use super::jet::{Jet, Scalar};

/// One camera model of the table (see the module documentation).
pub trait RayModel {
    /// The names of the model's own parameters, in [`RayModel::params`]'s order.
    fn param_names(&self) -> Vec<&'static str>;
    /// The model's own parameters (not fx fy cx cy).
    fn params(&self) -> Vec<f64>;
    /// The model from the named numbers its row of `list.rs` lists (`params: [...]`), in that
    /// order, validated. Models whose parameters are lists or flags keep this default and read
    /// their files in `io::models`.
    fn from_params(values: &[f64]) -> Result<Self, super::ModelError>
    where
        Self: Sized,
    {
        let _ = values;
        Err(super::ModelError::Other(
            "this model's parameters are not named numbers".into(),
        ))
    }
    /// The forward map without the domain check: camera-frame point → distorted normalized
    /// point. `None` only where it is undefined (a zero denominator).
    fn project_generic<T: Scalar>(&self, p: [T; 3]) -> Option<[T; 2]>;
    /// Whether a camera-frame point is in the valid domain (finite, not zero).
    fn contains_ray(&self, p: DVec3) -> bool;
    /// The inverse: distorted normalized point → unit camera-frame ray; `None` outside the
    /// valid domain.
    fn unproject(&self, m: DVec2) -> Option<DVec3>;
    /// The largest angle off the optical axis that the domain reaches (radians, ≤ π).
    fn max_angle(&self) -> f64;
    /// What the model's GLSL include reads from the camera block's `model[16]` array, in
    /// order (at most [`GPU_PARAMS`]): the parameters, and whatever the domain needs.
    fn gpu_params(&self) -> Vec<f64> {
        self.params()
    }
}

/// `values` as exactly `N` numbers (a row's `params` count), for [`RayModel::from_params`].
pub(crate) fn exactly<const N: usize>(values: &[f64]) -> Result<[f64; N], super::ModelError> {
    values.try_into().map_err(|_| {
        super::ModelError::Other(format!(
            "the model takes {N} parameter(s), got {}",
            values.len()
        ))
    })
}

/// Scalars in the camera block's `model` array (`glsl/include/camera_model.glsl`).
pub const GPU_PARAMS: usize = 64;

/// The forward map with its domain check: `None` outside the valid domain.
pub fn project<M: RayModel>(model: &M, p: DVec3) -> Option<DVec2> {
    let p = scaled(p)?;
    if !model.contains_ray(p) {
        return None;
    }
    let [x, y] = model.project_generic([p.x, p.y, p.z])?;
    let m = DVec2::new(x, y);
    m.is_finite().then_some(m)
}

/// The forward map and its Jacobian ∂m/∂p (two rows of three), exact, by forward-mode
/// derivatives of the one forward map. `None` outside the valid domain.
pub fn project_jacobian<M: RayModel>(model: &M, p: DVec3) -> Option<(DVec2, [DVec3; 2])> {
    let s = p.abs().max_element();
    let p = scaled(p)?;
    if !model.contains_ray(p) {
        return None;
    }
    let q = [Jet::var(p.x, 0), Jet::var(p.y, 1), Jet::var(p.z, 2)];
    let [x, y] = model.project_generic(q)?;
    let m = DVec2::new(x.v, y.v);
    // The map is homogeneous of degree 0 in p: its Jacobian at s·p is the one at p over s.
    let rows = [DVec3::from_array(x.d) / s, DVec3::from_array(y.d) / s];
    (m.is_finite() && rows.iter().all(|r| r.is_finite())).then_some((m, rows))
}

/// The pinhole-side forward map a warp needs: ideal normalized (X/Z, Y/Z) → distorted
/// normalized, with its 2×2 Jacobian (∂/∂x in column 0). `None` outside the domain.
pub fn distort_normalized<M: RayModel>(model: &M, x: DVec2) -> Option<(DVec2, DMat2)> {
    let p = DVec3::new(x.x, x.y, 1.0);
    // Far past any pinhole-side radius a warp asks for, and squares of it would overflow.
    if !p.is_finite() || x.abs().max_element() > 1e100 || !model.contains_ray(p) {
        return None;
    }
    let q = [Jet::<2>::var(x.x, 0), Jet::var(x.y, 1), Jet::cst(1.0)];
    let [u, v] = model.project_generic(q)?;
    let m = DVec2::new(u.v, v.v);
    let jac = DMat2::from_cols(DVec2::new(u.d[0], v.d[0]), DVec2::new(u.d[1], v.d[1]));
    (m.is_finite() && jac.is_finite()).then_some((m, jac))
}

/// |(x, y, z)|. The callers scale the point first ([`scaled`]), so the squares cannot overflow.
pub(crate) fn norm3<T: Scalar>(p: [T; 3]) -> T {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

/// Every model maps rays, so a point and any positive multiple of it project alike: the
/// point scaled to its largest component ±1, so that no model squares a huge coordinate into
/// an overflow (or a tiny one into zero). `None` for the zero or a non-finite vector.
pub(crate) fn scaled(p: DVec3) -> Option<DVec3> {
    let s = p.abs().max_element();
    (p.is_finite() && s > 0.0).then(|| p / s)
}

/// Normalizes a finite non-zero ray; `None` for anything else.
pub(crate) fn unit(ray: DVec3) -> Option<DVec3> {
    let n = ray.length();
    (ray.is_finite() && n > 0.0 && n.is_finite()).then(|| ray / n)
}

/// The angle of a camera-frame direction off the optical axis (0..π).
pub(crate) fn off_axis(p: DVec3) -> f64 {
    p.x.hypot(p.y).atan2(p.z)
}
