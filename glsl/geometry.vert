#version 450
// The geometry path's vertex shader: Lambers et al. Alg. 1 in Vulkan's conventions.
//
// The Sec. 3.1 projection gives clip coordinates; NDC -> window coordinates (Vulkan's NDC y
// already points down, like OpenCV's v) -> OpenCV pixel (window − 0.5: OpenCV puts pixel
// centres at integers, Vulkan at half-integers) -> the forward standard model, all 14
// coefficients -> back to window, NDC and clip (same w, so depth and perspective-correct
// interpolation are untouched).
//
// What the geometry shader needs to drop a triangle (Sec. 3.2) travels with each vertex:
// its undistorted NDC, and whether the model is defined there at all (in front of the camera,
// inside the lens's valid domain, finite).
#extension GL_GOOGLE_include_directive : require
// The pinhole render (no geometry shader) is this shader without the discard data.
// vklens:variant pinhole VKL_PINHOLE

#include "camera_model.glsl"
#include "geometry_frame.glsl"

// false: a plain pinhole render (the warp path's first pass); no model, no discard data.
layout(constant_id = 8) const bool DISTORT = true;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec4 in_color;
layout(location = 3) in uint in_id;

layout(location = 0) out vec4 v_color;
layout(location = 1) out vec2 v_uv;
layout(location = 2) flat out uint v_id;
layout(location = 3) out vec3 v_flow;       // xy: pixel motion since the previous pose; z: valid
layout(location = 4) out float v_depth;     // camera-frame z (metres)
#ifndef VKL_PINHOLE
layout(location = 5) out vec3 v_undistorted; // xy: undistorted NDC; z: 1 if the model applies
#endif

// Alg. 1 on one clip-space position: the distorted clip position, its OpenCV pixel, and
// whether the model is defined there.
bool alg1(vec4 clip, out vec4 distorted, out vec2 pixel, out vec2 ndc) {
    distorted = clip;
    ndc = vec2(0.0);
    pixel = vec2(0.0);
    if (!(clip.w > 0.0)) return false;  // at or behind the camera: no image point
    ndc = clip.xy / clip.w;
    vec2 size = frame.viewport.xy;
    pixel = (ndc * 0.5 + 0.5) * size - 0.5;
    if (!DISTORT) return true;
    vec2 x = vkl_to_normalized(pixel);
    vec2 d;
    bool ok = vkl_contains_ideal(x) && vkl_distort(x, d);
    pixel = vkl_to_pixel(d);
    ok = ok && !any(isnan(pixel)) && !any(isinf(pixel));
    vec2 distorted_ndc = (pixel + 0.5) / size * 2.0 - 1.0;
    distorted = vec4(distorted_ndc * clip.w, clip.zw);
    return ok;
}

void main() {
    vec4 world = vec4(in_position, 1.0);
    vec4 clip = frame.view_projection * world;
    vec4 distorted;
    vec2 pixel, ndc;
    bool ok = alg1(clip, distorted, pixel, ndc);
    gl_Position = distorted;

    vec4 previous_clip = frame.previous_view_projection * world;
    vec4 previous_distorted;
    vec2 previous_pixel, previous_ndc;
    bool previous_ok = alg1(previous_clip, previous_distorted, previous_pixel, previous_ndc);

    v_color = in_color;
    v_uv = in_uv;
    v_id = in_id;
    v_flow = vec3(pixel - previous_pixel, (ok && previous_ok) ? 1.0 : 0.0);
    v_depth = (frame.view * world).z;
#ifndef VKL_PINHOLE
    v_undistorted = vec3(ndc, ok ? 1.0 : 0.0);
#endif
}
