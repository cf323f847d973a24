#version 450
// The post-processing warp (seed 000 Sec. 3.3): every output pixel finds its source position —
// analytically with the inverse (or forward) model, or from a precomputed map — and samples
// the source image once per channel. With chromatic aberration on, R, G and B each have their
// own coordinate; each channel is still interpolated exactly once.
//
// Pixels with no valid source (outside the valid domain, or outside the source frame) get the
// fill value and mask 0; they are never smeared edge pixels.
//
// Variants: default rgba32f images; VKL_RGBA8 rgba8 (8-bit data); VKL_R32UI r32ui (object IDs,
// nearest sampling only: IDs are never blended).
#extension GL_GOOGLE_include_directive : require
// vklens:variant rgba8 VKL_RGBA8
// vklens:variant r32ui VKL_R32UI

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"
#include "warp_coords.glsl"

layout(constant_id = 11) const bool CHROMATIC = false;
layout(constant_id = 12) const bool USE_MAP = false;
layout(constant_id = 13) const bool NEAREST = false;
// The validity mask costs a full imageStore per pixel: only when someone asked for it.
layout(constant_id = 14) const bool WRITE_MASK = true;

#if defined(VKL_R32UI)
layout(set = 0, binding = 1, r32ui) uniform readonly uimage2D source;
layout(set = 0, binding = 2, r32ui) uniform writeonly uimage2D target;
#elif defined(VKL_RGBA8)
layout(set = 0, binding = 1, rgba8) uniform readonly image2D source;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D target;
#else
layout(set = 0, binding = 1, rgba32f) uniform readonly image2D source;
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2D target;
#endif
layout(set = 0, binding = 3, r8) uniform writeonly image2D mask;
// Precomputed source coordinates (NaN = no source), one map per channel (G is the only one
// without chromatic aberration).
layout(set = 0, binding = 4, rg32f) uniform readonly image2D map_g;
layout(set = 0, binding = 5, rg32f) uniform readonly image2D map_r;
layout(set = 0, binding = 6, rg32f) uniform readonly image2D map_b;

layout(push_constant) uniform WarpPush {
    vec4 ideal;      // fx fy cx cy of the pinhole side (source for distort, output for undistort)
    vec4 chromatic;  // per-channel magnification R G B, -
    vec4 fill;       // value for pixels without a source
    uvec4 sizes;     // source w h, output w h
} pc;

// Whether a source position lies on the source frame [-0.5, size - 0.5]².
bool on_frame(vec2 s) {
    vec2 size = vec2(pc.sizes.xy);
    return all(greaterThanEqual(s, vec2(-0.5))) && all(lessThanEqual(s, size - 0.5));
}

#if defined(VKL_R32UI)
#define TEXEL uvec4
#else
#define TEXEL vec4
#endif

TEXEL load(ivec2 q) {
    return imageLoad(source, clamp(q, ivec2(0), ivec2(pc.sizes.xy) - 1));
}

// One sample at source position s (OpenCV convention: texel centres at integers).
TEXEL sample_at(vec2 s) {
#if defined(VKL_R32UI)
    return load(ivec2(floor(s + 0.5)));
#else
    if (NEAREST) return load(ivec2(floor(s + 0.5)));
    vec2 f = s - floor(s);
    ivec2 q = ivec2(floor(s));
    // Manual bilinear from four imageLoads: as fast as a sampler on lavapipe and exact about
    // the pixel-centre convention (shared/notes/lavapipe-performance.md).
    return mix(mix(load(q), load(q + ivec2(1, 0)), f.x),
               mix(load(q + ivec2(0, 1)), load(q + ivec2(1, 1)), f.x), f.y);
#endif
}

bool coords(vec2 p, ivec2 id, int channel, float scale, out vec2 s) {
    if (USE_MAP) {
        vec2 m = channel == 0 ? imageLoad(map_r, id).xy
               : channel == 2 ? imageLoad(map_b, id).xy
               : imageLoad(map_g, id).xy;
        s = m;
        return !isnan(m.x) && on_frame(m);
    }
    return vkl_warp_source(p, pc.ideal, scale, s) && on_frame(s);
}

void main() {
    ivec2 id = ivec2(gl_GlobalInvocationID.xy);
    if (id.x >= int(pc.sizes.z) || id.y >= int(pc.sizes.w)) return;
    vec2 p = vec2(id);
    vec2 sg;
    bool ok = coords(p, id, 1, pc.chromatic.y, sg);
    TEXEL value = TEXEL(0);
    if (ok) {
        value = sample_at(sg);
#if !defined(VKL_R32UI)
        if (CHROMATIC) {
            vec2 sr;
            vec2 sb;
            bool ok_r = coords(p, id, 0, pc.chromatic.x, sr);
            bool ok_b = coords(p, id, 2, pc.chromatic.z, sb);
            ok = ok_r && ok_b;
            if (ok) {
                value.r = sample_at(sr).r;
                value.b = sample_at(sb).b;
            }
        }
#endif
    }
#if defined(VKL_R32UI)
    imageStore(target, id, ok ? value : uvec4(uint(pc.fill.x)));
#else
    imageStore(target, id, ok ? value : pc.fill);
#endif
    if (WRITE_MASK) imageStore(mask, id, vec4(ok ? 1.0 : 0.0));
}
