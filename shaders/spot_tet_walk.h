/* spot_tet_walk.h: the baked renderer's walk through the shell's tetrahedra (docs/design.md
 * section 5), one source for the shaders (baked_shell.comp builds each tetrahedron's planes and
 * rest map, baked_march.comp walks them) and their CPU twin (noise/shell.h: ShellWalk, which
 * the tests use). Compiles as GLSL and as C++ (GLM), after spot_shared.h, in the same common
 * subset of the two languages.
 *
 * The includer provides the accessor
 *   rvec4 spotWalkPlane(uint tet, uint f): face f's plane of tetrahedron tet (spotTetFacePlane);
 * in GLSL it reads the tetrahedra's storage buffer, in C++ (a class body, as noise/
 * generator_shared.h includes spot_generate.h) the twin's arrays.
 *
 * A tetrahedron's face f is the one opposite its corner f. A walk enters a tetrahedron through a
 * face (or starts inside it, at the eye: entry face 4) and leaves through the nearest of its
 * other face planes that the ray leaves through; the neighbour across that face (noise::
 * shellWalkNeighbours: neighbour x 4 + the face as the neighbour numbers it, -1 on the shell's
 * boundary) is entered next, through that face.
 */

SPOT_CONST uint kTetNoFace = 4u; /* entry face of a walk that starts inside (at the eye) */

/* ---- Building a tetrahedron's walk data (baked_shell.comp) ------------------------------- */

/* The plane of the face through corners a, b, c, its normal turned towards the opposite corner
 * (inwards): xyz the normal (not unit), w such that dot(xyz, x) + w >= 0 inside; (0, 0, 0, -1)
 * for a flat tetrahedron, which then holds no point. */
SPOT_FN rvec4 spotTetFacePlane(rvec3 a, rvec3 b, rvec3 c, rvec3 opposite) {
    rvec3 n = cross(b - a, c - a);
    real side = dot(n, opposite - a);
    if (side < real(0.0))
        n = -n;
    return side == real(0.0) ? rvec4(real(0.0), real(0.0), real(0.0), real(-1.0))
                             : rvec4(n, -dot(n, a));
}

/* The affine map from the tetrahedron's corners now (p0..p3, world) to the same corners at rest
 * (r0..r3, the bake's texture coordinates), as three rows: rest[j] = dot(row_j.xyz, x) + row_j.w.
 * All zero but the offset for a flat tetrahedron. */
SPOT_FN void spotTetRestMap(rvec3 p0, rvec3 p1, rvec3 p2, rvec3 p3, rvec3 r0, rvec3 r1, rvec3 r2,
                            rvec3 r3, SPOT_OUT(rvec4) row0, SPOT_OUT(rvec4) row1,
                            SPOT_OUT(rvec4) row2) {
    rmat3 pm = rmat3(p1 - p0, p2 - p0, p3 - p0);
    rmat3 m = determinant(pm) != real(0.0) ? rmat3(r1 - r0, r2 - r0, r3 - r0) * inverse(pm)
                                           : rmat3(real(0.0));
    rvec3 offset = r0 - m * p0;
    row0 = rvec4(m[0][0], m[1][0], m[2][0], offset[0]);
    row1 = rvec4(m[0][1], m[1][1], m[2][1], offset[1]);
    row2 = rvec4(m[0][2], m[1][2], m[2][2], offset[2]);
}

/* Whether the tetrahedron with corners p0..p3 (shellTetrahedra's order) is folded: the shell's
 * tetrahedra are positively oriented (p3 on the side of p0, p1, p2's counter-clockwise normal)
 * unless vertex normals that diverge over a crease turn one inside out, and then it overlaps its
 * neighbours. */
SPOT_FN bool spotTetFolded(rvec3 p0, rvec3 p1, rvec3 p2, rvec3 p3) {
    return dot(cross(p1 - p0, p2 - p0), p3 - p0) < real(0.0);
}

/* A point x of the tetrahedron at rest, by its rest map's rows. */
SPOT_FN rvec3 spotTetToRest(rvec4 row0, rvec4 row1, rvec4 row2, rvec3 x) {
    return rvec3(dot(rvec3(row0), x) + row0.w, dot(rvec3(row1), x) + row1.w,
                 dot(rvec3(row2), x) + row2.w);
}

