/* spot_shared.h: the one source of the math that both the CPU and the GPU run.
 *
 * This file compiles as GLSL (450) and as C++ (with GLM). In C++ it is never included directly:
 * shaders/spot_shared.hpp includes it twice, once inside namespace spot::shared::f32 with
 * `real` = float (the GPU's twin, for tests) and once inside spot::shared::f64 with `real` =
 * double (the CPU reference). In GLSL `real` is float. Keep to the common subset of the two
 * languages: no templates, no references (use SPOT_OUT), no recursion, no pointers, uint
 * arithmetic that wraps, literals wrapped in real(...).
 *
 * Spaces: "world" is the mesh's space; "kernel space" has x = comb direction in the tangent
 * plane, y = bitangent, z = surface normal, in kernel units (world length = kernel units x the
 * impulse's scale); "lobe space" is where a lobe is the unit isotropic Gaussian exp(-|u|^2/2).
 */
#ifndef __cplusplus
#define real float
#define rvec2 vec2
#define rvec3 vec3
#define rvec4 vec4
#define rmat3 mat3
#define SPOT_OUT(T) out T
#define SPOT_INOUT(T) inout T
#define SPOT_CONST const
#define SPOT_FN
#endif

/* ------------------------------------------------------------------------------------------ */
/* Counter-based random numbers. Every random value is a pure function of (key, counter), so   */
/* results do not depend on traversal order or thread count, and C++ and GLSL agree bit for    */
/* bit. The mixer is Chris Wellons' "lowbias32" (bias 0.17), chained for multi-word keys.      */
/* ------------------------------------------------------------------------------------------ */

