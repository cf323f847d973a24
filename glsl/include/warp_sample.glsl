// The warp's source side, shared by glsl/warp.comp and glsl/warp_raster.frag: the push
// constants, the source image (format by variant: rgba32f by default, VKL_RGBA8, VKL_R32UI,
// VKL_R32F) and one sample of it at an OpenCV source position.
#ifndef VKL_WARP_SAMPLE_GLSL
#define VKL_WARP_SAMPLE_GLSL

#ifndef VKL_WARP_SOURCE_BINDING
#define VKL_WARP_SOURCE_BINDING 1
#endif

#if defined(VKL_R32UI)
layout(set = 0, binding = VKL_WARP_SOURCE_BINDING, r32ui) uniform readonly uimage2D source;
#elif defined(VKL_R32F)
layout(set = 0, binding = VKL_WARP_SOURCE_BINDING, r32f) uniform readonly image2D source;
#elif defined(VKL_RGBA8)
layout(set = 0, binding = VKL_WARP_SOURCE_BINDING, rgba8) uniform readonly image2D source;
#else
layout(set = 0, binding = VKL_WARP_SOURCE_BINDING, rgba32f) uniform readonly image2D source;
#endif

// NEAREST: data that must not be interpolated (always for r32ui IDs).
layout(constant_id = 13) const bool NEAREST = false;

layout(push_constant) uniform WarpPush {
    vec4 ideal;      // fx fy cx cy of the pinhole side (source for distort, output for undistort)
    vec4 chromatic;  // per-channel magnification R G B, -
    vec4 fill;       // value for pixels without a source
    uvec4 sizes;     // source w h, output w h
    vec4 rectify[3]; // columns of Rᵀ·K_out⁻¹ (undistort with RECTIFY only)
} pc;

mat3 vkl_rectify() {
    return mat3(pc.rectify[0].xyz, pc.rectify[1].xyz, pc.rectify[2].xyz);
}

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

#endif
