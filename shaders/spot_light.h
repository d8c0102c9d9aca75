/* spot_light.h: the lit shading model, the one source of its formulas for the CPU and the GPU.
 *
 * Compiles as GLSL (450, after spot_shared.h) and as C++: shaders/spot_light.hpp includes it in
 * spot::shared::f32 (float: the GPU's twin, for tests) and spot::shared::f64 (double: the CPU
 * reference), beside spot_shared.h, with the same conventions (`real`, SPOT_FN, SPOT_OUT).
 *
 * Every direction is a unit vector in world space; `l` points from the shaded point towards the
 * light, `v` towards the eye. A shading function returns the radiance the lobe sends towards the
 * eye per unit of light arriving (the light's colour x intensity x its transmittance), including
 * the lobe's colour: the factor that replaces the unlit emission `color` in the
 * emission-absorption integral. The models (docs/design.md, "Lighting"):
 *
 *   lambert  n from the extinction gradient (spotGradientNormal), one-sided: c max(0, n.l)
 *   flake    n = the lobe's shortest axis, turned towards the eye: c max(0, n'.l)
 *   strand   t = the lobe's longest axis as placed (root to tip), Kajiya-Kay diffuse with two
 *            longitudinal highlights shifted as in Marschner et al. 2003:
 *              sin(t,l) [ c + s1 g(theta_h - shift1, w1) + s2 c g(theta_h - shift2, w2) ]
 *            theta_h = (asin(t.l) + asin(t.v)) / 2, g(x, w) = exp(-x^2 / (2 w^2)); the primary
 *            highlight is white, the secondary tinted by the lobe's colour.
 *
 * The sky is a hemisphere about +y of constant radiance; a lobe takes the diffuse part of its
 * model from it (spotLobeDiffuse), integrated over directions by sampling (spotSkyDirection).
 */
/* A lobe's shading model (preset key kernel.lobes[i].shading.model). */
SPOT_CONST uint kSpotShadeLambert = 0u;
SPOT_CONST uint kSpotShadeStrand = 1u;
SPOT_CONST uint kSpotShadeFlake = 2u;

/* sin of the angle between unit t and unit l: Kajiya-Kay's diffuse term of a thin cylinder (its
 * width seen from the light). */
SPOT_FN real spotStrandDiffuse(rvec3 t, rvec3 l) {
    real c = dot(t, l);
    return sqrt(max(real(0.0), real(1.0) - c * c));
}

/* asin(x) for x in [-1, 1] with absolute error below 2e-8 (Abramowitz & Stegun 4.4.46), written
 * here so the CPU and the GPU compute the same number: Vulkan lets a device's asin be off by
 * thousands of ulps (lavapipe's is, by 4e-5 rad at 0.7). */
SPOT_FN real spotAsin(real x) {
    real a = min(abs(x), real(1.0));
    real p = real(-0.0012624911);
    p = p * a + real(0.0066700901);
    p = p * a + real(-0.0170881256);
    p = p * a + real(0.0308918810);
    p = p * a + real(-0.0501743046);
    p = p * a + real(0.0889789874);
    p = p * a + real(-0.2145988016);
    p = p * a + real(1.5707963050);
    real r = real(1.5707963267948966) - sqrt(real(1.0) - a) * p;
    return x < real(0.0) ? -r : r;
}

/* Marschner's half angle theta_h = (theta_i + theta_r) / 2 (radians), theta_i = asin(t.l) and
 * theta_r = asin(t.v) the longitudinal angles of light and eye from the plane normal to t. */
SPOT_FN real spotStrandHalfAngle(rvec3 t, rvec3 l, rvec3 v) {
    return real(0.5) * (spotAsin(dot(t, l)) + spotAsin(dot(t, v)));
}

/* A longitudinal highlight: strength exp(-(theta_h - shift)^2 / (2 width^2)), angles in radians,
 * width > 0. `h` = (shift, width, strength). */
SPOT_FN real spotHighlight(real thetaH, rvec3 h) {
    real x = (thetaH - h.x) / h.y;
    return h.z * exp(real(-0.5) * x * x);
}

/* The strand model (file comment): radiance towards v per unit light from l, for a lobe of
 * colour c with unit tangent t; `primary` and `secondary` = (shift, width, strength). */
SPOT_FN rvec3 spotStrandShade(rvec3 t, rvec3 l, rvec3 v, rvec3 c, rvec3 primary, rvec3 secondary) {
    real thetaH = spotStrandHalfAngle(t, l, v);
    return spotStrandDiffuse(t, l) *
           (c + rvec3(spotHighlight(thetaH, primary)) + spotHighlight(thetaH, secondary) * c);
}

/* A flat lobe's normal turned towards the eye (two-sided): n, or -n when v is behind it. */
SPOT_FN rvec3 spotTwoSided(rvec3 n, rvec3 v) {
    return dot(n, v) < real(0.0) ? -n : n;
}

