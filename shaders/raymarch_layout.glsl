/* raymarch_layout.glsl: the ray-march renderer's structs, push constants, bindings,
 * specialization constants and constants, shared by C++ and GLSL (splat/methods/raymarch/raymarch_vk.h,
 * raymarch_shared.glsl and the raymarch_*.comp shaders). C++ and GLSL name bindings and
 * specialization constants by these constants, never by number.
 *
 * Same rules as spot_layout.h: 16-byte members only, so std430 (and push-constant) layout equals
 * the C++ layout; splat/methods/raymarch/raymarch_vk.h includes this file inside a namespace with glm types and
 * static_asserts the sizes. Units: world units; cell (i, j, k) spans [i h, (i + 1) h) x ...
 * (noise/cells.h).
 *
 * The "shell" is the set of cells where any kernel can have density: the surface cells dilated
 * by one cell (a kernel centred in a cell reaches only its 3x3x3 neighbourhood, docs/design.md section
 * 2). An open-addressing hash table maps a shell cell's ijk to its record. Each shell cell is cut
 * into kMarchSub^3 sub-cells, and each sub-cell lists the impulses of the cell's 27 neighbours
 * that may have density in it, each with the mask of its lobes that may (the lobe's box and the
 * slabs holding its support reach the sub-cell: splat/methods/raymarch/raymarch_vk.h); the march sums only those
 * lobes, in impulse and lobe order (the list is a subset, in the same order, of the 27
 * neighbours' lobes, and each lobe it leaves out has exactly zero density there).
 */
#ifndef SPOT_CONST
#define SPOT_CONST const
#endif

/* What every march pass reads besides the frame: depends only on the shell and the kernel, so it
 * is written when the impulses change (one storage buffer). */
struct SpotMarchParams {
    vec4 grid;    /* x: cell size h; y: 1 / h; z: lobe support k (sigmas); w: unused */
    ivec4 lo;     /* xyz: smallest shell cell index; w: hash table mask (capacity - 1) */
    ivec4 hi;     /* xyz: largest shell cell index (inclusive); w: longest probe, in slots past a
                     key's home slot (a lookup examines at most hi.w + 1 slots) */
    uvec4 counts; /* x: a lit frame: where the world lobes' colour changes start (the capacity x
                     lobes per impulse, spot_layout.h's SpotWorldLobe), else 0; y: lobes per
                     impulse; z: walk cap (cells a ray can cross in the shell's bounding box); w:
                     unused */
};

/* The push constants of the march and its resolve (112 bytes of lavapipe's 128). The camera is
 * SpotSplatFrame's (spot_splat.h), at the march's resolution: the output image's n times a side. */
struct SpotMarchPush {
    vec4 eye;     /* xyz: camera position; w: 1 orthographic, 0 perspective */
    vec4 forward; /* xyz: unit view direction; w: unused */
    vec4 right;   /* xyz: unit right axis; w: half width of the view at unit depth (perspective)
                     or in world units (orthographic) */
    vec4 up;      /* xyz: unit up axis (image rows grow downwards); w: half height, likewise */
    vec4 size;    /* x, y: march image width, height (pixels); z, w: unused */
    vec4 light;   /* xyz: unit direction towards the light (world); w: ambient in [0, 1] */
    uvec4 range;  /* x: first step this dispatch takes; y: one past its last step (a march is split
                     over dispatches so that no invocation loops past lavapipe's limit); z: steps N
                     per ray; w: supersampling n (n x n rays per output pixel) */
};

/* One shell cell. 16 bytes. */
struct SpotMarchCell {
    uvec4 head; /* x: impulses in the cell's 27 neighbours (0: the march's segments leave the cell
                   out: no kernel can reach it); y: impulses listed over its sub-cells; z, w:
                   unused */
};

/* The world box outside which every lobe of one impulse has zero density (each lobe's support
 * ellipsoid |A (x - c)| < k bounded per axis by k |row i of A^-1|, padded by 1% for rounding;
 * the whole space for a lobe whose inverse is not finite). The march skips an impulse whose box
 * does not hold the sample: exact, since the lobes it skips add exactly zero. 32 bytes. */
struct SpotMarchBox {
    vec4 lo; /* xyz: smallest corner; w: unused */
    vec4 hi; /* xyz: largest corner; w: unused */
};

/* Descriptor bindings (one numbering for the bin, march and resolve pipelines; each declares the
 * ones it reads). */
SPOT_CONST uint kMarchBindParams = 0u;       /* SpotMarchParams */
SPOT_CONST uint kMarchBindTable = 1u;        /* ivec4[]: hash slots (i, j, k, record or -1) */
SPOT_CONST uint kMarchBindCells = 2u;        /* SpotMarchCell[record] */
SPOT_CONST uint kMarchBindStarts = 3u;       /* uint[slots + 1]: list slot q is entries
                                                [starts[q], starts[q + 1]); with culling, slot
                                                record * kMarchSubCells + sub-cell (x-major),
                                                without, one slot per record */
