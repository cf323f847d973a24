// eucm.glsl — the enhanced unified camera model (model::eucm), mirroring the f64 code.
// model[0] = (α, β).

bool vkl_eucm_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT a = vkl_cam_block.model[0].x, b = vkl_cam_block.model[0].y;
    VKL_FLOAT rho = sqrt(b * dot(p.xy, p.xy) + p.z * p.z);
    m = VKL_VEC2(0.0);
    if (!(p.z > -vkl_unified_w(a) * rho)) return false;
    VKL_FLOAT den = a * rho + (1.0 - a) * p.z;
    m = p.xy / den;
    return den != 0.0;
}

bool vkl_eucm_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT a = vkl_cam_block.model[0].x, b = vkl_cam_block.model[0].y;
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_FLOAT r2 = dot(m, m);
    if (a > 0.5 && r2 >= 1.0 / ((2.0 * a - 1.0) * b)) return false;
    VKL_FLOAT root = 1.0 - (2.0 * a - 1.0) * b * r2;
    if (!(root >= 0.0)) return false;
    VKL_FLOAT mz = (1.0 - b * a * a * r2) / (a * sqrt(root) + 1.0 - a);
    ray = normalize(VKL_VEC3(m, mz));
    VKL_FLOAT rho = sqrt(b * dot(ray.xy, ray.xy) + ray.z * ray.z);
    return ray.z > -vkl_unified_w(a) * rho;
}