/* The diffuse part of a lobe's model, without its colour: what the sky lights. `axis` is the
 * strand's tangent, the flake's normal, or the lambert normal; l any unit direction. */
SPOT_FN real spotLobeDiffuse(uint model, rvec3 axis, rvec3 l, rvec3 v) {
    if (model == kSpotShadeStrand)
        return spotStrandDiffuse(axis, l);
    rvec3 n = model == kSpotShadeFlake ? spotTwoSided(axis, v) : axis;
    return max(real(0.0), dot(n, l));
}

/* A lobe's whole model towards v per unit light from l (file comment), colour c included. */
SPOT_FN rvec3 spotLobeShade(uint model, rvec3 axis, rvec3 l, rvec3 v, rvec3 c, rvec3 primary,
                            rvec3 secondary) {
    if (model == kSpotShadeStrand)
        return spotStrandShade(axis, l, v, c, primary, secondary);
    return spotLobeDiffuse(model, axis, l, v) * c;
}

/* The unit direction of a kernel-space axis `axisKernel` of a lobe centred at `lobeCentre` once
 * placed (spotPlaceLobe's F, s, kappa): F (s * (B axis)) normalized, B the bend's rotation at the
 * lobe. This is the image of the lobe's axis in the world, so a strand's tangent after bend. */
SPOT_FN rvec3 spotPlacedAxis(rvec3 axisKernel, rvec3 lobeCentre, rmat3 frame, rvec3 scale,
                             real kappa) {
    rmat3 bendRot;
    spotBendLobe(lobeCentre, kappa, bendRot);
    return normalize(frame * (scale * (bendRot * axisKernel)));
}

/* The unit normal of the plane a placed lobe's axes i != `axis` span: row `axis` of A (world ->
 * lobe space), normalized. A flake's normal for its shortest axis; sign arbitrary. */
SPOT_FN rvec3 spotPlacedNormal(rmat3 A, int axis) {
    return normalize(rvec3(A[0][axis], A[1][axis], A[2][axis]));
}

/* A direction on the upper hemisphere about +y, uniform in solid angle (pdf 1 / (2 pi)), from
 * two uniforms in [0, 1). The sky's estimator of one direction w is
 * 2 sky T(w) spotLobeDiffuse(w): (1 / pi) of the integral of sky T diffuse over the hemisphere,
 * which makes an unshadowed surface facing +y receive exactly `sky` x its colour. */
SPOT_FN rvec3 spotSkyDirection(real u1, real u2) {
    real y = u1;
    real r = sqrt(max(real(0.0), real(1.0) - y * y));
    real phi = real(6.283185307179586) * u2;
    return rvec3(r * cos(phi), y, r * sin(phi));
}

/* What arrives from a point light of intensity `intensity` at distance d: intensity / d^2 (the
 * inverse-square law). A directional light delivers its intensity unchanged. */
SPOT_FN real spotPointFalloff(real intensity, real d) {
    return intensity / max(d * d, real(1e-12));
}

/* Where the GPU looks a lobe's light up in the light-space structure (docs/design.md, "Lighting
 * on the GPU"): the point s sigmas from the lobe's centre c along its unit shading axis, moved
 * towards the light (unit l) to where that ray leaves the lobe's core, 1.5 sigmas (at most 1.1 k,
 * k the support), so that the structure counts little of the lobe itself (whose own shadow is
 * spotOwnShadow's) and all but little of what lies between the lobe and the light. Leaving the
 * whole support (3.3 sigmas) skipped the neighbours in between: the lobes of fur-bunny were lit
 * 0.038 too bright on average; from 1.5 sigmas, 0.001 (LightSpace.FurBunnyLobeLightAsThePassesUseIt).
 * The key light is looked up at s = -1 and +1: their mean lights the lobe's centre (the
 * two-point Gauss-Hermite rule along a strand: its root may lie in the coat's shadow and its tip
 * in the light) and half their difference its change per sigma along the axis
 * (light_common.glsl's litLobeColor); each sky direction at s = 0. A: world -> lobe space. */
SPOT_FN rvec3 spotLobeLightPoint(rmat3 A, rvec3 c, rvec3 axis, real s, rvec3 l, real k) {
    rvec3 d = A * l;
    real dd = max(dot(d, d), real(1e-30));
    rvec3 ua = A * axis;
    real la = length(ua);
    real step = la > real(0.0) ? s / la : real(0.0);
    rvec3 u0 = step * ua;
    real core = min(real(1.5), real(1.1) * k);
    real b = dot(u0, d);
    real exitT = (-b + sqrt(max(b * b - dd * (dot(u0, u0) - core * core), real(0.0)))) / dd;
    return c + step * axis + exitT * l;
}
