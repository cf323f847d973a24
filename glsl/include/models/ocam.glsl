// ocam.glsl — Scaramuzza's OCamCalib model (model::ocam), mirroring the f64 code: cam2world
// is the definition, world2cam its exact inverse on the branch where the angle grows, or
// OCamCalib's own fit `inverse_poly` where the camera says `fitted_inverse`.
// model[0] = (r_max, max angle, c, d), model[1] = (e, coefficient count, fitted inverse's
// coefficient count or 0, -), model[2..7] = poly's 24 coefficients, model[8..15] = the fit's.

// OCamCalib's angle off the axis of radius r's ray, atan2(r, −poly(r)), and its slope.
void vkl_ocam_angle(VKL_FLOAT r, out VKL_FLOAT angle, out VKL_FLOAT slope) {
    int n = int(vkl_cam_block.model[1].y);
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
    if (!(target <= vkl_cam_block.model[0].y)) return false;
    int fitted = int(vkl_cam_block.model[1].z);
    if (fitted > 0) {
        // OCamCalib's world2cam: θ from the image plane.
        VKL_FLOAT t = target - 1.57079632679489661923, rf = 0.0;
        for (int i = fitted - 1; i >= 0; --i) rf = rf * t + vkl_coef(32 + i);
        VKL_VEC2 xy = o * (rf / rho);
        VKL_FLOAT c = vkl_cam_block.model[0].z, d = vkl_cam_block.model[0].w, e = vkl_cam_block.model[1].x;
        m = VKL_VEC2(e * xy.x + xy.y, c * xy.x + d * xy.y);
        return true;
    }
    VKL_FLOAT lo = 0.0, hi = vkl_cam_block.model[0].x;
    VKL_FLOAT r = hi * target / vkl_cam_block.model[0].y;
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
    VKL_FLOAT c = vkl_cam_block.model[0].z, d = vkl_cam_block.model[0].w, e = vkl_cam_block.model[1].x;
    m = VKL_VEC2(e * xy.x + xy.y, c * xy.x + d * xy.y);
    return true;
}

bool vkl_ocam_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_FLOAT c = vkl_cam_block.model[0].z, d = vkl_cam_block.model[0].w, e = vkl_cam_block.model[1].x;
    // (row − yc, col − xc) = (m.y, m.x) = A (x, y), A = [[c, d], [e, 1]].
    VKL_VEC2 q = VKL_VEC2(m.y - d * m.x, -e * m.y + c * m.x) / (c - d * e);
    VKL_FLOAT r = length(q);
    if (!(r <= vkl_cam_block.model[0].x)) return false;
    int n = int(vkl_cam_block.model[1].y);
    VKL_FLOAT z = 0.0;
    for (int i = n - 1; i >= 0; --i) z = z * r + vkl_coef(8 + i);
    ray = normalize(VKL_VEC3(q.y, q.x, -z));
    return true;
}
