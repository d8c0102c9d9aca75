/* spot_splat.h: the splatting renderer's structs, bindings, specialization constants and constants,
 * shared by C++ and GLSL (splat/passes/splatting_vk.cpp and the splat_* shaders it runs).
 *
 * Same rules as spot_layout.h: 16-byte members only, so std430 (and push-constant) layout equals
 * the C++ layout; pass_vk.h includes this file inside a namespace with glm types and
 * static_asserts the sizes. Units: world units; pixels with (0, 0) the top-left corner of the
 * top-left pixel (noise/camera.h); colours linear RGB.
 */
#ifndef SPOT_CONST
#define SPOT_CONST const
#endif

/* Everything a pass needs to know about the frame: the push constants of every splat pipeline
 * (128 bytes, the limit lavapipe guarantees). */
struct SpotSplatFrame {
    vec4 eye;      /* xyz: camera position; w: 1 orthographic, 0 perspective */
    vec4 forward;  /* xyz: unit view direction; w: near plane (view depth) of the depth mapping */
    vec4 right;    /* xyz: unit right axis; w: half width of the view at unit depth (perspective) or
                      in world units (orthographic) */
    vec4 up;       /* xyz: unit up axis (image rows grow downwards); w: half height, likewise */
    vec4 size;     /* x, y: image width, height (pixels); z: pixel footprint per unit view depth
                      (perspective) or in world units (orthographic); w: lobe support k (sigmas) */
    uvec4 counts;  /* x: impulse capacity (the count itself is in a buffer); y: lobes per kernel;
                      z: kernel samples N (0 = analytic); w: kSplatFlag* bits */
    vec4 light;    /* xyz: unit direction towards the light (world); w: ambient in [0, 1] */
    vec4 base;     /* rgb: base mesh colour; w: unused */
};

/* One base-mesh vertex for vertex pulling (32 bytes). */
struct SpotMeshVertex {
    vec4 position; /* xyz: world; w unused */
    vec4 normal;   /* xyz: unit normal; w unused */
};

/* One lobe as the pixels of this frame see it (64 bytes), made by splat_prepare.comp from the
 * world lobe (A, c) and the camera. The pixel at p (pixel units, its centre) looks along the ray
 * origin(p) + t e(p), t its view depth: e(p) is the direction scaled to unit view depth
 * (dot(e, forward) = 1) for perspective, the unit view direction for orthographic. In lobe
 * space that ray is o' + t v with o' = A (origin - c) and v = A e. One of the two is affine in
 * the pixel and the other one point: for perspective v(p) = A e(p) is affine and o' = A (eye - c)
 * the same for every pixel; for orthographic the other way round. With delta = p - ref:
 *   a(p) = a0 + delta.x ax + delta.y ay   the affine one (v for perspective, o' for orthographic);
 *   b                                     the constant one.
 * A pixel then takes w = o' x v and n = o'.v: the ray's squared distance from the lobe centre in
 * lobe units is |w|^2 / |v|^2, and the density peaks at t* = -n / |v|^2 (spotScreenLobeDepth).
 * The fragment shaders get a(p) interpolated (noperspective, exact for an affine function) and b
 * flat, so no pixel pays for a matrix product; the compute paths evaluate a(p) themselves. The
 * lobe's colour is not stored: it is the kernel lobe's (a specialization constant) times the
 * impulse's (SpotKernelBound.color). (docs/design.md section 4.) */
struct SpotScreenLobe {
    vec4 a0; /* xyz: a at ref; w: ref.x (pixels) */
    vec4 ax; /* xyz: a's change per pixel along x; w: ref.y */
    vec4 ay; /* xyz: a's change per pixel along y; w: peak extinction x weight (x EWA amplitude);
                0: the lobe is off */
    vec4 b;  /* xyz: b; w: instanced's cover threshold, the optical depth from which the lobe
                covers a pixel opaque (spotCoverThreshold of its peak along the view) */
};

/* Screen bound of one kernel for the current view (48 bytes): an oriented rectangle holding every
 * pixel centre whose ray meets the kernel's support (its lobes' k-sigma ellipsoids project to
 * ellipses; the rectangle is their union's bound along the union's principal axis). */
