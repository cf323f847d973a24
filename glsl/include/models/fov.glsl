// fov.glsl — the field-of-view model (model::fov), mirroring the f64 code. model[0] =
// (ω, 2 tan(ω/2)).

bool vkl_fov_project(VKL_VEC3 p, out VKL_VEC2 m) {
    m = VKL_VEC2(0.0);
    if (!(p.z > 0.0)) return false;
    VKL_VEC2 x = p.xy / p.z;
    VKL_FLOAT w = vkl_cam_block.model[0].x, a = vkl_cam_block.model[0].y;
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
    VKL_FLOAT w = vkl_cam_block.model[0].x, a = vkl_cam_block.model[0].y;
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
