// thin_prism_fisheye.glsl — COLMAP's thin-prism fisheyes (model::thin_prism): the equidistant point
// q = θ (x, y)/r distorted on its plane, inverted by damped Newton (closed-form Jacobian)
// inside the plane's domain table (which sits where the standard model's does). model[0] = (radial first, radial
// coefficient count, -, -); then the radial coefficients (6), p1 p2, s1..s4.

// The plane's distortion and its Jacobian J (column-major: J[0] = d/dq.x), in closed form:
// Newton needs it at every step, and differences would cost four more evaluations.
VKL_VEC2 vkl_tp_distort_jacobian(VKL_VEC2 q, out VKL_MAT2 J) {
    VKL_FLOAT s2 = dot(q, q);
    int n = int(vkl_cam.model[0].y);
    // f(s) = Σ k_i s^(i+1), and f'(s) = Σ (i+1) k_i s^i, both by Horner.
    VKL_FLOAT f = 0.0, df = 0.0;
    for (int i = n - 1; i >= 0; --i) f = (f + vkl_coef(4 + i)) * s2;
    for (int i = n - 1; i >= 0; --i) df = df * s2 + VKL_FLOAT(i + 1) * vkl_coef(4 + i);
    VKL_VEC2 x = q * (1.0 + f);
    VKL_MAT2 dx = VKL_MAT2(1.0 + f) + VKL_MAT2(q * q.x, q * q.y) * (2.0 * df);
    bool first = vkl_cam.model[0].x > 0.5;
    VKL_VEC2 v = first ? x : q;
    VKL_FLOAT r2 = dot(v, v);
    VKL_FLOAT p1 = vkl_coef(10), p2 = vkl_coef(11);
    VKL_FLOAT sa = vkl_coef(12), sb = vkl_coef(13), sc = vkl_coef(14), sd = vkl_coef(15);
    VKL_FLOAT txy = 2.0 * v.x * v.y;
    VKL_VEC2 d = VKL_VEC2(x.x + txy * p1 + (r2 + 2.0 * v.x * v.x) * p2 + r2 * sa + r2 * r2 * sb,
                          x.y + (r2 + 2.0 * v.y * v.y) * p1 + txy * p2 + r2 * sc + r2 * r2 * sd);
    // Tangential and thin prism terms' Jacobian in v.
    VKL_FLOAT px = sa + 2.0 * sb * r2, py = sc + 2.0 * sd * r2;
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
    VKL_FLOAT s2 = dot(m, m), f = 0.0;
    for (int i = int(vkl_cam.model[0].y) - 1; i >= 0; --i) f = (f + vkl_coef(4 + i)) * s2;
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