struct SpotKernelBound {
    vec4 quad; /* xy: centre (pixels); zw: half extents along u and along v = (-u.y, u.x);
                  empty (culled) when z <= 0 */
    vec4 axis; /* xy: unit u (pixels); z: view depth of the kernel's centre of mass (sorting);
                  w: nearest view depth of its support (the quad's depth: behind the mesh, a
                  pixel's ray cannot reach the kernel before the mesh, so the depth test skips
                  it) */
    vec4 color; /* rgb: the impulse's colour multiplier (a lobe's colour is the kernel lobe's times
                   this); w: unused */
};

/* The quads' draw: an indexed triangle list, kernel k's quad the vertices 4k .. 4k + 3 (corner
 * c = index & 3: bit 0 the +u side, bit 1 the +v side) as the triangles (0, 1, 2) and (1, 3, 2),
 * those of a strip each led by the vertex that led it there (flat inputs come from it). One
 * draw of 6 indices a kernel rather than one instance of a 4-vertex strip a kernel: lavapipe
 * pays per instance, and shades each index's vertex once (docs/design.md section 8). */
SPOT_CONST uint kSplatQuadIndices = 6u;
/* The indirect buffer (kSplatBindDraw): its length in words and where the small kernels'
 * dispatch and count lie in it. */
SPOT_CONST uint kSplatDrawWords = 12u;
SPOT_CONST uint kSplatDrawDispatch = 8u;
SPOT_CONST uint kSplatDrawSmallCount = 11u;

/* Descriptor bindings of the splat pipelines (one numbering for all; each pipeline declares the
 * ones it reads). C++ and GLSL use these names, never numbers. */
SPOT_CONST uint kSplatBindImpulses = 0u;     /* SpotImpulse[] (prepare) */
SPOT_CONST uint kSplatBindLobes = 1u;        /* SpotLobe[]: the kernel (prepare) */
SPOT_CONST uint kSplatBindWorldLobes = 2u;   /* SpotWorldLobe[kernel * lobes + l] */
SPOT_CONST uint kSplatBindScreenLobes = 3u;  /* SpotScreenLobe[kernel * lobes + l] */
SPOT_CONST uint kSplatBindBounds = 4u;       /* SpotKernelBound[kernel] */
SPOT_CONST uint kSplatBindCount = 5u;        /* uint: the impulse count */
SPOT_CONST uint kSplatBindVisible = 6u;      /* uint[]: kept kernels, in draw order */
SPOT_CONST uint kSplatBindDraw = 7u;         /* uint[kSplatDrawWords]: [0, 5)
                                                VkDrawIndexedIndirectCommand of the quads;
                                                [kSplatDrawDispatch, +3)
                                                VkDispatchIndirectCommand of the small kernels'
                                                pass; [kSplatDrawSmallCount] their count */
SPOT_CONST uint kSplatBindMeshDistance = 8u; /* r32f image: ray distance to the mesh */
SPOT_CONST uint kSplatBindClosest = 9u;      /* uint64_t[pixel]: hybrid's closest (depth, kernel) */
SPOT_CONST uint kSplatBindKeys = 10u;        /* uint[]: sorted's sort keys */
SPOT_CONST uint kSplatBindBase = 11u;        /* rgba32f image: base colour (resolve) */
SPOT_CONST uint kSplatBindAccum = 12u;       /* rgba32f image: OIT accumulation (resolve) */
SPOT_CONST uint kSplatBindOpticalDepth = 13u; /* r32f image: summed optical depth (resolve) */
SPOT_CONST uint kSplatBindClosestKernel = 14u; /* r32ui image: hybrid depth pass's kernel */
SPOT_CONST uint kSplatBindResult = 15u;      /* rgba32f image: the frame's result */
SPOT_CONST uint kSplatBindCounters = 16u;    /* SpotSplatCounters (counted frames) */
SPOT_CONST uint kSplatBindVertices = 17u;    /* SpotMeshVertex[] (the base mesh pass) */
SPOT_CONST uint kSplatBindSmall = 18u;       /* uint[]: the small kernels (compute path), by
                                                size class, each in impulse order */
SPOT_CONST uint kSplatBindOitFixed = 19u;    /* uint64_t[pixel * kSplatFixedChannels + c]: the
                                                small kernels' OIT sums in fixed point */
SPOT_CONST uint kSplatBindOitTiles = 20u;    /* uint[tile]: non-zero where some pixel of the
                                                kSplatResolveTile^2 tile has fixed-point sums */
SPOT_CONST uint kSplatBindClosestList = 21u; /* SpotSplatList, then uint[pixel]: the pixels with a
                                                closest kernel (hybrid, instanced resolve) */
