// Sec. 3.2's rule past 90° off the axis, shared by the compute discard (glsl/discard.comp,
// through alg1.glsl) and the geometry shader (glsl/geometry.geom).
#ifndef VKL_WRAPS_BEHIND_GLSL
#define VKL_WRAPS_BEHIND_GLSL

// Whether a triangle with camera-frame vertices a, b, c, one of them at or behind the image
// plane, spreads more than 90° around the optical axis. A fisheye that sees past 90° keeps
// such vertices, and near the direction straight behind the lens its image is a thin ring:
// a triangle there whose vertices lie far apart around the axis (one wrapping around that
// direction lies all around it) lands on far-apart points of the ring, and the straight
// triangle between them would cross the image — Sec. 3.2's rule (drop, never stretch) drops
// it. A vertex on the axis itself (no direction around it) counts as far apart, and so does
// NaN. Triangles wholly in front of the image plane are the frustum's and the domain's.
//
// A panorama's image is cut instead (VKL_SEAM_BEHIND, model::Camera::crosses_seam): its
// longitude jumps from +180° to −180° across the half-plane x = 0 behind the camera, so a
// triangle with an edge through that half-plane would stretch across the whole image; it goes,
// and nothing else behind the camera does.
layout(constant_id = 27) const bool VKL_SEAM_BEHIND = false;

// Whether the segment a–b passes through the half-plane x = 0, z < 0.
bool alg1_crosses_seam(vec3 a, vec3 b) {
    if (!(a.x < 0.0) && !(b.x < 0.0) || a.x < 0.0 && b.x < 0.0) return false;
    float t = a.x / (a.x - b.x);
    return !(a.z + (b.z - a.z) * t >= 0.0);
}

bool alg1_spans_behind(vec3 a, vec3 b, vec3 c) {
    if (a.z > 0.0 && b.z > 0.0 && c.z > 0.0) return false;
    if (VKL_SEAM_BEHIND) {
        return alg1_crosses_seam(a, b) || alg1_crosses_seam(b, c) || alg1_crosses_seam(c, a);
    }
    // dot < 0 ⟺ more than 90° apart around the axis.
    return !(dot(a.xy, b.xy) > 0.0) || !(dot(b.xy, c.xy) > 0.0) || !(dot(c.xy, a.xy) > 0.0);
}

#endif
