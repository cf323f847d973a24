#version 450
// The geometry path's outputs (Lambers et al. Table 1): colour, object ID (exact: flat, never
// blended), 2D flow and camera depth. Each is written only when its attachment exists
// (specialization constants), so an unasked output costs nothing.
//
// Inputs come from geometry.geom (Alg. 1 with discard) or, for a pinhole render, straight
// from geometry.vert: both write the same locations 0-4.

layout(constant_id = 20) const bool WRITE_COLOR = true;
layout(constant_id = 21) const bool WRITE_IDS = false;
layout(constant_id = 22) const bool WRITE_FLOW = false;
layout(constant_id = 23) const bool WRITE_DEPTH = false;

layout(set = 0, binding = 2) uniform sampler2D scene_texture;

layout(location = 0) in vec4 g_color;
layout(location = 1) in vec2 g_uv;
layout(location = 2) flat in uint g_id;
layout(location = 3) in vec3 g_flow;
layout(location = 4) in float g_depth;

layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
layout(location = 2) out vec2 out_flow;
layout(location = 3) out float out_depth;

void main() {
    if (WRITE_COLOR) out_color = g_color * texture(scene_texture, g_uv);
    if (WRITE_IDS) out_id = g_id;
    // Flow is NaN where the surface point was not visible to the model in the previous pose.
    if (WRITE_FLOW) out_flow = g_flow.z > 0.999 ? g_flow.xy : vec2(uintBitsToFloat(0x7fc00000u));
    if (WRITE_DEPTH) out_depth = g_depth;
}
