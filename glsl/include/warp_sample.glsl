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

// NEAREST: data that must not be interpolated (always for r32ui IDs). BICUBIC: OpenCV's
// INTER_CUBIC (16 fetches). Neither: bilinear.
layout(constant_id = 13) const bool NEAREST = false;
layout(constant_id = 17) const bool BICUBIC = false;
// What positions off the source read, as OpenCV's remap borders: 0 constant (the pixel takes
// the fill), 1 replicate (the edge pixel repeats), 2 reflect (the image mirrors, edge included).
layout(constant_id = 18) const uint BORDER = 0u;

layout(push_constant) uniform WarpPush {
    vec4 ideal;      // fx fy cx cy of the pinhole side (source for distort, output for undistort)
    vec4 chromatic;  // per-channel magnification R G B, -
    vec4 fill;       // value for pixels without a source
    uvec4 sizes;     // source w h, output w h
    vec4 rectify[3]; // columns of Rᵀ·K_out⁻¹ (undistort with RECTIFY only)
    uvec4 band;      // the output pixels a dispatch covers: x0 y0 x1 y1 (x1, y1 excluded)
} pc;

mat3 vkl_rectify() {
    return mat3(pc.rectify[0].xyz, pc.rectify[1].xyz, pc.rectify[2].xyz);
}

// Whether a source position gives the pixel a value: on the source frame [-0.5, size - 0.5]²
// for the constant border, anywhere finite for the others.
bool has_source(vec2 s) {
    if (BORDER != 0u) return !any(isnan(s)) && !any(isinf(s));
    vec2 size = vec2(pc.sizes.xy);
    return all(greaterThanEqual(s, vec2(-0.5))) && all(lessThanEqual(s, size - 0.5));
}

// The source index tap i of a side of n pixels reads.
int border_index(int i, int n) {
    if (BORDER == 2u) {
        // Period 2n: the image, then its mirror image (edge pixel repeated).
        int m = i % (2 * n);
        if (m < 0) m += 2 * n;
        return m < n ? m : 2 * n - 1 - m;
    }
    return clamp(i, 0, n - 1);
}

// s moved to where it reads the same value within a few pixels of the frame (exact: the
// kernels are symmetric), so that far-off positions do not overflow the tap index.
float fold(float s, float n) {
    if (BORDER == 2u) {
        float m = mod(s + 0.5, 2.0 * n) - 0.5;
        return m > n - 0.5 ? 2.0 * n - 1.0 - m : m;
    }
    return clamp(s, -3.0, n + 2.0);
}

vec2 folded(vec2 s) {
    // The constant border samples only positions on the frame: nothing to fold.
    if (BORDER == 0u) return s;
    return vec2(fold(s.x, float(pc.sizes.x)), fold(s.y, float(pc.sizes.y)));
}

#if defined(VKL_R32UI)
#define TEXEL uvec4
#else
#define TEXEL vec4
#endif

TEXEL load(ivec2 q) {
    ivec2 n = ivec2(pc.sizes.xy);
    return imageLoad(source, ivec2(border_index(q.x, n.x), border_index(q.y, n.y)));
}

// OpenCV's cubic convolution weights (INTER_CUBIC, a = -0.75) of the taps at -1, 0, 1, 2 for
// a position t in [0, 1) past tap 0.
vec4 cubic_weights(float t) {
    const float A = -0.75;
    float u = t + 1.0;
    float w0 = ((A * u - 5.0 * A) * u + 8.0 * A) * u - 4.0 * A;
    float w1 = ((A + 2.0) * t - (A + 3.0)) * t * t + 1.0;
    float v = 1.0 - t;
    float w2 = ((A + 2.0) * v - (A + 3.0)) * v * v + 1.0;
    return vec4(w0, w1, w2, 1.0 - w0 - w1 - w2);
}

// One sample at source position s (OpenCV convention: texel centres at integers).
TEXEL sample_at(vec2 s) {
    s = folded(s);
#if defined(VKL_R32UI)
    return load(ivec2(floor(s + 0.5)));
#else
    if (NEAREST) return load(ivec2(floor(s + 0.5)));
    vec2 f = s - floor(s);
    ivec2 q = ivec2(floor(s));
    if (BICUBIC) {
        vec4 wx = cubic_weights(f.x);
        vec4 wy = cubic_weights(f.y);
        TEXEL v = TEXEL(0);
        for (int j = 0; j < 4; j++) {
            TEXEL row = TEXEL(0);
            for (int i = 0; i < 4; i++) row += wx[i] * load(q + ivec2(i - 1, j - 1));
            v += wy[j] * row;
        }
        return v;
    }
    // Manual bilinear from four imageLoads: as fast as a sampler on lavapipe and exact about
    // the pixel-centre convention (shared/notes/lavapipe-performance.md).
    return mix(mix(load(q), load(q + ivec2(1, 0)), f.x),
               mix(load(q + ivec2(0, 1)), load(q + ivec2(1, 1)), f.x), f.y);
#endif
}

#endif
