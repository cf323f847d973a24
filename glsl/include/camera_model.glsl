// camera_model.glsl — the OpenCV standard camera model in f32, mirroring src/model/opencv.rs
// function for function (forward, Jacobian, tilt, valid domain, Newton / Heikkilä /
// fixed-point inverses), and OpenCV's fisheye model, mirroring src/model/fisheye.rs.
// Tested against the f64 models on the shared reference points.
//
// The fisheye runs through the same stages: its radial map θ_d(atan r)/r is the "pre-tilt"
// distortion and its skew α takes the tilt's place (both are exact linear maps after the
// radial one), so every shader that works in pre-tilt space works for it unchanged.
//
// Pixel-centre convention: OpenCV's, pixel (0, 0) has its centre at (0, 0), so an image of
// width w covers x in [-0.5, w - 0.5]; a pinhole maps (X, Y, Z) to u = fx·X/Z + cx,
// v = fy·Y/Z + cy.
//
// Terms whose coefficients are all zero compile out: the host sets the specialization
// constants VKL_RADIAL .. VKL_TILT from the camera (model::Terms), so a k1 k2 camera runs no
// rational, prism or tilt code at all. Constant ids 0-7 belong to this file; shaders use 8+.
//
// Before including, a shader may define VKL_CAMERA_SET / VKL_CAMERA_BINDING (default 0, 0).
// The block layout is `pass::CameraParams` (f32) / `pass::CameraParams64` (f64) on the host,
// layout-tested against this SPIR-V.

#ifndef VKL_CAMERA_MODEL_GLSL
#define VKL_CAMERA_MODEL_GLSL

#ifndef VKL_CAMERA_SET
#define VKL_CAMERA_SET 0
#endif
#ifndef VKL_CAMERA_BINDING
#define VKL_CAMERA_BINDING 0
#endif

// model::ValidDomain::SAMPLES
#define VKL_DOMAIN_SAMPLES 256
#define VKL_TAU 6.283185307179586
// Precision: f32 by default; a shader compiled with VKL_F64 defined gets the same model in
// f64 (GLSL double; needs the shaderFloat64 device feature) and the `CameraParams64` block.
// f32 is what the warp uses; near a fold the problem is ill-conditioned (σ_min(J) → 0) and
// f32 rounding of the residual is amplified by 1/σ_min, which f64 avoids.
#ifdef VKL_F64
#define VKL_FLOAT double
#define VKL_VEC2 dvec2
#define VKL_VEC3 dvec3
#define VKL_VEC4 dvec4
#define VKL_MAT2 dmat2
#define VKL_PARAMS_BLOCK CameraParams64
// Machine epsilon: Newton stops when the residual reaches rounding level.
#define VKL_EPSILON 2.220446049250313e-16LF
// Newton accepts a solution whose residual is within this (normalized units, relative).
#define VKL_NEWTON_ACCEPT 1e-12LF
#else
#define VKL_FLOAT float
#define VKL_VEC2 vec2
#define VKL_VEC3 vec3
#define VKL_VEC4 vec4
#define VKL_MAT2 mat2
#define VKL_PARAMS_BLOCK CameraParams
#define VKL_EPSILON 1.1920929e-7
#define VKL_NEWTON_ACCEPT 2e-6
#endif
// model::opencv::NEWTON_MAX_HALVINGS: near a fold the first steps overshoot the domain.
#define VKL_NEWTON_MAX_HALVINGS 40
// model::opencv::CONTINUATION_STEPS: Newton's fallback from the principal point.
#define VKL_CONTINUATION_STEPS 8

