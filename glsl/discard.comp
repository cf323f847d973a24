#version 450
// Lambers et al. Sec. 3.2's triangle discard without a geometry shader, in two dispatches
// before the draw (the geometry shader is missing on MoltenVK and many mobile GPUs, and costs
// a stage per triangle where it exists):
//
//   STAGE 0, one invocation per vertex: Alg. 1 for the current pose (alg1.glsl, the vertex
//            shader's own arithmetic) -> the distorted clip position, the Sec. 3.2 test ->
//            one flag, and (for flow) Alg. 1 for the previous pose -> the flow;
//   STAGE 1, one invocation per triangle: its three indices when all three flags are set,
//            else a degenerate triangle (the first index three times) that rasterizes to
//            nothing. Triangles keep their order, so the depth test resolves ties as the
//            geometry-shader path does.
//
// The draw then reads positions and flow per vertex (geometry.vert, VKL_PULLED) over the
// rewritten index buffer: the model runs once per vertex and pose, in this pass only.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

#include "camera_model.glsl"
#include "geometry_frame.glsl"

layout(constant_id = 8) const bool DISTORT = true;
layout(constant_id = 9) const uint STAGE = 0;
layout(constant_id = 22) const bool WRITE_FLOW = true;

// The mesh's world positions, one vec4 (w = 1) per vertex: one aligned load per invocation
// instead of three strided ones from the vertex buffer.
layout(set = 0, binding = 2, std430) readonly buffer Points { vec4 points[]; };
layout(set = 0, binding = 3, std430) readonly buffer Indices { uint indices[]; };
layout(set = 0, binding = 4, std430) buffer Flags { uint flags[]; };
layout(set = 0, binding = 5, std430) writeonly buffer Kept { uint kept[]; };
layout(set = 0, binding = 6, std430) writeonly buffer Positions { vec4 positions[]; };
layout(set = 0, binding = 7, std430) writeonly buffer Motion { vec4 motion[]; };

layout(push_constant) uniform DiscardPush { uint count; } pc;

#include "alg1.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    if (STAGE == 0u) {
        vec4 world = points[i];
        vec4 clip = frame.view_projection * world;
        vec4 distorted;
        vec2 pixel, ndc;
        bool ok = alg1(clip, distorted, pixel, ndc);
        flags[i] = vkl_vertex_kept(ok, ndc) ? 1u : 0u;
        positions[i] = distorted;
        if (WRITE_FLOW) {
            vec4 previous_distorted;
            vec2 previous_pixel, previous_ndc;
            bool previous_ok = alg1(frame.previous_view_projection * world, previous_distorted,
                                    previous_pixel, previous_ndc);
            motion[i] = vec4(pixel - previous_pixel, (ok && previous_ok) ? 1.0 : 0.0, 0.0);
        }
    } else {
        uint a = indices[3u * i], b = indices[3u * i + 1u], c = indices[3u * i + 2u];
        bool keep = flags[a] != 0u && flags[b] != 0u && flags[c] != 0u;
        kept[3u * i] = a;
        kept[3u * i + 1u] = keep ? b : a;
        kept[3u * i + 2u] = keep ? c : a;
    }
}
