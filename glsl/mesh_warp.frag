#version 450
// Samples the source at the interpolated coordinate (bilinear, transparent black outside),
// or, for measuring the mesh's error, writes the coordinate itself.

layout(constant_id = 0) const bool WRITE_COORDINATES = false;

layout(set = 0, binding = 0) uniform sampler2D source;

layout(push_constant) uniform MeshWarpPush {
    vec4 sizes;  // output w, h; source w, h
} pc;

layout(location = 0) in vec2 v_source_pixel;
layout(location = 0) out vec4 out_color;

void main() {
    if (WRITE_COORDINATES) {
        out_color = vec4(v_source_pixel, 0.0, 1.0);
    } else {
        out_color = textureLod(source, (v_source_pixel + 0.5) / pc.sizes.zw, 0.0);
    }
}
