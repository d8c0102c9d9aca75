/* spot_deform.h: the formulas of animated surfaces (docs/design.md section 6), one source for the
 * GPU's deform passes (deform_*.comp) and the CPU (noise/deform.cpp; noise/animated_mesh.cpp
 * poses its vertices with spotPoseVertex).
 *
 * Included after spot_shared.h and spot_deform_layout.h; real-typed like spot_shared.h
 * (spot_deform.hpp instantiates it in float: the GPU's twin). Pure functions; the vertices'
 * pose is spot_pose.h.
 *
 * Everything that defines the noise is decided on the rest pose (section 2); an impulse is its
 * anchor (triangle, barycentrics, height, and its frame in the rest pose), and these functions
 * carry it to a pose.
 */


/* The rotation that carries a triangle from rest (p0, p1, p2) to a pose (q0, q1, q2): within the
 * plane, the rotation part (polar decomposition) of the linear map that takes the rest edges to
 * the posed ones; across, the turn of the face normal. Exact for a rigid motion, the same
 * whichever corner comes first, and a rotation (orthonormal, det 1) by construction. Where the
 * pose collapses the triangle (area below 1e-6 of its rest area) or the rest is degenerate, R is
 * left as it was and the result is false: its impulses keep the last valid frame. */
SPOT_FN bool spotTriangleRotation(rvec3 p0, rvec3 p1, rvec3 p2, rvec3 q0, rvec3 q1, rvec3 q2,
                                  SPOT_INOUT(rmat3) R) {
    rvec3 e1 = p1 - p0;
    rvec3 e2 = p2 - p0;
    rvec3 f1 = q1 - q0;
    rvec3 f2 = q2 - q0;
    rvec3 nr = cross(e1, e2);
    rvec3 nd = cross(f1, f2);
    real ar = sqrt(dot(nr, nr));
    real ad = sqrt(dot(nd, nd));
    real l1 = sqrt(dot(e1, e1));
    real m1 = sqrt(dot(f1, f1));
    if (!(ar > real(0.0)) || !(l1 > real(0.0)) || !(m1 > real(0.0)) || !(ad > real(1e-6) * ar) ||
        !(ad < real(1e30)))
        return false;
    rvec3 tr = e1 / l1;
    rvec3 zr = nr / ar;
    rvec3 br = cross(zr, tr);
    rvec3 td = f1 / m1;
    rvec3 zd = nd / ad;
    rvec3 bd = cross(zd, td);
    /* The in-plane map M = E' E^-1, E = [[l1, e2.t], [0, e2.b]] and E' the same of the pose;
     * its rotation part turns by atan2(M10 - M01, M00 + M11), and M10 = 0. */
    real e2b = ar / l1;
    real m00 = m1 / l1;
    real m01 = (dot(f2, td) - m1 * dot(e2, tr) / l1) / e2b;
    real m11 = (ad / m1) / e2b;
    real c = m00 + m11;
    real s = -m01;
    real r = sqrt(c * c + s * s);
    if (!(r > real(0.0)) || !(r < real(1e30)))
        return false;
    c /= r;
    s /= r;
    R = rmat3(c * td + s * bd, c * bd - s * td, zd) * transpose(rmat3(tr, br, zr));
    return true;
}

/* The posed surface at barycentrics b of a triangle with posed corners q and posed unit vertex
 * normals n: the point, and the unit normal there (the face normal where the interpolated one
 * vanishes, `fallback` where the face has none either). */
SPOT_FN rvec3 spotPosedNormal(rvec3 q0, rvec3 q1, rvec3 q2, rvec3 n0, rvec3 n1, rvec3 n2, rvec3 b,
                              rvec3 fallback) {
    rvec3 n = b.x * n0 + b.y * n1 + b.z * n2;
    if (!(dot(n, n) > real(1e-12)))
        n = cross(q1 - q0, q2 - q0);
    if (!(dot(n, n) > real(1e-24)) || !(dot(n, n) < real(1e30)))
        return fallback;
    return n / sqrt(dot(n, n));
}

/* An impulse's anchor carried to a pose: `root`, the posed surface point at barycentrics b of
 * its triangle (posed corners q, posed unit vertex normals n), and `position`, the root plus the
 * impulse's height along the posed normal there (spotPosedNormal; R x the rest normal where the
 * pose leaves none). Its frame is R x its rest frame, R its triangle's rotation. */
SPOT_FN void spotMoveAnchor(rvec3 q0, rvec3 q1, rvec3 q2, rvec3 n0, rvec3 n1, rvec3 n2, rvec3 b,
                            real height, rmat3 R, rvec3 restNormal, SPOT_OUT(rvec3) root,
                            SPOT_OUT(rvec3) position) {
    root = b.x * q0 + b.y * q1 + b.z * q2;
    position = root + height * spotPosedNormal(q0, q1, q2, n0, n1, n2, b, R * restNormal);
}

/* The wind's turn of an impulse about its root at time t: about normal x direction, so that the
 * kernel leans downwind, by strength x (0.6 + 0.4 sin(2 pi (f t + phase))) x (1 - variation x u),
 * a steady lean with gusts. The phase and u are the impulse's own random numbers (of its anchor,
 * `key`), so neighbours do not sway in lockstep, and the turn is a pure function of t. No turn
 * where the wind blows along the normal. */
SPOT_FN rmat3 spotWindRotation(rvec3 normal, rvec3 direction, real strength, real frequency,
                               real variation, real t, uint key) {
    rvec3 axis = cross(normal, direction);
    real len = sqrt(dot(axis, axis));
    if (!(len > real(1e-6)) || strength == real(0.0))
        return rmat3(real(1.0));
    axis /= len;
    real phase = spotRand(key, 0u);
    real u = spotRand(key, 1u);
    real angle = strength * (real(0.6) + real(0.4) * sin(real(6.283185307179586) *
                                                           (frequency * t + phase))) *
                 (real(1.0) - variation * u);
    real c = cos(angle);
    real s = sin(angle);
    /* Rodrigues: R = c I + s [axis]x + (1 - c) axis axis^T, by columns. */
    rvec3 k = axis * (real(1.0) - c);
    return rmat3(rvec3(c + k.x * axis.x, k.x * axis.y + s * axis.z, k.x * axis.z - s * axis.y),
                 rvec3(k.y * axis.x - s * axis.z, c + k.y * axis.y, k.y * axis.z + s * axis.x),
                 rvec3(k.z * axis.x + s * axis.y, k.z * axis.y - s * axis.x, c + k.z * axis.z));
}

/* The key of an impulse's anchor (its triangle and barycentrics' bits): what the wind's random
 * numbers hash, the same at every pose. */
SPOT_FN uint spotAnchorKey(uint triangle, real b1, real b2) {
    return spotHashCombine(spotHashCombine(spotHash(triangle + 0x2545f491u), floatBitsToUint(b1)),
                           floatBitsToUint(b2));
}
