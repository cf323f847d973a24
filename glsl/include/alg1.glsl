// Lambers et al. Alg. 1 on one clip-space position, shared by the vertex shader
// (glsl/geometry.vert) and the discard pass (glsl/discard.comp) so that both decide with the
// same arithmetic. The includer declares `frame` (geometry_frame.glsl), the camera model
// (camera_model.glsl) and `const bool DISTORT`. VKL_PLAIN (glsl/geometry.vert's plain variant)
// leaves the lens out, for a module that only ever runs with DISTORT false.
#ifndef VKL_ALG1_GLSL
#define VKL_ALG1_GLSL

#include "wraps_behind.glsl"

// A fisheye sees behind the image plane: its vertices are projected from their camera-frame
// position (X, Y, Z), read back from the clip position through Sec. 3.1's projection of the
// camera's own intrinsics (x_c = sx X + ox Z, y_c = sy Y + oy Z, w_c = Z; no division, so
// Z = 0 is an ordinary point), by the fisheye's own forward model; `ndc` is then the distorted
// NDC, and the vertex is dropped outside the lens's domain or nearer than near.

// The camera-frame point (X, Y, Z) of a fisheye vertex, from its clip position.
vec3 alg1_fisheye_point(vec4 clip) {
    vec2 size = frame.viewport.xy;
    vec2 f = vkl_cam.intrinsics.xy;
    vec2 lo = -(vkl_cam.intrinsics.zw + 0.5) / f;  // left, top (model::Frustum)
    vec2 hi = size / f + lo;                         // right, bottom
    vec2 s = 2.0 / (hi - lo);
    vec2 o = -(hi + lo) / (hi - lo);
    return vec3((clip.xy - o * clip.w) / s, clip.w);
}

// A pixel's NDC (OpenCV pixel centres, Vulkan's [-1, 1] across the image).
vec2 alg1_pixel_ndc(vec2 pixel) { return (pixel + 0.5) / frame.viewport.xy * 2.0 - 1.0; }

#ifndef VKL_PLAIN
// The standard model on the ideal point x: its pixel, the Jacobian J, and whether x lies in the
// valid domain and the pixel is finite.
bool alg1_lens(vec2 x, out vec2 pixel, out mat2 J) {
    vec2 d = x;
    J = mat2(1.0);  // what J is where the domain test fails (the distortion is not evaluated)
    bool ok = vkl_contains_ideal(x) && vkl_distort_jacobian(x, d, J);
    pixel = vkl_to_pixel(d);
    return ok && !any(isnan(pixel)) && !any(isinf(pixel));
}
#endif

// Alg. 1 in two halves, so that the compute discard can store a vertex's distorted NDC alone
// (glsl/discard.comp) and the draw rebuild its clip position from the undistorted one.
//
// The first half: the distorted NDC, the vertex's OpenCV pixel, its undistorted NDC (`ndc`,
// for Sec. 3.2's test; for a fisheye the distorted NDC, see above), and whether the model is
// defined there. Where it is not, `distorted_ndc` is the undistorted NDC or 0 (finite: the
// vertex is dropped with its triangles, never drawn).
//
// `J`: the lens's Jacobian at the point (distorted normalized coordinates in ideal ones), which
// the standard model computes with the point at no extra cost; the identity without
// distortion, 0 for a ray model (not differentiated here).
bool alg1_ndc_jacobian(vec4 clip, out vec2 distorted_ndc, out vec2 pixel, out vec2 ndc,
                       out mat2 J) {
    distorted_ndc = vec2(0.0);
    ndc = vec2(0.0);
    pixel = vec2(0.0);
    J = mat2(1.0);
    vec2 size = frame.viewport.xy;
#ifndef VKL_PLAIN
    if (DISTORT && VKL_RAY_MODEL) {
        vec3 p = alg1_fisheye_point(clip);
        float r = length(p);
        vec2 d;
        // domain_info.z: the cosine of the angle past which a vertex is dropped where the domain
        // reaches straight behind the lens (model::Camera::fisheye_vertex_limit), else -2.
        J = mat2(0.0);
        bool ok = r >= frame.viewport.w && p.z >= r * vkl_cam.domain_info.z
                  && vkl_ray_project(p, d);
        pixel = vkl_to_pixel(d);
        ok = ok && !any(isnan(pixel)) && !any(isinf(pixel));
        ndc = alg1_pixel_ndc(pixel);
        distorted_ndc = ok ? ndc : vec2(0.0);
        return ok;
    }
#endif
    if (!(clip.w > 0.0)) return false;  // at or behind the camera: no image point
    ndc = clip.xy / clip.w;
    distorted_ndc = ndc;
    pixel = (ndc * 0.5 + 0.5) * size - 0.5;
    if (!DISTORT) return true;
#ifdef VKL_PLAIN
    return true;
#else
    bool ok = alg1_lens(vkl_to_normalized(pixel), pixel, J);
    distorted_ndc = ok ? alg1_pixel_ndc(pixel) : ndc;
    return ok;
#endif
}

bool alg1_ndc(vec4 clip, out vec2 distorted_ndc, out vec2 pixel, out vec2 ndc) {
    mat2 J;
    return alg1_ndc_jacobian(clip, distorted_ndc, pixel, ndc, J);
}

// The second half: the clip position of a vertex with undistorted clip position `clip` whose
// image lies at `distorted_ndc`. The same w as the pinhole projection, so depth and
// perspective-correct interpolation are untouched; a fisheye's w is the vertex's distance
// |(X, Y, Z)| (positive on every side of the camera, so nothing is clipped away and
// attributes interpolate with the distance), its depth 1 − near / |(X, Y, Z)|.
vec4 alg1_clip(vec4 clip, vec2 distorted_ndc) {
#ifndef VKL_PLAIN
    if (DISTORT && VKL_RAY_MODEL) {
        float r = length(alg1_fisheye_point(clip));
        return vec4(distorted_ndc * r, (1.0 - frame.viewport.w / r) * r, r);
    }
#endif
    return vec4(distorted_ndc * clip.w, clip.zw);
}

// alg1_clip for a camera-frame point known by its depth z and its distance r alone: the
// Sec. 3.1 projection's z and w depend on the depth alone (model::vulkan_projection).
vec4 alg1_clip_at(float z, float r, vec2 distorted_ndc) {
#ifndef VKL_PLAIN
    if (DISTORT && VKL_RAY_MODEL) {
        return vec4(distorted_ndc * r, (1.0 - frame.viewport.w / r) * r, r);
    }
#endif
    vec2 zw = frame.projection[2].zw * z + frame.projection[3].zw;
    return vec4(distorted_ndc * zw.y, zw);
}

// Alg. 1 on one clip-space position: the distorted clip position, its OpenCV pixel, and
// whether the model is defined there.
bool alg1(vec4 clip, out vec4 distorted, out vec2 pixel, out vec2 ndc) {
    vec2 distorted_ndc;
    bool ok = alg1_ndc(clip, distorted_ndc, pixel, ndc);
    distorted = ok ? alg1_clip(clip, distorted_ndc) : clip;
    return ok;
}

// Sec. 3.2's test on one vertex: the model applies there, and its undistorted NDC lies
// inside [-(1+δ+D), 1+δ+D]². Written so that NaN fails: !(a <= b) is true for NaN.
bool vkl_vertex_kept(bool ok, vec2 ndc) {
    float bound = frame.viewport.z;
    return ok && abs(ndc.x) <= bound && abs(ndc.y) <= bound;
}

#endif