SPOT_CONST uint kMarchBindList = 4u;         /* uint[]: list entries, ascending impulse per slot:
                                                impulse | lobe mask << kMarchEntryLobeShift */
SPOT_CONST uint kMarchBindWorldLobes = 5u;   /* SpotWorldLobe[impulse * lobes + l] */
SPOT_CONST uint kMarchBindBoxes = 6u;        /* SpotMarchBox[impulse] */
SPOT_CONST uint kMarchBindMeshDistance = 7u; /* r32f image: ray distance to the mesh */
SPOT_CONST uint kMarchBindBase = 8u;         /* rgba32f image: the mesh colour behind each ray */
SPOT_CONST uint kMarchBindState = 9u;        /* vec4[march pixel]: radiance, transmittance */
SPOT_CONST uint kMarchBindLoops = 10u;       /* uint[1 + march pixels]: the most loops of any
                                                invocation, then per pixel */
SPOT_CONST uint kMarchBindResult = 11u;      /* rgba32f image: the frame's result */
SPOT_CONST uint kMarchBindImpulses = 12u;    /* SpotImpulse[] (bin) */
SPOT_CONST uint kMarchBindCount = 13u;       /* uint: the impulse count (bin) */
SPOT_CONST uint kMarchBindBins = 14u;        /* uint[]: per record first, end, count (bin) */
SPOT_CONST uint kMarchBindLobeBoxes = 15u;   /* SpotMarchBox[impulse * lobes + l] (bin) */
SPOT_CONST uint kMarchBindWalkBits = 16u;    /* uvec2[brick]: per kMarchWalkBrick^3 brick of the
                                                shell's bounding box (x-major from lo), one bit per
                                                cell ((x * 4 + y) * 4 + z within the brick, x, y in
                                                bits 0-31, then .y): the cells the walk keeps
                                                (kMarchSpecWalkBits) */

/* Specialization constant ids (the march and resolve are compiled per setting). */
SPOT_CONST uint kMarchSpecLobes = 0u;   /* uint: lobes per kernel, 1..8 */
SPOT_CONST uint kMarchSpecLambert = 1u; /* bool: Lambert + ambient shading, else unlit */
SPOT_CONST uint kMarchSpecCull = 2u;    /* bool: skip impulses whose box misses the sample */
SPOT_CONST uint kMarchSpecCount = 3u;   /* bool: write each invocation's loop count (tests) */
SPOT_CONST uint kMarchSpecWalkBits = 4u; /* bool: the walk reads kMarchBindWalkBits, not the hash
                                            table (when the bounding box is small enough) */

/* A list entry: the impulse index in the low bits (fewer than 2^22 impulses: 65,535 workgroups of
 * 64), the mask of its lobes that may have density in the sub-cell (bit l: lobe l) above. */
SPOT_CONST uint kMarchEntryLobeShift = 22u;
SPOT_CONST uint kMarchEntryImpulse = 0x3fffffu;

/* Cells per brick side of the walk's bits (4^3 = 64 bits per brick). */
SPOT_CONST int kMarchWalkBrick = 4;

/* Sub-cells per cell side: each shell cell's lists are kept per sub-cell. 5, measured against 2,
 * 3, 4 and 6 (CPU time per warm frame on fur-bunny, lichen-torus and ring-sphere): finer lists
 * are shorter, up to about 5; past it the time stops falling while the list starts grow as the
 * cube (500 bytes per shell cell at 5). */
SPOT_CONST uint kMarchSub = 5u;
SPOT_CONST uint kMarchSubCells = 125u; /* kMarchSub^3 */

/* Shell segments kept per ray: entering and leaving the shell more often than this merges the
 * rest into the last segment (its gaps are sampled too, and find no density there). */
SPOT_CONST uint kMarchMaxSegments = 16u;

/* Transmittance below which the rest of a ray cannot change a pixel visibly (the reference's). */
SPOT_CONST float kMarchOpaque = 1e-6;

/* "No boundary along this axis" and "no mesh" distances, world units. */
SPOT_CONST float kMarchFar = 3.0e38;

/* Hash table slot marking an empty slot (table entries are ivec4(i, j, k, record), record < 0
 * when empty). */
SPOT_CONST int kMarchEmptySlot = -1;

/* lavapipe (Mesa 22.3) stops every shader invocation after this many loop iterations in total,
 * silently (docs/design.md section 8). */
SPOT_CONST uint kMarchLavapipeLoopLimit = 65535u;

/* The loop iterations a march invocation may need at most, by the host's bound (see
 * RaymarchRenderer): 65,535 less about 8%, a margin for anything the bound's model of the compiled
 * loops might miss. */
SPOT_CONST uint kMarchLoopBudget = 60000u;
