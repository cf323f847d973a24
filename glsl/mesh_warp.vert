#version 450
// The Durham radial-correction paper's Sec. II-B's mesh-based warp: an n×n grid over the output image whose vertices
// carry the exact source coordinate of their output position (computed once per camera on
// the host, in f64); the rasterizer interpolates it linearly in between.

layout(location = 0) in vec2 in_output_pixel;  // OpenCV pixel coordinates in the output
layout(location = 1) in vec2 in_source_pixel;  // where that point's light comes from

layout(push_constant) uniform MeshWarpPush {
    vec4 sizes;  // output w, h; source w, h
} pc;

layout(location = 0) out vec2 v_source_pixel;

void main() {
    // OpenCV pixel → Vulkan NDC (pixel centres at half-integers in window coordinates).
    vec2 ndc = (in_output_pixel + 0.5) / pc.sizes.xy * 2.0 - 1.0;
    gl_Position = vec4(ndc, 0.0, 1.0);
    v_source_pixel = in_source_pixel;
}
