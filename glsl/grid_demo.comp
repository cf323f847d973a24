#version 450
// A procedural pinhole image (checkerboard, grid lines every GRID px, principal-point cross)
// seen through the lens: for every distorted output pixel, the Newton inverse finds the ideal
// pixel it came from, and the pattern is evaluated there — an analytic warp with no source
// image. Pixels outside the valid domain are transparent; pixels whose ideal point falls
// outside the pinhole frame (what a post-processing warp cannot fill without overscan, seed
// 000 Sec. 3.3) are drawn hatched grey.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera_model.glsl"

layout(constant_id = 8) const uint GRID = 50;

// One packed RGBA8 pixel per element, row-major.
layout(set = 0, binding = 1, std430) writeonly buffer Pixels { uint pixels[]; };

layout(push_constant) uniform Push { uvec2 size; } pc;

uint pack(vec4 c) { return packUnorm4x8(clamp(c, 0.0, 1.0)); }

void main() {
    vkl_load_camera();
    uvec2 id = gl_GlobalInvocationID.xy;
    if (id.x >= pc.size.x || id.y >= pc.size.y) return;
    uint index = id.y * pc.size.x + id.x;
    vec2 d = vkl_to_normalized(vec2(id));
    vec2 x;
    if (!vkl_undistort_newton(d, x)) {
        pixels[index] = pack(vec4(0.0));
        return;
    }
    vec2 ideal = vkl_to_pixel(x);
    vec2 frame = vec2(pc.size) - 0.5;
    if (any(lessThan(ideal, vec2(-0.5))) || any(greaterThan(ideal, frame))) {
        float hatch = step(0.5, fract((float(id.x) + float(id.y)) / 12.0));
        pixels[index] = pack(vec4(vec3(0.35 + 0.1 * hatch), 1.0));
        return;
    }
    // How many ideal pixels one output pixel covers: 1 / sqrt(det J) of the forward map.
    vec2 fd;
    mat2 J;
    vkl_distort_jacobian(x, fd, J);
    float footprint = 1.0 / sqrt(max(abs(determinant(J)), 1e-6));
    float g = float(GRID);
    vec2 cell = floor(ideal / (2.0 * g));
    bool dark = mod(cell.x + cell.y, 2.0) > 0.5;
    vec3 colour = dark ? vec3(0.80, 0.84, 0.90) : vec3(0.97, 0.97, 0.95);
    vec2 dist = abs(fract(ideal / g + 0.5) - 0.5) * g;  // distance to the nearest grid line
    float line = clamp(1.5 - min(dist.x, dist.y) / footprint, 0.0, 1.0);
    colour = mix(colour, vec3(0.10, 0.22, 0.55), line);
    vec2 c = vkl_cam.intrinsics.zw;
    vec2 off = abs(ideal - c);
    float cross_ = (min(off.x, off.y) < 1.5 * footprint && max(off.x, off.y) < 20.0) ? 1.0 : 0.0;
    colour = mix(colour, vec3(0.85, 0.1, 0.1), cross_);
    pixels[index] = pack(vec4(colour, 1.0));
}
