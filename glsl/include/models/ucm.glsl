// ucm.glsl — Basalt's unified camera model (model::ucm), mirroring the f64 code line for
// line. model[0].x = α.

bool vkl_ucm_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT a = vkl_cam_block.model[0].x;
    VKL_FLOAT d = length(p);
    m = VKL_VEC2(0.0);
    if (!(p.z > -vkl_unified_w(a) * d)) return false;
    VKL_FLOAT den = a * d + (1.0 - a) * p.z;
    m = p.xy / den;
    return den != 0.0;
}

bool vkl_ucm_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT a = vkl_cam_block.model[0].x;
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_FLOAT r2 = dot(m, m);
    if (a > 0.5 && r2 >= 1.0 / (2.0 * a - 1.0)) return false;
    VKL_FLOAT xi = a / (1.0 - a);
    VKL_VEC2 mm = m * (1.0 - a);
    VKL_FLOAT s2 = dot(mm, mm);
    VKL_FLOAT root = 1.0 + (1.0 - xi * xi) * s2;
    if (!(root >= 0.0)) return false;
    VKL_FLOAT f = (xi + sqrt(root)) / (1.0 + s2);
    ray = normalize(VKL_VEC3(f * mm, f - xi));
    return ray.z > -vkl_unified_w(a);
}
