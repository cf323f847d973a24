#version 450
// Object IDs, depth and range through a lens from a cube map's faces (the cube route's data
// outputs, beside glsl/sphere_warp.comp's colour). Each output pixel's ray takes the ID of the
// nearest face texel — never blended: an ID edge is never a mix of two. Its depth is not the
// faces' z resampled (a face's z is the distance along that face's axis, not the lens
// camera's): the nearest texel and its four neighbours are surface points, each its texel's
// ray times its face depth; where the nearest and a neighbour across and one down or up are
// one object, the ray meets their plane (exact for a planar surface), else the nearest one's
// depth along its face axis is carried onto the ray (range = depth / (ray · axis)).
// z = range · ray.z.
#extension GL_GOOGLE_include_directive : require
// Per model (VKL_ONLY_MODEL): a camera's pipeline compiles its model alone.
// vklens:per-model

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"

layout(set = 0, binding = 1) uniform usamplerCube ids_cube;
layout(set = 0, binding = 2) uniform samplerCube depth_cube;
layout(set = 0, binding = 3, r32ui) uniform writeonly uimage2D ids_out;
layout(set = 0, binding = 4, r32f) uniform writeonly image2D depth_out;
layout(set = 0, binding = 5, r32f) uniform writeonly image2D range_out;

// `SpherePush` of glsl/sphere_warp.comp (pass::sphere_warp::SpherePush); chromatic and fill
// unread.
layout(push_constant) uniform SpherePush {
    vec4 chromatic;
    vec4 fill;
    uvec4 sizes;     // -, -, output w h
    uvec4 band;      // x0 y0 x1 y1 (x1, y1 excluded)
} pc;

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

// The face a unit ray r falls on (its major axis, as Vulkan's cube addressing picks it), as
// the face camera's axes in the lens frame: right, down, look (pass::sphere_warp::CubeFace).
void face_of(vec3 r, out vec3 right, out vec3 down, out vec3 look) {
    vec3 a = abs(r);
    if (a.x >= a.y && a.x >= a.z) {
        float s = sign(r.x);
        look = vec3(s, 0.0, 0.0); right = vec3(0.0, 0.0, -s); down = vec3(0.0, 1.0, 0.0);
    } else if (a.y >= a.z) {
        float s = sign(r.y);
        look = vec3(0.0, s, 0.0); right = vec3(1.0, 0.0, 0.0); down = vec3(0.0, 0.0, -s);
    } else {
        float s = sign(r.z);
        look = vec3(0.0, 0.0, s); right = vec3(s, 0.0, 0.0); down = vec3(0.0, 1.0, 0.0);
    }
}

// A texel of the face (right, down, look): the direction to its centre (face z = 1), and its
// ID and face depth.
vec3 texel_dir(ivec2 t, float side, vec3 right, vec3 down, vec3 look) {
    vec2 c = vec2(t) - 0.5 * (side - 1.0);  // pixel - cx, with fx = fy = side / 2
    return right * (c.x / (0.5 * side)) + down * (c.y / (0.5 * side)) + look;
}

void main() {
    vkl_load_camera();
    ivec2 id = ivec2(gl_GlobalInvocationID.xy + pc.band.xy);
    if (id.x >= int(min(pc.band.z, pc.sizes.z)) || id.y >= int(min(pc.band.w, pc.sizes.w))) return;
    vec3 r;
    uint object = 0u;
    float range = uintBitsToFloat(0x7f800000u);  // +inf: nothing seen
    float z = range;
    if (ray_of(vec2(id), r)) {
        vec3 right, down, look;
        face_of(r, right, down, look);
        float side = float(textureSize(depth_cube, 0).x);
        float along = dot(r, look);
        // The ray in the face's pixels; its nearest texel and that texel's four neighbours
        // (clamped to the face).
        vec2 s = vec2(dot(r, right), dot(r, down)) / along * (0.5 * side) + 0.5 * (side - 1.0);
        ivec2 near = clamp(ivec2(round(s)), ivec2(0), ivec2(int(side) - 1));
        // Towards the ray first: the quadrant it lies in.
        ivec2 toward = ivec2(s.x >= float(near.x) ? 1 : -1, s.y >= float(near.y) ? 1 : -1);
        ivec2 offsets[5] = ivec2[5](ivec2(0), ivec2(toward.x, 0), ivec2(0, toward.y),
                                    ivec2(-toward.x, 0), ivec2(0, -toward.y));
        uint ids5[5];
        vec3 points[5];
        for (int k = 0; k < 5; k++) {
            ivec2 t = clamp(near + offsets[k], ivec2(0), ivec2(int(side) - 1));
            vec3 d = texel_dir(t, side, right, down, look);
            // Vulkan's cube addressing is y-up (glsl/sphere_warp.comp): y negated.
            vec3 lookup = vec3(d.x, -d.y, d.z);
            ids5[k] = textureLod(ids_cube, lookup, 0.0).r;
            points[k] = d * textureLod(depth_cube, lookup, 0.0).r;
        }
        object = ids5[0];
        if (object != 0u && !any(isinf(points[0]))) {
            // Carried along the face axis: the nearest sample's depth on this ray.
            range = dot(points[0], look) / along;
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
