// A moving rolling shutter per vertex: the readout time at which a vertex's own line reads it,
// and the camera-frame point at that time. The port of `FrameMotion::project`
// (src/model/rolling_shutter.rs): the camera turns by slerp and its centre moves linearly
// between the pose of the first line (s = 0) and the pose of the last (s = 1), as Hedborg et
// al. interpolate poses within a frame ("Rolling shutter bundle adjustment", 2012), and the
// vertex appears where g(s) = s − line_time(π(X at pose(s))) is zero (Meingast, Geyer and
// Sastry, "Geometric models of rolling-shutter cameras", 2005). The same scan for the first
// sign change over 16 cells, the same Illinois false-position refinement, the same bounded
// loops, so that the GPU finds the root the CPU finds; only the tolerances are f32's, and the
// poses are taken about the middle line's (VklMotion) rather than the first's.
//
// π is the camera's model on the camera-frame point through the functions a still camera's
// vertices go through: the standard model's (alg1_lens) on the ideal point X/Z, Y/Z, a ray
// model's by Alg. 1's first half (alg1_ndc) on the Sec. 3.1 clip position. The includer
// declares `frame` (geometry_frame.glsl), the camera model, `const bool DISTORT`, `WRITE_FLOW`
// (whether flow needs the previous frame too) and includes alg1.glsl first.
//
// VKL_READOUT = 0 (a global shutter, or a still camera) compiles none of it: every caller
// branches on the constant, which the driver folds away.
#ifndef VKL_ROLLING_SHUTTER_GLSL
#define VKL_ROLLING_SHUTTER_GLSL

// A condition on uniform values alone, kept a branch decided when the shader runs. lavapipe
// (Mesa 22 and 23) replaces the uniforms that an `if` reads and nothing else by their values
// at each draw or dispatch and, where that folds away half the shader, compiles the shader
// again, at every draw or dispatch: milliseconds per frame for this file's solve, which a
// still frame skips. An invocation index no invocation has keeps the condition per invocation
// (the includer defines VKL_INVOCATION); elsewhere it costs one comparison.
#define VKL_RUNTIME(condition) ((condition) || VKL_INVOCATION == 0xFFFFFFFFu)

// 0: global; 1 top_to_bottom, 2 bottom_to_top, 3 left_to_right, 4 right_to_left
// (spec::READOUT, `Readout::gpu_id`).
layout(constant_id = 24) const uint VKL_READOUT = 0u;

// model::rolling_shutter::SCAN_CELLS and MAX_REFINE_STEPS.
const uint VKL_RS_SCAN_CELLS = 16u;
const uint VKL_RS_MAX_REFINE_STEPS = 64u;
// The bracket is refined until its two pixels agree to this (px): f32 pixels of a 4k image
// carry about 2e-4 px of rounding, so the refinement mostly ends where the bracket can shrink
// no further, one unit in the last place of s wide.
const float VKL_RS_PIXEL_TOLERANCE = 1e-4;
// A bracket that can shrink no further is a root when its pixels are this close (px); further
// apart it straddles a jump of the lens map, as on the CPU (MAX_ERROR_PX there, f64's).
const float VKL_RS_MAX_ERROR_PX = 1e-2;

// model::rolling_shutter::MAX_CONTRACTION: the bound on |d line_time / ds| below which g is
// strictly increasing with room to spare, and the scan is skipped.
const float VKL_RS_MAX_CONTRACTION = 0.5;
// Steps of the bounded solve before it gives up and scans (it converges in 2 to 4).
const uint VKL_RS_BOUNDED_STEPS = 8u;
// The bounded solve stops where its next step would move the pixel by less than this (px):
// a quarter of the refinement's tolerance, for the estimate of the step is the secant's, and
// a solve that stops a step early is as far off as that step.
const float VKL_RS_BOUNDED_STEP_TOLERANCE = 0.25 * VKL_RS_PIXEL_TOLERANCE;

// One frame's motion about its middle line (geometry_frame.glsl's VklMotionBlock): the middle
// line's world-to-camera rotation and camera centre, the unit axis and angle of the turn from
// the first line's camera frame to the last line's, and the centre's travel in the middle
// line's camera frame.
struct VklMotion {
    mat3 rotation;
    vec3 axis;
    float angle;
    vec3 centre;
    vec3 travel;
};

VklMotion vkl_motion(VklMotionBlock b) {
    return VklMotion(b.rotation, b.turn.xyz, b.turn.w, b.centre.xyz, b.travel.xyz);
}

