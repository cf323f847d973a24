// The per-frame block of the geometry path (glsl/geometry.vert, glsl/geometry.geom,
// glsl/mesh_warp.vert), mirrored by `GeometryFrame` in src/pass/geometry.rs.
#ifndef VKL_GEOMETRY_FRAME_GLSL
#define VKL_GEOMETRY_FRAME_GLSL

layout(set = 0, binding = 1, std140) uniform GeometryFrame {
    mat4 view_projection;           // Sec. 3.1 projection × world-to-camera pose
    mat4 previous_view_projection;  // the same for the pose the flow starts from
    mat4 view;                      // world-to-camera pose (depth output: camera z)
    vec4 viewport;                  // x, y: image width, height (px); z: the discard bound
                                    // 1 + δ + D on |undistorted NDC|; w: near (a
                                    // fisheye's vertices are dropped nearer than it)
} frame;

#endif
