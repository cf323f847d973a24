#version 450
// The geometry path's vertex shader: Lambers et al. Alg. 1 in Vulkan's conventions.
//
// The Sec. 3.1 projection gives clip coordinates; NDC -> window coordinates (Vulkan's NDC y
// already points down, like OpenCV's v) -> OpenCV pixel (window − 0.5: OpenCV puts pixel
// centres at integers, Vulkan at half-integers) -> the forward standard model, all 14
// coefficients -> back to window, NDC and clip (same w, so depth and perspective-correct
// interpolation are untouched).
//
// What the geometry shader needs to drop a triangle (Sec. 3.2) travels with each vertex:
// its undistorted NDC, and whether the model is defined there at all (in front of the camera,
// inside the lens's valid domain, finite).
#extension GL_GOOGLE_include_directive : require
// The pinhole render (no geometry shader) is this shader without the discard data.
// vklens:variant pinhole VKL_PINHOLE
// With the compute discard, Alg. 1 has already run once per vertex and pose
// (glsl/discard.comp): this shader only reads its results, as vertex attributes (fetched like
// the mesh's own, so a vertex-cache miss costs a fetch, not the model again).
// vklens:variant pulled VKL_PULLED
// The same, with the flow the discard pass computed.
// vklens:variant pulled_flow VKL_PULLED_FLOW
// The pinhole render of a frame every line sees from one pose (the warp's and the cube map's
// sources, a camera without a lens): no lens model and no readout solve in the module at all.
// A driver compiles the whole module before specialization folds DISTORT and VKL_READOUT away,
// and the model it would drop is most of that time (on lavapipe, seconds per pipeline).
// vklens:variant plain VKL_PLAIN
// The geometry-shader path of a frame every line sees from one pose: no readout solve.
// vklens:variant global VKL_GLOBAL_SHUTTER
// Each variant also per model (VKL_ONLY_MODEL): a camera's pipeline compiles its model alone.
// vklens:per-model
#ifdef VKL_PULLED_FLOW
#define VKL_PULLED
#endif
#ifdef VKL_PLAIN
#define VKL_PINHOLE
#define VKL_GLOBAL_SHUTTER
#endif

#include "camera_model.glsl"
#include "geometry_frame.glsl"

// false: a plain pinhole render (the warp path's first pass); no model, no discard data.
layout(constant_id = 8) const bool DISTORT = true;
// Flow is the only output that needs the previous pose.
layout(constant_id = 22) const bool WRITE_FLOW = true;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec4 in_color;
layout(location = 3) in uint in_id;

layout(location = 0) out vec4 v_color;
layout(location = 1) out vec2 v_uv;
layout(location = 2) flat out uint v_id;
layout(location = 3) out vec3 v_flow;       // xy: pixel motion since the previous pose; z: valid
layout(location = 4) out vec3 v_position;   // camera-frame position (metres): depth is its z
#if !defined(VKL_PINHOLE) && !defined(VKL_PULLED)
layout(location = 5) out vec3 v_undistorted; // xy: undistorted NDC; z: 1 if the model applies
layout(location = 6) out vec3 v_camera;      // camera-frame position (the wrap-behind test)
#endif
#ifdef VKL_PULLED
// Per vertex, from the discard pass: the distorted NDC, and the flow (xy) with whether both
// poses see the vertex (z).
layout(location = 4) in vec2 in_distorted_ndc;
#endif
#ifdef VKL_PULLED_FLOW
layout(location = 5) in vec4 in_motion;
#endif

// rolling_shutter.glsl's VKL_RUNTIME needs a per-invocation value.
#define VKL_INVOCATION uint(gl_VertexIndex)
#include "alg1.glsl"
#include "rolling_shutter.glsl"

void main() {
    vkl_load_camera();
    vkl_load_frame();
    vec4 world = vec4(in_position, 1.0);
    v_color = in_color;
    v_uv = in_uv;
    v_id = in_id;
    v_position = (frame.view * world).xyz;
#ifdef VKL_PULLED
#ifdef VKL_PULLED_FLOW
    if (VKL_READOUT != 0u && vkl_rs_moving()) {
        if (WRITE_FLOW) {
            // The discard pass solved the vertex's readout time (in_motion.w): its
            // camera-frame point then is one rotation away, the lens is not evaluated again.
            vec3 p = vkl_rs_camera_point(vkl_motion_current(), in_position, in_motion.w);
            v_position = p;
            gl_Position = alg1_clip(frame.projection * vec4(p, 1.0), in_distorted_ndc);
        } else {
            // Without flow, the discard pass left the point's depth and distance.
            // A point with that depth and distance stands in for it (depth and range are
            // interpolated from the vertices under a moving rolling shutter).
            v_position = vec3(sqrt(max(in_motion.y * in_motion.y - in_motion.x * in_motion.x,
                                        0.0)), 0.0, in_motion.x);
            gl_Position = alg1_clip_at(in_motion.x, in_motion.y, in_distorted_ndc);
        }
    } else {
        gl_Position = alg1_clip(frame.view_projection * world, in_distorted_ndc);
    }
    v_flow = WRITE_FLOW ? in_motion.xyz : vec3(0.0);
#else
    gl_Position = alg1_clip(frame.view_projection * world, in_distorted_ndc);
    v_flow = vec3(0.0);
#endif
#else
#ifndef VKL_GLOBAL_SHUTTER
    if (VKL_READOUT != 0u) {
        // A moving rolling shutter: the vertex where its own line reads it, and flow from
        // where the previous frame's lines read it.
        // This module solves every vertex in full: it never leaves one to a later pass.
        VklRsSample r;
        VklRsSample q;
        vkl_rs_frames(in_position, r, q);
        gl_Position = r.ok ? alg1_clip(r.clip, r.distorted_ndc) : r.clip;
        v_position = r.camera;
        bool previous_ok = r.ok;
        vec2 previous_pixel = r.pixel;
        if (WRITE_FLOW) {
            previous_ok = q.ok;
            previous_pixel = q.pixel;
        }
        v_flow = vec3(r.pixel - previous_pixel, (r.ok && previous_ok) ? 1.0 : 0.0);
#ifndef VKL_PINHOLE
        v_undistorted = vec3(r.ndc, r.ok ? 1.0 : 0.0);
        v_camera = r.camera;
#endif
        return;
    }
#endif
    vec4 clip = frame.view_projection * world;
    vec4 distorted;
    vec2 pixel, ndc;
    bool ok = alg1(clip, distorted, pixel, ndc);
    gl_Position = distorted;

    vec2 previous_pixel = pixel;
    bool previous_ok = ok;
    if (WRITE_FLOW) {
        vec4 previous_clip = frame.previous_view_projection * world;
        vec4 previous_distorted;
        vec2 previous_ndc;
        previous_ok = alg1(previous_clip, previous_distorted, previous_pixel, previous_ndc);
    }
    v_flow = vec3(pixel - previous_pixel, (ok && previous_ok) ? 1.0 : 0.0);
#ifndef VKL_PINHOLE
    v_undistorted = vec3(ndc, ok ? 1.0 : 0.0);
    v_camera = (frame.view * world).xyz;
#endif
#endif
}