VklMotion vkl_motion_current() {
    return vkl_motion(frame.motion);
}

// The motion of the frame flow starts from.
VklMotion vkl_motion_previous() {
    return vkl_motion(frame.previous_motion);
}

// The world point x in the middle line's camera frame, R_cw(½) (x − C(½)): the difference
// first, exact for points near the camera. Every sample of x's solve starts from it.
vec3 vkl_rs_middle(VklMotion m, vec3 x) {
    return m.rotation * (x - m.centre);
}

// v turned by phi about the motion's axis (Rodrigues' formula), given cos and sin of phi.
vec3 vkl_rs_turn(VklMotion m, float c, float sn, vec3 v) {
    return v * c + cross(m.axis, v) * sn + m.axis * (dot(m.axis, v) * (1.0 - c));
}

// The point `middle` (vkl_rs_middle) in the camera frame at readout time s, and its velocity
// d/ds there: with u = s − ½, R_cw(s) (x − C(s)) = exp(u ω)ᵀ (middle − u · travel), since the
// turn's axis is the same in every line's camera frame. The turn moves the point by
// −angle · axis × camera, the centre's travel by −exp(u ω)ᵀ travel.
vec3 vkl_rs_camera_at(VklMotion m, vec3 middle, float s, out vec3 velocity) {
    float u = s - 0.5;
    float phi = -u * m.angle;
    float c = cos(phi);
    float sn = sin(phi);
    vec3 camera = vkl_rs_turn(m, c, sn, middle - u * m.travel);
    velocity = -m.angle * cross(m.axis, camera) - vkl_rs_turn(m, c, sn, m.travel);
    return camera;
}

// The world point x in the camera frame at readout time s.
vec3 vkl_rs_camera_point(VklMotion m, vec3 x, float s) {
    vec3 unused;
    return vkl_rs_camera_at(m, vkl_rs_middle(m, x), s, unused);
}

// When the pixel is read (model::rolling_shutter::line_time): 0 the first line, 1 the last.
float vkl_line_time(vec2 pixel) {
    bool rows = VKL_READOUT <= 2u;
    float lines = rows ? frame.viewport.y : frame.viewport.x;
    float last = max(lines - 1.0, 0.0);
    if (last == 0.0) return 0.0;
    float t = (rows ? pixel.y : pixel.x) / last;
    return (VKL_READOUT == 1u || VKL_READOUT == 3u) ? t : 1.0 - t;
}

// d line_time / d pixel: line_time is affine in the pixel.
vec2 vkl_line_gradient() {
    bool rows = VKL_READOUT <= 2u;
    float last = max((rows ? frame.viewport.y : frame.viewport.x) - 1.0, 0.0);
    float rate = last == 0.0 ? 0.0 : ((VKL_READOUT == 1u || VKL_READOUT == 3u) ? 1.0 : -1.0) / last;
    return rows ? vec2(0.0, rate) : vec2(rate, 0.0);
}

// One evaluation of g: the point seen from the pose at s, with what Alg. 1 made of it.
struct VklRsSample {
    float s;
    float g;
    vec2 pixel;
    vec2 distorted_ndc; // these three: the root's (vkl_rs_finish), a ray model's every sample's
    vec2 ndc;           // alg1_ndc's undistorted NDC (Sec. 3.2's test)
    vec4 clip;          // the Sec. 3.1 clip position of `camera`
    vec3 camera;        // the camera-frame point at s
    bool ok;            // the lens sees it, and g is finite
};

// Whether samples carry g′: the standard model's Jacobian gives it; a ray model is not
// differentiated here (its solve takes a fixed-point step and secant steps).
#define VKL_RS_NEWTON (!(DISTORT && VKL_RAY_MODEL))

// Where the point moves at a sample, for Newton's steps: the camera-frame point's velocity
// (d/ds), the pixel's through the lens's Jacobian, and g′ = 1 − d line_time / ds (1 without
// VKL_RS_NEWTON).
struct VklRsVelocity {
    vec3 camera;
    vec2 pixel;
    float slope;
};

