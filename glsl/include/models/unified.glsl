// unified.glsl — Basalt's unified camera model (model::ucm), the enhanced unified model
// (model::eucm) and the double sphere model (model::double_sphere), mirroring the f64 code
// line for line. model[0]: ucm (α), eucm (α, β), double sphere (ξ, α).

// The unified models' w: the domain is z > −w·ρ.
VKL_FLOAT vkl_unified_w(VKL_FLOAT a) { return a > 0.5 ? (1.0 - a) / a : a / (1.0 - a); }

bool vkl_ucm_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT a = vkl_cam.model[0].x;
    VKL_FLOAT d = length(p);
    m = VKL_VEC2(0.0);
    if (!(p.z > -vkl_unified_w(a) * d)) return false;
    VKL_FLOAT den = a * d + (1.0 - a) * p.z;
    m = p.xy / den;
    return den != 0.0;
}

bool vkl_ucm_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT a = vkl_cam.model[0].x;
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

bool vkl_eucm_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT a = vkl_cam.model[0].x, b = vkl_cam.model[0].y;
    VKL_FLOAT rho = sqrt(b * dot(p.xy, p.xy) + p.z * p.z);
    m = VKL_VEC2(0.0);
    if (!(p.z > -vkl_unified_w(a) * rho)) return false;
    VKL_FLOAT den = a * rho + (1.0 - a) * p.z;
    m = p.xy / den;
    return den != 0.0;
}

bool vkl_eucm_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT a = vkl_cam.model[0].x, b = vkl_cam.model[0].y;
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

VKL_FLOAT vkl_ds_w2() {
    VKL_FLOAT xi = vkl_cam.model[0].x;
    VKL_FLOAT w1 = vkl_unified_w(vkl_cam.model[0].y);
    return (w1 + xi) / sqrt(2.0 * w1 * xi + xi * xi + 1.0);
}

bool vkl_ds_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT xi = vkl_cam.model[0].x, a = vkl_cam.model[0].y;
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
    VKL_FLOAT xi = vkl_cam.model[0].x, a = vkl_cam.model[0].y;
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