layout(constant_id = 0) const bool VKL_RADIAL = true;      // k1 k2 k3
layout(constant_id = 1) const bool VKL_RATIONAL = true;    // k4 k5 k6
layout(constant_id = 2) const bool VKL_TANGENTIAL = true;  // p1 p2
layout(constant_id = 3) const bool VKL_PRISM = true;       // s1 s2 s3 s4
layout(constant_id = 4) const bool VKL_TILT = true;        // tau_x tau_y
layout(constant_id = 5) const uint VKL_NEWTON_ITERATIONS = 20;
// Which camera model the shader is specialized for (pass::spec::MODEL). 0: OpenCV's standard
// model (a Brown lens runs as its standard twin). A shader specialized for a model this file
// does not implement answers "invalid" everywhere rather than evaluate the wrong model.
// 1: OpenCV's fisheye model (model::Fisheye); VKL_RADIAL then says whether any k is non-zero.
// The others: the rest of the model list (src/model/list.rs, model::ModelKind), one include
// each under include/models/. Each maps camera-frame rays, and the pinhole-side maps a warp
// needs follow from its forward map and inverse (vkl_distort_jacobian, vkl_undistort_newton).
// build.rs writes the ids, the includes and the dispatch from that list.
#include "model_ids.glsl"
layout(constant_id = 6) const uint VKL_MODEL = VKL_MODEL_OPENCV;
// false: every ideal point this shader tests either lies inside the domain's smallest boundary
// radius or is dropped whatever the answer (the compute discard, when its Sec. 3.2 bound lies
// inside that radius), so the inner radius alone decides and the table lookup is compiled out.
// lavapipe runs both sides of every branch for every vertex, so the lookup otherwise costs as
// much as half of the standard model.
layout(constant_id = 7) const bool VKL_DOMAIN_TABLE = true;
#define VKL_FISHEYE (VKL_MODEL == VKL_MODEL_FISHEYE)
// The models after the fisheye: rays in, rays out, through include/models/.
#define VKL_GENERIC (VKL_MODEL >= VKL_MODEL_OMNI)
// Every model but the standard one maps camera-frame rays (and may see past 90°).
#define VKL_RAY_MODEL (VKL_MODEL != VKL_MODEL_OPENCV)
// model::ValidDomain::RADIUS_CAP: the pinhole side of a ray model ends here (89.94°).
#define VKL_RADIUS_CAP 1000.0
// Below this radius (normalized) θ_d(atan r)/r is its series 1 + (k1 − 1/3) r²: the quotient
// would lose digits, and the error of the series, O(r⁴), is far below rounding there.
#define VKL_FISHEYE_SMALL 1e-4

// The camera's scalar members, read once at the top of main() into `vkl_cam` (a private copy)
// by vkl_load_camera(), as geometry_frame.glsl's frame: lavapipe (Mesa 22 and 23) reads a
// block member with one scalar load only outside control flow and gathers it lane by lane,
// with a bounds check per lane, inside any branch or loop. The model's parameters and the
// domain table, which some models index per invocation, stay in the block.
struct VklCamera {
    VKL_VEC4 intrinsics;        // fx fy cx cy
    VKL_VEC4 radial;            // k1 k2 k3 -          fisheye: k1 k2 k3 k4
    VKL_VEC4 rational;          // k4 k5 k6 -          fisheye: α, θ_max, θ_d(θ_max), -
    VKL_VEC4 tangential_prism;  // p1 p2 s1 s2
    VKL_VEC4 prism;             // s3 s4 - -
    VKL_VEC4 tilt[3];           // rows of OpenCV's tilt matrix (xyz)
    VKL_VEC4 untilt[3];         // rows of its inverse
    VKL_VEC4 domain_info;       // x: smallest ideal boundary radius, y: smallest distorted one,
                                // z: cos of Alg. 1's vertex limit for a ray model (-2: none)
};

layout(set = VKL_CAMERA_SET, binding = VKL_CAMERA_BINDING, std140) uniform VKL_PARAMS_BLOCK {
    VklCamera values;
    VKL_VEC4 model[16];         // the ray model's own parameters (model::table::RayModel::gpu_params)
    VKL_VEC4 domain[VKL_DOMAIN_SAMPLES]; // x: ideal boundary radius, y: distorted, at angle TAU*i/N
} vkl_cam_block;

VklCamera vkl_cam;

// Every includer's main() calls this first, outside any branch.
void vkl_load_camera() { vkl_cam = vkl_cam_block.values; }

VKL_VEC2 vkl_to_pixel(VKL_VEC2 x) { return x * vkl_cam.intrinsics.xy + vkl_cam.intrinsics.zw; }
VKL_VEC2 vkl_to_normalized(VKL_VEC2 p) { return (p - vkl_cam.intrinsics.zw) / vkl_cam.intrinsics.xy; }

// Radial numerator and denominator of R(s), s = r², and their derivatives in s.
void vkl_radial(VKL_FLOAT s, out VKL_FLOAT num, out VKL_FLOAT den, out VKL_FLOAT dnum, out VKL_FLOAT dden) {
    num = 1.0; dnum = 0.0; den = 1.0; dden = 0.0;
    if (VKL_RADIAL) {
        VKL_VEC3 k = vkl_cam.radial.xyz;
        num = 1.0 + s * (k.x + s * (k.y + s * k.z));
        dnum = k.x + s * (2.0 * k.y + 3.0 * s * k.z);
    }
    if (VKL_RATIONAL) {
        VKL_VEC3 k = vkl_cam.rational.xyz;
        den = 1.0 + s * (k.x + s * (k.y + s * k.z));
        dden = k.x + s * (2.0 * k.y + 3.0 * s * k.z);
    }
}