// A sample with its velocity. The standard model goes straight from the camera-frame point to
// its ideal point X/Z, Y/Z, which Alg. 1 reads back from the Sec. 3.1 clip position through
// the NDC and the pinhole pixel with four divisions more (and its rounding): the solve runs
// this twice per vertex, and lavapipe runs every instruction of it for every vertex. The clip
// position and the NDC are the root's alone (vkl_rs_finish); a ray model's come with its
// sample.
//
// `middle` is the point in the middle line's camera frame (vkl_rs_middle), `camera` and
// `velocity` the point and its velocity at s (vkl_rs_camera_at): the sample at s = ½ has them
// without a turn (vkl_rs_bounded's first step).
VklRsSample vkl_rs_sample_point(float s, vec3 camera, vec3 velocity, out VklRsVelocity v) {
    VklRsSample r;
    r.s = s;
    r.camera = camera;
    v.camera = velocity;
    r.clip = vec4(0.0);
    r.ndc = vec2(0.0);
    r.distorted_ndc = vec2(0.0);
    v.pixel = vec2(0.0);
    if (DISTORT && VKL_RAY_MODEL) {
        r.clip = frame.projection * vec4(r.camera, 1.0);
        mat2 J;
        r.ok = alg1_ndc_jacobian(r.clip, r.distorted_ndc, r.pixel, r.ndc, J);
    } else {
        float z = r.camera.z;
        vec2 ideal = r.camera.xy / z;
        mat2 J = mat2(1.0);
        r.pixel = vkl_to_pixel(ideal);
        r.ok = z > 0.0;
#ifndef VKL_PLAIN
        if (DISTORT) r.ok = r.ok && alg1_lens(ideal, r.pixel, J);
#endif
        // The ideal point's velocity by the quotient rule, the pixel's through J.
        v.pixel = vkl_cam.intrinsics.xy * (J * ((v.camera.xy - ideal * v.camera.z) / z));
    }
    r.g = s - vkl_line_time(r.pixel);
    r.ok = r.ok && !isnan(r.g) && !isinf(r.g) && !isnan(r.camera.z) && !isinf(r.camera.z);
    v.slope = VKL_RS_NEWTON ? 1.0 - dot(vkl_line_gradient(), v.pixel) : 1.0;
    return r;
}

// The root's clip position (Sec. 3.1), undistorted NDC (Sec. 3.2's test) and distorted NDC
// from its camera-frame point and pixel, as alg1_ndc_jacobian gives them: 0 at or behind the
// camera, the undistorted NDC where the lens does not see the point (finite, for the
// rasterizer's clipping alone). A ray model's sample has them already.
void vkl_rs_finish(inout VklRsSample r) {
    if (DISTORT && VKL_RAY_MODEL) return;
    r.clip = frame.projection * vec4(r.camera, 1.0);
    r.ndc = vec2(0.0);
    r.distorted_ndc = vec2(0.0);
    if (!(r.clip.w > 0.0)) return;
    r.ndc = r.clip.xy / r.clip.w;
    r.distorted_ndc = r.ok ? alg1_pixel_ndc(r.pixel) : r.ndc;
}

// The sample at s with its velocity.
VklRsSample vkl_rs_sample_velocity(VklMotion m, vec3 middle, float s, out VklRsVelocity v) {
    vec3 velocity;
    vec3 camera = vkl_rs_camera_at(m, middle, s, velocity);
    return vkl_rs_sample_point(s, camera, velocity, v);
}

// A sample alone (the velocity is dead code the driver drops).
VklRsSample vkl_rs_sample(VklMotion m, vec3 middle, float s) {
    VklRsVelocity unused;
    return vkl_rs_sample_velocity(m, middle, s, unused);
}

// The sample at s on the tangent at c (velocity v; the standard model's Alg. 1).
VklRsSample vkl_rs_tangent(VklRsSample c, VklRsVelocity v, float s) {
    float ds = s - c.s;
    VklRsSample r = c;
    r.s = s;
    r.g = c.g + ds * v.slope;
    r.pixel = c.pixel + ds * v.pixel;
    r.camera = c.camera + ds * v.camera;
    return r;
}

VklRsSample vkl_rs_closest(VklRsSample a, VklRsSample b) {
    return abs(a.g) <= abs(b.g) ? a : b;
}

