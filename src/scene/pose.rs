//! Camera poses in OpenCV's convention: `p_camera = R p_world + t`, camera frame x right,
//! y down, z forward; rotations as Rodrigues vectors (`rvec`) like `cv2.solvePnP` and
//! `cv2.calibrateCamera` report them.

use crate::{Error, Result};
use glam::{DMat3, DMat4, DVec3, DVec4};

/// A rigid world-to-camera transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub rotation: DMat3,
    pub translation: DVec3,
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// From OpenCV's `rvec` (axis × angle, radians) and `tvec`.
    pub fn from_rvec_tvec(rvec: DVec3, tvec: DVec3) -> Self {
        let angle = rvec.length();
        let rotation = if angle < 1e-300 {
            DMat3::IDENTITY
        } else {
            DMat3::from_axis_angle(rvec / angle, angle)
        };
        Pose {
            rotation,
            translation: tvec,
        }
    }

    /// The Rodrigues vector of the rotation (as `cv2.Rodrigues` returns it).
    pub fn rvec(&self) -> DVec3 {
        let (axis, angle) = glam::DQuat::from_mat3(&self.rotation).to_axis_angle();
        // to_axis_angle may return an angle above π; fold it into [0, π].
        let angle = if angle > std::f64::consts::PI {
            angle - std::f64::consts::TAU
        } else {
            angle
        };
        axis * angle
    }

    /// A camera at `eye` looking at `target`, with `down` (a world direction) appearing
    /// downwards in the image.
    pub fn look_at(eye: DVec3, target: DVec3, down: DVec3) -> Self {
        let z = (target - eye).normalize();
        let mut x = down.cross(z);
        if x.length_squared() < 1e-20 {
            // `down` is parallel to the view direction: any perpendicular will do.
            x = z.any_orthonormal_vector();
        }
        let x = x.normalize();
        let y = z.cross(x);
        let rotation = DMat3::from_cols(x, y, z).transpose();
        Pose {
            rotation,
            translation: -(rotation * eye),
        }
    }

    /// World point → camera frame.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.translation
    }

    /// The camera centre in world coordinates.
    pub fn centre(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }

    /// As a 4×4 matrix (world → camera).
    pub fn matrix(&self) -> DMat4 {
        let r = self.rotation;
        DMat4::from_cols(
            r.x_axis.extend(0.0),
            r.y_axis.extend(0.0),
            r.z_axis.extend(0.0),
            DVec4::new(
                self.translation.x,
                self.translation.y,
                self.translation.z,
                1.0,
            ),
        )
    }

    /// Parses `rx,ry,rz,tx,ty,tz` (an OpenCV rvec then tvec).
    pub fn parse(text: &str) -> Result<Pose> {
        let v: Vec<f64> = text
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                Error::input(format!(
                    "pose {text:?}: expected six numbers rx,ry,rz,tx,ty,tz"
                ))
            })?;
        if v.len() != 6 || v.iter().any(|x| !x.is_finite()) {
            return Err(Error::input(format!(
                "pose {text:?}: expected six finite numbers rx,ry,rz,tx,ty,tz (an OpenCV rvec, then tvec in metres)"
            )));
        }
        Ok(Pose::from_rvec_tvec(
            DVec3::new(v[0], v[1], v[2]),
            DVec3::new(v[3], v[4], v[5]),
        ))
    }
}

/// The model layer's world → camera transform (the rolling-shutter projection takes it).
impl From<Pose> for crate::model::rolling_shutter::WorldToCamera {
    fn from(p: Pose) -> Self {
        crate::model::rolling_shutter::WorldToCamera {
            rotation: p.rotation,
            translation: p.translation,
        }
    }
}

/// A pose of the model layer's motion (the pose of a line's readout time) as the renderer's.
impl From<crate::model::rolling_shutter::WorldToCamera> for Pose {
    fn from(p: crate::model::rolling_shutter::WorldToCamera) -> Self {
        Pose {
            rotation: p.rotation,
            translation: p.translation,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rodrigues_round_trip_and_look_at() {
        let rvec = DVec3::new(0.3, -0.2, 0.1);
        let p = Pose::from_rvec_tvec(rvec, DVec3::new(1.0, 2.0, 3.0));
        assert!((p.rvec() - rvec).length() < 1e-12);
        let eye = DVec3::new(1.0, -2.0, -5.0);
        let look = Pose::look_at(eye, DVec3::ZERO, DVec3::Y);
        // The target is straight ahead, the eye at the origin of the camera frame.
        let t = look.apply(DVec3::ZERO);
        assert!(t.x.abs() < 1e-12 && t.y.abs() < 1e-12 && t.z > 0.0);
        assert!(look.apply(eye).length() < 1e-12);
        assert!((look.centre() - eye).length() < 1e-12);
        // World "down" stays down in the image.
        assert!(look.apply(DVec3::Y).y > t.y);
    }
}
