// ftheta.glsl — NVIDIA's f-theta model (model::ftheta), mirroring the f64 code: the
// reference polynomial is the definition, the other direction is solved on its increasing
// branch, or evaluated by the file's other polynomial where the camera says `fitted_inverse`.
// model[0] = (reference: 0 PIXELDIST_TO_ANGLE, 1 ANGLE_TO_PIXELDIST; θ_max; branch end; fitted
// inverse: 1), model[1] = (c, d, e, -), model[2..3] = fw's 8 coefficients, model[4..5] = bw's.

bool vkl_ftheta_project(VKL_VEC3 p, out VKL_VEC2 m) {
    m = VKL_VEC2(0.0);
    VKL_FLOAT rho = length(p.xy);
    if (rho == 0.0) return p.z > 0.0;
    VKL_FLOAT theta = vkl_atan2(rho, p.z);
    if (!(theta < vkl_cam_block.model[0].y)) return false;
    VKL_FLOAT delta, slope;
    if (vkl_cam_block.model[0].x == 1.0 || vkl_cam_block.model[0].w == 1.0) {
        vkl_poly8(8, theta, delta, slope);
    } else if (!vkl_poly8_solve(16, theta, vkl_cam_block.model[0].z, delta)) {
        return false;
    }
    VKL_VEC2 q = p.xy * (delta / rho);
    VKL_VEC3 cde = vkl_cam_block.model[1].xyz;
    m = VKL_VEC2(cde.x * q.x + cde.y * q.y, cde.z * q.x + q.y);
    return true;
}

bool vkl_ftheta_unproject(VKL_VEC2 m, out VKL_VEC3 ray) {
    ray = VKL_VEC3(0.0, 0.0, 1.0);
    VKL_VEC3 cde = vkl_cam_block.model[1].xyz;
    VKL_VEC2 q = VKL_VEC2(m.x - cde.y * m.y, -cde.z * m.x + cde.x * m.y) / (cde.x - cde.y * cde.z);
    VKL_FLOAT r = length(q);
    if (r == 0.0) return true;
    VKL_FLOAT theta, slope;
    if (vkl_cam_block.model[0].x == 0.0 || vkl_cam_block.model[0].w == 1.0) {
        if (vkl_cam_block.model[0].x == 0.0 && !(r <= vkl_cam_block.model[0].z)) return false;
        vkl_poly8(16, r, theta, slope);
    } else if (!vkl_poly8_solve(8, r, vkl_cam_block.model[0].z, theta)) {
        return false;
    }
    if (!(theta >= 0.0 && theta < vkl_cam_block.model[0].y)) return false;
    VKL_FLOAT sn, cs;
    vkl_sin_cos(theta, sn, cs);
    ray = VKL_VEC3(q / r * sn, cs);
    return true;
}