// The fisheye's trigonometry. GLSL has none in double: in f64 the functions are series after
// argument reduction, accurate to f64 rounding on the ranges the model uses.
#ifdef VKL_F64
#define VKL_HALF_PI 1.5707963267948966LF
// atan for x ≥ 0: x > 1 folds to π/2 − atan(1/x); above tan(π/12), atan(x) = π/6 +
// atan((√3 x − 1)/(x + √3)); the series then converges as 0.27^(2n).
double vkl_atan(double x) {
    bool inv = x > 1.0;
    if (inv) x = 1.0 / x;
    bool shift = x > 0.2679491924311227LF;
    if (shift) x = (x * 1.7320508075688772LF - 1.0) / (x + 1.7320508075688772LF);
    double x2 = x * x, term = x, sum = x;
    for (int n = 1; n < 16; ++n) {
        term *= -x2;
        sum += term / double(2 * n + 1);
    }
    if (shift) sum += 0.5235987755982989LF;
    return inv ? VKL_HALF_PI - sum : sum;
}
// atan2(y, x) for y ≥ 0 (an angle off the axis, 0..π).
double vkl_atan2(double y, double x) {
    if (x > 0.0) return vkl_atan(y / x);
    if (x < 0.0) return 2.0 * VKL_HALF_PI - vkl_atan(y / -x);
    return y > 0.0 ? VKL_HALF_PI : 0.0;
}
// sin and cos of θ in [0, π], from the series at θ − π/2 (|s| ≤ π/2: 12 terms reach 1e-20).
void vkl_sin_cos(double theta, out double sn, out double cs) {
    double s = theta - VKL_HALF_PI, s2 = s * s;
    double ts = s, tc = 1.0, ss = s, sc = 1.0;
    for (int n = 1; n < 13; ++n) {
        ts *= -s2 / double((2 * n) * (2 * n + 1));
        tc *= -s2 / double((2 * n - 1) * (2 * n));
        ss += ts;
        sc += tc;
    }
    sn = sc;
    cs = -ss;
}
#else
// atan in f32 by the same reduction and series as the f64 one: GLSL leaves atan's precision
// to the driver, and lavapipe's is ~1e-6 rad, which an f-theta lens of 1900 px/rad turns
// into 3e-3 px (measured); this one is within a few ulp.
float vkl_atan(float x) {
    bool inv = x > 1.0;
    if (inv) x = 1.0 / x;
    bool shift = x > 0.26794919;
    if (shift) x = (x * 1.7320508 - 1.0) / (x + 1.7320508);
    float x2 = x * x, term = x, sum = x;
    for (int n = 1; n < 7; ++n) {
        term *= -x2;
        sum += term / float(2 * n + 1);
    }
    if (shift) sum += 0.52359878;
    return inv ? 1.5707964 - sum : sum;
}
// atan2(y, x) for y ≥ 0 (an angle off the axis, 0..π).
float vkl_atan2(float y, float x) {
    if (x > 0.0) return vkl_atan(y / x);
    if (x < 0.0) return 3.1415927 - vkl_atan(y / -x);
    return y > 0.0 ? 1.5707964 : 0.0;
}
void vkl_sin_cos(float theta, out float sn, out float cs) { sn = sin(theta); cs = cos(theta); }
#endif

// The fisheye's θ_d(θ) = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸) and its derivative.
void vkl_fisheye_theta_d(VKL_FLOAT t, out VKL_FLOAT td, out VKL_FLOAT dtd) {
    VKL_VEC4 k = VKL_RADIAL ? vkl_cam.radial : VKL_VEC4(0.0);
    VKL_FLOAT t2 = t * t;
    td = t * (1.0 + t2 * (k.x + t2 * (k.y + t2 * (k.z + t2 * k.w))));
    dtd = 1.0 + t2 * (3.0 * k.x + t2 * (5.0 * k.y + t2 * (7.0 * k.z + t2 * 9.0 * k.w)));
}

