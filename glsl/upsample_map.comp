#version 450
// A full-resolution coordinate map from a coarse one (every STRIDE-th pixel solved exactly):
// bilinear or cubic (CUBIC) interpolation of the coarse samples, then optionally REFINE Newton
// steps from that start (quadratic convergence), and a forward check of the result (see
// MAX_RESIDUAL_PX). Where a cell corner has no source (next to a fold), the pixel is marked
// invalid: validity is conservative by at most one coarse cell there (the bench counts those
// pixels). Solving such pixels exactly here would cost the whole exact solve on lavapipe, which
// executes branch bodies predicated (measured: 103 ms instead of 22 ms at 1080p). Distort
// direction only (undistort's forward model is cheap enough per pixel).
#extension GL_GOOGLE_include_directive : require
// One module per model too (VKL_ONLY_MODEL): a camera's map compiles its own model alone.
// vklens:per-model

// A wide workgroup (pass::warp::UPSAMPLE_GROUP, which the dispatch divides by): its cells
// write rows of pixels that lie next to each other in memory. On lavapipe 8 × 8 cells (a
// square of pixels) made the upsampling a third slower.
layout(local_size_x = 32, local_size_y = 2) in;

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
// Cubic Lagrange through the 4×4 coarse samples around the cell instead of bilinear through
// its corners (model::warp::MapInterpolation): O(STRIDE⁴) error instead of O(STRIDE²), so a
// coarser grid reaches the same accuracy with 4× fewer exact solves per halving of density.
layout(constant_id = 15) const bool CUBIC = false;

layout(set = 0, binding = 1, rg32f) uniform readonly image2D coarse;
layout(set = 0, binding = 2, rg32f) uniform writeonly image2D map;

layout(push_constant) uniform MapPush {
    vec4 ideal;
    vec4 chromatic;  // x: this channel's magnification
    vec4 unused;
    uvec4 sizes;     // source w h, output w h
    vec4 rectify[3]; // as WarpPush.rectify (unused: distort only)
} pc;

// Cubic Lagrange weights of the nodes -1, 0, 1, 2 at t (model::warp::lagrange_weights).
vec4 vkl_lagrange(float t) {
    return vec4(-t * (t - 1.0) * (t - 2.0) / 6.0,
                (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
                -(t + 1.0) * t * (t - 2.0) / 2.0,
                (t + 1.0) * t * (t - 1.0) / 6.0);
}

// Coarse sample k sits at pixel (k - 1) * STRIDE (one ring beyond the cells for the cubic
// stencil, model::warp::coarse_size). Samples are taken relative to the cell's first corner so
// that f32 rounds the small differences, not the pixel coordinates.
vec2 sample_rel(ivec2 k, vec2 base, inout bool valid) {
    vec2 v = imageLoad(coarse, k).xy;
    valid = valid && !isnan(v.x);
    return v - base;
}

void main() {
    vkl_load_camera();
    // One invocation per coarse cell: its samples are read once for the STRIDE² pixels it
    // writes. On lavapipe the fixed cost of an invocation is about half a copy pass per frame
    // (shared/notes/lavapipe-performance.md): one invocation per pixel made the upsampling
    // cost more than the copy pass (measured at 1080p, stride 4: 35 ms, now 19 ms).
    ivec2 cell = ivec2(gl_GlobalInvocationID.xy);
    ivec2 origin = cell * int(STRIDE);
    if (origin.x >= int(pc.sizes.z) || origin.y >= int(pc.sizes.w)) return;
    ivec2 k = cell + ivec2(1);
    vec2 a = imageLoad(coarse, k).xy;
    bool corners = !isnan(a.x);
    vec2 b = sample_rel(k + ivec2(1, 0), a, corners);
    vec2 d = sample_rel(k + ivec2(0, 1), a, corners);
    vec2 e = sample_rel(k + ivec2(1, 1), a, corners);
    // q[r][c]: the 4×4 stencil, rows and columns at coarse offsets -1..2 from the corner.
    vec2 q[4][4];
    bool cubic = CUBIC && corners;
    if (CUBIC) {
        for (int r = 0; r < 4; ++r) {
            for (int c = 0; c < 4; ++c) {
                q[r][c] = sample_rel(k + ivec2(c - 1, r - 1), a, cubic);
            }
        }
    }
    float nan = uintBitsToFloat(0x7fc00000u);
    for (uint j = 0u; j < STRIDE; ++j) {
        float ty = float(j) / float(STRIDE);
        vec2 column[4];
        if (CUBIC) {
            vec4 wy = vkl_lagrange(ty);
            for (int c = 0; c < 4; ++c) {
                column[c] = wy.x * q[0][c] + wy.y * q[1][c] + wy.z * q[2][c] + wy.w * q[3][c];
            }
        }
        for (uint i = 0u; i < STRIDE; ++i) {
            ivec2 id = origin + ivec2(i, j);
            if (id.x >= int(pc.sizes.z) || id.y >= int(pc.sizes.w)) continue;
            float tx = float(i) / float(STRIDE);
            vec2 s = mix(mix(vec2(0.0), b, tx), mix(d, e, tx), ty);
            if (CUBIC && cubic) {
                vec4 wx = vkl_lagrange(tx);
                s = wx.x * column[0] + wx.y * column[1] + wx.z * column[2] + wx.w * column[3];
            }
            s += a;
            bool ok = corners;
            if (REFINE > 0u || CHECK_RESIDUAL) {
                // Newton in normalized ideal space towards the pre-tilt target of this pixel.
                vec2 t;
                ok = ok && vkl_remove_tilt(vkl_to_normalized(vec2(id)) / pc.chromatic.x, t);
                vec2 x = (s - pc.ideal.zw) / pc.ideal.xy;
                vec2 fx;
                mat2 J;
                for (uint n = 0u; n < REFINE; ++n) {
                    ok = ok && vkl_map_pre_tilt(x, fx, J) && determinant(J) > 0.0;
                    if (ok) x -= inverse(J) * (fx - t);
                }
                s = x * pc.ideal.xy + pc.ideal.zw;
                if (CHECK_RESIDUAL) {
                    ok = ok && vkl_map_pre_tilt(x, fx, J)
                        && length((fx - t) * vkl_cam.intrinsics.xy) <= MAX_RESIDUAL_PX;
                }
            }
            imageStore(map, id, ok ? vec4(s, 0.0, 0.0) : vec4(nan, nan, 0.0, 0.0));
        }
    }
}
