// fov_equirect.glsl — the field-of-view model (model::fov; model[0] = ω, 2 tan(ω/2)), the
// equirectangular panorama (model::equirect; no parameters) and the division model
// (model::division), mirroring the f64 code.

bool vkl_fov_project(VKL_VEC3 p, out VKL_VEC2 m) {
    m = VKL_VEC2(0.0);
    if (!(p.z > 0.0)) return false;
    VKL_VEC2 x = p.xy / p.z;
    VKL_FLOAT w = vkl_cam.model[0].x, a = vkl_cam.model[0].y;
    if (w == 0.0) { m = x; return true; }
    VKL_FLOAT r2 = dot(x, x);
    VKL_FLOAT factor;
    // model::fov::SERIES_RADIUS
    if (r2 < 1e-8) {
        VKL_FLOAT a2 = a * a;
        factor = (1.0 + r2 * (r2 * (a2 * a2 / 5.0) - a2 / 3.0)) * (a / w);
    } else {
        VKL_FLOAT r = sqrt(r2);
        factor = vkl_atan(r * a) / (r * w);
    }
    m = x * factor;
    return true;
}

bool vkl_fov_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT w = vkl_cam.model[0].x, a = vkl_cam.model[0].y;
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    if (w == 0.0) { ray = normalize(VKL_VEC3(m, 1.0)); return true; }
    VKL_FLOAT rd = length(m);
    if (rd == 0.0) return true;
    VKL_FLOAT angle = rd * w;
    if (!(angle < 1.5707963267948966)) return false;
    VKL_FLOAT sn, cs;
    vkl_sin_cos(angle, sn, cs);
    VKL_FLOAT ru = sn / cs / a;
    ray = normalize(VKL_VEC3(m / rd * ru, 1.0));
    return true;
}

// atan2(y, x) for any sign of y.
VKL_FLOAT vkl_atan2_signed(VKL_FLOAT y, VKL_FLOAT x) {
    VKL_FLOAT t = vkl_atan2(abs(y), x);
    return y < 0.0 ? -t : t;
}

bool vkl_equirect_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT h = length(p.xz);
    m = VKL_VEC2(0.0);
    if (h == 0.0) {
        m = VKL_VEC2(0.0, p.y > 0.0 ? 1.5707963267948966 : -1.5707963267948966);
        return p.y != 0.0;
    }
    m = VKL_VEC2(vkl_atan2_signed(p.x, p.z), vkl_atan2_signed(p.y, h));
    return true;
}

// sin and cos of any angle in [−π, π].
void vkl_sin_cos_signed(VKL_FLOAT t, out VKL_FLOAT sn, out VKL_FLOAT cs) {
    vkl_sin_cos(abs(t), sn, cs);
    if (t < 0.0) sn = -sn;
}

bool vkl_equirect_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    if (!(abs(m.x) <= 3.141592653589793 && abs(m.y) <= 1.5707963267948966)) return false;
    VKL_FLOAT sl, cl, so, co;
    vkl_sin_cos_signed(m.y, sl, cl);
    vkl_sin_cos_signed(m.x, so, co);
    ray = VKL_VEC3(cl * so, sl, cl * co);
    return true;
}

// The division model (model::division; model[0].x = k).
bool vkl_division_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT k = vkl_cam.model[0].x;
    m = VKL_VEC2(0.0);
    VKL_FLOAT disc = p.z * p.z - 4.0 * k * dot(p.xy, p.xy);
    if (!(p.z > 0.0 && disc >= 0.0)) return false;
    m = 2.0 * p.xy / (p.z + sqrt(disc));
    return true;
}

bool vkl_division_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT k = vkl_cam.model[0].x;
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_FLOAT r2 = dot(m, m);
    if (k > 0.0 && r2 * k > 1.0) return false;
    VKL_FLOAT d = 1.0 + k * r2;
    if (!(d > 0.0)) return false;
    ray = normalize(VKL_VEC3(m / d, 1.0));
    return true;
}
