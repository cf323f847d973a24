#version 450
// The map warp of glsl/warp.comp run as a fragment shader over a full-screen triangle. The
// per-pixel work is the same (the map of each channel, a manual bilinear sample of the
// source per channel, the fill value where there is no source); only the way the driver walks
// the pixels differs. On lavapipe the rasterizer shades pixels in blocks without the fixed
// per-invocation cost of a compute dispatch (shared/notes/lavapipe-performance.md): measured
// by `vklens bench warp` (map_raster), the plain map warp gains about 25 %, the chromatic one
// less, since its twelve source reads, not the invocation, dominate it.
#extension GL_GOOGLE_include_directive : require
// vklens:variant rgba8 VKL_RGBA8

#define VKL_WARP_SOURCE_BINDING 3
#include "warp_sample.glsl"

layout(constant_id = 11) const bool CHROMATIC = false;

layout(set = 0, binding = 0, rg32f) uniform readonly image2D map_g;
layout(set = 0, binding = 1, rg32f) uniform readonly image2D map_r;
layout(set = 0, binding = 2, rg32f) uniform readonly image2D map_b;

layout(location = 0) out vec4 out_color;

bool map_source(vec2 m) {
    return !isnan(m.x) && has_source(m);
}

void main() {
    ivec2 id = ivec2(gl_FragCoord.xy);
    vec2 sg = imageLoad(map_g, id).xy;
    bool ok = map_source(sg);
    vec4 value = vec4(0.0);
    if (ok) {
        value = sample_at(sg);
        if (CHROMATIC) {
            vec2 sr = imageLoad(map_r, id).xy;
            vec2 sb = imageLoad(map_b, id).xy;
            ok = map_source(sr) && map_source(sb);
            if (ok) {
                value.r = sample_at(sr).r;
                value.b = sample_at(sb).b;
            }
        }
    }
    out_color = ok ? value : pc.fill;
}
