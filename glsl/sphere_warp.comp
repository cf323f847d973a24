#version 450
// The warp from a 360° source: every output pixel's ray — the camera's inverse model, past
// 90° off the axis for a fisheye — samples a cube map (six pinhole faces) or an
// equirectangular panorama by direction. This is how a lens wider than any pinhole frustum is
// rendered: the rasterizer draws the six faces, this pass looks them up (Heidrich et al.
// approximate a lens by perspective projections; one projection cannot hold 180° and more).
//
// The cube is sampled through a Vulkan cube view, which filters bilinearly across face edges:
// no seam. The panorama wraps in longitude (sampler REPEAT in u).
//
// Variant: VKL_EQUIRECT samples a 2D panorama instead of the cube. The output is rgba32f
// whatever the source's format (sampling returns floats for UNORM and float images alike), or
// with VKL_RGBA8_TARGET rgba8, for 8-bit colour: a quarter of the bytes to store and read back
// (and lavapipe stores rgba8 texels several times faster than rgba32f ones).
#extension GL_GOOGLE_include_directive : require
// vklens:variant equirect VKL_EQUIRECT
// vklens:variant rgba8 VKL_RGBA8_TARGET
// Each variant also per model (VKL_ONLY_MODEL): a camera's pipeline compiles its model alone.
// vklens:per-model

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"

layout(constant_id = 11) const bool CHROMATIC = false;
layout(constant_id = 14) const bool WRITE_MASK = true;

#ifdef VKL_EQUIRECT
layout(set = 0, binding = 1) uniform sampler2D source;
#else
layout(set = 0, binding = 1) uniform samplerCube source;
#endif
#ifdef VKL_RGBA8_TARGET
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D target;
#else
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2D target;
#endif
layout(set = 0, binding = 3, r8) uniform writeonly image2D mask;

layout(push_constant) uniform SpherePush {
    vec4 chromatic;  // per-channel magnification R G B, -
    vec4 fill;       // value for pixels without a source
    uvec4 sizes;     // -, -, output w h
    uvec4 band;      // the output pixels a dispatch covers: x0 y0 x1 y1 (x1, y1 excluded)
} pc;

// The unit camera-frame ray output pixel p sees, for channel magnification `scale`.
bool ray_of(vec2 p, float scale, out vec3 ray) {
    vec2 d = vkl_to_normalized(p) / scale;
    ray = vec3(0.0, 0.0, 1.0);
    if (VKL_RAY_MODEL) return vkl_ray_unproject(d, ray);
    vec2 x;
    if (!vkl_undistort_newton(d, x)) return false;
    ray = normalize(vec3(x, 1.0));
    return true;
}

vec4 sample_ray(vec3 r) {
#ifdef VKL_EQUIRECT
    // Longitude 0 straight ahead (+z), +90° to the right (+x); latitude −90° straight up (−y,
    // the top row), +90° down: pass::sphere_warp::equirect_direction is the inverse.
    float lon = atan(r.x, r.z);
    float lat = asin(clamp(r.y, -1.0, 1.0));
    vec2 uv = vec2(lon / VKL_TAU + 0.5, lat / (0.5 * VKL_TAU) + 0.5);
    return textureLod(source, uv, 0.0);
#else
    // The faces are proper rotations of the OpenCV camera frame (y down); Vulkan's cube
    // addressing is y-up, so the ray is looked up with y negated (pass::sphere_warp::CubeFace).
    return textureLod(source, vec3(r.x, -r.y, r.z), 0.0);
#endif
}

void main() {
    vkl_load_camera();
    // A dispatch covers the band of output pixels pc.band names (the whole output, or one
    // band of a rolling shutter's lines, each warped from its own cube).
    ivec2 id = ivec2(gl_GlobalInvocationID.xy + pc.band.xy);
    if (id.x >= int(min(pc.band.z, pc.sizes.z)) || id.y >= int(min(pc.band.w, pc.sizes.w))) return;
    vec2 p = vec2(id);
    // G first, then R and B, from one call site in a loop: a driver inlines the lens's inverse
    // at every call before specialization folds CHROMATIC away (glsl/warp.comp says the same).
    uint channels = CHROMATIC ? 3u : 1u;
    vec3 rays[3];
    bool ok = true;
    for (uint k = 0u; k < channels && ok; k++) {
        int c = k == 0u ? 1 : (k == 1u ? 0 : 2);
        float scale = c == 1 ? pc.chromatic.y : (c == 0 ? pc.chromatic.x : pc.chromatic.z);
        ok = ray_of(p, scale, rays[c]);
    }
    vec4 value = pc.fill;
    if (ok) {
        value = sample_ray(rays[1]);
        if (CHROMATIC) {
            value.r = sample_ray(rays[0]).r;
            value.b = sample_ray(rays[2]).b;
        }
    }
    imageStore(target, id, ok ? value : pc.fill);
    if (WRITE_MASK) imageStore(mask, id, vec4(ok ? 1.0 : 0.0));
}
