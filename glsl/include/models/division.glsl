// division.glsl — the division model (model::division), mirroring the f64 code.
// model[0].x = k.

bool vkl_division_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT k = vkl_cam_block.model[0].x;
    m = VKL_VEC2(0.0);
    VKL_FLOAT disc = p.z * p.z - 4.0 * k * dot(p.xy, p.xy);
    if (!(p.z > 0.0 && disc >= 0.0)) return false;
    m = 2.0 * p.xy / (p.z + sqrt(disc));
    return true;
}

bool vkl_division_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT k = vkl_cam_block.model[0].x;
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_FLOAT r2 = dot(m, m);
    if (k > 0.0 && r2 * k > 1.0) return false;
    VKL_FLOAT d = 1.0 + k * r2;
    if (!(d > 0.0)) return false;
    ray = normalize(VKL_VEC3(m / d, 1.0));
    return true;
}
