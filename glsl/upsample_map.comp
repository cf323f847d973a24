#version 450
// A full-resolution coordinate map from a coarse one (every STRIDE-th pixel solved exactly):
// bilinear interpolation of the coarse samples, then optionally REFINE Newton steps from that
// start (quadratic convergence), and a forward check of the result (see MAX_RESIDUAL_PX).
// Where a coarse neighbour has no source (next to a fold), the pixel is marked invalid: validity is conservative by at most one coarse cell there (the bench
// counts those pixels). Solving such pixels exactly here would cost the whole exact solve on
// lavapipe, which executes branch bodies predicated (measured: 103 ms instead of 22 ms at
// 1080p). Distort direction only (undistort's forward model is cheap enough per pixel).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"
#include "warp_coords.glsl"

layout(constant_id = 11) const uint STRIDE = 8;
layout(constant_id = 12) const uint REFINE = 0;
// Largest forward residual (distorted pixels) a coarse-map pixel may have; beyond it the pixel
// is marked invalid. Next to a fold the inverse changes so fast that interpolating across one
// cell can be off by pixels (measured: 12.6 px on rational_wide at stride 4) although all four
// corners are valid; one forward evaluation per pixel catches that.
layout(constant_id = 13) const float MAX_RESIDUAL_PX = 0.05;
// The host turns the check off when no fold is in view and its f64 estimate of the worst
// interpolation error (at every cell centre) is under half of MAX_RESIDUAL_PX
// (WarpGeometry::coarse_interpolation_error). On lavapipe only a specialization constant
// removes the cost: branch bodies run predicated.
layout(constant_id = 14) const bool CHECK_RESIDUAL = true;

layout(set = 0, binding = 1, rg32f) uniform readonly image2D coarse;
layout(set = 0, binding = 2, rg32f) uniform writeonly image2D map;

layout(push_constant) uniform MapPush {
    vec4 ideal;
    vec4 chromatic;  // x: this channel's magnification
    vec4 unused;
    uvec4 sizes;     // source w h, output w h
} pc;

void main() {
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    if (id.x >= int(pc.sizes.z) || id.y >= int(pc.sizes.w)) return;
    vec2 g = vec2(id) / float(STRIDE);
    ivec2 c = ivec2(floor(g));
    vec2 f = g - vec2(c);
    vec2 a = imageLoad(coarse, c).xy;
    vec2 b = imageLoad(coarse, c + ivec2(1, 0)).xy;
    vec2 d = imageLoad(coarse, c + ivec2(0, 1)).xy;
    vec2 e = imageLoad(coarse, c + ivec2(1, 1)).xy;
    float nan = uintBitsToFloat(0x7fc00000u);
    vec2 s;
    bool ok;
    if (isnan(a.x) || isnan(b.x) || isnan(d.x) || isnan(e.x)) {
        ok = false;
    } else {
        s = mix(mix(a, b, f.x), mix(d, e, f.x), f.y);
        // Newton in normalized ideal space towards the pre-tilt target of this pixel.
        vec2 t;
        ok = vkl_remove_tilt(vkl_to_normalized(vec2(id)) / pc.chromatic.x, t);
        vec2 x = (s - pc.ideal.zw) / pc.ideal.xy;
        vec2 fx;
        mat2 J;
        for (uint i = 0u; i < REFINE; ++i) {
            ok = ok && vkl_distort_pre_tilt(x, fx, J) && determinant(J) > 0.0;
            if (ok) x -= inverse(J) * (fx - t);
        }
        s = x * pc.ideal.xy + pc.ideal.zw;
        if (CHECK_RESIDUAL) {
            ok = ok && vkl_distort_pre_tilt(x, fx, J)
                && length((fx - t) * vkl_cam.intrinsics.xy) <= MAX_RESIDUAL_PX;
        }
    }
    imageStore(map, id, ok ? vec4(s, 0.0, 0.0) : vec4(nan, nan, 0.0, 0.0));
}
