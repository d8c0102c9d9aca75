/* baked_layout.glsl: what the baked renderer's host code (splat/methods/baked/baked_vk.cpp) and its shaders
 * (baked_*.comp, baked_tet.vert, baked_peel.frag) share: bindings, the parameter block, the
 * sparse grid's leaf tables. Compiles as C++ (GLM types, SPOT_CONST and SPOT_FN
 * defined by the includer) and as GLSL. docs/design.md section 5 describes the renderer. */

/* The sparse grid: the bake's OpenVDB leaves (8^3 voxels) as bricks. Brick b of the density
 * levels holds leaf L's voxels and the first of its +x, +y and +z neighbours' (an apron: voxels
 * L x 8 + [0, 8]^3, 9^3 of them, 0 where the neighbour is not stored), so the 8 voxels of a
 * trilinear sample whose lowest corner lies in L are all in L's brick: one leaf lookup a sample,
 * not 8. A voxel is 8 bytes, vec4(extinction x colour, extinction) / unit.x as two
 * packHalf2x16 words (unit: SpotBakedParams), at bricks[b * kBakedBrickVoxels + offset] with
 * offset = (x * 9 + y) * 9 + z for its position xyz in the brick; the density bricks are split
 * over up to kBakedBrickBuffers storage buffers of counts.w bricks each (one buffer's range is
 * limited: 128 MiB on lavapipe), brick b in buffer b / counts.w. Brick b of the distance grid
 * is a float per voxel at distances[b * 512 + offset], offset = (i & 7) << 6 | (j & 7) << 3 |
 * (k & 7) for voxel ijk (no apron). A leaf is found in a dense table over
 * the box of its section's leaves (section s: levels 0..levels-1, then the distance grid at
 * kBakedDistanceSection): leaf L's entry, the brick or kBakedEmptySlot, is
 * table[leafOrigin[s].w + (r.z leafDims[s].y + r.y) leafDims[s].x + r.x] with
 * r = L - leafOrigin[s].xyz inside [0, leafDims[s].xyz); outside the box no leaf is stored. One
 * read, no probing: the table holds an int per leaf of the box (the bunny's bakes: under 1 MiB),
 * where a hash table's probe loops cost lavapipe the longest probe of the SIMD batch. */
SPOT_CONST uint kBakedLeafBits = 3u;
SPOT_CONST uint kBakedLeafVoxels = 512u;
SPOT_CONST uint kBakedBrickSide = 9u;     /* a density brick: its leaf and a voxel of apron */
SPOT_CONST uint kBakedBrickVoxels = 729u;
SPOT_CONST int kBakedEmptySlot = -1;
SPOT_CONST uint kBakedSections = 12u;          /* 8 levels at most, the distance grid, spare */
SPOT_CONST uint kBakedDistanceSection = 8u;
SPOT_CONST uint kBakedBrickBuffers = 4u;
/* The march's step: this fraction of the level's voxel, in rest-pose (texture) units. One voxel:
 * on fur-bunny at 128x128 (16 layers) 31.36 dB against the reference, half a voxel 31.33 dB
 * at 1.2 times the cost (the trilinear reconstruction, not the step, limits the error). */
SPOT_CONST float kBakedStepFraction = 1.0f;
/* Loop iterations one invocation may run (lavapipe stops one at 65,535; docs/design.md 8). */
SPOT_CONST uint kBakedLoopBudget = 60000u;
/* A layer's walk (baked_march.comp): at most this many tetrahedra and this many samples (skipped
 * ones included); a layer that reaches either ends there (the next layer starts at the next
 * entry face behind that point). */
SPOT_CONST uint kBakedMaxLayerTets = 2048u;
SPOT_CONST uint kBakedMaxLayerSamples = 4096u;
/* A transmittance below this ends the walk, and the pixel counts as opaque (no later layer). */
SPOT_CONST float kBakedOpaque = 1e-4f;
/* Lit scenes (docs/design.md, "Lighting"; baked_march.comp's lit march). Lights at most (the
 * scene's bound, noise::kMaxLights). */
SPOT_CONST uint kBakedMaxLights = 8u;
/* The sky's directions, fixed on the upper hemisphere (baked_march.comp's skyDirection), each
 * with its own shadow march. */
SPOT_CONST uint kBakedSkyDirections = 4u;
/* A shadow march's steps at most (a step or a skip over an empty leaf each); the light is taken
 * as unobstructed beyond them. */
