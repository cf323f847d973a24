// thin_prism_fisheye.glsl — COLMAP's thin-prism fisheyes (model::thin_prism): the
// equidistant point q = θ (x, y)/r distorted on its plane, inverted by damped Newton
// (closed-form Jacobian) inside the plane's domain table (which sits where the standard
// model's does). model[0] = (radial first, radial coefficient count, -, -), model[1] =
// k1..k4, model[2] = (k5, k6, p1, p2), model[3] = s1..s4.

// The plane's distortion and its Jacobian J (column-major: J[0] = d/dq.x), in closed form:
// Newton needs it at every step, and differences would cost four more evaluations.
VKL_VEC2 vkl_tp_distort_jacobian(VKL_VEC2 q, out VKL_MAT2 J) {
    // Fixed reads of the block, no loop: on lavapipe a dynamically indexed uniform array is
    // a chain of selects per read. Unused coefficients are zero.
    VKL_VEC4 ka = vkl_cam_block.model[1];          // k1 k2 k3 k4
    VKL_VEC2 kb = vkl_cam_block.model[2].xy;       // k5 k6
    VKL_FLOAT p1 = vkl_cam_block.model[2].z, p2 = vkl_cam_block.model[2].w;
    VKL_VEC4 sp = vkl_cam_block.model[3];          // s1 s2 s3 s4
    VKL_FLOAT s2 = dot(q, q);
    // f(s) = Σ k_i s^i (i = 1..6) and f'(s), by Horner.
    VKL_FLOAT f = s2 * (ka.x + s2 * (ka.y + s2 * (ka.z + s2 * (ka.w + s2 * (kb.x + s2 * kb.y)))));
    VKL_FLOAT df = ka.x + s2 * (2.0 * ka.y + s2 * (3.0 * ka.z + s2 * (4.0 * ka.w + s2 * (5.0 * kb.x + s2 * 6.0 * kb.y))));
    VKL_VEC2 x = q * (1.0 + f);
    VKL_MAT2 dx = VKL_MAT2(1.0 + f) + VKL_MAT2(q * q.x, q * q.y) * (2.0 * df);
    bool first = vkl_cam_block.model[0].x > 0.5;
    VKL_VEC2 v = first ? x : q;
    VKL_FLOAT r2 = dot(v, v);
    VKL_FLOAT txy = 2.0 * v.x * v.y;
    VKL_VEC2 d = VKL_VEC2(x.x + txy * p1 + (r2 + 2.0 * v.x * v.x) * p2 + r2 * sp.x + r2 * r2 * sp.y,
                          x.y + (r2 + 2.0 * v.y * v.y) * p1 + txy * p2 + r2 * sp.z + r2 * r2 * sp.w);
    // Tangential and thin prism terms' Jacobian in v.
    VKL_FLOAT px = sp.x + 2.0 * sp.y * r2, py = sp.z + 2.0 * sp.w * r2;
    VKL_MAT2 jt = VKL_MAT2(
        VKL_VEC2(2.0 * p1 * v.y + 6.0 * p2 * v.x + 2.0 * v.x * px, 2.0 * p1 * v.x + 2.0 * p2 * v.y + 2.0 * v.x * py),
        VKL_VEC2(2.0 * p1 * v.x + 2.0 * p2 * v.y + 2.0 * v.y * px, 6.0 * p1 * v.y + 2.0 * p2 * v.x + 2.0 * v.y * py));
    J = first ? dx + jt * dx : dx + jt;
    return d;
}

VKL_VEC2 vkl_tp_distort(VKL_VEC2 q) {
    VKL_MAT2 J;
    return vkl_tp_distort_jacobian(q, J);
}

bool vkl_tp_project(VKL_VEC3 p, out VKL_VEC2 m) {
    m = VKL_VEC2(0.0);
    if (!(p.z > 0.0)) return false;
    VKL_FLOAT r = length(p.xy);
    VKL_VEC2 q = r > 0.0 ? p.xy * (vkl_atan2(r, p.z) / r) : VKL_VEC2(0.0);
    if (!vkl_table_contains_ideal(q)) return false;
    m = vkl_tp_distort(q);
    return true;
}

// Damped Newton from q towards distort(q) = t; true when it ends inside the domain with a
// vanishing residual.
bool vkl_tp_newton(VKL_VEC2 t, inout VKL_VEC2 q) {
    VKL_FLOAT rho = length(t);
    VKL_MAT2 J;
    VKL_VEC2 f = vkl_tp_distort_jacobian(q, J);
    for (uint i = 0u; i < VKL_NEWTON_ITERATIONS; ++i) {
        VKL_FLOAT residual = length(f - t);
        if (residual <= VKL_EPSILON * (1.0 + rho)) break;
        if (!(determinant(J) > 0.0)) return false;
        VKL_VEC2 step = inverse(J) * (f - t);
        VKL_FLOAT s = 1.0;
        bool accepted = false;
        for (int k = 0; k < VKL_NEWTON_MAX_HALVINGS; ++k) {
            VKL_VEC2 c = q - step * s;
            VKL_MAT2 Jc;
            VKL_VEC2 fc = vkl_tp_distort_jacobian(c, Jc);
            if (vkl_table_contains_ideal(c) && length(fc - t) < residual * (1.0 - 1e-4 * s)) {
                q = c;
                f = fc;
                J = Jc;
                accepted = true;
                break;
            }
            s *= 0.5;
        }
        if (!accepted) break;
    }
    return length(f - t) <= VKL_NEWTON_ACCEPT * (1.0 + rho) && vkl_table_contains_ideal(q);
}

bool vkl_tp_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    if (length(m) == 0.0) return true;
    if (!vkl_contains_distorted(m)) return false;
    // Start where the radial factor alone would put it (model::thin_prism, the same start).
    VKL_VEC4 ka = vkl_cam_block.model[1];
    VKL_VEC2 kb = vkl_cam_block.model[2].xy;
    VKL_FLOAT s2 = dot(m, m);
    VKL_FLOAT f = s2 * (ka.x + s2 * (ka.y + s2 * (ka.z + s2 * (ka.w + s2 * (kb.x + s2 * kb.y)))));
    VKL_VEC2 q = m / (1.0 + f);
    if (any(isnan(q)) || any(isinf(q))) q = m;
    bool ok = vkl_tp_newton(m, q);
    // Continuation from the centre where the first start lies in another basin.
    for (int k = 1; k <= VKL_CONTINUATION_STEPS && !ok; ++k) {
        if (k == 1) q = VKL_VEC2(0.0);
        bool step_ok = vkl_tp_newton(m * (VKL_FLOAT(k) / VKL_FLOAT(VKL_CONTINUATION_STEPS)), q);
        if (!step_ok) return false;
        ok = k == VKL_CONTINUATION_STEPS;
    }
    if (!ok) return false;
    VKL_FLOAT theta = length(q);
    if (!(theta < 1.5707963267948966)) return false;
    VKL_FLOAT sn, cs;
    vkl_sin_cos(theta, sn, cs);
    ray = VKL_VEC3(q / theta * sn, cs);
    return true;
}
