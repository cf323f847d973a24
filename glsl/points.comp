#version 450
// The camera model on a list of points: `vklens points distort|undistort --backend gpu`, the
// GPU side of the reference tests, and the GPU rows of `vklens bench inverse`.
//
// MODE 0 (distort):   ideal normalized (X/Z, Y/Z) -> distorted pixel.
// MODE 1 (undistort): distorted pixel -> ideal normalized, by METHOD.
// MODE 2 (project):   camera-frame point (X, Y, Z), read as inputs[2i].xy, inputs[2i + 1].x
//                     -> distorted pixel (a fisheye sees behind the image plane too).
// MODE 3 (unproject): distorted pixel -> unit camera-frame ray, in outputs[i].xyw.
// outputs[i] = (result.xy, valid ? 1 : 0, ray z or 0). Compiled twice: f32, and f64 (VKL_F64).
#extension GL_GOOGLE_include_directive : require
// vklens:variant f64 VKL_F64
// A driver compiles every mode's model before specialization folds MODE away, and on lavapipe
// the inverse models inlined for modes 1 and 3 are most of a forward pipeline's compile time:
// the forward variants hold modes 0 and 2 alone, the inverse variants modes 1 and 3.
// vklens:variant forward VKL_POINTS_FORWARD
// vklens:variant forward_f64 VKL_F64,VKL_POINTS_FORWARD
// vklens:variant inverse VKL_POINTS_INVERSE
// vklens:variant inverse_f64 VKL_F64,VKL_POINTS_INVERSE
// Each variant also per model (VKL_ONLY_MODEL): a camera's pipeline compiles its model alone.
// vklens:per-model

layout(local_size_x = 64) in;

#include "camera_model.glsl"

layout(constant_id = 8) const uint MODE = 0;
layout(constant_id = 9) const uint METHOD = 0;  // 0 newton, 1 heikkila, 2 fixed-point
layout(constant_id = 10) const uint FIXED_POINT_ITERATIONS = 5;

layout(set = 0, binding = 1, std430) readonly buffer Inputs { VKL_VEC2 inputs[]; };
layout(set = 0, binding = 2, std430) writeonly buffer Outputs { VKL_VEC4 outputs[]; };

layout(push_constant) uniform Push { uint count; } pc;

void main() {
    vkl_load_camera();
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    VKL_VEC2 result = VKL_VEC2(0.0);
    bool valid = false;
#ifndef VKL_POINTS_INVERSE
    if (MODE == 2u) {
        VKL_VEC3 q = VKL_VEC3(inputs[2u * i], inputs[2u * i + 1u].x);
        VKL_VEC2 d = VKL_VEC2(0.0);
        if (VKL_RAY_MODEL) {
            valid = vkl_ray_project(q, d);
        } else {
            valid = q.z > 0.0 && vkl_distort(q.xy / q.z, d);
        }
        result = vkl_to_pixel(d);
        valid = valid && !any(isnan(result)) && !any(isinf(result));
        outputs[i] = VKL_VEC4(result, valid ? 1.0 : 0.0, 0.0);
        return;
    }
#endif
    VKL_VEC2 p = inputs[i];
#ifndef VKL_POINTS_FORWARD
    if (MODE == 3u) {
        VKL_VEC3 ray = VKL_VEC3(0.0);
        VKL_VEC2 d = vkl_to_normalized(p);
        if (VKL_RAY_MODEL) {
            valid = vkl_ray_unproject(d, ray);
        } else {
            VKL_VEC2 x;
            valid = vkl_undistort_newton(d, x);
            ray = normalize(VKL_VEC3(x, 1.0));
        }
        valid = valid && !any(isnan(ray)) && !any(isinf(ray));
        outputs[i] = VKL_VEC4(ray.xy, valid ? 1.0 : 0.0, ray.z);
        return;
    }
#endif
#ifndef VKL_POINTS_INVERSE
    if (MODE == 0u) {
        VKL_VEC2 d;
        valid = vkl_distort(p, d);
        result = vkl_to_pixel(d);
    }
#endif
#ifndef VKL_POINTS_FORWARD
    if (MODE == 1u) {
        VKL_VEC2 d = vkl_to_normalized(p);
        if (METHOD == 0u) {
            valid = vkl_undistort_newton(d, result);
        } else if (METHOD == 1u) {
            valid = vkl_undistort_heikkila(d, result);
        } else {
            valid = vkl_undistort_fixed_point(d, FIXED_POINT_ITERATIONS, result);
        }
    }
#endif
    valid = valid && !any(isnan(result)) && !any(isinf(result));
    outputs[i] = VKL_VEC4(result, valid ? 1.0 : 0.0, 0.0);
}
