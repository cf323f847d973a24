// polynomial.glsl — NVIDIA's f-theta model (model::ftheta) and Scaramuzza's OCamCalib model
// (model::ocam), mirroring the f64 code: the reference polynomial is the definition, its
// inverse is solved by Newton safeguarded by bisection on the branch where it increases.
//
// ftheta: model[0] = (reference: 0 PIXELDIST_TO_ANGLE, 1 ANGLE_TO_PIXELDIST; θ_max; branch
// end; -), model[1] = (c, d, e, -), model[2..3] = fw's 8 coefficients, model[4..5] = bw's.
// ocam: model[0] = (r_max, max angle, c, d), model[1] = (e, coefficient count, -, -),
// model[2..7] = poly's 24 coefficients.

VKL_FLOAT vkl_coef(int i) { return vkl_cam.model[i / 4][i % 4]; }

// Σ cᵢ tⁱ over the 8 coefficients from model index `first`, and its slope.
void vkl_poly8(int first, VKL_FLOAT t, out VKL_FLOAT v, out VKL_FLOAT s) {
    v = 0.0; s = 0.0;
    for (int i = 7; i >= 0; --i) {
        s = s * t + v;
        v = v * t + vkl_coef(first + i);
    }
}

// Solves poly8(first)(t) = target on [0, hi] where it increases; false outside its range.
bool vkl_poly8_solve(int first, VKL_FLOAT target, VKL_FLOAT hi, out VKL_FLOAT t) {
    VKL_FLOAT v0, s0, v1, s1;
    vkl_poly8(first, 0.0, v0, s0);
    vkl_poly8(first, hi, v1, s1);
    t = 0.0;
    if (!(target >= v0 && target <= v1)) return false;
    VKL_FLOAT lo = 0.0;
    t = v1 > v0 ? hi * (target - v0) / (v1 - v0) : 0.0;
    for (int i = 0; i < 60; ++i) {
        VKL_FLOAT v, s;
        vkl_poly8(first, t, v, s);
        VKL_FLOAT r = v - target;
        if (r == 0.0) break;
        if (r < 0.0) lo = t; else hi = t;
        VKL_FLOAT next = t - r / s;
        if (next == t) break;
        t = (s > 0.0 && next > lo && next < hi) ? next : 0.5 * (lo + hi);
        if (hi - lo <= 4.0 * VKL_EPSILON * hi) break;
    }
    return true;
}

bool vkl_ftheta_project(VKL_VEC3 p, out VKL_VEC2 m) {
    m = VKL_VEC2(0.0);
    VKL_FLOAT rho = length(p.xy);
    if (rho == 0.0) return p.z > 0.0;
    VKL_FLOAT theta = vkl_atan2(rho, p.z);
    if (!(theta < vkl_cam.model[0].y)) return false;
    VKL_FLOAT delta, slope;
    if (vkl_cam.model[0].x == 1.0) {
        vkl_poly8(8, theta, delta, slope);
    } else if (!vkl_poly8_solve(16, theta, vkl_cam.model[0].z, delta)) {
        return false;
    }
    VKL_VEC2 q = p.xy * (delta / rho);
    VKL_VEC3 cde = vkl_cam.model[1].xyz;
    m = VKL_VEC2(cde.x * q.x + cde.y * q.y, cde.z * q.x + q.y);
    return true;
}

bool vkl_ftheta_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_VEC3 cde = vkl_cam.model[1].xyz;
    VKL_VEC2 q = VKL_VEC2(m.x - cde.y * m.y, -cde.z * m.x + cde.x * m.y) / (cde.x - cde.y * cde.z);
    VKL_FLOAT r = length(q);
    if (r == 0.0) return true;
    VKL_FLOAT theta, slope;
    if (vkl_cam.model[0].x == 0.0) {
        if (!(r <= vkl_cam.model[0].z)) return false;
        vkl_poly8(16, r, theta, slope);
    } else if (!vkl_poly8_solve(8, r, vkl_cam.model[0].z, theta)) {
        return false;
    }
    if (!(theta >= 0.0 && theta < vkl_cam.model[0].y)) return false;
    VKL_FLOAT sn, cs;
    vkl_sin_cos(theta, sn, cs);
    ray = VKL_VEC3(q / r * sn, cs);
    return true;
}

// OCamCalib's angle off the axis of radius r's ray, atan2(r, −poly(r)), and its slope.
void vkl_ocam_angle(VKL_FLOAT r, out VKL_FLOAT angle, out VKL_FLOAT slope) {
    int n = int(vkl_cam.model[1].y);
    VKL_FLOAT z = 0.0, dz = 0.0;
    for (int i = n - 1; i >= 0; --i) {
        dz = dz * r + z;
        z = z * r + vkl_coef(8 + i);
    }
    angle = vkl_atan2(r, -z);
    slope = (-z + r * dz) / (r * r + z * z);
}

bool vkl_ocam_project(VKL_VEC3 p, out VKL_VEC2 m) {
    m = VKL_VEC2(0.0);
    // OCamCalib's frame: x along rows (our y), y along columns (our x).
    VKL_VEC2 o = p.yx;
    VKL_FLOAT rho = length(o);
    if (rho == 0.0) return p.z > 0.0;
    VKL_FLOAT target = vkl_atan2(rho, p.z);
    if (!(target <= vkl_cam.model[0].y)) return false;
    VKL_FLOAT lo = 0.0, hi = vkl_cam.model[0].x;
    VKL_FLOAT r = hi * target / vkl_cam.model[0].y;
    for (int i = 0; i < 60; ++i) {
        VKL_FLOAT a, s;
        vkl_ocam_angle(r, a, s);
        VKL_FLOAT res = a - target;
        if (res == 0.0) break;
        if (res < 0.0) lo = r; else hi = r;
        VKL_FLOAT next = r - res / s;
        if (next == r) break;
        r = (s > 0.0 && next > lo && next < hi) ? next : 0.5 * (lo + hi);
        if (hi - lo <= 4.0 * VKL_EPSILON * hi) break;
    }
    VKL_VEC2 xy = o * (r / rho);
    VKL_FLOAT c = vkl_cam.model[0].z, d = vkl_cam.model[0].w, e = vkl_cam.model[1].x;
    m = VKL_VEC2(e * xy.x + xy.y, c * xy.x + d * xy.y);
    return true;
}

bool vkl_ocam_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_FLOAT c = vkl_cam.model[0].z, d = vkl_cam.model[0].w, e = vkl_cam.model[1].x;
    // (row − yc, col − xc) = (m.y, m.x) = A (x, y), A = [[c, d], [e, 1]].
    VKL_VEC2 q = VKL_VEC2(m.y - d * m.x, -e * m.y + c * m.x) / (c - d * e);
    VKL_FLOAT r = length(q);
    if (!(r <= vkl_cam.model[0].x)) return false;
    int n = int(vkl_cam.model[1].y);
    VKL_FLOAT z = 0.0;
    for (int i = n - 1; i >= 0; --i) z = z * r + vkl_coef(8 + i);
    ray = normalize(VKL_VEC3(q.y, q.x, -z));
    return true;
}
