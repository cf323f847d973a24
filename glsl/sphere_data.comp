#version 450
// Object IDs, depth and range through a lens from a source's IDs and depths: a cube map's
// faces (the cube route's data outputs, beside glsl/sphere_warp.comp's colour, or a
// renderer's own faces), a pinhole image of the same centre and axes (VKL_SOURCE_PINHOLE), or
// an equirectangular panorama (VKL_SOURCE_EQUIRECT). Each output pixel's ray takes the ID of
// the nearest source texel — never blended: an ID edge is never a mix of two. Its depth is not
// the source's depth resampled (a face's z is the distance along that face's axis, not the
// lens camera's): the nearest texel and its four neighbours are surface points, each its
// texel's ray times its depth; where the nearest and a neighbour across and one down or up are
// one object, the ray meets their plane (exact for a planar surface), else the nearest one's
// point is carried onto the ray along the source's axis (its z for a face or pinhole image,
// its range for a panorama). z = range · ray.z.
#extension GL_GOOGLE_include_directive : require
// vklens:variant pinhole VKL_SOURCE_PINHOLE
// vklens:variant equirect VKL_SOURCE_EQUIRECT
// Per model (VKL_ONLY_MODEL): a camera's pipeline compiles its model alone.
// vklens:per-model

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"

#if defined(VKL_SOURCE_PINHOLE) || defined(VKL_SOURCE_EQUIRECT)
layout(set = 0, binding = 1) uniform usampler2D ids_source;
layout(set = 0, binding = 2) uniform sampler2D depth_source;
#else
layout(set = 0, binding = 1) uniform usamplerCube ids_source;
layout(set = 0, binding = 2) uniform samplerCube depth_source;
#endif
layout(set = 0, binding = 3, r32ui) uniform writeonly uimage2D ids_out;
layout(set = 0, binding = 4, r32f) uniform writeonly image2D depth_out;
layout(set = 0, binding = 5, r32f) uniform writeonly image2D range_out;

// `SpherePush` of glsl/sphere_warp.comp (pass::sphere_warp::SpherePush); here `chromatic`
// holds a pinhole source's fx fy cx cy, and fill is unread.
layout(push_constant) uniform SpherePush {
    vec4 chromatic;
    vec4 fill;
    uvec4 sizes;     // -, -, output w h
    uvec4 band;      // x0 y0 x1 y1 (x1, y1 excluded)
} pc;

const float VKL_PI = 3.14159265358979;

// The unit camera-frame ray output pixel p sees.
bool ray_of(vec2 p, out vec3 ray) {
    vec2 d = vkl_to_normalized(p);
    ray = vec3(0.0, 0.0, 1.0);
    if (VKL_RAY_MODEL) {
        if (!vkl_ray_unproject(d, ray)) return false;
        ray = normalize(ray);
        return true;
    }
    vec2 x;
    if (!vkl_undistort_newton(d, x)) return false;
    ray = normalize(vec3(x, 1.0));
    return true;
}

// The source's frame for a unit ray r: the image's right, down and look axes in the lens
// frame (a cube face by r's major axis, as Vulkan's cube addressing picks it:
// pass::sphere_warp::CubeFace; a pinhole or panorama image is the lens camera's own frame).
void frame_of(vec3 r, out vec3 right, out vec3 down, out vec3 look) {
    right = vec3(1.0, 0.0, 0.0); down = vec3(0.0, 1.0, 0.0); look = vec3(0.0, 0.0, 1.0);
#if !defined(VKL_SOURCE_PINHOLE) && !defined(VKL_SOURCE_EQUIRECT)
    vec3 a = abs(r);
    if (a.x >= a.y && a.x >= a.z) {
        float s = sign(r.x);
        look = vec3(s, 0.0, 0.0); right = vec3(0.0, 0.0, -s);
    } else if (a.y >= a.z) {
        float s = sign(r.y);
        look = vec3(0.0, s, 0.0); down = vec3(0.0, 0.0, -s);
    } else {
        float s = sign(r.z);
        look = vec3(0.0, 0.0, s); right = vec3(s, 0.0, 0.0);
    }
#endif
}

// Where ray r falls in the source image (pixel coordinates, centres at integers); false where
// the source does not see it.
bool source_coords(vec3 r, vec3 right, vec3 down, vec3 look, vec2 size, out vec2 s) {
#if defined(VKL_SOURCE_EQUIRECT)
    float lon = atan(r.x, r.z);
    float lat = asin(clamp(r.y, -1.0, 1.0));
    s = vec2((lon / (2.0 * VKL_PI) + 0.5) * size.x, (lat / VKL_PI + 0.5) * size.y) - 0.5;
    return true;
#elif defined(VKL_SOURCE_PINHOLE)
    s = vec2(0.0);
    if (!(r.z > 0.0)) return false;
    s = r.xy / r.z * pc.chromatic.xy + pc.chromatic.zw;
    return all(greaterThan(s, vec2(-0.5))) && all(lessThan(s, size - 0.5));
#else
    float along = dot(r, look);
    s = vec2(dot(r, right), dot(r, down)) / along * (0.5 * size.x) + 0.5 * (size.x - 1.0);
    return true;
#endif
}