// The root of g between a and b (g of opposite signs, a.s < b.s): Illinois false position with
// Dekker's guard against steps too small to count, a bisection step where the bracket shrank
// by less than half twice in a row (model::rolling_shutter::refine, step for step). False
// where the lens does not see the point inside the bracket, or the bracket closes on a jump.
bool vkl_rs_refine(VklMotion m, vec3 middle, VklRsSample a, VklRsSample b, out VklRsSample root) {
    float ga = a.g;
    float gb = b.g;
    int replaced = 0;  // -1: the last step replaced a; 1: b
    int slow_steps = 0;
    root = a;
    for (uint i = 0u; i < VKL_RS_MAX_REFINE_STEPS; i++) {
        float width = b.s - a.s;
        vec2 d = abs(b.pixel - a.pixel);
        float gap = max(d.x, d.y);
        if (gap <= VKL_RS_PIXEL_TOLERANCE) {
            root = vkl_rs_closest(a, b);
            return true;
        }
        float s;
        if (slow_steps >= 2) {
            slow_steps = 0;
            s = 0.5 * (a.s + b.s);
        } else {
            s = (a.s * gb - b.s * ga) / (gb - ga);
        }
        float step = 0.5 * VKL_RS_PIXEL_TOLERANCE * width / gap;
        s = (!isnan(s) && !isinf(s) && step < 0.5 * width) ? clamp(s, a.s + step, b.s - step)
                                                             : 0.5 * (a.s + b.s);
        if (!(s > a.s && s < b.s)) break;  // as narrow as f32 makes it
        VklRsSample c = vkl_rs_sample(m, middle, s);
        if (!c.ok) return false;
        if (c.g == 0.0) {
            root = c;
            return true;
        }
        if ((c.g < 0.0) == (a.g < 0.0)) {
            a = c;
            ga = c.g;
            if (replaced == -1) gb *= 0.5;
            replaced = -1;
        } else {
            b = c;
            gb = c.g;
            if (replaced == 1) ga *= 0.5;
            replaced = 1;
        }
        slow_steps = (b.s - a.s > 0.5 * width) ? slow_steps + 1 : 0;
    }
    vec2 d = abs(b.pixel - a.pixel);
    root = vkl_rs_closest(a, b);
    return max(d.x, d.y) <= VKL_RS_MAX_ERROR_PX;
}

// The distance from a point to the segment the camera centre moves along, both in the middle
// line's camera frame (`middle`: vkl_rs_middle), where the centre runs from −travel / 2 to
// travel / 2.
float vkl_rs_path_distance(VklMotion m, vec3 middle) {
    vec3 d = m.travel;
    float dd = dot(d, d);
    float t = dd > 0.0 ? clamp(dot(middle, d) / dd, -0.5, 0.5) : 0.0;
    return length(middle - t * d);
}

// model::rolling_shutter::RATE_TABLE: entries of frame_block.readout_rates.
const uint VKL_RS_RATE_TABLE = 32u;

// The lens's line rate over the rays at most theta off the axis (LineRate::within); negative
// past the cone.
float vkl_rs_line_rate(float theta) {
    float cone = frame.readout_bound.x;
    float i = ceil(max(theta, 0.0) / cone * float(VKL_RS_RATE_TABLE - 1u));
    // NaN fails the comparison too.
    if (!(i < float(VKL_RS_RATE_TABLE))) return -1.0;
    uint k = min(uint(i), VKL_RS_RATE_TABLE - 1u);
    return frame_block.readout_rates[k / 4u][k % 4u];
}

