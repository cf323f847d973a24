// warp_coords.glsl — where an output pixel's light comes from, for the warp and the map
// builder. Mirrors src/imaging/cpu_warp.rs (the f64 reference warp) step for step.
//
// MODE 0 (distort): the output is the lens image of camera `vkl_cam`; the source is a pinhole
//   image with intrinsics `ideal` (possibly overscanned). Inverse model per pixel.
// MODE 1 (undistort / precorrect): the output is a pinhole image with intrinsics `ideal`; the
//   source is the lens image of `vkl_cam`. Forward model per pixel (initUndistortRectifyMap).
//   RECTIFY: the output looks along a rotated frame (OpenCV's R, a ROS camera_info's R), and
//   `rectify` (the homography Rᵀ·K_out⁻¹) takes an output pixel to the lens camera's ray.
//
// Lateral chromatic aberration (the Durham radial-correction paper Sec. III; Lensfun's linear TCA): channel c's image is
// magnified by `scale` about the principal point, in distorted normalized coordinates.

#ifndef VKL_WARP_COORDS_GLSL
#define VKL_WARP_COORDS_GLSL

layout(constant_id = 8) const uint MODE = 0;
layout(constant_id = 9) const uint METHOD = 0;  // 0 newton, 1 heikkila, 2 fixed-point
layout(constant_id = 10) const uint FIXED_POINT_ITERATIONS = 5;
layout(constant_id = 16) const bool RECTIFY = false;

// Source pixel (OpenCV pixel-centre convention) for output pixel `p`; false: no valid source.
bool vkl_warp_source(vec2 p, vec4 ideal, mat3 rectify, float scale, out vec2 src) {
    src = vec2(0.0);
#ifndef VKL_WARP_FORWARD
    if (MODE == 0u) {
        vec2 d = vkl_to_normalized(p) / scale;
        vec2 x;
        bool ok;
        if (METHOD == 0u) {
            ok = vkl_undistort_newton(d, x);
        } else if (METHOD == 1u) {
            ok = vkl_undistort_heikkila(d, x);
        } else {
            ok = vkl_undistort_fixed_point(d, FIXED_POINT_ITERATIONS, x);
        }
        src = x * ideal.xy + ideal.zw;
        return ok;
    }
#endif
    vec2 x = (p - ideal.zw) / ideal.xy;
    if (RECTIFY) {
        vec3 ray = rectify * vec3(p, 1.0);
        // A ray the rotation turns behind the lens camera has no image in it.
        if (!(ray.z > 0.0)) return false;
        x = ray.xy / ray.z;
    }
    // The ideal point must be in the valid domain (beyond a fold the forward model wraps back
    // over valid pixels: sampling there would smear the image).
    if (!vkl_contains_ideal(x)) return false;
    vec2 d;
    if (!vkl_distort(x, d)) return false;
    src = vkl_to_pixel(d * scale);
    return true;
}

#endif
