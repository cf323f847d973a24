// Lambers et al. Alg. 1 on one clip-space position, shared by the vertex shader
// (glsl/geometry.vert) and the discard pass (glsl/discard.comp) so that both decide with the
// same arithmetic. The includer declares `frame` (geometry_frame.glsl), the camera model
// (camera_model.glsl) and `const bool DISTORT`.
#ifndef VKL_ALG1_GLSL
#define VKL_ALG1_GLSL

// Alg. 1 on one clip-space position: the distorted clip position, its OpenCV pixel, and
// whether the model is defined there.
//
// A fisheye sees behind the image plane: its vertices are projected from their camera-frame
// position (X, Y, Z), read back from the clip position through Sec. 3.1's projection of the
// camera's own intrinsics (x_c = sx X + ox Z, y_c = sy Y + oy Z, w_c = Z; no division, so
// Z = 0 is an ordinary point), by the fisheye's own forward model. Its clip position then has
// w = |(X, Y, Z)| (positive on every side of the camera, so nothing is clipped away and
// attributes interpolate with the distance) and depth 1 − near / |(X, Y, Z)|; `ndc` is the
// distorted NDC, and the vertex is dropped outside the lens's domain or nearer than near.
bool alg1_fisheye(vec4 clip, out vec4 distorted, out vec2 pixel, out vec2 ndc) {
    distorted = clip;
    ndc = vec2(0.0);
    pixel = vec2(0.0);
    vec2 size = frame.viewport.xy;
    vec2 f = vkl_cam.intrinsics.xy;
    vec2 lo = -(vkl_cam.intrinsics.zw + 0.5) / f;  // left, top (model::Frustum)
    vec2 hi = size / f + lo;                         // right, bottom
    vec2 s = 2.0 / (hi - lo);
    vec2 o = -(hi + lo) / (hi - lo);
    vec3 p = vec3((clip.xy - o * clip.w) / s, clip.w);
    float r = length(p);
    vec2 d;
    bool ok = r >= frame.viewport.w && vkl_fisheye_project(p, d);
    pixel = vkl_to_pixel(d);
    ok = ok && !any(isnan(pixel)) && !any(isinf(pixel));
    ndc = (pixel + 0.5) / size * 2.0 - 1.0;
    distorted = vec4(ndc * r, (1.0 - frame.viewport.w / r) * r, r);
    return ok;
}

bool alg1(vec4 clip, out vec4 distorted, out vec2 pixel, out vec2 ndc) {
    if (DISTORT && VKL_FISHEYE) return alg1_fisheye(clip, distorted, pixel, ndc);
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

// Sec. 3.2's test on one vertex: the model applies there, and its undistorted NDC lies
// inside [-(1+δ+D), 1+δ+D]². Written so that NaN fails: !(a <= b) is true for NaN.
bool vkl_vertex_kept(bool ok, vec2 ndc) {
    float bound = frame.viewport.z;
    return ok && abs(ndc.x) <= bound && abs(ndc.y) <= bound;
}

#endif