// Texel t's ray: the point it shows is this times its stored depth (a face's or pinhole
// image's z: the ray at z = 1; a panorama's range: the unit ray).
vec3 texel_ray(ivec2 t, vec2 size, vec3 right, vec3 down, vec3 look) {
#if defined(VKL_SOURCE_EQUIRECT)
    vec2 m = ((vec2(t) + 0.5) / size - 0.5) * vec2(2.0 * VKL_PI, VKL_PI);
    return vec3(cos(m.y) * sin(m.x), sin(m.y), cos(m.y) * cos(m.x));
#elif defined(VKL_SOURCE_PINHOLE)
    return vec3((vec2(t) - pc.chromatic.zw) / pc.chromatic.xy, 1.0);
#else
    vec2 c = vec2(t) - 0.5 * (size.x - 1.0);  // pixel - cx, with fx = fy = side / 2
    return right * (c.x / (0.5 * size.x)) + down * (c.y / (0.5 * size.x)) + look;
#endif
}

// Texel t's ID and stored depth.
void fetch(ivec2 t, vec3 ray, out uint object, out float depth) {
#if defined(VKL_SOURCE_PINHOLE) || defined(VKL_SOURCE_EQUIRECT)
    object = texelFetch(ids_source, t, 0).r;
    depth = texelFetch(depth_source, t, 0).r;
#else
    // Vulkan's cube addressing is y-up (glsl/sphere_warp.comp): y negated.
    vec3 lookup = vec3(ray.x, -ray.y, ray.z);
    object = textureLod(ids_source, lookup, 0.0).r;
    depth = textureLod(depth_source, lookup, 0.0).r;
#endif
}

// Texel t clamped to the image; a panorama wraps in longitude.
ivec2 clamp_texel(ivec2 t, ivec2 size) {
#if defined(VKL_SOURCE_EQUIRECT)
    t.x = (t.x % size.x + size.x) % size.x;
#endif
    return clamp(t, ivec2(0), size - 1);
}

void main() {
    vkl_load_camera();
    ivec2 id = ivec2(gl_GlobalInvocationID.xy + pc.band.xy);
    if (id.x >= int(min(pc.band.z, pc.sizes.z)) || id.y >= int(min(pc.band.w, pc.sizes.w))) return;
    vec3 r;
    uint object = 0u;
    float range = uintBitsToFloat(0x7f800000u);  // +inf: nothing seen
    float z = range;
    vec3 right, down, look;
    vec2 s;
    ivec2 size = textureSize(depth_source, 0).xy;
    bool seen = ray_of(vec2(id), r);
    if (seen) frame_of(r, right, down, look);
    if (seen && source_coords(r, right, down, look, vec2(size), s)) {
        // The nearest texel and its four neighbours, towards the ray first.
        ivec2 near = clamp_texel(ivec2(round(s)), size);
        ivec2 toward = ivec2(s.x >= float(near.x) ? 1 : -1, s.y >= float(near.y) ? 1 : -1);
        ivec2 offsets[5] = ivec2[5](ivec2(0), ivec2(toward.x, 0), ivec2(0, toward.y),
                                    ivec2(-toward.x, 0), ivec2(0, -toward.y));
        uint ids5[5];
        vec3 points[5];
        for (int k = 0; k < 5; k++) {
            ivec2 t = clamp_texel(near + offsets[k], size);
            vec3 ray = texel_ray(t, vec2(size), right, down, look);
            float depth;
            fetch(t, ray, ids5[k], depth);
            points[k] = ray * depth;
        }
        object = ids5[0];
        if (object != 0u && !any(isinf(points[0])) && !any(isnan(points[0]))) {
            // Carried onto this ray along the source's axis (a panorama: its range).
#if defined(VKL_SOURCE_EQUIRECT)
            range = length(points[0]);
#else
            range = dot(points[0], look) / dot(r, look);
#endif
            // The nearest texel with a neighbour across and one down (or up) of the same
            // object, the quadrant towards the ray first: three points of its surface.
            ivec2 pairs[4] = ivec2[4](ivec2(1, 2), ivec2(3, 2), ivec2(1, 4), ivec2(3, 4));
            for (int k = 0; k < 4; k++) {
                ivec2 p = pairs[k];
                if (ids5[p.x] != object || ids5[p.y] != object) continue;
                vec3 a = points[0];
                vec3 n = cross(points[p.x] - a, points[p.y] - a);
                float hit = dot(n, a) / dot(n, r);
                if (hit > 0.0 && !isinf(hit) && !isnan(hit)) {
                    range = hit;
                    break;
                }
            }
            z = range * r.z;
        }
    }
    imageStore(ids_out, id, uvec4(object));
    imageStore(depth_out, id, vec4(z));
    imageStore(range_out, id, vec4(range));
}