SPOT_CONST uint kBakedShadowSteps = 128u;
/* Optical depth at which a shadow march stops (e^-8: 3e-4 of the light passes). */
SPOT_CONST float kBakedShadowOpaqueDepth = 5.0f;
/* A sample is lit only where it adds at least this much of its light to the pixel (its alpha
 * times the transmittance in front of it): below it, the shadow marches cost and show nothing. */
SPOT_CONST float kBakedLitMinWeight = 1e-3f;
/* No tetrahedron (the eye test's "the eye is outside the shell"). */
SPOT_CONST uint kBakedNoTet = 0xffffffffu;

/* Bindings (set 0, push descriptors). */
SPOT_CONST uint kBakedBindParams = 0u;      /* SpotBakedParams */
SPOT_CONST uint kBakedBindVertices = 1u;    /* SpotMeshVertex[]: the mesh now (world) */
SPOT_CONST uint kBakedBindRest = 2u;        /* SpotMeshVertex[]: the mesh at rest (the bake's) */
SPOT_CONST uint kBakedBindIndices = 3u;     /* uint[3 x triangles] */
SPOT_CONST uint kBakedBindTets = 4u;        /* SpotBakedTet[3 x triangles] */
SPOT_CONST uint kBakedBindTable = 5u;       /* int[]: the leaf tables */
SPOT_CONST uint kBakedBindBricks = 6u;      /* uvec2[]: density bricks of every level (the first buffer's) */
SPOT_CONST uint kBakedBindSolid = 7u;       /* uint[]: lit, the mesh's inside at level
                                               SpotBakedParams::shadow.x: bit (z ny + y) nx + x for
                                               voxel xyz of the level's box of leaves (n = 8 x its
                                               leaves), 1 where its centre lies inside the mesh
                                               (the march's modules with BAKED_LIT) */
SPOT_CONST uint kBakedBindPrevDepth = 8u;   /* rgba32f image: x the depth the next peel's entries
                                               lie behind (the previous layer's entry; 0: none),
                                               y the ray parameter the layers have sampled to */
SPOT_CONST uint kBakedBindLayerEntry = 9u;  /* uvec2 per pixel (row-major): this layer's entry,
                                               x 4 tet + face + 1 (0: none), y its depth's bits
                                               (baked_peel.frag) */
SPOT_CONST uint kBakedBindMeshDistance = 10u; /* r32f image: ray distance to the mesh */
SPOT_CONST uint kBakedBindAccum = 11u;      /* rgba32f image: premultiplied colour, alpha */
SPOT_CONST uint kBakedBindBase = 12u;       /* rgba32f image: the mesh's colour, then the frame's
                                               result (each march composites its pixels into it) */
SPOT_CONST uint kBakedBindBaseKept = 13u;   /* rgba32f image: the mesh's colour at the pixels the
                                               first layer walks (its march keeps it there) */
SPOT_CONST uint kBakedBindLoops = 14u;      /* uint: the most loop iterations (counted frames) */
SPOT_CONST uint kBakedBindNeighbours = 15u; /* ivec4[3 x triangles]: across face f, 4 tet + its face there, or -1 */
SPOT_CONST uint kBakedBindEyeTet = 17u;     /* uint: the lowest tetrahedron holding the eye, or kBakedNoTet */
SPOT_CONST uint kBakedBindExitDepth = 18u;  /* rgba32f image: the same, as the march writes it */
SPOT_CONST uint kBakedBindBricks1 = 20u;    /* uvec2[]: the second to fourth buffers of density bricks */
SPOT_CONST uint kBakedBindBricks2 = 21u;
SPOT_CONST uint kBakedBindBricks3 = 22u;
SPOT_CONST uint kBakedBindShading = 25u;    /* uvec2[]: lit, the shading bricks (BakeData), density
                                               brick b's at the same place in the same split */
SPOT_CONST uint kBakedBindShading1 = 26u;
SPOT_CONST uint kBakedBindShading2 = 27u;
SPOT_CONST uint kBakedBindShading3 = 28u;
SPOT_CONST uint kBakedBindEntryMasks = 16u; /* uint[triangles]: bit 4 k + f where face f of the
                                               triangle's tetrahedron k is an entry face (host) */
SPOT_CONST uint kBakedBindPeelDraw = 23u;   /* VkDrawIndirectCommand (16 bytes), then uint[]: the
                                               entry faces that face the eye, 4 tet + face each
                                               (baked_shell.comp, this frame) */
