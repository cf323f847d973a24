#version 450
// Lambers et al. Sec. 3.2's triangle discard without a geometry shader (the geometry shader is
// missing on MoltenVK and many mobile GPUs, and costs a stage per triangle where it exists).
// Three dispatches before the draw, the last two sized by the GPU itself (indirect):
//
//   STAGE 0, one invocation per vertex: Alg. 1 for the current pose (alg1.glsl, the same
//            arithmetic as the vertex shader of the geometry-shader path) -> the distorted
//            NDC, and for flow Alg. 1 for the previous pose -> the pixel motion. The draw
//            reads both as vertex attributes and rebuilds the clip position from its own
//            pinhole projection (alg1_clip): the model runs once per vertex and pose, never
//            again per triangle or per vertex-cache miss. A vertex that fails the Sec. 3.2
//            test is appended to the dropped list.
//   STAGE 1, one invocation per vertex on the dropped list of the *previous* draw of this
//            mesh (run before stage 0 empties it): its triangles get their indices back.
//   STAGE 3, with a moving rolling shutter, one invocation per vertex stage 0 deferred: stage 0
//            solves each vertex's readout time where the frame's motion bounds it
//            (rolling_shutter.glsl's vkl_rs_bounded: a few evaluations of the lens) and hands
//            the rest to this stage, which scans and refines as the CPU does and then does
//            stage 0's work for them. A driver that masks SIMD lanes rather than branching
//            (lavapipe) would otherwise run the scan's and the refinement's first evaluations
//            for every vertex, needed or not.
//   STAGE 2, one invocation per vertex on the new dropped list: each triangle it belongs to
//            becomes degenerate (its first index three times), which rasterizes to nothing.
//            A kept vertex at or behind the image plane (a fisheye seeing past 90°) is on the
//            list too, marked: of its triangles, only those spread more than 90° around the
//            axis are dropped (alg1_spans_behind).
//
// The draw's index buffer is the mesh's own but for the triangles that touch a dropped
// vertex, so a frame costs its dropped vertices' triangles, not a pass over every triangle;
// triangles keep their order, so the depth test resolves ties as the geometry-shader path
// does. Stages 1 and 2 only ever write a triangle's original indices or its degenerate form,
// so two dropped vertices of one triangle write the same values.
//
// What stage 0 reads and stores is what it costs on lavapipe, which turns a storage-buffer
// access at a per-lane index into a loop over lanes and components: a vertex's three position
// floats straight from the mesh's vertex buffer, and two floats back, not a clip position's
// four (its image and texel-buffer stores measured slower still).
#extension GL_GOOGLE_include_directive : require
// A driver compiles the whole module before specialization folds STAGE and VKL_READOUT away,
// and the lens model it would then drop, inlined at every call, is most of that time (on
// lavapipe, seconds per pipeline). So each pipeline gets a module holding what it runs:
// stages 1 and 2 never run Alg. 1 (the indices variant leaves stage 0 out), and a frame
// every line sees from one pose never solves a readout time (the global variant leaves the
// solve out; this module, with it, serves a moving rolling shutter).
// vklens:variant indices VKL_DISCARD_INDICES
// vklens:variant global VKL_GLOBAL_SHUTTER
// vklens:variant bounded VKL_RS_BOUNDED_ONLY
// Each variant also per model (VKL_ONLY_MODEL): a camera's pipeline compiles its model alone.
// vklens:per-model

layout(local_size_x = 64) in;

#include "camera_model.glsl"
#include "geometry_frame.glsl"

layout(constant_id = 8) const bool DISTORT = true;
layout(constant_id = 9) const uint STAGE = 0;
layout(constant_id = 22) const bool WRITE_FLOW = true;

// The mesh's vertex buffer (scene::Vertex, 8 floats; the position first).
layout(set = 0, binding = 2, std430) readonly buffer Vertices { float vertex_data[]; };
#define VKL_VERTEX_FLOATS 8u
// Per vertex, read by the draw as vertex attributes: the distorted NDC, and the flow (xy) with
// whether both poses see the vertex (z).
layout(set = 0, binding = 3, std430) writeonly buffer Positions { vec2 positions[]; };
// With a moving rolling shutter, w holds the vertex's solved readout time: stage 2 (and the
// draw, where xyz hold the flow) rebuild its camera-frame point from it without solving
// again; without flow, x and y hold the point's depth and distance for the draw.
layout(set = 0, binding = 4, std430) buffer Motion { vec4 motion[]; };
// The dropped vertices (and, marked with VKL_CHECK_BIT, kept vertices whose triangles are
// tested for wrapping behind the lens), and the indirect dispatch that visits them: `groups` is
// ceil(count / 64), `one_y` and `one_z` stay 1 (VkDispatchIndirectCommand). The host resets
// the header between stages 1 and 0.
layout(set = 0, binding = 5, std430) buffer Dropped {
    uint groups;
    uint one_y;
    uint one_z;
    uint count;
    uint vertices[];
} dropped;
// The triangles of vertex v are incidence[incidence_start[v] .. incidence_start[v + 1]].
layout(set = 0, binding = 6, std430) readonly buffer IncidenceStart { uint incidence_start[]; };
layout(set = 0, binding = 7, std430) readonly buffer Incidence { uint incidence[]; };
layout(set = 0, binding = 8, std430) readonly buffer Indices { uint indices[]; };
layout(set = 0, binding = 9, std430) writeonly buffer Kept { uint kept[]; };
// The vertices stage 0 left to stage 3 (a moving rolling shutter the bound does not cover),
// behind the indirect dispatch that visits them, as `Dropped`. The host resets the header
// with the dropped list's.
layout(set = 0, binding = 10, std430) buffer Deferred {
    uint groups;
    uint one_y;
    uint one_z;
    uint count;
    uint vertices[];
} deferred;

