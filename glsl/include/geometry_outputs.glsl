// The geometry path's fragment stage (glsl/geometry.frag, glsl/geometry_exact.frag): the
// outputs of Lambers et al. Table 1 — colour, object ID (exact: flat, never blended), 2D flow
// and camera depth — and the range along the pixel's ray. Each is written only when its
// attachment exists (specialization constants), so an unasked output costs nothing.
//
// Inputs come from geometry.geom (Alg. 1 with discard) or, for a pinhole render, straight
// from geometry.vert: both write the same locations.
//
// Depth and range. A lens draws a triangle as the straight-edged triangle between its
// distorted vertices, so what is interpolated at a pixel is a point of the 3D triangle near
// the one the pixel's own ray hits, not that one (and with a ray model, whose w is the
// vertex's distance, not even the right mix of vertices). With VKL_EXACT_DEPTH the point is
// recomputed: the pixel's ray (the inverse model) meets the triangle's plane, whose
// direction the interpolated points' screen derivatives span (any interpolated point is an
// affine mix of the vertices, so it lies in that plane). A pinhole render's interpolation is
// already exact; under a moving rolling shutter each vertex is drawn from its own readout
// time, no one pose's ray reaches the triangle, and depth and range stay interpolated.

layout(constant_id = 20) const bool WRITE_COLOR = true;
layout(constant_id = 21) const bool WRITE_IDS = false;
layout(constant_id = 22) const bool WRITE_FLOW = false;
layout(constant_id = 23) const bool WRITE_DEPTH = false;
layout(constant_id = 25) const bool WRITE_RANGE = false;

layout(set = 0, binding = 2) uniform sampler2D scene_texture;

layout(location = 0) in vec4 g_color;
layout(location = 1) in vec2 g_uv;
layout(location = 2) flat in uint g_id;
layout(location = 3) in vec3 g_flow;
layout(location = 4) in vec3 g_position;  // camera-frame position (metres): depth is its z

layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
layout(location = 2) out vec2 out_flow;
layout(location = 3) out float out_depth;
layout(location = 4) out float out_range;

#ifdef VKL_EXACT_DEPTH
#include "camera_model.glsl"

// The camera-frame ray (any length) OpenCV pixel p sees, by the camera's inverse model.
bool vkl_pixel_ray(vec2 p, out vec3 ray) {
    vec2 d = vkl_to_normalized(p);
    ray = vec3(0.0, 0.0, 1.0);
    if (VKL_RAY_MODEL) return vkl_ray_unproject(d, ray);
    vec2 x;
    if (!vkl_undistort_newton(d, x)) return false;
    ray = vec3(x, 1.0);
    return true;
}

// Where the pixel's ray meets the plane through `p` spanned by its screen derivatives; `p`
// itself where that is not defined (a triangle seen edge on, no preimage).
vec3 vkl_exact_point(vec3 p) {
    vec3 n = cross(dFdx(p), dFdy(p));
    vec3 ray;
    if (!vkl_pixel_ray(gl_FragCoord.xy - 0.5, ray)) return p;
    float s = dot(n, p) / dot(n, ray);
    return (s > 0.0 && !isinf(s)) ? ray * s : p;
}
#endif

void main() {
    if (WRITE_COLOR) out_color = g_color * texture(scene_texture, g_uv);
    if (WRITE_IDS) out_id = g_id;
    // Flow is NaN where the surface point was not visible to the model in the previous pose.
    if (WRITE_FLOW) out_flow = g_flow.z > 0.999 ? g_flow.xy : vec2(uintBitsToFloat(0x7fc00000u));
    vec3 p = g_position;
#ifdef VKL_EXACT_DEPTH
    if (WRITE_DEPTH || WRITE_RANGE) {
        vkl_load_camera();
        p = vkl_exact_point(p);
    }
#endif
    if (WRITE_DEPTH) out_depth = p.z;
    if (WRITE_RANGE) out_range = length(p);
}
