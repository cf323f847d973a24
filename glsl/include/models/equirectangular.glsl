// equirectangular.glsl — the equirectangular panorama (model::equirect; no parameters),
// mirroring the f64 code.

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

bool vkl_equirect_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    if (!(abs(m.x) <= 3.141592653589793 && abs(m.y) <= 1.5707963267948966)) return false;
    VKL_FLOAT sl, cl, so, co;
    vkl_sin_cos_signed(m.y, sl, cl);
    vkl_sin_cos_signed(m.x, so, co);
    ray = VKL_VEC3(cl * so, sl, cl * co);
    return true;
}