// The fisheye's radial map on pinhole-normalized coordinates (Z > 0): x ↦ g(r) x with
// g = θ_d(atan r) / r, and its Jacobian g I + (g'(r)/r) x xᵀ (model::Fisheye::distort_normalized).
void vkl_fisheye_pre_skew(VKL_VEC2 p, out VKL_VEC2 d, out VKL_MAT2 J) {
    // |p| by its larger component first: length() of a huge point overflows to ∞ in f32.
    VKL_FLOAT m = max(abs(p.x), abs(p.y));
    VKL_FLOAT rho = m > 0.0 ? m * length(p / m) : 0.0;
    VKL_FLOAT g, dg_over_rho;
    if (rho < VKL_FISHEYE_SMALL) {
        VKL_FLOAT c = (VKL_RADIAL ? vkl_cam.radial.x : 0.0) - 1.0 / 3.0;
        g = 1.0 + c * rho * rho;
        dg_over_rho = 2.0 * c;
    } else {
        VKL_FLOAT td, dtd;
        vkl_fisheye_theta_d(vkl_atan(rho), td, dtd);
        g = td / rho;
        dg_over_rho = (dtd / (1.0 + rho * rho) - g) / (rho * rho);
    }
    d = p * g;
    J = VKL_MAT2(g) + VKL_MAT2(p * p.x, p * p.y) * dg_over_rho;
}

// The fisheye's inverse on θ: the angle off the axis whose θ_d is rho, by safeguarded Newton
// on [0, θ_max] where θ_d increases. False past θ_d(θ_max) (outside the domain).
bool vkl_fisheye_theta(VKL_FLOAT rho, out VKL_FLOAT theta) {
    VKL_FLOAT lo = 0.0;
    VKL_FLOAT hi = vkl_cam.rational.y;
    theta = 0.0;
    if (!(rho <= vkl_cam.rational.z)) return false;
    theta = min(rho, hi);
    for (int i = 0; i < 60; ++i) {
        VKL_FLOAT td, dtd;
        vkl_fisheye_theta_d(theta, td, dtd);
        VKL_FLOAT v = td - rho;
        if (v == 0.0) break;
        if (v < 0.0) lo = theta; else hi = theta;
        VKL_FLOAT next = theta - v / dtd;
        if (next == theta) break;
        theta = (dtd > 0.0 && next > lo && next < hi) ? next : 0.5 * (lo + hi);
        if (hi - lo < 2.0 * VKL_EPSILON * hi) break;
    }
    // As model::Fisheye::undistort_ray: the answer must reproduce rho.
    VKL_FLOAT td, dtd;
    vkl_fisheye_theta_d(theta, td, dtd);
    return abs(td - rho) <= 4.0 * VKL_NEWTON_ACCEPT * (1.0 + rho);
}

// Inverse of the fisheye to a unit camera-frame ray, past 90° too: distorted normalized
// (skew included) -> direction (model::Fisheye::undistort_ray). False outside the domain.
bool vkl_fisheye_unproject(VKL_VEC2 d, out VKL_VEC3 ray) {
    VKL_VEC2 pre = VKL_VEC2(d.x - vkl_cam.rational.x * d.y, d.y);
    VKL_FLOAT rho = length(pre);
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    if (rho == 0.0) return true;
    VKL_FLOAT theta;
    if (!vkl_fisheye_theta(rho, theta)) return false;
    VKL_FLOAT sn, cs;
    vkl_sin_cos(theta, sn, cs);
    ray = VKL_VEC3(pre / rho * sn, cs);
    return true;
}

// The fisheye's forward map on a camera-frame direction of any hemisphere: the distorted
// normalized point, skew included. False outside the domain (θ > θ_max) and for the zero vector.
bool vkl_fisheye_project(VKL_VEC3 p, out VKL_VEC2 d) {
    VKL_FLOAT r = length(p.xy);
    d = VKL_VEC2(0.0);
    if (r == 0.0) return p.z > 0.0;
    VKL_FLOAT theta = vkl_atan2(r, p.z);
    if (theta > vkl_cam.rational.y) return false;
    VKL_FLOAT td, dtd;
    vkl_fisheye_theta_d(theta, td, dtd);
    VKL_VEC2 pre = p.xy * (td / r);
    d = VKL_VEC2(pre.x + vkl_cam.rational.x * pre.y, pre.y);
    return true;
}

