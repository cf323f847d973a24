// omni.glsl — Mei's unified model with radial-tangential distortion (model::omni). model[0] =
// (ξ, Kalibr's w); k1 k2 p1 p2 and the radial-tangential part's domain table sit where the
// standard model's do, and its inverse is the standard model's Newton.

bool vkl_omni_project(VKL_VEC3 p, out VKL_VEC2 m) {
    VKL_FLOAT xi = vkl_cam_block.model[0].x, w = vkl_cam_block.model[0].y;
    VKL_FLOAT d = length(p);
    m = VKL_VEC2(0.0);
    if (!(p.z > -w * d)) return false;
    VKL_VEC2 s = p.xy / (p.z + xi * d);
    if (!vkl_table_contains_ideal(s)) return false;
    VKL_MAT2 J;
    return vkl_distort_pre_tilt(s, m, J);
}

bool vkl_omni_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    VKL_FLOAT xi = vkl_cam_block.model[0].x, w = vkl_cam_block.model[0].y;
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_VEC2 s;
    if (!vkl_standard_undistort(m, s)) return false;
    VKL_FLOAT r2 = dot(s, s);
    VKL_FLOAT root = 1.0 + (1.0 - xi * xi) * r2;
    if (!(root >= 0.0)) return false;
    VKL_FLOAT f = (xi + sqrt(root)) / (1.0 + r2);
    ray = normalize(VKL_VEC3(f * s, f - xi));
    return ray.z > -w;
}
