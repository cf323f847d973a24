// The per-frame block of the geometry path (glsl/geometry.vert, glsl/geometry.geom,
// glsl/mesh_warp.vert), mirrored by `GeometryFrame` in src/pass/geometry.rs.
#ifndef VKL_GEOMETRY_FRAME_GLSL
#define VKL_GEOMETRY_FRAME_GLSL

// A frame's motion during the readout about its middle line (s = ½), `MotionGpu` in
// src/pass/geometry.rs: the camera-frame point at readout time s is the middle line's, its
// centre moved by (s − ½) travel and turned back by (s − ½) angle about the axis.
struct VklMotionBlock {
    mat3 rotation;                  // R_cw(½): the middle line's world-to-camera rotation
    vec4 turn;                      // xyz: unit axis, w: angle of R_wc0ᵀ R_wc1 (radians)
    vec4 centre;                    // xyz: the camera centre C(½); w: 1 where the camera moves
                                    // during the frame, else 0
    vec4 travel;                    // xyz: R_cw(½) (C1 − C0)
};

// Every member but the rate table, read once at the top of main() into `frame` (a private
// copy) by vkl_load_frame(). lavapipe (Mesa 22 and 23) reads a uniform block member at a
// uniform offset with one scalar load only outside control flow; inside any branch or loop it
// gathers it lane by lane with a bounds check per lane (about twenty instructions for each
// float), and a moving rolling shutter's solve reads some eighty floats of this block inside
// its branches and loops.
struct VklFrame {
    mat4 view_projection;           // Sec. 3.1 projection × world-to-camera pose
    mat4 previous_view_projection;  // the same for the pose the flow starts from
    mat4 view;                      // world-to-camera pose (depth output: camera z)
    vec4 viewport;                  // x, y: image width, height (px); z: the discard bound
                                    // 1 + δ + D on |undistorted NDC|; w: near (a
                                    // fisheye's vertices are dropped nearer than it)
    // A moving rolling shutter (rolling_shutter.glsl; unread where VKL_READOUT is 0): the
    // camera-frame point at the solved readout time goes through this Sec. 3.1 projection, and
    // the frame's motion is `motion`.
    mat4 projection;
    mat4 previous_view;             // the first line's pose of the frame flow starts from
    VklMotionBlock motion;
    VklMotionBlock previous_motion; // the motion of the frame flow starts from
    vec4 readout_bound;             // x: the half angle of the cone the line rate holds on
                                    // (radians off the axis; 0: no rate, scan)
};

layout(set = 0, binding = 1, std140) uniform GeometryFrame {
    VklFrame values;
    vec4 readout_rates[8];          // the line rate (readout time per radian of ray direction)
                                    // of cones of growing half angle, 32 entries; indexed per
                                    // vertex, so read from the block
} frame_block;

VklFrame frame;

// Every includer's main() calls this first, outside any branch.
void vkl_load_frame() { frame = frame_block.values; }

#endif