// Pre-tilt distortion (x', y') of an ideal normalized point, and its Jacobian J (column-major:
// J[0] = d/dx). False where the rational denominator is zero. The fisheye's is its radial map.
bool vkl_distort_pre_tilt(VKL_VEC2 p, out VKL_VEC2 d, out VKL_MAT2 J) {
    d = p;
    J = VKL_MAT2(1.0);
    if (VKL_FISHEYE) {
        vkl_fisheye_pre_skew(p, d, J);
        return true;
    }
    VKL_FLOAT s = dot(p, p);
    VKL_FLOAT num, den, dnum, dden;
    vkl_radial(s, num, den, dnum, dden);
    if (den == 0.0) return false;
    VKL_FLOAT r = num / den;
    VKL_FLOAT dr = (dnum * den - num * dden) / (den * den);
    d = p * r;
    VKL_FLOAT j00 = r + 2.0 * p.x * p.x * dr;
    VKL_FLOAT j01 = 2.0 * p.x * p.y * dr;
    VKL_FLOAT j10 = j01;
    VKL_FLOAT j11 = r + 2.0 * p.y * p.y * dr;
    if (VKL_TANGENTIAL) {
        VKL_FLOAT p1 = vkl_cam.tangential_prism.x;
        VKL_FLOAT p2 = vkl_cam.tangential_prism.y;
        d += VKL_VEC2(2.0 * p1 * p.x * p.y + p2 * (s + 2.0 * p.x * p.x),
                  p1 * (s + 2.0 * p.y * p.y) + 2.0 * p2 * p.x * p.y);
        j00 += 2.0 * p1 * p.y + 6.0 * p2 * p.x;
        j01 += 2.0 * p1 * p.x + 2.0 * p2 * p.y;
        j10 += 2.0 * p1 * p.x + 2.0 * p2 * p.y;
        j11 += 6.0 * p1 * p.y + 2.0 * p2 * p.x;
    }
    if (VKL_PRISM) {
        VKL_VEC2 s12 = vkl_cam.tangential_prism.zw;
        VKL_VEC2 s34 = vkl_cam.prism.xy;
        d += VKL_VEC2(s12.x * s + s12.y * s * s, s34.x * s + s34.y * s * s);
        VKL_FLOAT prism_x = s12.x + 2.0 * s12.y * s;
        VKL_FLOAT prism_y = s34.x + 2.0 * s34.y * s;
        j00 += 2.0 * p.x * prism_x;
        j01 += 2.0 * p.y * prism_x;
        j10 += 2.0 * p.x * prism_y;
        j11 += 2.0 * p.y * prism_y;
    }
    J = VKL_MAT2(j00, j10, j01, j11);
    return true;
}

// OpenCV's tilt homography applied to a pre-tilt point, with its Jacobian T.
bool vkl_apply_tilt(VKL_VEC2 p, out VKL_VEC2 d, out VKL_MAT2 T) {
    d = p;
    T = VKL_MAT2(1.0);
    if (VKL_FISHEYE) {
        // The fisheye's skew: (x' + α y', y').
        VKL_FLOAT alpha = vkl_cam.rational.x;
        d = VKL_VEC2(p.x + alpha * p.y, p.y);
        T = VKL_MAT2(1.0, 0.0, alpha, 1.0);
        return true;
    }
    if (!VKL_TILT) return true;
    VKL_VEC3 q = VKL_VEC3(p, 1.0);
    VKL_VEC3 h = VKL_VEC3(dot(vkl_cam.tilt[0].xyz, q), dot(vkl_cam.tilt[1].xyz, q), dot(vkl_cam.tilt[2].xyz, q));
    if (h.z == 0.0) return false;
    d = h.xy / h.z;
    VKL_VEC3 m0 = vkl_cam.tilt[0].xyz;
    VKL_VEC3 m1 = vkl_cam.tilt[1].xyz;
    VKL_VEC3 m2 = vkl_cam.tilt[2].xyz;
    T = VKL_MAT2(VKL_VEC2(m0.x - d.x * m2.x, m1.x - d.y * m2.x) / h.z,
             VKL_VEC2(m0.y - d.x * m2.y, m1.y - d.y * m2.y) / h.z);
    return true;
}

// Removes the tilt exactly: distorted normalized (x'', y'') -> pre-tilt (x', y').
bool vkl_remove_tilt(VKL_VEC2 d, out VKL_VEC2 p) {
    p = d;
    if (VKL_FISHEYE) {
        p = VKL_VEC2(d.x - vkl_cam.rational.x * d.y, d.y);
        return true;
    }
    if (!VKL_TILT) return true;
    VKL_VEC3 q = VKL_VEC3(d, 1.0);
    VKL_VEC3 h = VKL_VEC3(dot(vkl_cam.untilt[0].xyz, q), dot(vkl_cam.untilt[1].xyz, q), dot(vkl_cam.untilt[2].xyz, q));
    if (!(h.z > 0.0)) return false;
    p = h.xy / h.z;
    return true;
}

// The standard model's and the fisheye's forward map on normalized coordinates with its
// Jacobian: ideal (X/Z, Y/Z) -> distorted.
bool vkl_standard_distort(VKL_VEC2 x, out VKL_VEC2 d, out VKL_MAT2 J) {
    VKL_VEC2 pre;
    VKL_MAT2 Jpre;
    VKL_MAT2 T;
    d = x;
    J = VKL_MAT2(1.0);
    if (!vkl_distort_pre_tilt(x, pre, Jpre)) return false;
    if (!vkl_apply_tilt(pre, d, T)) return false;
    J = T * Jpre;
    return true;
}