SPOT_CONST uint kSplatBindClipList = 22u;    /* SpotSplatList, then uint[kernel]: the kernels with
                                                a lobe that projects to no ellipse (prepare) */

/* A list for an indirect second dispatch over what a first one found. The resolve's list of the
 * pixels with a closest kernel (hybrid, instanced): its first dispatch resolves every other pixel
 * and lists these, packed x | y << 16; its second, indirect, evaluates the closest kernel at each
 * listed pixel (kSplatSpecResolveList). lavapipe runs a shader's straight-line code for every
 * SIMD batch of 8 pixels, whether or not a lane needs it, so one dispatch evaluating the kernel
 * where a pixel has one cost that evaluation at every pixel. The prepare's list, the same way: the
 * kernels with a lobe that projects to no ellipse, bounded by its second dispatch
 * (kSplatSpecClipped). */
struct SpotSplatList {
    uint groupsX; /* the second dispatch's VkDispatchIndirectCommand: (count + 63) / 64, 1, 1 */
    uint groupsY;
    uint groupsZ;
    uint count; /* listed pixels (or kernels) */
};

/* Counters the splat pass writes when counting (RenderSettings::countFragments). */
struct SpotSplatCounters {
    uvec4 fragments; /* x, y: fragments shaded (low and high 32 bits); z, w: pixels where a
                        kernel's alpha >= 1/255 (low, high) */
};

/* Specialization constant ids: each pipeline is compiled for one setting, not every path. What
   changes the bindings a pass declares (the hybrid's closest kernel, what a resolve reads) is a
   module of its own instead (shaders/CMakeLists.txt, SPOT_SHADER_VARIANTS); ids 6 and 8 were
   those and are free. */
SPOT_CONST uint kSplatSpecLobes = 0u;        /* uint: lobes per kernel, 1..8 */
SPOT_CONST uint kSplatSpecSamples = 1u;      /* uint: kernel samples N, 0 = analytic */
SPOT_CONST uint kSplatSpecLambert = 2u;      /* bool: Lambert shading */
SPOT_CONST uint kSplatSpecOrthographic = 3u; /* bool: orthographic camera */
SPOT_CONST uint kSplatSpecEwa = 4u;          /* bool: EWA widening (prepare) */
SPOT_CONST uint kSplatSpecWeight = 5u;       /* uint: kSpotWeight* (oit, hybrid, resolve) */
SPOT_CONST uint kSplatSpecCount = 7u;        /* bool: count fragments and covered pixels */
SPOT_CONST uint kSplatSpecScreen = 9u;       /* bool: prepare writes screen lobes and bounds too
                                                (the ray-march reads world lobes only) */
SPOT_CONST uint kSplatSpecResolveList = 11u; /* bool: the resolve's second dispatch, over the
                                                listed pixels (SpotSplatList) */
SPOT_CONST uint kSplatSpecSmallPixels = 10u; /* uint: kernels whose quad's pixel box holds at most
                                                this many pixel centres take the compute path
                                                (splat_small.comp); 0: every kernel is drawn */
SPOT_CONST uint kSplatSpecWorldLobes = 12u;  /* bool: prepare stores the world lobes (read by
                                                Lambert shading and N samples; the ray-march's
                                                prepare, kSplatSpecScreen false, always does) */
SPOT_CONST uint kSplatSpecClipped = 13u;     /* bool: prepare's second dispatch, over the kernels
                                                its first listed (SpotSplatList): those with a
                                                lobe that projects to no ellipse */
SPOT_CONST uint kSplatSpecLit = 14u;         /* bool: lit (each lobe's colour is its world lobe's,
                                                which prepare lit: light_common.glsl) */
SPOT_CONST uint kSplatSpecLobeColor = 16u;   /* float x 24: the kernel lobes' colours, lobe l's
                                                r, g, b at ids 16 + 3 l + 0, 1, 2 (constants in
                                                the fragment shaders: llvmpipe pays dearly for
                                                every buffer load or flat input there) */

/* SpotSplatFrame.counts.w bits (what stays a run-time flag). */
SPOT_CONST uint kSplatFlagLambert = 2u;     /* Lambert + ambient shading, else unlit */

/* Lobes per kernel at most (the kernel's varyings are sized for them). */
SPOT_CONST uint kSplatMaxLobes = 8u;

