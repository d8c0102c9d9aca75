/* spot_surface.h: a point on the mesh surface (interpolated position, normal, tangent and uv), one
 * source for the GPU generator (spot_generate.h includes it), its CPU twin, and the CPU's
 * noise::surfacePoint (the reference's base mesh, the editor's picking and brushes).
 *
 * Compiles as GLSL and as C++ (real-typed: noise/surface.cpp instantiates it in double, the
 * generator in float). The includer provides the mesh accessors
 *   uvec3 spotMeshTriangle(uint t); rvec3 spotMeshPosition(uint v); rvec3 spotMeshNormal(uint v);
 *   rvec3 spotMeshTangent(uint v) (zero when the mesh has none); rvec2 spotMeshUv(uint v) (zero
 *   when the mesh has none).
 */

struct SpotSurface {
    rvec3 position;
    rvec3 normal;
    rvec3 tangent;
    rvec2 uv;
    uint triangle;
    rvec3 bary;
};

/* v / |v| with a correctly rounded square root and division, where GLSL's normalize may use an
 * approximate reciprocal square root (lavapipe does): the lattice and the surface frame then come
 * out bit-identical on the CPU and the GPU, so the discrete decisions made from them (which
 * triangle and cell a lattice site falls in) agree. */
SPOT_FN rvec3 spotUnit(rvec3 v) { return v / sqrt(dot(v, v)); }

/* Tangent used where a mesh has no tangents: world -y (the way fur hangs) projected on the tangent
 * plane, or world +x where the normal is vertical. Continuous over smooth surfaces except where
 * the normal passes through +-y, unlike a generic orthonormal basis whose seam would show as a
 * sudden change of comb direction. */
SPOT_FN rvec3 spotDefaultTangent(rvec3 n) {
    rvec3 t = rvec3(real(0.0), real(-1.0), real(0.0)) - n * -n.y;
    if (dot(t, t) < real(1e-8))
        t = rvec3(real(1.0), real(0.0), real(0.0)) - n * n.x;
    return spotUnit(t);
}

/* The surface at barycentric b = (b0, b1, b2) of triangle `tri`: interpolated position, normal
 * (unit; the face normal where the interpolation vanishes), tangent (unit, _|_ normal: the
 * interpolated vertex tangent, else spotDefaultTangent) and uv. */
SPOT_FN SpotSurface spotSurfaceAt(uint tri, rvec3 b) {
    uvec3 t = spotMeshTriangle(tri);
    SpotSurface s;
    s.triangle = tri;
    s.bary = b;
    rvec3 p0 = spotMeshPosition(t.x);
    rvec3 p1 = spotMeshPosition(t.y);
    rvec3 p2 = spotMeshPosition(t.z);
    s.position = b.x * p0 + b.y * p1 + b.z * p2;
    rvec3 n = b.x * spotMeshNormal(t.x) + b.y * spotMeshNormal(t.y) + b.z * spotMeshNormal(t.z);
    if (!(dot(n, n) > real(1e-12)))
        n = cross(p1 - p0, p2 - p0);
    s.normal = spotUnit(n);
    s.uv = b.x * spotMeshUv(t.x) + b.y * spotMeshUv(t.y) + b.z * spotMeshUv(t.z);
    rvec3 tg = b.x * spotMeshTangent(t.x) + b.y * spotMeshTangent(t.y) + b.z * spotMeshTangent(t.z);
    tg -= s.normal * dot(tg, s.normal);
    s.tangent = dot(tg, tg) > real(1e-12) ? spotUnit(tg) : spotDefaultTangent(s.normal);
    return s;
}