// Boundary radius of the valid domain at `angle`: component 0 ideal, 1 distorted.
VKL_FLOAT vkl_domain_radius(float angle, int which) {
    float t = fract(angle / VKL_TAU) * float(VKL_DOMAIN_SAMPLES);
    int i = min(int(floor(t)), VKL_DOMAIN_SAMPLES - 1);
    VKL_FLOAT f = VKL_FLOAT(t - float(i));
    VKL_FLOAT a = vkl_cam_block.domain[i][which];
    VKL_FLOAT b = vkl_cam_block.domain[(i + 1) % VKL_DOMAIN_SAMPLES][which];
    return mix(a, b, f);
}

// Whether an ideal (pre-tilt normalized) point is in the domain table's valid domain. Inside
// the smallest boundary radius no table lookup is needed (the common case).
bool vkl_table_contains_ideal(VKL_VEC2 x) {
    VKL_FLOAT r2 = dot(x, x);
    if (r2 <= vkl_cam.domain_info.x * vkl_cam.domain_info.x) return true;
    if (!VKL_DOMAIN_TABLE) return false;
    return sqrt(r2) <= vkl_domain_radius(atan(float(x.y), float(x.x)), 0);
}

// Whether a distorted (pre-tilt) point has its preimage in the valid domain.
bool vkl_contains_distorted(VKL_VEC2 d) {
    VKL_FLOAT r2 = dot(d, d);
    if (r2 <= vkl_cam.domain_info.y * vkl_cam.domain_info.y) return true;
    return sqrt(r2) <= vkl_domain_radius(atan(float(d.y), float(d.x)), 1);
}

// Start for Newton: the exact inverse of the radial part along the target's direction, by
// safeguarded Newton / bisection on [0, boundary radius].
VKL_VEC2 vkl_radial_start(VKL_VEC2 t) {
    VKL_FLOAT rho = length(t);
    VKL_VEC2 dir = t / rho;
    VKL_FLOAT hi = vkl_domain_radius(atan(float(dir.y), float(dir.x)), 0);
    VKL_FLOAT lo = 0.0;
    VKL_FLOAT r = min(rho, hi);
    for (int i = 0; i < 40; ++i) {
        VKL_FLOAT s = r * r;
        VKL_FLOAT num, den, dnum, dden;
        vkl_radial(s, num, den, dnum, dden);
        VKL_FLOAT R = num / den;
        VKL_FLOAT v = r * R - rho;
        VKL_FLOAT dv = R + 2.0 * s * (dnum * den - num * dden) / (den * den);
        if (v == 0.0) break;
        if (v < 0.0) lo = r; else hi = r;
        VKL_FLOAT next = r - v / dv;
        // Converged from one side (the bracket need not shrink then).
        if (next == r) break;
        r = (dv > 0.0 && next > lo && next < hi) ? next : 0.5 * (lo + hi);
        if (hi - lo < 2.0 * VKL_EPSILON * hi) break;
    }
    return dir * r;
}

// The damped Newton iteration from x (model::opencv::OpenCvCamera::newton_from): true when it
// ends in the domain with a vanishing residual and a positive Jacobian determinant.
bool vkl_newton_from(VKL_VEC2 t, inout VKL_VEC2 x) {
    VKL_FLOAT rho = length(t);
    VKL_VEC2 f;
    VKL_MAT2 J;
    if (!vkl_distort_pre_tilt(x, f, J)) return false;
    for (uint i = 0u; i < VKL_NEWTON_ITERATIONS; ++i) {
        VKL_FLOAT residual = length(f - t);
        if (residual <= VKL_EPSILON * (1.0 + rho)) break;
        if (!(determinant(J) > 0.0)) return false;
        VKL_VEC2 step = inverse(J) * (f - t);
        // Converged to rounding: the step no longer changes x.
        if (all(equal(x - step, x))) break;
        VKL_FLOAT s = 1.0;
        bool accepted = false;
        for (int k = 0; k < VKL_NEWTON_MAX_HALVINGS; ++k) {
            VKL_VEC2 c = x - step * s;
            VKL_VEC2 fc;
            VKL_MAT2 Jc;
            if (vkl_table_contains_ideal(c) && vkl_distort_pre_tilt(c, fc, Jc)
                    && length(fc - t) < residual * (1.0 - 1e-4 * s)) {
                x = c;
                f = fc;
                J = Jc;
                accepted = true;
                break;
            }
            s *= 0.5;
        }
        if (!accepted) break;
    }
    return length(f - t) <= VKL_NEWTON_ACCEPT * (1.0 + rho) && determinant(J) > 0.0
        && vkl_table_contains_ideal(x);
}