/* Lambert shading's per-lobe gradient terms reach the fragment shader as varyings for kernels of
 * at most this many lobes (splat_common.glsl, vShadeA and vShadeB); with more they would exceed
 * lavapipe's 32 varying locations, and the fragment shader loads the world lobes instead. */
SPOT_CONST uint kSplatMaxShadeVaryingLobes = 6u;

/* Kernel samples (paper eq. 10's N_s) at most. Every shader invocation stays far below lavapipe's
 * 65,535 loop iterations: a march costs N x (lobes + 1) <= 2048 x 9 = 18,432 iterations, the
 * analytic path at most about 300. */
SPOT_CONST uint kSplatMaxKernelSamples = 2048u;

/* Analytic path with Lambert shading: normals per lobe and pixel (splatLobeShading). Loop budget
 * of the analytic path: 8 lobes x 4 points x 8 lobes of gradient = 256 iterations. */
SPOT_CONST uint kSplatShadingSamples = 4u;

/* Hybrid: a kernel competes for "closest" at a pixel only where its alpha exceeds this (one 8-bit
 * step): fainter kernels would claim the front while hiding nothing. Also the alpha from which a
 * pixel counts as covered by a kernel (fragment efficiency). */
SPOT_CONST float kSplatHybridMinAlpha = 1.0 / 255.0;

/* Hybrid with a closest-kernel depth pass: the depth written is the kernel's view depth along the
 * pixel's ray times this power of two, so it orders exactly as the depths do (the atomicMin key's
 * order) for every depth up to 2^20 world units (farther ones all tie at 1, then the first kernel
 * wins, as atomicMin's kernel index does on equal depths). */
SPOT_CONST float kSplatClosestDepthScale = 1.0 / 1048576.0;


/* Ray distance stored where no mesh is hit. */
SPOT_CONST float kSplatNoMesh = 3.0e38;

/* The small kernels' compute path (splat_small.comp, docs/design.md section 4). A kept kernel whose
 * quad's axis-aligned pixel box (clamped to the image) holds at most RenderSettings::smallPixels
 * pixel centres (default kSplatSmallPixels) is not drawn, nor is a thin one whose box holds at
 * most kSplatMaxSmallPixels (kSplatThinHalfWidth, splat_compact.comp): one compute invocation
 * loops over those centres, so its loop never exceeds kSplatMaxSmallPixels iterations (lavapipe
 * allows 65,535; the lobe loops inside add at most about 300 each). */
SPOT_CONST uint kSplatSmallPixels = 36u;
SPOT_CONST uint kSplatMaxSmallPixels = 256u;
/* A kept kernel whose quad is thin, half as wide as this in pixels or less (a strand, a blade seen
 * edge-on), takes the compute path too when its box holds at most kSplatMaxSmallPixels centres. */
SPOT_CONST float kSplatThinHalfWidth = 1.5;
SPOT_CONST uint kSplatSmallThreads = 64u; /* workgroup size of the compute path */

/* The compute path's OIT sums: per pixel premul.rgb x w, alpha x w and tau (5 channels), each
 * contribution clamped to [0, kSplatFixedMax] and added as round-down(value x kSplatFixedScale)
 * with a 64-bit integer atomicAdd: integer addition is associative, so the sums do not depend on
 * the order the invocations run in. Scale 2^28: a resolution of 3.7e-9 (the raster target's
 * float32 has 6e-8 relative to a sum of 1); the largest contribution (2^24) is 2^52, so a pixel
 * holds 2^11 of those, or 2^23 of the largest real one (a McGuire-Bavoil weight of 3e3 x alpha 1),
 * before the unsigned 64-bit sum could wrap. The resolve adds the sums to the raster targets'. */
SPOT_CONST uint kSplatFixedChannels = 5u;
/* The resolve's workgroup is a tile of kSplatResolveTile^2 pixels; it reads (and clears) the
 * fixed-point sums of a tile only where the compute path flagged it (kSplatBindOitTiles, cleared
 * by a fill every frame). */
SPOT_CONST uint kSplatResolveTile = 8u;
SPOT_CONST float kSplatFixedScale = 268435456.0;
SPOT_CONST float kSplatFixedMax = 16777216.0;

/* Workgroup size of the deterministic stream compaction (one workgroup). */
SPOT_CONST uint kSplatCompactThreads = 256u;

/* Pixels added around each kernel's exact bound: the bound and the fragment shader round
 * differently, and a pixel centre on the truncation ellipse sees (almost) nothing anyway. */
SPOT_CONST float kSplatBoundPadding = 0.01;
