/* spot_shadow.h: the GPU methods' light-space structure and lit shading inputs, shared by C++
 * (shaders/spot_shadow.hpp, namespace spot::gpu) and GLSL (after spot_shared.h). Every member is
 * a 16-byte vector (std430 = C++ layout).
 *
 * The structure is a deep opacity map per shadow view (docs/design.md, "Lighting on the GPU"):
 * a view looks at the frame's kernels and mesh from a light (orthographic for a directional light
 * or a sky direction, perspective from a point light). Each of its R x R texels is one ray from
 * the light; along it, the optical depth of every lobe (widened by the texel, mass conserved) is
 * summed exactly over D layers of thickness `layer` that start where the first lobe's support
 * begins in the texel's tile of kShadowTile x kShadowTile texels (Yuksel and Keyser 2008 start
 * them per texel; per tile costs one atomic a lobe, and the layers span the tile's depths). A
 * second map holds the depth of the mesh's nearest triangle along each texel's ray. A lookup at a world
 * point interpolates the cumulative optical depth between layer boundaries and bilinearly between
 * texels, and multiplies by the mesh's visibility.
 *
 * Light-space coordinates of a point p: (x, y) on the view's plane and s along the ray.
 *   orthographic: x = p.U, y = p.W, s = p.D (D the direction light travels);
 *   perspective:  q = p - origin, z = q.D, x = q.U / z, y = q.W / z, s = |q| (z > 0 only).
 * The texels cover the square around the mesh's box (as posed) grown by the kernel's reach, which
 * holds every lobe's support; the host finds it each frame (SpotShadowExtent).
 */

SPOT_CONST uint kShadowGroup = 64u;       /* invocations per workgroup of every shadow pass */
SPOT_CONST uint kShadowMaxViews = 16u;    /* the lights with shadows plus the sky's directions */
SPOT_CONST uint kShadowMaxSky = 8u;       /* sky directions at most */
SPOT_CONST uint kShadowMaxLayers = 16u;
SPOT_CONST uint kShadowTile = 16u;        /* a work item covers at most 16 x 16 texels */
SPOT_CONST uint kShadowTileBits = 13u;    /* tile coordinates are 13 bits: R <= 16 x 8192 */
/* Optical depth is summed in fixed point (integer atomics: the same sums in any order), and one
 * lobe's deposit in one layer is clamped below 2^32 / (kShadowFixed x a few thousand). */
SPOT_CONST float kShadowFixed = 4096.0;
SPOT_CONST float kShadowMaxDeposit = 64.0;
SPOT_CONST uint kShadowTriangleBit = 0x80000000u; /* a work item's source is a mesh triangle */

/* Descriptor bindings (one numbering; each pipeline declares what it reads). 23 and up so the
 * splat passes that look the structure up (prepare, the mesh) keep their own bindings. */
SPOT_CONST uint kShadowBindParams = 23u;   /* SpotLitParams */
SPOT_CONST uint kShadowBindExtents = 24u;  /* SpotShadowExtent[view] */
SPOT_CONST uint kShadowBindLayers = 25u;   /* uint[]: per view R x R x D x 3: optical depth
                                              and its two moments in fixed point, then (prefix
                                              pass) the cumulative depth (float bits) and the
                                              layer's box (packUnorm2x16) */
SPOT_CONST uint kShadowBindFirst = 26u;    /* uint[]: per view, per tile: where the layers start
                                              (s, spotOrderedBits), then per texel the mesh's
                                              depth (R x R, the same) */
SPOT_CONST uint kShadowBindPlaced = 27u;   /* SpotWorldLobe[impulse * lobes + l]: placed, unwidened */
SPOT_CONST uint kShadowBindItems = 28u;    /* SpotShadowList, then uvec2[]: the work items */
SPOT_CONST uint kShadowBindImpulses = 29u; /* SpotImpulse[] */
SPOT_CONST uint kShadowBindLobes = 30u;    /* SpotLobe[]: the kernel */
SPOT_CONST uint kShadowBindCount = 31u;    /* uint: the impulse count */
SPOT_CONST uint kShadowBindVertices = 32u; /* SpotMeshVertex[] (posed) */
SPOT_CONST uint kShadowBindIndices = 33u;  /* uint[3 x triangles] */

/* A lobe's own shadow (spot_shared.h's spotOwnShadow, 3 rings) tabulated once per support k: a
 * grid over (ln a, ln b, c), each of a and b from e^-7 to e^7 (clamped: below, the lobe is
 * transparent that way; above, opaque), c from -1 to 1. It follows the params (kShadowBindParams:
 * SpotLitParams, then float[kOwnShadowA x kOwnShadowB x kOwnShadowC], a fastest). A trilinear
 * lookup is within 0.006 of the function (0.001 mean) over a and b in [e^-5, e^4], at the cost of
 * eight loads instead of its 9 x 3 erf evaluations. */
SPOT_CONST uint kOwnShadowA = 32u;
SPOT_CONST uint kOwnShadowB = 32u;
SPOT_CONST uint kOwnShadowC = 17u;
SPOT_CONST float kOwnShadowLogLo = -7.0;
SPOT_CONST float kOwnShadowLogHi = 7.0;