/* ---- The walk (baked_march.comp; SPOT_TET_WALK_BUILD_ONLY leaves it out, and with it the
 * accessor it needs) ----------------------------------------------------------------------- */
#ifndef SPOT_TET_WALK_BUILD_ONLY

/* Where the ray origin + t dir crosses `plane`: at t = num / den, entering where den > 0 and
 * leaving where den < 0 (den = 0: parallel, inside where num <= 0). */
SPOT_FN void spotTetCrossing(rvec4 plane, rvec3 origin, rvec3 dir, SPOT_OUT(real) num,
                             SPOT_OUT(real) den) {
    num = -(dot(rvec3(plane), origin) + plane.w);
    den = dot(rvec3(plane), dir);
}

/* The ray parameter at which a walk enters tetrahedron `tet` through face `entryFace`: where the
 * ray crosses that face's plane, at least 0 (0 when parallel to it). */
SPOT_FN real spotTetEntry(uint tet, uint entryFace, rvec3 origin, rvec3 dir) {
    real num;
    real den;
    spotTetCrossing(spotWalkPlane(tet, entryFace), origin, dir, num, den);
    return den != real(0.0) ? max(num / den, real(0.0)) : real(0.0);
}

/* The face through which the walk leaves tetrahedron `tet`, entered through `entryFace`
 * (kTetNoFace: the ray starts inside, at the eye): tOut receives its parameter (not clamped to
 * the entry). The walk follows the ray's preimage through the shell's tetrahedra, which is one
 * curve even where the shell folds (vertex normals that diverge over a crease invert some
 * tetrahedra, and neighbouring prisms then overlap): where the ray crosses the entry face into
 * the tetrahedron as t grows (always, in a shell without folds) it runs forward, and leaves
 * through the nearest of the other planes that it leaves through; where it crosses the entry
 * face out of the tetrahedron (a folded, inverted one lies on the side it came from), the
 * preimage runs backward through it, and leaves through the farthest of the other planes that
 * the ray enters through, before the entry: `backward` tells which. Walking on into the
 * neighbour there keeps to the curve; following only the forward rule, a walk in a fold left the
 * shell early or circled among the fold's tetrahedra. kTetNoFace when no face qualifies (a flat or
 * degenerate tetrahedron: the walk stops there). With `count`, `loops` counts the planes examined
 * (the shader's loop budget: 4 per tetrahedron). */
SPOT_FN uint spotTetExit(uint tet, uint entryFace, rvec3 origin, rvec3 dir, bool count,
                         SPOT_OUT(real) tOut, SPOT_OUT(bool) backward, SPOT_INOUT(uint) loops) {
    real num;
    real den;
    backward = false;
    if (entryFace != kTetNoFace) {
        if (count)
            ++loops;
        spotTetCrossing(spotWalkPlane(tet, entryFace), origin, dir, num, den);
        backward = den < real(0.0);
    }
    tOut = backward ? real(-3.0e38) : real(3.0e38);
    uint exitFace = kTetNoFace;
    /* The 3 faces after the entry face (from inside, entry face 4: faces 1 to 3, then 0). */
    for (uint i = 1u; i < 4u; ++i) {
        if (count)
            ++loops;
        uint f = (entryFace + i) & 3u;
        spotTetCrossing(spotWalkPlane(tet, f), origin, dir, num, den);
        if (backward ? den > real(0.0) && num / den > tOut : den < real(0.0) && num / den < tOut) {
            tOut = num / den;
            exitFace = f;
        }
    }
    if (entryFace == kTetNoFace) {
        if (count)
            ++loops;
        spotTetCrossing(spotWalkPlane(tet, 0u), origin, dir, num, den);
        if (den < real(0.0) && num / den < tOut) {
            tOut = num / den;
            exitFace = 0u;
        }
    }
    return exitFace;
}

/* The step across an exit face: `next` is the face's shellWalkNeighbours entry. False on the
 * shell's boundary (next < 0); else `tet` and `entryFace` become the neighbour and the face
 * it is entered through. */
SPOT_FN bool spotTetNext(int next, SPOT_INOUT(uint) tet, SPOT_INOUT(uint) entryFace) {
    if (next < 0)
        return false;
    tet = uint(next) >> 2u;
    entryFace = uint(next) & 3u;
    return true;
}

#endif /* SPOT_TET_WALK_BUILD_ONLY */