// Newton's method with the analytic Jacobian, damped to stay in the valid domain.
// Distorted normalized -> ideal normalized; false outside the valid domain. Started from the
// radial inverse; where that start lies in another basin (tangential or prism terms next to a
// fold at a wide angle), continuation from the principal point along the segment to t
// (model::opencv::CONTINUATION_STEPS steps). Only such pixels ever run the second loop.
bool vkl_standard_undistort(VKL_VEC2 d, out VKL_VEC2 x) {
    x = VKL_VEC2(0.0);
    VKL_VEC2 t;
    if (!vkl_remove_tilt(d, t)) return false;
    if (!vkl_contains_distorted(t)) return false;
    if (length(t) == 0.0) return true;
    if (VKL_FISHEYE) {
        // One dimension: θ from θ_d, then the pinhole point tan θ along t's direction.
        VKL_FLOAT theta;
        if (!vkl_fisheye_theta(length(t), theta)) return false;
        VKL_FLOAT sn, cs;
        vkl_sin_cos(theta, sn, cs);
        if (!(cs > 0.0)) return false;
        x = t / length(t) * (sn / cs);
        return vkl_table_contains_ideal(x);
    }
    x = vkl_radial_start(t);
    // One call site, so the iteration is compiled once: round 0 is the radial start; rounds
    // 1..N, reached only if it fails, walk the target out from the principal point.
    for (int k = 0; k <= VKL_CONTINUATION_STEPS; ++k) {
        if (k == 1) x = VKL_VEC2(0.0);
        VKL_FLOAT along = k == 0 ? 1.0 : VKL_FLOAT(k) / VKL_FLOAT(VKL_CONTINUATION_STEPS);
        bool ok = vkl_newton_from(t * along, x);
        if (k == 0 && ok) return true;
        if (k > 0 && !ok) return false;
    }
    return true;
}

// What the models' includes share, then each model's include and the dispatch over them.
#include "models/common.glsl"
#include "model_dispatch.glsl"

// The pinhole side of a model after the fisheye: ideal normalized x -> distorted normalized,
// and its Jacobian by central differences (it only steers Newton's refinements; the residual
// decides, so its f32 truncation costs iterations, never accuracy).
bool vkl_generic_distort(VKL_VEC2 x, out VKL_VEC2 d, out VKL_MAT2 J) {
    J = VKL_MAT2(1.0);
    if (!(dot(x, x) <= VKL_RADIUS_CAP * VKL_RADIUS_CAP)) { d = x; return false; }
    if (!vkl_ray_project(VKL_VEC3(x, 1.0), d)) return false;
    VKL_FLOAT h = 1e-3 * max(1.0, length(x));
    VKL_VEC2 a, b, c, e;
    bool ok = vkl_ray_project(VKL_VEC3(x + VKL_VEC2(h, 0.0), 1.0), a)
        && vkl_ray_project(VKL_VEC3(x - VKL_VEC2(h, 0.0), 1.0), b)
        && vkl_ray_project(VKL_VEC3(x + VKL_VEC2(0.0, h), 1.0), c)
        && vkl_ray_project(VKL_VEC3(x - VKL_VEC2(0.0, h), 1.0), e);
    if (ok) J = VKL_MAT2((a - b) / (2.0 * h), (c - e) / (2.0 * h));
    return true;
}

// Whether an ideal (pinhole-normalized) point is in the valid domain.
bool vkl_contains_ideal(VKL_VEC2 x) {
    if (VKL_GENERIC) {
        VKL_VEC2 d;
        return dot(x, x) <= VKL_RADIUS_CAP * VKL_RADIUS_CAP && vkl_ray_project(VKL_VEC3(x, 1.0), d);
    }
    return vkl_table_contains_ideal(x);
}

// The pre-tilt map and its Jacobian for a pass that refines on the pinhole side (the
// map upsampler): the standard model's pre-tilt distortion, or a ray model's whole map.
bool vkl_map_pre_tilt(VKL_VEC2 x, out VKL_VEC2 d, out VKL_MAT2 J) {
    if (VKL_GENERIC) return vkl_generic_distort(x, d, J);
    return vkl_distort_pre_tilt(x, d, J);
}

