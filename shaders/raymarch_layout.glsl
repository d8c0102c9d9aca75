/* raymarch_layout.glsl: the ray-march renderer's structs and constants, shared by C++ and GLSL
 * (splat/raymarch_vk.h, raymarch_shared.glsl and the raymarch_*.comp shaders).
 *
 * Same rules as spot_layout.h: 16-byte members only, so std430 layout equals the C++ layout;
 * splat/raymarch_vk.h includes this file inside a namespace with glm types and static_asserts the
 * sizes. Units: world units; cell (i, j, k) spans [i h, (i + 1) h) x ... (noise/cells.h).
 *
 * The "shell" is the set of cells where any kernel can have density: the surface cells dilated
 * by one cell (a kernel centred in a cell reaches only its 3x3x3 neighbourhood, DESIGN section
 * 2). Every shell cell has a record listing the impulses of its 27 neighbours; an open-addressing
 * hash table maps a cell's ijk to its record.
 */
#ifndef SPOT_CONST
#define SPOT_CONST const
#endif

/* Everything the march reads besides the buffers (one storage buffer: the push constants are
 * full with SpotSplatFrame, which the march shares with the mesh pass). */
struct SpotMarchParams {
    vec4 grid;    /* x: cell size h; y: 1 / h; z: lobe support k (sigmas); w: unused */
    ivec4 lo;     /* xyz: smallest shell cell index; w: hash table mask (capacity - 1) */
    ivec4 hi;     /* xyz: largest shell cell index (inclusive); w: longest probe, in slots past a
                     key's home slot (a lookup examines at most hi.w + 1 slots) */
    uvec4 counts; /* x: steps N per pixel; y: lobes per impulse; z: walk cap (cells a ray can cross
                     in the shell's bounding box); w: kMarchFlag* bits */
    vec4 light;   /* xyz: unit direction towards the light (world); w: ambient in [0, 1] */
    uvec4 range;  /* x: first step this dispatch takes; y: one past its last step (a march is
                     split over dispatches so that no invocation loops past lavapipe's limit);
                     z: supersampling n (n x n rays per output pixel); w: unused */
};

/* One shell cell: the impulses of its 27 neighbour cells as ranges of the impulse array (impulses
 * are in cell order, so the three cells (i + di, j + dj, k - 1 .. k + 1) of one column are one
 * contiguous range: at most 9 ranges, none empty). 96 bytes. */
struct SpotMarchCell {
    uvec4 head;     /* x: range count (<= 9); y: impulses in all ranges; z, w: unused */
    uvec4 range[5]; /* (first impulse, impulse count) pairs: range r is range[r / 2] components
                       2 (r % 2) and 2 (r % 2) + 1 */
};

/* The world box outside which every lobe of one impulse has zero density (each lobe's support
 * ellipsoid |A (x - c)| < k bounded per axis by k |row i of A^-1|, padded by 1% for rounding;
 * the whole space for a lobe whose inverse is not finite). The march skips an impulse whose box
 * does not hold the sample: exact, since the lobes it skips add exactly zero. 32 bytes. */
struct SpotMarchBox {
    vec4 lo; /* xyz: smallest corner; w: unused */
    vec4 hi; /* xyz: largest corner; w: unused */
};

/* SpotMarchParams.counts.w bits. */
SPOT_CONST uint kMarchFlagLambert = 1u;   /* Lambert + ambient shading, else unlit */
SPOT_CONST uint kMarchFlagNoCulling = 2u; /* evaluate every impulse's lobes, box or not (tests) */

/* Shell segments kept per ray: entering and leaving the shell more often than this merges the
 * rest into the last segment (its gaps are sampled too, and find no density there). */
SPOT_CONST uint kMarchMaxSegments = 16u;

/* Transmittance below which the rest of a ray cannot change a pixel visibly (the reference's). */
SPOT_CONST float kMarchOpaque = 1e-6;

/* "No boundary along this axis" and "no mesh" distances, world units. */
SPOT_CONST float kMarchFar = 3.0e38;

/* Hash table slot marking an empty slot (SpotMarchParams table entries are ivec4(i, j, k, record),
 * record < 0 when empty). */
SPOT_CONST int kMarchEmptySlot = -1;

/* lavapipe (Mesa 22.3) stops every shader invocation after this many loop iterations in total,
 * silently (DESIGN section 8). */
SPOT_CONST uint kMarchLavapipeLoopLimit = 65535u;

/* The loop iterations a march invocation may need at most, by the host's bound (see
 * RaymarchRenderer): 65,535 less about 8%, a margin for anything the bound's model of the compiled
 * loops might miss. */
SPOT_CONST uint kMarchLoopBudget = 60000u;