layout(push_constant) uniform DiscardPush { uint count; } pc;

#define VKL_CHECK_BIT 0x80000000u

// Vertex v's world position, from the mesh's vertex buffer.
vec4 vkl_world(uint v) {
    uint k = VKL_VERTEX_FLOATS * v;
    return vec4(vertex_data[k], vertex_data[k + 1u], vertex_data[k + 2u], 1.0);
}

// rolling_shutter.glsl's VKL_RUNTIME needs a per-invocation value.
#define VKL_INVOCATION gl_GlobalInvocationID.x
#include "alg1.glsl"
#include "rolling_shutter.glsl"

// Vertex v's camera-frame position: at the readout time stage 0 solved, for a moving rolling
// shutter.
vec3 vkl_camera(uint v) {
    vec4 world = vkl_world(v);
#ifndef VKL_GLOBAL_SHUTTER
    if (VKL_READOUT != 0u && vkl_rs_moving()) {
        return vkl_rs_camera_point(vkl_motion_current(), world.xyz, motion[v].w);
    }
#endif
    return (frame.view * world).xyz;
}

#ifndef VKL_DISCARD_INDICES
// Stage 0's work on vertex i (stage 3's on a deferred one).
void vkl_per_vertex(uint i) {
    vec4 world = vkl_world(i);
    vec4 clip;
    vec2 distorted_ndc, pixel, ndc;
    bool ok;
#ifndef VKL_GLOBAL_SHUTTER
    if (VKL_READOUT != 0u) {
        VklRsSample r;
        VklRsSample q;
        bool solved = vkl_rs_frames(world.xyz, r, q);
        if (!solved) {
            uint slot = atomicAdd(deferred.count, 1u);
            deferred.vertices[slot] = i;
            if (slot % 64u == 0u) atomicAdd(deferred.groups, 1u);
            return;
        }
        clip = r.clip;
        distorted_ndc = r.distorted_ndc;
        pixel = r.pixel;
        ndc = r.ndc;
        ok = r.ok;
        // Without flow, xy carry what the draw needs of the camera-frame point (its depth and
        // its distance), which it would otherwise rebuild from s at a rotation's cost, per
        // vertex invocation. The standard model's draw needs the depth alone, and never
        // rebuilds the point (it keeps no vertex behind the lens for stage 2 to test): lavapipe
        // stores a per-vertex vector lane by lane and component by component, so that vertex
        // stores one float, not four.
        if (WRITE_FLOW) {
            motion[i] = vec4(r.pixel - q.pixel, (r.ok && q.ok) ? 1.0 : 0.0, r.s);
        } else if (DISTORT && VKL_RAY_MODEL) {
            motion[i] = vec4(r.camera.z, length(r.camera), 0.0, r.s);
        } else {
            motion[i].x = r.camera.z;
        }
    } else
#endif
    {
        clip = frame.view_projection * world;
        ok = alg1_ndc(clip, distorted_ndc, pixel, ndc);
    }
    positions[i] = distorted_ndc;
    if (WRITE_FLOW && VKL_READOUT == 0u) {
        vec2 previous_ndc, previous_pixel, previous_undistorted;
        bool previous_ok = alg1_ndc(frame.previous_view_projection * world, previous_ndc,
                                    previous_pixel, previous_undistorted);
        motion[i] = vec4(pixel - previous_pixel, (ok && previous_ok) ? 1.0 : 0.0, 0.0);
    }
    bool kept = vkl_vertex_kept(ok, ndc);
    // clip.w is the camera-frame z (Sec. 3.1's projection).
    if (!kept || !(clip.w > 0.0)) {
        uint slot = atomicAdd(dropped.count, 1u);
        dropped.vertices[slot] = kept ? (i | VKL_CHECK_BIT) : i;
        // The first of every 64 adds a workgroup to stage 2's dispatch.
        if (slot % 64u == 0u) atomicAdd(dropped.groups, 1u);
    }
}
#endif

void main() {
    vkl_load_camera();
    vkl_load_frame();
    uint i = gl_GlobalInvocationID.x;
#ifndef VKL_DISCARD_INDICES
    // Stages 0 and 3 call vkl_per_vertex from one site: a driver inlines every call site's
    // copy of the readout solve before specialization drops the stage that does not run
    // (two sites cost lavapipe twice the compile).
    if (STAGE == 0u || STAGE == 3u) {
        bool run = STAGE == 0u ? i < pc.count : i < deferred.count;
        if (run) vkl_per_vertex(STAGE == 0u ? i : deferred.vertices[i]);
        return;
    }
#endif
    {
        if (i >= dropped.count) return;
        uint entry = dropped.vertices[i];
        uint v = entry & ~VKL_CHECK_BIT;
        bool check = (entry & VKL_CHECK_BIT) != 0u;
        uint end = incidence_start[v + 1u];
        for (uint k = incidence_start[v]; k < end; k++) {
            uint t = 3u * incidence[k];
            uint a = indices[t];
            if (STAGE == 1u) {
                kept[t + 1u] = indices[t + 1u];
                kept[t + 2u] = indices[t + 2u];
            } else {
                bool drop = true;
                if (check) {
                    vec3 p = vkl_camera(a);
                    vec3 q = vkl_camera(indices[t + 1u]);
                    vec3 r = vkl_camera(indices[t + 2u]);
                    drop = alg1_spans_behind(p, q, r);
                }
                if (drop) {
                    kept[t + 1u] = a;
                    kept[t + 2u] = a;
                }
            }
        }
    }
}