// The solve where the frame's motion bounds how fast x's own line time moves
// (model::rolling_shutter::FrameMotion::line_rate_bound): the ray to x turns at most
// `speed` = angle + |C1 − C0| / d(x, C0C1) radians per unit of readout time, so during the frame
// it stays within speed / 2 of its ray at mid-frame, θ off the axis; the lens moves a ray's
// line by at most vkl_rs_line_rate(θ + speed / 2) readout time per radian there, and
// T(s) = line_time(π(x at pose s)) has |T′| ≤ L = speed · that rate. With L ≤ ½,
// g(s) = s − T(s) has g′ ∈ [1 − L, 1 + L]: strictly increasing, one root at most, and the
// first root in readout order the scan looks for is the only one. Then Newton's steps from
// mid-frame (g′ from the lens's Jacobian, which the standard model computes with the point;
// a ray model takes a fixed-point step and secant steps), their slopes clamped to
// [1 − L, 1 + L] so that each step lands where the derivative bounds say the root can be, find
// it in two evaluations on the bench's pan, the root read off the second one's tangent, instead
// of the scan's 17 and the refinement's. A fixed-point first step and secant steps took three.
//
// False, for the scan to decide as before, on anything the bound does not cover: no rate, a
// sample the lens does not see, a ray that could leave the cone, a point nearer the centres'
// path than the near plane, no convergence in VKL_RS_BOUNDED_STEPS. A point no line reads (g
// of one sign over [0, 1], known from g at the end of the readout it lies beyond) keeps the
// position of that end, as the scan gives it. `middle` is x in the middle line's camera frame
// (vkl_rs_middle), the first sample's point.
bool vkl_rs_bounded(VklMotion m, vec3 middle, out VklRsSample root) {
    float distance = vkl_rs_path_distance(m, middle);
    float speed = m.angle + length(m.travel) / distance;
    VklRsVelocity va;
    VklRsSample a;
    float low = 0.0;
    float high = 0.0;
    float slope;
    float s = 0.5;
    // Step 0 is the sample at s = ½, the middle line's point itself, moving by
    // −angle · axis × middle − travel; it shares the later steps' one call of the lens (a
    // driver compiles a copy of the lens model per call site: two sites cost lavapipe half
    // a second more per pipeline).
    for (uint i = 0u; i <= VKL_RS_BOUNDED_STEPS; i++) {
        vec3 velocity;
        vec3 camera;
        if (i == 0u) {
            camera = middle;
            velocity = -m.angle * cross(m.axis, middle) - m.travel;
        } else {
            camera = vkl_rs_camera_at(m, middle, s, velocity);
        }
        VklRsVelocity vc;
        VklRsSample c = vkl_rs_sample_point(s, camera, velocity, vc);
        if (i == 0u) {
            a = c;
            va = vc;
            root = a;
            if (!(VKL_RUNTIME(frame.readout_bound.x > 0.0) && distance >= frame.viewport.w && a.ok)) {
                return false;
            }
            float theta = acos(clamp(a.camera.z / length(a.camera), -1.0, 1.0));
            float bound = speed * vkl_rs_line_rate(theta + 0.5 * speed);
            if (!(bound >= 0.0 && bound <= VKL_RS_MAX_CONTRACTION)) return false;
            low = 1.0 - bound;
            high = 1.0 + bound;
            // Newton's steps where the lens's Jacobian gives g′, else a fixed-point step
            // (|s1 − s*| ≤ L |s0 − s*|) and secant steps; every slope clamped to what the
            // bound allows.
            slope = isnan(va.slope) ? 1.0 : clamp(va.slope, low, high);
            s = clamp(a.s - a.g / slope, 0.0, 1.0);
            continue;
        }
        if (!c.ok) return false;
        root = c;
        // g increases: g(0) > 0 or g(1) < 0 puts every root outside the readout.
        if (c.g == 0.0 || (c.s == 0.0 && c.g > 0.0) || (c.s == 1.0 && c.g < 0.0)) return true;
        float span = abs(c.s - a.s);
        slope = VKL_RS_NEWTON ? vc.slope : (c.g - a.g) / (c.s - a.s);
        slope = isnan(slope) ? 1.0 : clamp(slope, low, high);
        float next = clamp(c.s - c.g / slope, 0.0, 1.0);
        // Where the next step would move the pixel by less than the tolerance (at the pixel
        // speed of the last step), c is the root to f32's precision: the steps converge
        // superlinearly, so what the next would move the pixel bounds c's error.
        vec2 pixel_speed = abs(c.pixel - a.pixel) / span;
        float step = abs(next - c.s);
        if (next == c.s || max(pixel_speed.x, pixel_speed.y) * step
                               <= VKL_RS_BOUNDED_STEP_TOLERANCE) {
            return true;
        }
        // With velocities, the sample at `next` is read off c's tangent where Taylor's
        // remainders leave it within the tolerance: the tangent strays from the pixel's path by
        // ½ |p″| step², and Newton's step misses the root by |g″| / (2 g′) step², each second
        // derivative taken from how the first changed between a and c.
        if (VKL_RS_NEWTON) {
            vec2 curvature = abs(vc.pixel - va.pixel) / span;
            float miss = abs(vc.slope - va.slope) / span / (2.0 * slope);
            vec2 off = (0.5 * curvature + abs(vc.pixel) * miss) * step * step;
            if (max(off.x, off.y) <= VKL_RS_BOUNDED_STEP_TOLERANCE) {
                root = vkl_rs_tangent(c, vc, next);
                return true;
            }
        }
        a = c;
        va = vc;
        s = next;
    }
    return false;
}

