// common.glsl — what several model includes share: the unified models' w, sign-aware
// trigonometry, and ascending polynomials over the camera block's model[] array.

// The unified models' w: the domain is z > −w·ρ.
VKL_FLOAT vkl_unified_w(VKL_FLOAT a) { return a > 0.5 ? (1.0 - a) / a : a / (1.0 - a); }

// atan2(y, x) for any sign of y.
VKL_FLOAT vkl_atan2_signed(VKL_FLOAT y, VKL_FLOAT x) {
    VKL_FLOAT t = vkl_atan2(abs(y), x);
    return y < 0.0 ? -t : t;
}

// sin and cos of any angle in [−π, π].
void vkl_sin_cos_signed(VKL_FLOAT t, out VKL_FLOAT sn, out VKL_FLOAT cs) {
    vkl_sin_cos(abs(t), sn, cs);
    if (t < 0.0) sn = -sn;
}

VKL_FLOAT vkl_coef(int i) { return vkl_cam_block.model[i / 4][i % 4]; }

// Σ cᵢ tⁱ over the 8 coefficients from model index `first`, and its slope.
void vkl_poly8(int first, VKL_FLOAT t, out VKL_FLOAT v, out VKL_FLOAT s) {
    v = 0.0; s = 0.0;
    for (int i = 7; i >= 0; --i) {
        s = s * t + v;
        v = v * t + vkl_coef(first + i);
    }
}

// Solves poly8(first)(t) = target on [0, hi] where it increases; false outside its range.
bool vkl_poly8_solve(int first, VKL_FLOAT target, VKL_FLOAT hi, out VKL_FLOAT t) {
    VKL_FLOAT v0, s0, v1, s1;
    vkl_poly8(first, 0.0, v0, s0);
    vkl_poly8(first, hi, v1, s1);
    t = 0.0;
    if (!(target >= v0 && target <= v1)) return false;
    VKL_FLOAT lo = 0.0;
    t = v1 > v0 ? hi * (target - v0) / (v1 - v0) : 0.0;
    for (int i = 0; i < 60; ++i) {
        VKL_FLOAT v, s;
        vkl_poly8(first, t, v, s);
        VKL_FLOAT r = v - target;
        if (r == 0.0) break;
        if (r < 0.0) lo = t; else hi = t;
        VKL_FLOAT next = t - r / s;
        if (next == t) break;
        t = (s > 0.0 && next > lo && next < hi) ? next : 0.5 * (lo + hi);
        if (hi - lo <= 4.0 * VKL_EPSILON * hi) break;
    }
    return true;
}
