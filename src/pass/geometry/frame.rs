//! The per-frame uniforms of the geometry path (`glsl/include/geometry_frame.glsl`): the
//! frame block and the rolling shutter's motion block, and the poses they come from.

use super::*;

/// `uniform GeometryFrame` of `glsl/include/geometry_frame.glsl` (std140).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GeometryFrame {
    pub view_projection: [[f32; 4]; 4],
    pub previous_view_projection: [[f32; 4]; 4],
    pub view: [[f32; 4]; 4],
    /// width, height, discard bound 1 + δ + D, near.
    pub viewport: [f32; 4],
    /// The Sec. 3.1 projection alone: a moving rolling shutter's camera-frame points go
    /// through it at their own readout time.
    pub projection: [[f32; 4]; 4],
    /// The first line's pose of the frame flow starts from (`view` is this frame's).
    pub previous_view: [[f32; 4]; 4],
    /// The frame's motion during the readout, and the motion of the frame flow starts from.
    pub motion: MotionGpu,
    pub previous_motion: MotionGpu,
    /// x: the half angle of the cone the lens's line rate was measured on ([`LineRate::cone`],
    /// radians; 0 where it has none, and every vertex is solved by the scan), yzw: 0.
    pub readout_bound: [f32; 4],
    /// The line rate of cones of growing half angle ([`LineRate::per_radian`], entry i in
    /// component i % 4 of row i / 4): with each motion's turn and centres it bounds how fast a
    /// vertex's own line time moves during the readout.
    pub readout_rates: [[f32; 4]; RATE_TABLE / 4],
}

/// `struct VklMotionBlock` of `glsl/include/geometry_frame.glsl` (std140): a frame's motion
/// during the readout about its middle line's pose (s = ½), where the shaders evaluate it.
/// The turn from the first line's camera frame to the last line's has the same axis in every
/// camera frame of the readout, so the camera-frame point at s is the middle line's turned
/// by (s − ½) · angle, and the centre's travel is linear in s: the middle line's point is
/// computed once per vertex, and the solve's first sample, at s = ½, is that point.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct MotionGpu {
    /// R_cw(½), the middle line's world-to-camera rotation (columns, std140 `mat3`).
    pub rotation: [[f32; 4]; 3],
    /// xyz: the unit axis, w: the angle of the turn from the first line's camera frame to
    /// the last line's ([`FrameMotion::axis`], [`FrameMotion::angle`]).
    pub turn: [f32; 4],
    /// xyz: the camera centre C(½) when the middle line is read; w: 1 where the camera moves
    /// during the frame, else 0 (a still frame takes the global shutter's arithmetic, bit
    /// for bit).
    pub centre: [f32; 4],
    /// xyz: R_cw(½) (C1 − C0), the centre's travel during the readout in the middle line's
    /// camera frame; w: 0.
    pub travel: [f32; 4],
}

/// One frame's poses: when the first line is read, and when the last is (the same for a
/// camera that does not move during the frame).
#[derive(Debug, Clone, Copy)]
pub(super) struct Motion {
    pub(super) pose: Pose,
    pub(super) end: Pose,
}

impl Motion {
    pub(super) fn new(pose: Pose, end: Pose) -> Self {
        Motion { pose, end }
    }

    pub(super) fn still(pose: Pose) -> Self {
        Motion { pose, end: pose }
    }

    pub(super) fn is_still(&self) -> bool {
        self.pose == self.end
    }

    /// The motion as `GeometryFrame` holds it.
    pub(super) fn gpu(&self) -> MotionGpu {
        let m = FrameMotion::new(self.pose.into(), self.end.into());
        let middle = m.at(0.5);
        let [c0, c1] = m.centres();
        let moving = if self.is_still() { 0.0 } else { 1.0 };
        let r = middle.rotation.as_mat3();
        MotionGpu {
            rotation: [r.x_axis, r.y_axis, r.z_axis].map(|c| c.extend(0.0).to_array()),
            turn: m.axis().as_vec3().extend(m.angle() as f32).to_array(),
            centre: m.centre_at(0.5).as_vec3().extend(moving).to_array(),
            travel: (middle.rotation * (c1 - c0))
                .as_vec3()
                .extend(0.0)
                .to_array(),
        }
    }
}