SPOT_CONST uint kBakedBindList = 19u;       /* SpotBakedList: this layer's list of pixels to march
                                               (one header per layer, each bound at its offset) */
SPOT_CONST uint kBakedBindListPixels = 24u; /* uint[width x height]: the listed pixels, x | y << 16 */

/* Specialization ids. */
SPOT_CONST uint kBakedSpecCount = 64u;      /* bool: count loop iterations (ids below are splat_common.glsl's) */
SPOT_CONST uint kBakedSpecFirstLayer = 65u; /* bool: the first layer (its peel has no previous exit;
                                                its march starts from nothing accumulated, or at
                                                the eye's tetrahedron if any) */

struct SpotBakedTet {
    vec4 world[4];  /* xyz: corner now, world units */
    vec4 plane[4];  /* face i (opposite corner i): xyz its normal turned inwards, w such that
                       dot(xyz, x) + w >= 0 inside; (0, 0, 0, -1) for a flat tetrahedron */
    vec4 toRest[3]; /* the affine map from world now to rest (world units of the bake, the texture
                       coordinate): rest[j] = dot(toRest[j].xyz, x) + toRest[j].w */
};

/* A light of a lit scene, as the lit march reads it. */
struct SpotBakedLight {
    vec4 position; /* w 0: directional, xyz the unit direction towards it; w 1: point, xyz its
                      position (world) */
    vec4 radiance; /* rgb: colour x intensity (a point light's at unit distance); w: 1 when it
                      casts shadows */
};

struct SpotBakedParams {
    vec4 grid;     /* x: level 0's voxel size; y: its inverse; z: distance cap (level-0 voxels); w: shell thickness */
    uvec4 counts;  /* x: triangles; y: levels; z: tetrahedra; w: bricks per brick buffer */
    vec4 unit;     /* x: what a density brick's stored 1 is (its largest value over 32,768: the
                      half floats' range, and their relative precision of 2^-11 everywhere) */
    ivec4 leafOrigin[kBakedSections]; /* per section: xyz its lowest leaf; w its first table entry */
    ivec4 leafDims[kBakedSections];   /* per section: xyz the leaves of its box (0 when empty) */
    /* Lit scenes (zero otherwise). */
    uvec4 lit;     /* x: lights; y: the axis model (kSpotShadeStrand, kSpotShadeFlake or
                      kSpotShadeLambert: the kernel's, strand where it has any); z: 1 when every
                      lobe has that model (the axis shades the whole sample), 0 when it shades
                      |axis| of it and the gradient normal the rest */
    uvec4 shadow;  /* x: the level of the mesh's solid (kBakedBindSolid): 1, or 0 in a bake of
                      one level */
    vec4 sky;      /* rgb: the sky's radiance (colour x intensity) */
    vec4 primary;  /* xyz: the axis model's highlights (shift, width in radians, strength): the */
    vec4 secondary; /* mean of its lobes' */
    SpotBakedLight lights[kBakedMaxLights];
};

/* The pixels a layer's march walks (listed by its peel, baked_peel.frag; kBakedBindListPixels). */
struct SpotBakedList {
    uvec3 groups; /* the march's indirect dispatch over its entries, 64 a workgroup: rows of at
                     most kBakedMarchRowGroups workgroups (x), as many rows as needed (y), 1 */
    uint count;   /* entries */
};

/* The march's workgroups a row of its dispatch (SpotBakedList.groups): a device takes at least
 * 65,535 workgroups in each dimension, so one row alone would stop at about 4.2 million
 * entries, less than a 2048x2048 frame; 65,535 rows of 1,024 (65,536 entries each) reach 4.29e9. */
SPOT_CONST uint kBakedMarchRowGroups = 1024u;
SPOT_CONST uint kBakedMarchGroupSize = 64u;

/* The dispatch that covers `entries` (SpotBakedList.groups.xy); monotone in `entries`, so that
 * the peel's appends can raise it with atomicMax. */
SPOT_FN uvec2 spotBakedMarchGroups(uint entries) {
    uint groups = entries / kBakedMarchGroupSize + uint(entries % kBakedMarchGroupSize != 0u);
    return uvec2(min(groups, kBakedMarchRowGroups), (groups + kBakedMarchRowGroups - 1u) / kBakedMarchRowGroups);
}