// Distorted normalized -> ideal normalized; false outside the valid domain (and, for a ray
// model, behind the image plane or past the radius cap).
bool vkl_undistort_newton(VKL_VEC2 d, out VKL_VEC2 x) {
    x = VKL_VEC2(0.0);
    if (VKL_GENERIC) {
        VKL_VEC3 ray;
        if (!vkl_ray_unproject(d, ray) || !(ray.z > 0.0)) return false;
        x = ray.xy / ray.z;
        return dot(x, x) <= VKL_RADIUS_CAP * VKL_RADIUS_CAP;
    }
    return vkl_standard_undistort(d, x);
}

// Forward model on normalized coordinates with its Jacobian: ideal (X/Z, Y/Z) -> distorted.
bool vkl_distort_jacobian(VKL_VEC2 x, out VKL_VEC2 d, out VKL_MAT2 J) {
    if (VKL_GENERIC) return vkl_generic_distort(x, d, J);
    return vkl_standard_distort(x, d, J);
}

// Forward model on normalized coordinates.
bool vkl_distort(VKL_VEC2 x, out VKL_VEC2 d) {
    VKL_MAT2 J;
    return vkl_distort_jacobian(x, d, J);
}

// Lambers et al. Eq. 2 (Heikkilä): closed-form approximate inverse, k1 k2 p1 p2 only.
bool vkl_undistort_heikkila(VKL_VEC2 d, out VKL_VEC2 x) {
    x = VKL_VEC2(0.0);
    // The standard model's approximation; the host refuses it for the ray models.
    if (VKL_RAY_MODEL) return false;
    VKL_VEC2 t;
    if (!vkl_remove_tilt(d, t)) return false;
    if (!vkl_contains_distorted(t)) return false;
    VKL_FLOAT k1 = VKL_RADIAL ? vkl_cam.radial.x : 0.0;
    VKL_FLOAT k2 = VKL_RADIAL ? vkl_cam.radial.y : 0.0;
    VKL_FLOAT p1 = VKL_TANGENTIAL ? vkl_cam.tangential_prism.x : 0.0;
    VKL_FLOAT p2 = VKL_TANGENTIAL ? vkl_cam.tangential_prism.y : 0.0;
    VKL_FLOAT r2 = dot(t, t);
    VKL_FLOAT d1 = k1 * r2 + k2 * r2 * r2;
    VKL_FLOAT denom = 4.0 * k1 * r2 + 6.0 * k2 * r2 * r2 + 8.0 * p1 * t.y + 8.0 * p2 * t.x + 1.0;
    if (!(abs(denom) > 1e-12)) return false;
    VKL_FLOAT d2 = 1.0 / denom;
    x = VKL_VEC2(t.x - d2 * (d1 * t.x + 2.0 * p1 * t.x * t.y + p2 * (r2 + 2.0 * t.x * t.x)),
             t.y - d2 * (d1 * t.y + p1 * (r2 + 2.0 * t.y * t.y) + 2.0 * p2 * t.x * t.y));
    return true;
}

// OpenCV's undistortPoints iteration with n iterations.
bool vkl_undistort_fixed_point(VKL_VEC2 d, uint n, out VKL_VEC2 x) {
    x = VKL_VEC2(0.0);
    // The standard model's iteration; the host refuses it for the ray models.
    if (VKL_RAY_MODEL) return false;
    VKL_VEC2 y0;
    if (!vkl_remove_tilt(d, y0)) return false;
    if (!vkl_contains_distorted(y0)) return false;
    x = y0;
    for (uint i = 0u; i < n; ++i) {
        VKL_FLOAT r2 = dot(x, x);
        VKL_FLOAT num, den, dnum, dden;
        vkl_radial(r2, num, den, dnum, dden);
        VKL_FLOAT icdist = den / num;
        if (!(icdist >= 0.0)) return false;
        VKL_VEC2 delta = VKL_VEC2(0.0);
        if (VKL_TANGENTIAL) {
            VKL_FLOAT p1 = vkl_cam.tangential_prism.x;
            VKL_FLOAT p2 = vkl_cam.tangential_prism.y;
            delta += VKL_VEC2(2.0 * p1 * x.x * x.y + p2 * (r2 + 2.0 * x.x * x.x),
                          p1 * (r2 + 2.0 * x.y * x.y) + 2.0 * p2 * x.x * x.y);
        }
        if (VKL_PRISM) {
            delta += VKL_VEC2(vkl_cam.tangential_prism.z * r2 + vkl_cam.tangential_prism.w * r2 * r2,
                          vkl_cam.prism.x * r2 + vkl_cam.prism.y * r2 * r2);
        }
        x = (y0 - delta) * icdist;
    }
    return true;
}

#endif
