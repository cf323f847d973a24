// Lambers et al. Alg. 1 on one clip-space position, shared by the vertex shader
// (glsl/geometry.vert) and the discard pass (glsl/discard.comp) so that both decide with the
// same arithmetic. The includer declares `frame` (geometry_frame.glsl), the camera model
// (camera_model.glsl) and `const bool DISTORT`.
#ifndef VKL_ALG1_GLSL
#define VKL_ALG1_GLSL

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

// Sec. 3.2's test on one vertex: the model applies there, and its undistorted NDC lies
// inside [-(1+δ+D), 1+δ+D]². Written so that NaN fails: !(a <= b) is true for NaN.
bool vkl_vertex_kept(bool ok, vec2 ndc) {
    float bound = frame.viewport.z;
    return ok && abs(ndc.x) <= bound && abs(ndc.y) <= bound;
}

#endif