/* The depth scale at node i of n along a or b. */
SPOT_FN real spotOwnShadowNode(uint i, uint n) {
    return exp(kOwnShadowLogLo + (kOwnShadowLogHi - kOwnShadowLogLo) * real(i) / real(n - 1u));
}

/* The table's cell for (a, b, c): the index of its lowest corner and the weights towards the
 * upper corners along a, b and c. */
SPOT_FN uint spotOwnShadowCell(real a, real b, real c, SPOT_OUT(rvec3) w) {
    rvec3 f = rvec3(
        clamp((log(max(a, real(1e-30))) - kOwnShadowLogLo) / (kOwnShadowLogHi - kOwnShadowLogLo),
              real(0.0), real(1.0)) *
            real(kOwnShadowA - 1u),
        clamp((log(max(b, real(1e-30))) - kOwnShadowLogLo) / (kOwnShadowLogHi - kOwnShadowLogLo),
              real(0.0), real(1.0)) *
            real(kOwnShadowB - 1u),
        clamp(c * real(0.5) + real(0.5), real(0.0), real(1.0)) * real(kOwnShadowC - 1u));
    uint ia = min(uint(f.x), kOwnShadowA - 2u);
    uint ib = min(uint(f.y), kOwnShadowB - 2u);
    uint ic = min(uint(f.z), kOwnShadowC - 2u);
    w = f - rvec3(real(ia), real(ib), real(ic));
    return (ic * kOwnShadowB + ib) * kOwnShadowA + ia;
}

/* A light of a lit frame. */
struct SpotLitLight {
    vec4 where;    /* directional: xyz unit towards the light, w 0; point: xyz position, w 1 */
    vec4 radiance; /* rgb: colour x intensity; w: its shadow view + 1 (0: shadows off) */
};

/* A kernel lobe's lit model (spot_light.h). */
struct SpotLitLobe {
    uvec4 model;    /* x: kSpotShade*; y: the shortest kernel axis (flake's normal) */
    vec4 axis;      /* xyz: the kernel-space longest axis, root to tip (strand's tangent) */
    vec4 primary;   /* strand highlights: shift, width (radians), strength */
    vec4 secondary;
};

/* A shadow view (written by the host). */
struct SpotShadowView {
    vec4 origin;   /* xyz: the point light (perspective); w: 1 perspective, 0 orthographic */
    vec4 axisU;    /* xyz: unit x axis; w: texels per side R */
    vec4 axisW;    /* xyz: unit y axis; w: layers D */
    vec4 axisD;    /* xyz: unit direction of travel (orthographic) or the frustum's axis; w: layer
                      thickness (world units) */
    uvec4 offsets; /* x: first word of its layers; y: of its start map (one word a tile); z: of
                      its mesh depth map (in kShadowBindFirst); w: R */
};

/* Everything a lit frame's shading reads. */
struct SpotLitParams {
    uvec4 counts;    /* x: lights; y: sky directions; z: shadow views; w: kernel lobes */
    vec4 sky;        /* rgb: the sky's radiance x 2 / (sky directions); w: unused */
    vec4 skyDirs[kShadowMaxSky];    /* xyz: unit direction towards the sky; w: its view (float) */
    SpotLitLight lights[8];
    SpotLitLobe lobes[8];
    SpotShadowView views[kShadowMaxViews];
};

/* A view's extent in light-space x and y (order-preserving bits, spotOrderedBits). */
struct SpotShadowExtent {
    uvec4 lo; /* x, y: light-space lower corner; z, w unused */
    uvec4 hi; /* x, y: upper corner */
};

/* The work items' list: its indirect dispatch, then its count (the items follow). */
struct SpotShadowList {
    uint groupsX;
    uint groupsY;
    uint groupsZ;
    uint count;
};

/* Order-preserving bits of a float (the unsigned order of the result is the float order). */
SPOT_FN uint spotOrderedBits(uint bits) {
    return (bits & 0x80000000u) != 0u ? ~bits : (bits | 0x80000000u);
}
SPOT_FN uint spotOrderedToBits(uint ordered) {
    return (ordered & 0x80000000u) != 0u ? (ordered & 0x7fffffffu) : ~ordered;
}

/* The square the texels cover, from a view's extent: lower corner (x, y) and texel size (z). The
 * larger side plus one texel each way (lookups at the border keep a neighbour). */
SPOT_FN rvec3 spotShadowSquare(rvec2 lo, rvec2 hi, real texels) {
    rvec2 centre = real(0.5) * (lo + hi);
    real side = max(max(hi.x - lo.x, hi.y - lo.y), real(1e-20));
    real h = side / max(texels - real(2.0), real(1.0));
    return rvec3(centre - real(0.5) * texels * h, h);
}

/* The shadow passes' push constants. */
struct SpotShadowPush {
    uvec4 n; /* x: what the dispatch runs over (impulse capacity, triangles, vertices or texels);
                y: lobes per kernel; z: shadow views; w: the item list's capacity */
    vec4 k;  /* x: the support (sigmas) */
};

/* Tests: light_probe.comp looks the structure up at points (vec4[]: xyz the point, w its view;
 * w receives the transmittance). */
SPOT_CONST uint kShadowBindProbe = 34u;