SPOT_FN uint spotHash(uint x) {
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

SPOT_FN uint spotHashCombine(uint seed, uint value) { return spotHash(seed ^ spotHash(value + 0x9e3779b9u)); }

/* Key of a surface cell: (cell i, j, k) and the global seed. */
SPOT_FN uint spotCellKey(int i, int j, int k, uint seed) {
    uint h = spotHash(seed + 0x68e31da4u);
    h = spotHashCombine(h, uint(i));
    h = spotHashCombine(h, uint(j));
    h = spotHashCombine(h, uint(k));
    return h;
}

/* Key of one impulse candidate inside a cell. */
SPOT_FN uint spotImpulseKey(uint cellKey, uint index) { return spotHashCombine(cellKey ^ 0xb5297a4du, index); }

/* Uniform in [0, 1): 24 random bits, exactly representable in float. */
SPOT_FN real spotRand(uint key, uint counter) {
    uint h = spotHash(key ^ spotHash(counter * 0x9e3779b9u + 0x1b873593u));
    return real(h >> 8u) * real(1.0 / 16777216.0);
}

/* Random streams inside one impulse key: fixed counters, so adding a new attribute later does not
 * reshuffle the existing ones. */
SPOT_CONST uint kRandPiece = 0u;      /* which surface piece of the cell */
SPOT_CONST uint kRandBary0 = 1u;      /* position inside the piece */
SPOT_CONST uint kRandBary1 = 2u;
SPOT_CONST uint kRandDensity = 3u;    /* the density test xi < d(p) */
SPOT_CONST uint kRandHeight = 4u;
SPOT_CONST uint kRandTilt = 5u;
SPOT_CONST uint kRandSpin = 6u;
SPOT_CONST uint kRandBend = 7u;
SPOT_CONST uint kRandScale = 8u;
SPOT_CONST uint kRandColor = 9u;
SPOT_CONST uint kRandWeight = 10u;
SPOT_CONST uint kRandJitterU = 11u;
SPOT_CONST uint kRandJitterV = 12u;
SPOT_CONST uint kRandLod = 13u;      /* level-of-detail thinning */
/* The level of detail keeps at least this fraction of a cell's impulses (weights grow by at most
 * its inverse, which keeps the optical depths finite and the noise bounded). */
SPOT_CONST float kMinLodKeep = 1.0 / 64.0;

/* Largest Poisson mean drawn by inversion in one chunk: exp(-16) is far from underflow in float,
 * and the inversion loop stays short. */
SPOT_CONST real kPoissonChunk = real(16.0);
/* Hard cap on the candidates of one cell, so no loop can approach lavapipe's 65,535-iteration
 * limit; the cell builder refuses densities whose expected count comes near it. */
SPOT_CONST uint kMaxCandidatesPerCell = 16384u;

/* Poisson-distributed count with mean `lambda`, drawn by inversion in chunks of mean at most
 * kPoissonChunk (a sum of independent Poisson variables is Poisson). `key` seeds the draws. */
SPOT_FN uint spotPoisson(real lambda, uint key) {
    uint count = 0u;
    real remaining = max(lambda, real(0.0));
    uint chunk = 0u;
    while (remaining > real(0.0) && count < kMaxCandidatesPerCell) {
        real mean = min(remaining, kPoissonChunk);
        remaining -= mean;
        real u = spotRand(key, 0x40000000u + chunk);
        chunk += 1u;
        real p = exp(-mean);
        real cdf = p;
        uint k = 0u;
        /* Stop at 8x the chunk mean: the tail beyond is below 1e-30. */
        while (u > cdf && k < 128u) {
            k += 1u;
            p *= mean / real(k);
            cdf += p;
        }
        count += k;
    }
    return min(count, kMaxCandidatesPerCell);
}

/* Uniform point in a triangle from two uniforms: barycentric weights (w0, w1, w2). */
SPOT_FN rvec3 spotSampleTriangle(real u1, real u2) {
    real su = sqrt(u1);
    return rvec3(real(1.0) - su, su * (real(1.0) - u2), su * u2);
}

/* Orthonormal basis around unit n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited"):
 * continuous everywhere except the z = 0 seam, no normalization needed. */
SPOT_FN void spotOrthonormalBasis(rvec3 n, SPOT_OUT(rvec3) t, SPOT_OUT(rvec3) b) {
    real s = n.z >= real(0.0) ? real(1.0) : real(-1.0);
    real a = real(-1.0) / (s + n.z);
    real c = n.x * n.y * a;
    t = rvec3(real(1.0) + s * n.x * n.x * a, s * c, -s * n.x);
    b = rvec3(c, s + n.y * n.y * a, -n.y);
}

/* Kernel frame at an impulse, as the columns of a rotation (kernel space -> world):
 * x = comb direction projected on the tangent plane, then tilted by `tilt` radians from the
 * normal towards the comb (fur lying down) and spun by `spin` radians about the tilted axis.
 * If the comb is (nearly) parallel to n, `fallbackTangent` is used instead. */
SPOT_FN rmat3 spotKernelFrame(rvec3 n, rvec3 comb, rvec3 fallbackTangent, real tilt, real spin) {
    rvec3 x0 = comb - n * dot(comb, n);
    real len = length(x0);
    if (len < real(1e-6) * max(length(comb), real(1e-30)) || !(len > real(0.0))) {
        x0 = fallbackTangent - n * dot(fallbackTangent, n);
        len = length(x0);
        if (!(len > real(1e-12))) {
            rvec3 t;
            rvec3 b;
            spotOrthonormalBasis(n, t, b);
            x0 = t;
            len = real(1.0);
        }
    }
    x0 = x0 / len;
    rvec3 y0 = cross(n, x0);
    real ct = cos(tilt);
    real st = sin(tilt);
    rvec3 z1 = ct * n + st * x0;
    rvec3 x1 = ct * x0 - st * n;
    real cs = cos(spin);
    real ss = sin(spin);
    rvec3 x2 = cs * x1 + ss * y0;
    rvec3 y2 = cs * y0 - ss * x1;
    return rmat3(x2, y2, z1);
}

/* Bend a lobe along a circular arc in the kernel's xz plane: a point at height z (kernel units) on
 * the kernel's z axis moves to arc length z on a circle of curvature `kappa` (radians per kernel
 * unit) curving towards +x, and the lobe turns with the arc's tangent. Returns the bent centre;
 * `rot` receives the rotation to apply to the lobe's linear part. */
SPOT_FN rvec3 spotBendLobe(rvec3 centre, real kappa, SPOT_OUT(rmat3) rot) {
    real phi = kappa * centre.z;
    real c = cos(phi);
    real s = sin(phi);
    rot = rmat3(rvec3(c, real(0.0), -s), rvec3(real(0.0), real(1.0), real(0.0)), rvec3(s, real(0.0), c));
    rvec3 arc;
    if (abs(phi) < real(1e-4)) {
        arc = rvec3(real(0.5) * kappa * centre.z * centre.z, real(0.0), centre.z);
    } else {
        arc = rvec3((real(1.0) - c) / kappa, real(0.0), s / kappa);
    }
    return arc + rot * rvec3(centre.x, centre.y, real(0.0));
}

/* ------------------------------------------------------------------------------------------ */
/* Gaussian line integrals.                                                                     */
/* ------------------------------------------------------------------------------------------ */

/* erfc with fractional error below 1.2e-7 everywhere (Numerical Recipes' Chebyshev fit);
 * written here because GLSL has no erf. */
SPOT_FN real spotErfcApprox(real x) {
    real z = abs(x);
    real t = real(1.0) / (real(1.0) + real(0.5) * z);
    real r = t * exp(-z * z - real(1.26551223) +
                     t * (real(1.00002368) +
                          t * (real(0.37409196) +
                               t * (real(0.09678418) +
                                    t * (real(-0.18628806) +
                                         t * (real(0.27886807) +
                                              t * (real(-1.13520398) +
                                                   t * (real(1.48851587) +
                                                        t * (real(-0.82215223) + t * real(0.17087277))))))))));
    return x >= real(0.0) ? r : real(2.0) - r;
}

#ifdef __cplusplus
/* In double precision the C++ side uses the library's erfc (the reference must be exact); the
 * float instantiation uses the same approximation as the GPU. */
SPOT_FN real spotErfc(real x) {
    if constexpr (sizeof(real) == sizeof(double))
        return std::erfc(x);
    else
        return spotErfcApprox(x);
}
#else
SPOT_FN real spotErfc(real x) { return spotErfcApprox(x); }
#endif

/* 0.5 * (erf(b) - erf(a)) for a <= b, without cancellation in the tails. */
SPOT_FN real spotErfDifferenceHalf(real a, real b) {
    if (a >= real(0.0))
        return real(0.5) * (spotErfc(a) - spotErfc(b));
    if (b <= real(0.0))
        return real(0.5) * (spotErfc(-b) - spotErfc(-a));
    return real(1.0) - real(0.5) * (spotErfc(-a) + spotErfc(b));
}

SPOT_CONST real kSqrtTwoPi = real(2.5066282746310002);
SPOT_CONST real kInvSqrtTwo = real(0.70710678118654752);

/* Optical depth per unit peak extinction of one lobe along the ray o + t d, t in [t0, t1], with
 * o and d already in lobe space (o = A (origin - centre), d = A dir). The lobe is truncated at
 * radius k (sigmas): only the chord inside |u| < k counts. Returns 0 when the ray misses.
 * `tPeak` receives the parameter of the density maximum along the ray. */
SPOT_FN real spotLobeDepth(rvec3 o, rvec3 d, real t0, real t1, real k, SPOT_OUT(real) tPeak) {
    real dd = dot(d, d);
    tPeak = real(0.0);
    if (!(dd > real(0.0)))
        return real(0.0);
    real tStar = -dot(o, d) / dd;
    tPeak = tStar;
    rvec3 perp = o + tStar * d;
    real perp2 = dot(perp, perp);
    real k2 = k * k;
    if (perp2 >= k2)
        return real(0.0);
    real invLen = real(1.0) / sqrt(dd);
    real halfChord = sqrt(k2 - perp2) * invLen;
    real a = max(t0, tStar - halfChord);
    real b = min(t1, tStar + halfChord);
    if (!(b > a))
        return real(0.0);
    real len = sqrt(dd);
    real fraction = spotErfDifferenceHalf((a - tStar) * len * kInvSqrtTwo, (b - tStar) * len * kInvSqrtTwo);
    return kSqrtTwoPi * invLen * exp(real(-0.5) * perp2) * fraction;
}

/* The polynomial of Abramowitz and Stegun 7.1.26: erf(x) = 1 - spotErfPoly(x) exp(-x^2) for
 * x >= 0, absolute error below 1.5e-7. */
SPOT_FN real spotErfPoly(real x) {
    real t = real(1.0) / (real(1.0) + real(0.3275911) * x);
    return t * (real(0.254829592) +
                t * (real(-0.284496736) +
                     t * (real(1.421413741) + t * (real(-1.453152027) + t * real(1.061405429)))));
}

/* g x erf(u / sqrt 2) for any u (odd in u), g > 0 a factor the caller multiplies in anyway: the
 * clipped ends of a chord. */
SPOT_FN real spotScaledErfHalfSqrt2(real u, real g) {
    real x = abs(u) * kInvSqrtTwo;
    real r = g * (real(1.0) - spotErfPoly(x) * exp(-x * x));
    return u < real(0.0) ? -r : r;
}

/* The same optical depth from a lobe's screen form (spot_splat.h, SpotScreenLobe): for the ray
 * origin + t e (t in view depth units), w = o' x v and on = dot(o', v) with o' the ray origin and
 * v = A e its direction, both in lobe space. The squared distance of the line from the lobe centre
 * is |w|^2 / |v|^2 (no cancellation, unlike |o'|^2 - on^2 / |v|^2), the density peaks at
 * t* = -on / |v|^2, and the lobe-space arc length s = (t - t*) |v| runs over the chord
 * |s| < h = sqrt(k^2 - |w|^2 / |v|^2) clipped to t in [0, tEnd]. Returns the integral over t (per
 * unit peak extinction; multiply by |e| for world units), 0 when the ray misses; `tPeak` receives
 * t* (0 where the line misses the support).
 * Cost matters here (the splat fragment shaders run it per lobe and pixel), so erf is
 * Abramowitz and Stegun's (absolute error 1.5e-7 on the chord's fraction), and each end s of the
 * clipped chord costs one division and one exponential: with G = exp(-|w|^2 / (2 |v|^2)),
 * G erf(|s| / sqrt 2) = G - poly exp(-(|w|^2 / |v|^2 + s^2) / 2). There is no branch: lavapipe
 * runs the code of every branch that any of its 8 lanes takes, so the clipped and unclipped ends
 * take the same formula (at an unclipped end, s = +-h, the exponential is exp(-k^2 / 2)). */
SPOT_FN real spotScreenLobeDepth(rvec3 w, rvec3 v, real on, real tEnd, real k, SPOT_OUT(real) tPeak) {
    real vv = dot(v, v);
    real ww = dot(w, w);
    real rs = real(1.0) / sqrt(vv);
    real inv = rs * rs;
    real len = vv * rs;
    real perp2 = ww * inv;
    real tStar = -on * inv;
    real h = sqrt(max(k * k - perp2, real(0.0)));
    real ua = max(-tStar * len, -h);         /* the ray's start, t = 0, or the chord's */
    real ub = min((tEnd - tStar) * len, h);  /* the mesh, or the chord's end */
    real gauss = exp(real(-0.5) * perp2);
    real ga = gauss - spotErfPoly(abs(ua) * kInvSqrtTwo) * exp(real(-0.5) * (perp2 + ua * ua));
    real gb = gauss - spotErfPoly(abs(ub) * kInvSqrtTwo) * exp(real(-0.5) * (perp2 + ub * ub));
    ga = ua < real(0.0) ? -ga : ga;
    gb = ub < real(0.0) ? -gb : gb;
    bool meets = ww < k * k * vv; /* the line meets the support */
    tPeak = meets ? tStar : real(0.0);
    return meets && ub > ua ? kSqrtTwoPi * real(0.5) * (gb - ga) * rs : real(0.0);
}

/* Density of a lobe at lobe-space point u, per unit peak extinction, truncated at k. */
SPOT_FN real spotLobeDensity(rvec3 u, real k) {
    real r2 = dot(u, u);
    return r2 < k * k ? exp(real(-0.5) * r2) : real(0.0);
}

/* Cholesky factor (lower triangular) of a symmetric positive definite 3x3 matrix, as columns. */
SPOT_FN rmat3 spotCholesky3(rmat3 m) {
    real l00 = sqrt(max(m[0][0], real(0.0)));
    real l10 = l00 > real(0.0) ? m[0][1] / l00 : real(0.0);
    real l20 = l00 > real(0.0) ? m[0][2] / l00 : real(0.0);
    real l11 = sqrt(max(m[1][1] - l10 * l10, real(0.0)));
    real l21 = l11 > real(0.0) ? (m[1][2] - l20 * l10) / l11 : real(0.0);
    real l22 = sqrt(max(m[2][2] - l20 * l20 - l21 * l21, real(0.0)));
    /* columns: (l00, l10, l20), (0, l11, l21), (0, 0, l22) */
    return rmat3(rvec3(l00, l10, l20), rvec3(real(0.0), l11, l21), rvec3(real(0.0), real(0.0), l22));
}

/* EWA widening of a lobe by an isotropic pixel footprint of standard deviation s (world units)
 * perpendicular to the unit view direction dir: V' = V + s^2 (I - dir dir^T), where V = L L^T is
 * the lobe's world covariance and A = L^-1 is its world-to-lobe linear map. Works in lobe space,
 * M = A V' A^T = I + s^2 (A A^T - (A dir)(A dir)^T) >= I, so the factorization is well
 * conditioned even for degenerate lobes. Returns the widened world-to-lobe map A' = C^-1 A
 * (M = C C^T); `amplitudeScale` receives sqrt(det V / det V') = 1 / det C, which conserves the
 * lobe's mass (its integral over space) and so the optical depth integrated over the image. */
SPOT_FN rmat3 spotWidenLobe(rmat3 A, rvec3 dir, real s, SPOT_OUT(real) amplitudeScale) {
    rvec3 ad = A * dir;
    rmat3 m = A * transpose(A) - outerProduct(ad, ad);
    m = s * s * m;
    m[0][0] += real(1.0);
    m[1][1] += real(1.0);
    m[2][2] += real(1.0);
    rmat3 c = spotCholesky3(m);
    amplitudeScale = real(1.0) / (c[0][0] * c[1][1] * c[2][2]);
    /* Inverse of the lower-triangular c, by forward substitution. */
    real i00 = real(1.0) / c[0][0];
    real i11 = real(1.0) / c[1][1];
    real i22 = real(1.0) / c[2][2];
    real i10 = -c[0][1] * i00 * i11;
    real i21 = -c[1][2] * i11 * i22;
    real i20 = -(c[0][2] * i00 + c[1][2] * i10) * i22;
    rmat3 cInv = rmat3(rvec3(i00, i10, i20), rvec3(real(0.0), i11, i21), rvec3(real(0.0), real(0.0), i22));
    return cInv * A;
}

/* The entire exponential integral Ein(x) = integral from 0 to x of (1 - e^-u) / u du, x >= 0: the
 * area a 2D Gaussian of peak optical depth x covers, over 2 pi sqrt(det) of its covariance
 * (integral of 1 - exp(-x g) over the plane, g the unit-peak Gaussian). Below 1 its series
 * (9 terms, error below 3e-8); from 1 ln x + gamma + E1(x), E1 by Abramowitz and Stegun 5.1.54
 * (x e^x E1(x) as a ratio of quartics, relative error below 5e-8). Relative error below 3e-7
 * everywhere; Ein(x) ~ x for small x, ~ ln x + 0.5772 for large. Branch-free: both forms are
 * computed and one is picked (lavapipe runs every branch its lanes take anyway). */
SPOT_FN real spotEin(real x) {
    real xs = min(x, real(1.0));
    real p = real(1.0 / 3265920.0);
    p = p * xs - real(1.0 / 322560.0);
    p = p * xs + real(1.0 / 35280.0);
    p = p * xs - real(1.0 / 4320.0);
    p = p * xs + real(1.0 / 600.0);
    p = p * xs - real(1.0 / 96.0);
    p = p * xs + real(1.0 / 18.0);
    p = p * xs - real(0.25);
    p = p * xs + real(1.0);
    real xl = max(x, real(1.0));
    real num = (((xl + real(8.5733287401)) * xl + real(18.0590169730)) * xl + real(8.6347608925)) * xl +
               real(0.2677737343);
    real den = (((xl + real(9.5733223454)) * xl + real(25.6329561486)) * xl + real(21.0996530827)) * xl +
               real(3.9584969228);
    real large = log(xl) + real(0.5772156649015329) + exp(-xl) / xl * num / den;
    return x < real(1.0) ? xs * p : large;
}

/* The inverse of spotEin for y >= 0: the x with Ein(x) = y, within 3e-7 relative. Three Newton
 * steps (Ein'(x) = (1 - e^-x) / x) from x - x^2/4 = y below 0.6 and x = e^(y - gamma) above;
 * Ein is concave, so after the first step the iterates rise to the root. */
SPOT_FN real spotEinInverse(real y) {
    real x = y < real(0.6) ? real(2.0) - real(2.0) * sqrt(max(real(1.0) - y, real(0.0)))
                           : max(exp(y - real(0.5772156649015329)), real(0.6));
    for (int i = 0; i < 3; ++i) {
        real slope = x > real(1e-4) ? (real(1.0) - exp(-x)) / x : real(1.0) - real(0.5) * x;
        x = max(x - (spotEin(x) - y) / slope, real(0.5) * x);
    }
    return x;
}
/* The optical depth from which a lobe of peak optical depth t (through its centre, along the
 * view) is drawn opaque by a binary splat (instanced), so that the opaque footprint covers as much
 * of the image as the lobe does: the region t g >= c of a Gaussian has area
 * 2 pi sqrt(det Sigma) ln(t / c), which is 2 pi sqrt(det Sigma) Ein(t) for c = t e^-Ein(t). A
 * fixed alpha of 0.5 (the paper's) drew no faint lobe at all (a far coat vanished) and
 * shrank opaque ones; c runs from t (a faint lobe: a dot of its own coverage's area) down to
 * e^-gamma = 0.56 (an opaque one). */
SPOT_FN real spotCoverThreshold(real t) { return t * exp(-spotEin(t)); }

/* J(x) = integral from 0 to x of Ein(u) / u du = sum_k (-1)^(k+1) x^k / (k! k^2), x >= 0: with Ein,
 * the second moment of what a 2D Gaussian of peak optical depth x covers. Over the plane, the
 * opacity 1 - exp(-x g) (g the unit-peak Gaussian of covariance Sigma) has integral
 * 2 pi sqrt(det Sigma) Ein(x) and covariance (J(x) / Ein(x)) Sigma: an opaque lobe's opacity
 * reaches further out than its optical depth's sigmas (its edge lies where x g ~ 1). Below 2 the
 * series (14 terms, relative error below 1e-10); from 2 its expansion
 * (ln x)^2 / 2 + gamma ln x + gamma^2 / 2 + pi^2 / 12 - e^-x / (x (x + 2.7462)) (the last term's
 * constant fitted here; relative error below 5e-6). */
SPOT_FN real spotEinMoment(real x) {
    real xs = min(x, real(2.0));
    real p = real(-5.8524212233314926e-14);
    p = p * xs + real(9.5023928028530262e-13);
    p = p * xs - real(1.4497747908241736e-11);
    p = p * xs + real(2.0704221806150180e-10);
    p = p * xs - real(2.7557319223985891e-09);
    p = p * xs + real(3.4021381758007273e-08);
    p = p * xs - real(3.8752480158730159e-07);
    p = p * xs + real(4.0492387431162940e-06);
    p = p * xs - real(3.8580246913580246e-05);
    p = p * xs + real(3.3333333333333332e-04);
    p = p * xs - real(2.6041666666666665e-03);
    p = p * xs + real(1.8518518518518517e-02);
    p = p * xs - real(1.2500000000000000e-01);
    p = p * xs + real(1.0000000000000000e+00);
    real xl = max(x, real(2.0));
    real lx = log(xl);
    real large = real(0.5) * lx * lx + real(0.5772156649015329) * lx + real(0.9890559953279725) -
                 exp(-xl) / (xl * (xl + real(2.746191617258081)));
    return x < real(2.0) ? xs * p : large;
}

/* How far a Gaussian of peak optical depth x covers relative to its sigmas: the covariance of its
 * opacity footprint over that of its optical depth, J(x) / Ein(x) (1 for a thin lobe, about
 * ln(x) / 2 for an opaque one). */
SPOT_FN real spotCoverageSpread(real x) {
    return x > real(1e-6) ? spotEinMoment(x) / spotEin(x) : real(1.0) + real(0.125) * x;
}

/* The x with Ein(x)^2 / J(x) = y, for 0 <= y < 2 (Ein^2 / J rises from 0, about x for small x,
 * towards 2, as 2 / (1 + (pi^2 / 6) / (ln x + gamma)^2)). Newton steps in ln x from the small
 * and the large form's inverses; relative error below 3e-4 in float (1e-11 in double). */
SPOT_FN real spotCoverageShapeInverse(real y) {
    real yl = min(y, real(1.9999999));
    real large = sqrt(real(1.6449340668482264) / max(real(2.0) / yl - real(1.0), real(1e-30))) -
                 real(0.5772156649015329);
    real u = y < real(1.0) ? log(max(y * (real(1.0) + real(0.375) * y), real(1e-30))) : large;
    for (int i = 0; i < 4; ++i) {
        real x = exp(u);
        real e = spotEin(x);
        real j = max(spotEinMoment(x), real(1e-30));
        real slope = e * (real(2.0) * (real(1.0) - exp(-x)) * j - e * e) / (j * j);
        u -= (e * e / j - y) / max(slope, real(1e-30));
    }
    return y > real(0.0) ? exp(u) : real(0.0);
}

/* EWA widening that keeps what a lobe covers of the image and where (docs/design.md,
 * "Filtering"). Seen along dir, a lobe is a 2D Gaussian of optical depth with peak t (through
 * its centre) and covariance Sigma, whose opacity footprint 1 - exp(-depth) covers
 * 2 pi sqrt(det Sigma) Ein(t) of the image plane with covariance m(t) Sigma (spotEinMoment,
 * m = J / Ein). The pixel filter (variance s^2 per axis) keeps that coverage and adds s^2 to the
 * footprint's covariance. The widened lobe is the Gaussian whose opacity footprint has exactly
 * these: covariance Sigma' = (m(t) Sigma + s^2 I) / m(t') and peak t' from
 * Ein(t')^2 / J(t') = r Ein(t)^2 / J(t), r = sqrt(det(m Sigma) / det(m Sigma + s^2 I)); in 3D,
 * V' = (m(t) V + s^2 (I - dir dir^T)) / m(t'). For a thin lobe (small t) m = 1 and this is
 * spotWidenLobe's mass conservation. spotWidenLobe alone keeps the optical depth over the image
 * and so widens an opaque strand thinner than a pixel into more cover than it has: splatting was
 * 11% too bright on fur. Keeping the coverage alone with the lobe's shape widened (Sigma + s^2 I)
 * lowers the peak and so shortens an opaque strand or blade along its length, whose opacity ends
 * where depth ~ 1: grass tips against the sky lost a sixth of their cover. Matching the second
 * moments as well keeps the length (the least-squares fit of a Gaussian to the filtered opacity
 * was within 1-2% of this coverage and stretch, measured for peaks 0.5 to 200 and aspect ratios
 * 1 to 10). r is the projected footprint's ratio: spotWidenLobe's 3D amplitude scale differs from
 * it wherever the lobe's axes are not aligned with dir, and using that instead had cost grazing
 * grass 7.8 dB. Returns the widened world-to-lobe map; `amplitude` (the lobe's peak extinction)
 * becomes the widened lobe's. */
SPOT_FN rmat3 spotWidenLobeCoverage(rmat3 A, rvec3 dir, real s, SPOT_INOUT(real) amplitude) {
    real along = length(A * dir); /* 1 / the lobe's depth per unit peak, along dir */
    real peak = amplitude * kSqrtTwoPi / along;
    real spread = spotCoverageSpread(peak);
    rmat3 spreadA = A * (real(1.0) / sqrt(spread)); /* covariance m V */
    real massScale;
    rmat3 widened = spotWidenLobe(spreadA, dir, s, massScale);
    real ratio = massScale * length(spreadA * dir) / length(widened * dir);
    real e = spotEin(peak);
    real shape = peak > real(1e-6) ? e * e / max(spotEinMoment(peak), real(1e-30)) : peak;
    real peakWidened = spotCoverageShapeInverse(ratio * shape);
    widened = widened * sqrt(spotCoverageSpread(peakWidened));
    amplitude = peakWidened * length(widened * dir) / kSqrtTwoPi;
    return widened;
}

/* A kernel lobe placed in the world by an impulse. The lobe is T = [L | c] in kernel space
 * (`lobeInv` = L^-1, `lobeCentre` = c); the impulse has kernel frame F (columns: kernel x, y, z in
 * world), scale s (world units per kernel unit), bend curvature kappa (radians per kernel unit)
 * and position p. A world point x lies at lobe-space u = A (x - centre), where the kernel-space
 * lobe is first bent (spotBendLobe), then x = p + F (s * k). Returns A; `centre` receives the
 * lobe's world centre. */
SPOT_FN rmat3 spotPlaceLobe(rmat3 lobeInv, rvec3 lobeCentre, rmat3 frame, rvec3 scale, real kappa,
                            rvec3 position, SPOT_OUT(rvec3) centre) {
    rmat3 bendRot;
    rvec3 c = spotBendLobe(lobeCentre, kappa, bendRot);
    centre = position + frame * (scale * c);
    rmat3 invScale = rmat3(rvec3(real(1.0) / scale.x, real(0.0), real(0.0)),
                           rvec3(real(0.0), real(1.0) / scale.y, real(0.0)),
                           rvec3(real(0.0), real(0.0), real(1.0) / scale.z));
    return lobeInv * transpose(bendRot) * invScale * transpose(frame);
}

/* ------------------------------------------------------------------------------------------ */
/* Smooth value noise (fields).                                                                 */
/* ------------------------------------------------------------------------------------------ */

/* Lattice value in [0,1] at integer point (ix, iy, iz): 24 hashed bits, exact in float. */
SPOT_FN real spotLatticeValue(uint ix, uint iy, uint iz, uint seed) {
    uint h = spotHash(seed ^ 0x3c6ef372u);
    h = spotHashCombine(h, ix);
    h = spotHashCombine(h, iy);
    h = spotHashCombine(h, iz);
    return real(h >> 8u) * real(1.0 / 16777215.0);
}

/* Quintic fade 6t^5 - 15t^4 + 10t^3: the noise is C2, no grid creases. */
SPOT_FN real spotFade(real t) { return t * t * t * (t * (t * real(6.0) - real(15.0)) + real(10.0)); }

/* floor(x) as a lattice index; coordinates are clamped to +-2^30 first (beyond that, float has
 * no fractional part and the noise is meaningless anyway). */
SPOT_FN uint spotLatticeIndex(real floored) {
    return uint(int(clamp(floored, real(-1073741824.0), real(1073741824.0))));
}

SPOT_FN real spotValueNoiseOctave(rvec3 p, uint seed) {
    rvec3 fl = floor(p);
    rvec3 f = p - fl;
    uint x0 = spotLatticeIndex(fl.x);
    uint y0 = spotLatticeIndex(fl.y);
    uint z0 = spotLatticeIndex(fl.z);
    real u = spotFade(f.x);
    real v = spotFade(f.y);
    real w = spotFade(f.z);
    real c000 = spotLatticeValue(x0, y0, z0, seed);
    real c100 = spotLatticeValue(x0 + 1u, y0, z0, seed);
    real c010 = spotLatticeValue(x0, y0 + 1u, z0, seed);
    real c110 = spotLatticeValue(x0 + 1u, y0 + 1u, z0, seed);
    real c001 = spotLatticeValue(x0, y0, z0 + 1u, seed);
    real c101 = spotLatticeValue(x0 + 1u, y0, z0 + 1u, seed);
    real c011 = spotLatticeValue(x0, y0 + 1u, z0 + 1u, seed);
    real c111 = spotLatticeValue(x0 + 1u, y0 + 1u, z0 + 1u, seed);
    real y0z0 = c000 + (c100 - c000) * u;
    real y1z0 = c010 + (c110 - c010) * u;
    real y0z1 = c001 + (c101 - c001) * u;
    real y1z1 = c011 + (c111 - c011) * u;
    real z0v = y0z0 + (y1z0 - y0z0) * v;
    real z1v = y0z1 + (y1z1 - y0z1) * v;
    return z0v + (z1v - z0v) * w;
}

/* Fractal value noise in [0,1]: `octaves` (1..8) at doubling frequency and halving amplitude,
 * each octave on its own lattice, normalized back to [0,1]. */
SPOT_FN real spotValueNoise(rvec3 p, int octaves, uint seed) {
    if (!(abs(p.x) < real(1e30)) || !(abs(p.y) < real(1e30)) || !(abs(p.z) < real(1e30)))
        p = rvec3(real(0.0));
    int n = clamp(octaves, 1, 8);
    real sum = real(0.0);
    real amplitudeSum = real(0.0);
    real amplitude = real(1.0);
    for (int o = 0; o < n; ++o) {
        sum += amplitude * spotValueNoiseOctave(p, spotHashCombine(seed, uint(o)));
        amplitudeSum += amplitude;
        amplitude *= real(0.5);
        p *= real(2.0);
    }
    return clamp(sum / amplitudeSum, real(0.0), real(1.0));
}

/* ------------------------------------------------------------------------------------------ */
/* Splatting (splat/passes/splatting_vk.cpp and the splat_*.glsl shaders).                             */
/* ------------------------------------------------------------------------------------------ */

/* 1 - exp(-x) for x >= 0, without cancellation for small x (GLSL has no expm1): the opacity of
 * an optical depth x. */
SPOT_FN real spotOneMinusExp(real x) {
    if (x < real(1e-3))
        return x * (real(1.0) - x * (real(0.5) - x * real(1.0 / 6.0)));
    return real(1.0) - exp(-x);
}

/* The ray o + t d (lobe space, as for spotLobeDepth) against a lobe truncated at k sigmas: the
 * peak parameter tStar (where the ray passes nearest the lobe's centre), the squared lobe-space
 * distance perp2 there, and the chord's half length halfChord (in t), so that the chord is
 * [tStar - halfChord, tStar + halfChord]. Returns false (and zeros) when the ray misses the
 * support. The splatting shaders (spotLobeChord) and the CPU reference share it. */
SPOT_FN bool spotLobeLine(rvec3 o, rvec3 d, real k, SPOT_OUT(real) tStar, SPOT_OUT(real) perp2,
                          SPOT_OUT(real) halfChord) {
    tStar = real(0.0);
    perp2 = real(0.0);
    halfChord = real(0.0);
    real dd = dot(d, d);
    if (!(dd > real(0.0)))
        return false;
    tStar = -dot(o, d) / dd;
    rvec3 perp = o + tStar * d;
    perp2 = dot(perp, perp);
    if (!(perp2 < k * k))
        return false;
    halfChord = sqrt((k * k - perp2) / dd);
    return true;
}

/* The chord [ta, tb] of the ray o + t d (lobe space, as for spotLobeDepth) inside a lobe truncated
 * at k sigmas. Returns false (and ta = tb = 0) when the ray misses the support. */
SPOT_FN bool spotLobeChord(rvec3 o, rvec3 d, real k, SPOT_OUT(real) ta, SPOT_OUT(real) tb) {
    ta = real(0.0);
    tb = real(0.0);
    real tStar;
    real perp2;
    real halfChord;
    if (!spotLobeLine(o, d, k, tStar, perp2, halfChord))
        return false;
    ta = tStar - halfChord;
    tb = tStar + halfChord;
    return true;
}

/* Exact extent along one image axis of the ellipsoid x = c + M u, |u| <= k (M = A^-1, A the
 * world-to-lobe map), seen from `eye` looking along unit `forward`: the range [lo, hi] of
 * s(x) = dot(x - eye, axis) / dot(x - eye, forward) (perspective: tangent units) or of
 * dot(x - eye, axis) (orthographic: world units), `axis` a unit image axis. The bounding values
 * are the planes through the eye tangent to the ellipsoid, roots of a quadratic (a plane
 * n.x = d touches the ellipsoid where |n.(c - eye) - d| = k |M^T n|). `zLo`, `zHi` receive the
 * view depth range. Returns false (and an unbounded range) when a perspective ellipsoid reaches
 * the eye plane. */
SPOT_FN bool spotEllipsoidRange(rvec3 rel, rmat3 M, real k, rvec3 axis, rvec3 forward, bool orthographic,
                                SPOT_OUT(real) lo, SPOT_OUT(real) hi, SPOT_OUT(real) zLo, SPOT_OUT(real) zHi) {
    rvec3 ma = transpose(M) * axis;
    rvec3 mf = transpose(M) * forward;
    real ar = dot(rel, axis);
    real af = dot(rel, forward);
    real k2 = k * k;
    real depthHalf = k * length(mf);
    zLo = af - depthHalf;
    zHi = af + depthHalf;
    if (orthographic) {
        real h = k * length(ma);
        lo = ar - h;
        hi = ar + h;
        return true;
    }
    real qa = af * af - k2 * dot(mf, mf);
    if (!(af > real(0.0)) || !(qa > real(0.0))) {
        lo = real(-3.0e38);
        hi = real(3.0e38);
        return false;
    }
    real qb = ar * af - k2 * dot(ma, mf);
    real qc = ar * ar - k2 * dot(ma, ma);
    real root = sqrt(max(qb * qb - qa * qc, real(0.0)));
    lo = (qb - root) / qa;
    hi = (qb + root) / qa;
    return true;
}

/* Lambert + ambient shading factor (docs/design.md section 4): ambient + (1 - ambient) max(0, n.l), n and
 * l unit. The reference shades with the same formula. */
SPOT_FN real spotLambertFactor(rvec3 n, rvec3 l, real ambient) {
    return ambient + (real(1.0) - ambient) * max(real(0.0), dot(n, l));
}

/* A lobe's term of the gradient of the negative summed density (which points out of the strands)
 * at lobe-space point u = A (x - centre), rho its density there: rho A^T u. */
SPOT_FN rvec3 spotLobeGradient(rmat3 A, rvec3 u, real rho) { return rho * (transpose(A) * u); }

/* The shading normal of a medium from its summed spotLobeGradient terms g: g / |g|, or `fallback`
 * (the reverse view direction) where g vanishes or is not below `far` (not finite). The CPU
 * reference and the ray march shade with it. */
SPOT_FN rvec3 spotGradientNormal(rvec3 g, rvec3 fallback, real far) {
    real len = length(g);
    return len > real(0.0) && len < far ? g / len : fallback;
}

/* The primary ray of a camera, as noise::CameraRays builds it: sx in [-1, 1] left to right, sy in
 * [-1, 1] bottom to top (sx = 2 px / width - 1, sy = 1 - 2 py / height); `right` and `up` are the
 * unit camera axes times the half width and half height of the view at unit distance
 * (perspective) or in world units (orthographic). `dir` is unit length, so t is world distance. */
SPOT_FN void spotCameraRay(rvec3 eye, rvec3 forward, rvec3 right, rvec3 up, bool orthographic,
                           real sx, real sy, SPOT_OUT(rvec3) origin, SPOT_OUT(rvec3) dir) {
    if (orthographic) {
        origin = eye + sx * right + sy * up;
        dir = forward;
    } else {
        origin = eye;
        dir = normalize(forward + sx * right + sy * up);
    }
}

/* Continuous pixel position p (pixels, (0, 0) the top-left corner of the image; noise/camera.h)
 * of an image of `size` pixels, as the screen coordinates spotCameraRay takes: sx in [-1, 1] left
 * to right, sy in [-1, 1] bottom to top. */
SPOT_FN rvec2 spotPixelToScreen(rvec2 p, rvec2 size) {
    return rvec2(real(2.0) * p.x / size.x - real(1.0), real(1.0) - real(2.0) * p.y / size.y);
}

/* The primary ray through continuous pixel position p of an image of `size` pixels (the one
 * mapping from pixels to rays: noise::CameraRays, the splatting and baked shaders and the ray
 * march all call it); `right`, `up` and the rest as for spotCameraRay. */
SPOT_FN void spotPixelRay(rvec3 eye, rvec3 forward, rvec3 right, rvec3 up, bool orthographic,
                          rvec2 size, rvec2 p, SPOT_OUT(rvec3) origin, SPOT_OUT(rvec3) dir) {
    rvec2 s = spotPixelToScreen(p, size);
    spotCameraRay(eye, forward, right, up, orthographic, s.x, s.y, origin, dir);
}

/* Weighted blended OIT weights (McGuire and Bavoil 2013, "Weighted Blended Order-Independent
 * Transparency", JCGT 2(2)). Constant: w = 1, a plain unordered blend (paper fig. 3.3).
 * McGuire-Bavoil: their eq. (7), w = alpha clamp(10 / (1e-5 + (z/5)^2 + (z/200)^6), 1e-2, 3e3),
 * with z the view depth in world units, unscaled: MB13 tuned the constants for depths of about
 * 0.1 to 500; our scenes are 1-10 units deep, the steep (z/5)^2 part, so a kernel twice as far
 * weighs about four times less. */
SPOT_CONST uint kSpotWeightConstant = 0u;
SPOT_CONST uint kSpotWeightMcGuireBavoil = 1u;
SPOT_FN real spotOitWeight(real z, real alpha, uint mode) {
    if (mode == kSpotWeightConstant)
        return real(1.0);
    real a = z / real(5.0);
    real b = z / real(200.0);
    real b2 = b * b;
    return alpha * min(max(real(10.0) / (real(1e-5) + a * a + b2 * b2 * b2), real(1e-2)), real(3e3));
}

/* Reversed depth-buffer value of view depth z (world units) with near plane `zNear`: near / z,
 * 1 at the near plane and falling towards 0 far away, so float depth keeps its relative precision
 * at every distance. Compare with GREATER. */
SPOT_FN real spotReversedDepth(real z, real zNear) { return zNear / max(z, zNear); }

/* Inverse of erf on (-1, 1), Giles 2010 ("Approximating the erfinv function", GPU Computing Gems):
 * relative error about 4e-7 in single precision (also in the double instantiation: nothing on the
 * CPU reference's path uses it). Arguments are clamped just inside (-1, 1). */
SPOT_FN real spotErfinvApprox(real x) {
    x = min(max(x, real(-0.99999994)), real(0.99999994));
    real w = -log((real(1.0) - x) * (real(1.0) + x));
    real p;
    if (w < real(5.0)) {
        w = w - real(2.5);
        p = real(2.81022636e-08);
        p = real(3.43273939e-07) + p * w;
        p = real(-3.5233877e-06) + p * w;
        p = real(-4.39150654e-06) + p * w;
        p = real(0.00021858087) + p * w;
        p = real(-0.00125372503) + p * w;
        p = real(-0.00417768164) + p * w;
        p = real(0.246640727) + p * w;
        p = real(1.50140941) + p * w;
    } else {
        w = sqrt(w) - real(3.0);
        p = real(-0.000200214257);
        p = real(0.000100950558) + p * w;
        p = real(0.00134934322) + p * w;
        p = real(-0.00367342844) + p * w;
        p = real(0.00573950773) + p * w;
        p = real(-0.0076224613) + p * w;
        p = real(0.00943887047) + p * w;
        p = real(1.00167406) + p * w;
        p = real(2.83297682) + p * w;
    }
    return p * x;
}

/* The ray parameter t at which a lobe's optical depth along o + t d, counted from the start of its
 * chord inside [t0, t1] (as spotLobeDepth integrates it), reaches `fraction` (in [0, 1]) of its
 * total. The peak parameter when the ray misses. */
SPOT_FN real spotLobeDepthQuantile(rvec3 o, rvec3 d, real t0, real t1, real k, real fraction) {
    real dd = dot(d, d);
    if (!(dd > real(0.0)))
        return t0;
    real tStar = -dot(o, d) / dd;
    rvec3 perp = o + tStar * d;
    real perp2 = dot(perp, perp);
    if (!(perp2 < k * k))
        return tStar;
    real halfChord = sqrt((k * k - perp2) / dd);
    real a = max(t0, tStar - halfChord);
    real b = min(t1, tStar + halfChord);
    if (!(b > a))
        return tStar;
    real len = sqrt(dd);
    real erfA = real(1.0) - spotErfc((a - tStar) * len * kInvSqrtTwo);
    real erfB = real(1.0) - spotErfc((b - tStar) * len * kInvSqrtTwo);
    real x = spotErfinvApprox(erfA + fraction * (erfB - erfA));
    return min(max(tStar + x / (len * kInvSqrtTwo), a), b);
}

/* Where, as a fraction of a medium's optical depth tau, the emission seen through it reaches the
 * share q (in [0, 1]) of its total: seen from the front, emission up to depth s is 1 - exp(-s), so
 * s = -ln(1 - q (1 - exp(-tau))). Tends to q for a thin medium and to ln(1 / (1 - q)) / tau for an
 * opaque one (its front surface). */
SPOT_FN real spotEmissionQuantileFraction(real tau, real q) {
    if (!(tau > real(0.0)))
        return q;
    real x = q * spotOneMinusExp(tau);
    real s = x < real(1e-3) ? x * (real(1.0) + x * (real(0.5) + x * real(1.0 / 3.0))) : -log(real(1.0) - x);
    return min(s / tau, real(1.0));
}

/* How much of a lobe's own light it lets the eye see (docs/design.md, "Lighting on the GPU"): what
 * it emits towards the eye, weighted by exp(-its own optical depth towards the light) at the
 * emitting point, over what it emits. In lobe space the lobe is a unit Gaussian (truncated at k
 * sigmas), so this depends on three numbers only: a = amp / |A v| and b = amp / |A l|, its optical
 * depth scales along the eye's rays and the light's, and c, the cosine between the two directions
 * in lobe space. The eye's rays cross the lobe at offsets r from its centre, on three rings
 * (r = 0.5, 1.25, 2 sigmas, each standing for its annulus) at angles 0, 90 and 180 degrees from
 * the side the light comes from (the ray at -90 sees what the one at +90 sees); along each, 2
 * points split what the ray sees it emit into equal shares. `rings`: how many of the three (0:
 * the ray through the centre alone). An opaque strand shows its lit side to an eye beside the
 * light and mostly its thin, less shadowed fringe to an eye across from it. */
SPOT_FN real spotOwnShadow(real a, real b, real c, real k, uint rings) {
    if (!(a > real(0.0)) || !(b >= real(0.0)))
        return real(1.0);
    rvec3 n = rvec3(real(0.0), real(0.0), real(1.0));                       // the eye's rays
    rvec3 m = rvec3(sqrt(max(real(1.0) - c * c, real(0.0))), real(0.0), c); // towards the light
    real seen = real(0.0);
    real lit = real(0.0);
    real tPeak;
    for (uint ring = rings > 0u ? 1u : 0u; ring <= rings; ++ring) {
        // annuli [0, .9], [.9, 1.6], [1.6, 2.5] / pi, a quarter each way; the centre alone: 1
        real radius = ring == 0u   ? real(0.0)
                      : ring == 1u ? real(0.5)
                      : ring == 2u ? real(1.25)
                                   : real(2.0);
        real area = ring == 0u   ? real(1.0)
                    : ring == 1u ? real(0.2025)
                    : ring == 2u ? real(0.4375)
                                 : real(0.9225);
        for (uint i = 0u; i < (ring == 0u ? 1u : 3u); ++i) {
            rvec3 offset = radius * (i == 0u   ? rvec3(real(1.0), real(0.0), real(0.0))
                                     : i == 1u ? rvec3(real(0.0), real(1.0), real(0.0))
                                               : rvec3(real(-1.0), real(0.0), real(0.0)));
            real tau = a * spotLobeDepth(offset, n, real(-1e30), real(1e30), k, tPeak);
            real emitted = (i == 1u ? real(2.0) : real(1.0)) * area * spotOneMinusExp(tau);
            if (!(emitted > real(0.0)))
                continue;
            real own = real(0.0);
            for (uint j = 0u; j < 2u; ++j) {
                real f = spotEmissionQuantileFraction(tau, (real(j) + real(0.5)) * real(0.5));
                real t = spotLobeDepthQuantile(offset, n, real(-1e30), real(1e30), k, f);
                own += real(0.5) *
                       exp(-b * spotLobeDepth(offset + t * n, m, real(0.0), real(1e30), k, tPeak));
            }
            seen += emitted;
            lit += emitted * own;
        }
    }
    return seen > real(0.0) ? lit / seen : real(1.0);
}
