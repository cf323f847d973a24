#version 450
// Lambers et al. Sec. 3.2's triangle discard: a triangle with any vertex whose *undistorted* NDC
// lies outside [-(1+δ+D), 1+δ+D]², or where the model does not apply (at or behind the
// camera, outside the lens's valid domain), is dropped whole — never stretched across the
// image. Everything else passes through unchanged.
#extension GL_GOOGLE_include_directive : require

#include "geometry_frame.glsl"
#include "wraps_behind.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

layout(location = 0) in vec4 v_color[];
layout(location = 1) in vec2 v_uv[];
layout(location = 2) flat in uint v_id[];
layout(location = 3) in vec3 v_flow[];
layout(location = 4) in vec3 v_position[];
layout(location = 5) in vec3 v_undistorted[];
layout(location = 6) in vec3 v_camera[];

layout(location = 0) out vec4 g_color;
layout(location = 1) out vec2 g_uv;
layout(location = 2) flat out uint g_id;
layout(location = 3) out vec3 g_flow;
layout(location = 4) out vec3 g_position;

void main() {
    vkl_load_frame();
    float bound = frame.viewport.z;
    for (int i = 0; i < 3; i++) {
        vec3 u = v_undistorted[i];
        // Written so that NaN fails: !(a <= b) is true for NaN.
        if (!(u.z > 0.5) || !(abs(u.x) <= bound) || !(abs(u.y) <= bound)) return;
    }
    // A fisheye that sees past 90° keeps vertices behind the image plane: a triangle there
    // spread far around the axis goes (alg1_spans_behind).
    if (alg1_spans_behind(v_camera[0], v_camera[1], v_camera[2])) return;
    for (int i = 0; i < 3; i++) {
        gl_Position = gl_in[i].gl_Position;
        g_color = v_color[i];
        g_uv = v_uv[i];
        g_id = v_id[i];
        g_flow = v_flow[i];
        g_position = v_position[i];
        EmitVertex();
    }
    EndPrimitive();
}
