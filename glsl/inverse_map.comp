#version 450
// Builds a coordinate map once per camera (and per channel): for every output pixel, the
// source position the warp would compute analytically, or NaN where there is none. Later
// frames sample the map instead of solving the model (the lookup-table approach engines use).
#extension GL_GOOGLE_include_directive : require
// One module per model too (VKL_ONLY_MODEL): a camera's map compiles its own model alone.
// vklens:per-model

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"
#include "warp_coords.glsl"

// Solve every STRIDE-th pixel only (a coarse map for upsample_map.comp); 1: every pixel.
// A coarse map has one ring of samples beyond its cells (cubic stencils): sample k sits at
// pixel (k - 1) * STRIDE (model::warp::coarse_size).
layout(constant_id = 11) const uint STRIDE = 1;
const int RING = STRIDE > 1 ? 1 : 0;

layout(set = 0, binding = 1, rg32f) uniform writeonly image2D map;

layout(push_constant) uniform MapPush {
    vec4 ideal;      // as WarpPush.ideal
    vec4 chromatic;  // x: this channel's magnification
    vec4 unused;
    uvec4 sizes;     // source w h, map w h
    vec4 rectify[3]; // as WarpPush.rectify
} pc;

void main() {
    vkl_load_camera();
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    if (id.x >= int(pc.sizes.z) || id.y >= int(pc.sizes.w)) return;
    vec2 s;
    bool ok = vkl_warp_source(vec2((id - RING) * int(STRIDE)), pc.ideal,
                              mat3(pc.rectify[0].xyz, pc.rectify[1].xyz, pc.rectify[2].xyz),
                              pc.chromatic.x, s);
    float nan = uintBitsToFloat(0x7fc00000u);
    imageStore(map, id, ok ? vec4(s, 0.0, 0.0) : vec4(nan, nan, 0.0, 0.0));
}
