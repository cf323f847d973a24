#version 450
// The post-processing warp (Lambers et al. Sec. 3.3): every output pixel finds its source position —
// analytically with the inverse (or forward) model, or from a precomputed map — and samples
// the source image once per channel. With chromatic aberration on, R, G and B each have their
// own coordinate; each channel is still interpolated exactly once.
//
// Pixels with no valid source (outside the valid domain, or, with the constant border, outside
// the source frame) get the fill value and mask 0; they are never smeared edge pixels. The
// replicate and reflect borders (OpenCV's remap borders) give off-frame positions the edge or
// the mirror image instead, and mask 1.
//
// Variants: default rgba32f images; VKL_RGBA8 rgba8 (8-bit data); VKL_R32UI r32ui (object IDs,
// nearest sampling only: IDs are never blended); VKL_R32F r32f (depth, nearest only: the host
// refuses bilinear, which would blend +inf background into a surface's edge).
#extension GL_GOOGLE_include_directive : require
// vklens:variant rgba8 VKL_RGBA8
// vklens:variant r32ui VKL_R32UI
// vklens:variant r32f VKL_R32F
// The undistort direction (MODE 1) runs the forward model alone: its modules leave the
// inverses out, which the driver would otherwise compile before specialization drops them.
// vklens:variant forward VKL_WARP_FORWARD
// vklens:variant rgba8_forward VKL_RGBA8,VKL_WARP_FORWARD
// Each variant also per model (VKL_ONLY_MODEL): a camera's pipeline compiles its own model
// alone, not every model's code before specialization drops the others.
// vklens:per-model

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"
#include "warp_coords.glsl"

layout(constant_id = 11) const bool CHROMATIC = false;
layout(constant_id = 12) const bool USE_MAP = false;
// The validity mask costs a full imageStore per pixel: only when someone asked for it.
layout(constant_id = 14) const bool WRITE_MASK = true;

#define VKL_WARP_SOURCE_BINDING 1
#include "warp_sample.glsl"

#if defined(VKL_R32UI)
layout(set = 0, binding = 2, r32ui) uniform writeonly uimage2D target;
#elif defined(VKL_R32F)
layout(set = 0, binding = 2, r32f) uniform writeonly image2D target;
#elif defined(VKL_RGBA8)
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D target;
#else
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2D target;
#endif
layout(set = 0, binding = 3, r8) uniform writeonly image2D mask;
// Precomputed source coordinates (NaN = no source), one map per channel (G is the only one
// without chromatic aberration).
layout(set = 0, binding = 4, rg32f) uniform readonly image2D map_g;
layout(set = 0, binding = 5, rg32f) uniform readonly image2D map_r;
layout(set = 0, binding = 6, rg32f) uniform readonly image2D map_b;

bool coords(vec2 p, ivec2 id, int channel, float scale, out vec2 s) {
    if (USE_MAP) {
        vec2 m = channel == 0 ? imageLoad(map_r, id).xy
               : channel == 2 ? imageLoad(map_b, id).xy
               : imageLoad(map_g, id).xy;
        s = m;
        return !isnan(m.x) && has_source(m);
    }
    return vkl_warp_source(p, pc.ideal, vkl_rectify(), scale, s) && has_source(s);
}

void main() {
    vkl_load_camera();
    // A dispatch covers the band of output pixels pc.band names (the whole output, or one
    // band of a rolling shutter's lines, each warped from its own source render).
    ivec2 id = ivec2(gl_GlobalInvocationID.xy + pc.band.xy);
    if (id.x >= int(min(pc.band.z, pc.sizes.z)) || id.y >= int(min(pc.band.w, pc.sizes.w))) return;
    vec2 p = vec2(id);
    // G first (the only channel without chromatic aberration), then R and B. One call site in
    // a loop, not three: a driver inlines the inverse model at every call before
    // specialization folds CHROMATIC and METHOD away, and on lavapipe that inlining was most of
    // the pipeline's compile time.
#if defined(VKL_R32UI)
    const uint channels = 1u;
#else
    uint channels = CHROMATIC ? 3u : 1u;
#endif
    vec2 src[3];
    bool ok = true;
    for (uint k = 0u; k < channels && ok; k++) {
        int c = k == 0u ? 1 : (k == 1u ? 0 : 2);
        float scale = c == 1 ? pc.chromatic.y : (c == 0 ? pc.chromatic.x : pc.chromatic.z);
        ok = coords(p, id, c, scale, src[c]);
    }
    TEXEL value = TEXEL(0);
    if (ok) {
        value = sample_at(src[1]);
#if !defined(VKL_R32UI)
        if (CHROMATIC) {
            value.r = sample_at(src[0]).r;
            value.b = sample_at(src[2]).b;
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