// Where the world point appears through motion m (`middle`: the point in the middle line's
// camera frame, vkl_rs_middle): the first self-consistent readout time in
// readout order (`ok` false where the lens does not see it; then `clip` is a finite clip
// position of the point at some readout time, for the rasterizer's clipping alone). Points no
// line reads keep their position at the nearer end of the readout.
//
// The scan stops at the first sign change and the refinement runs outside it: the lanes of one
// SIMD batch find their brackets in different cells, and a refinement inside the scan would run
// once per cell that any lane brackets, the others idle; here they refine together. A bracket
// that closes on a jump of the lens map rather than a root resumes the scan after it, as on the
// CPU.
#ifdef VKL_RS_BOUNDED_ONLY
// A module for a pass that hands what the bound does not cover to a later dispatch
// (glsl/discard.comp's stage 3): the bounded solve alone, false where it does not decide.
bool vkl_rs_solve(VklMotion m, vec3 middle, out VklRsSample r) {
    return vkl_rs_bounded(m, middle, r);
}
#else
VklRsSample vkl_rs_project(VklMotion m, vec3 middle) {
    VklRsSample bounded;
    if (vkl_rs_bounded(m, middle, bounded)) return bounded;
    VklRsSample previous;
    VklRsSample first;
    VklRsSample last;
    bool has_previous = false;
    bool seen_everywhere = true;
    bool crossed = false;
    uint k = 0u;
    for (uint attempt = 0u; attempt <= VKL_RS_SCAN_CELLS; attempt++) {
        bool found = false;
        VklRsSample a;
        VklRsSample b;
        for (; k <= VKL_RS_SCAN_CELLS && !found; k++) {
            VklRsSample c = vkl_rs_sample(m, middle, float(k) / float(VKL_RS_SCAN_CELLS));
            if (c.ok) {
                if (c.g == 0.0) return c;
                if (has_previous && ((previous.g < 0.0) != (c.g < 0.0))) {
                    crossed = true;
                    found = true;
                    a = previous;
                    b = c;
                }
            } else {
                seen_everywhere = false;
            }
            if (k == 0u) first = c;
            last = c;
            previous = c;
            has_previous = c.ok;
        }
        if (!found) break;
        VklRsSample root;
        if (vkl_rs_refine(m, middle, a, b, root)) return root;
    }
    VklRsSample end = first.g > 0.0 ? first : last;
    end.ok = !crossed && seen_everywhere;
    return end;
}

bool vkl_rs_solve(VklMotion m, vec3 middle, out VklRsSample r) {
    r = vkl_rs_project(m, middle);
    return true;
}
#endif

// A frame whose camera does not move during the readout: Alg. 1 from its one pose, with the
// global shutter's very arithmetic, so that a still frame renders bit for bit as it does
// without a readout.
VklRsSample vkl_rs_still(vec3 x, mat4 view_projection, mat4 view) {
    VklRsSample r;
    vec4 world = vec4(x, 1.0);
    r.s = 0.0;
    r.g = 0.0;
    r.clip = view_projection * world;
    r.ok = alg1_ndc(r.clip, r.distorted_ndc, r.pixel, r.ndc);
    r.camera = (view * world).xyz;
    return r;
}

// Whether this frame's camera moves during the readout (motion.centre.w: 1 or 0).
bool vkl_rs_moving() {
    return VKL_RUNTIME(frame.motion.centre.w != 0.0);
}

// Where the lines of this frame (previous: of the frame flow starts from) see the world point
// x; false where a VKL_RS_BOUNDED_ONLY module leaves it to a later pass. One function for both
// frames, so that a shader that needs both calls the solve from one site: a driver inlines
// every call site's copy before specialization prunes any.
bool vkl_rs_at(bool previous, vec3 x, out VklRsSample r) {
    bool moving = previous ? VKL_RUNTIME(frame.previous_motion.centre.w != 0.0) : vkl_rs_moving();
    if (moving) {
        VklMotion m = previous ? vkl_motion_previous() : vkl_motion_current();
        bool solved = vkl_rs_solve(m, vkl_rs_middle(m, x), r);
        vkl_rs_finish(r);
        return solved;
    }
    r = vkl_rs_still(x, previous ? frame.previous_view_projection : frame.view_projection,
                     previous ? frame.previous_view : frame.view);
    return true;
}

// This frame's solve into r and, with flow, the previous frame's into q, both from vkl_rs_at's
// one call site; false where either is left to a later pass.
bool vkl_rs_frames(vec3 x, out VklRsSample r, out VklRsSample q) {
    bool solved = true;
    for (uint k = 0u; k < (WRITE_FLOW ? 2u : 1u); k++) {
        VklRsSample p;
        solved = vkl_rs_at(k == 1u, x, p) && solved;
        if (k == 0u) r = p; else q = p;
    }
    return solved;
}

#endif
