// double_sphere.glsl — the double sphere model (model::double_sphere), mirroring the f64
// code. model[0] = (ξ, α).

VKL_FLOAT vkl_ds_w2() {
    VKL_FLOAT xi = vkl_cam_block.model[0].x;
    VKL_FLOAT w1 = vkl_unified_w(vkl_cam_block.model[0].y);
    return (w1 + xi) / sqrt(2.0 * w1 * xi + xi * xi + 1.0);
}

bool vkl_ds_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT xi = vkl_cam_block.model[0].x, a = vkl_cam_block.model[0].y;
    VKL_FLOAT d1 = length(p);
    m = VKL_VEC2(0.0);
    if (!(p.z > -vkl_ds_w2() * d1)) return false;
    VKL_FLOAT k = xi * d1 + p.z;
    VKL_FLOAT d2 = sqrt(dot(p.xy, p.xy) + k * k);
    VKL_FLOAT den = a * d2 + (1.0 - a) * k;
    m = p.xy / den;
    return den != 0.0;
}

bool vkl_ds_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT xi = vkl_cam_block.model[0].x, a = vkl_cam_block.model[0].y;
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_FLOAT r2 = dot(m, m);
    if (a > 0.5 && r2 >= 1.0 / (2.0 * a - 1.0)) return false;
    VKL_FLOAT root = 1.0 - (2.0 * a - 1.0) * r2;
    if (!(root >= 0.0)) return false;
    VKL_FLOAT mz = (1.0 - a * a * r2) / (a * sqrt(root) + 1.0 - a);
    VKL_FLOAT inner = mz * mz + (1.0 - xi * xi) * r2;
    if (!(inner >= 0.0)) return false;
    VKL_FLOAT k = (mz * xi + sqrt(inner)) / (mz * mz + r2);
    ray = normalize(VKL_VEC3(k * m, k * mz - xi));
    return ray.z > -vkl_ds_w2();
}
