/* spot_layout.h: structs shared by C++ and GLSL (std430 storage buffers, push constants).
 *
 * Every member is a 16-byte vector so the std430 layout equals the C++ layout without padding
 * rules to remember. In C++ this file is included by shaders/spot_layout.hpp inside namespace
 * spot::gpu with glm types, which static_asserts the sizes; tests/shaders/layout_test.cpp asserts
 * every field's offset, on the host and in the compiled SPIR-V. In GLSL it is included directly.
 *
 * Units: world units, radians; colours linear RGB.
 */

/* A surface cell as the GPU generator sees it. */
struct SpotCell {
    ivec4 ijk;  /* xyz: cell index; w: piece count */
    uvec4 info; /* x: first piece; y: floatBitsToUint(area); z, w: the offset and the count of
                   the candidates the GPU generator examines (written by the host) */
};

/* A piece of one triangle inside a cell, in the triangle's barycentric coordinates (b1, b2). */
struct SpotPiece {
    vec4 c01; /* corner 0 (x, y), corner 1 (z, w) */
    vec4 c2;  /* corner 2 (x, y); z: area; w: uintBitsToFloat(triangle) */
};

/* One impulse (144 bytes). */
struct SpotImpulse {
    vec4 position; /* xyz: kernel origin; w: weight |w| */
    vec4 normal;   /* xyz: surface normal; w: bend (radians per kernel unit) */
    vec4 comb;     /* xyz: comb direction in the tangent plane; w: height offset */
    vec4 frameX;   /* kernel frame columns (kernel -> world rotation); w unused */
    vec4 frameY;   /* w: the clump strength the kernel was clumped with (0: none) */
    vec4 frameZ;   /* w: the distance from the anchor to its clump's centre (0: none) */
    vec4 scale;    /* xyz: world units per kernel unit; w: uintBitsToFloat(triangle) */
    vec4 color;    /* rgb: colour multiplier; w: barycentric b1 */
    ivec4 cell;    /* xyz: generating cell; w: floatBitsToInt(barycentric b2) */
};

/* One kernel lobe in kernel space (64 bytes). */
struct SpotLobe {
    vec4 inv0;  /* columns of (R S)^-1, kernel -> lobe space; w: centre.x (kernel units) */
    vec4 inv1;  /* w: centre.y */
    vec4 inv2;  /* w: centre.z */
    vec4 color; /* rgb; w: peak extinction (1 / world unit) */
};

/* A lobe placed in the world for the current view, EWA-widened (64 bytes). In a lit frame,
 * `color` is the lobe's lit colour at its centre, and the buffer holds a second half after the
 * capacity's lobes: lobe i's record at [capacity x lobes + i] is not a placed lobe but how its
 * lit colour changes along its shading axis (splat_prepare.comp): a0.rgb the change per sigma
 * (the key lights' transmittance differs from root to tip), a1.xyz the axis in this lobe space,
 * so that a point u of it is x = a1.u sigmas along the axis and has the colour
 * color + a0 clamp(x, -1, 1) (splat_common.glsl's splatLitColor, raymarch_shared.glsl's march). */
struct SpotWorldLobe {
    vec4 a0;    /* columns of A (world -> lobe space); w: centre.x */
    vec4 a1;    /* w: centre.y */
    vec4 a2;    /* w: centre.z */
    vec4 color; /* rgb: lobe colour x impulse colour; w: extinction x weight x EWA amplitude */
};

/* A bound field in the shared form (144 bytes): what the generator evaluates, on either side. */
struct SpotField {
    ivec4 kind;    /* x: the kind (spot_generate.h kField*: 0 constant, 1 gradient, 2 noise,
                      3 vertex, 4 image, 5 painted, 6 tangent), plus kFieldLayered or
                      kFieldLayeredDensity when a paint layer lies over it (axis.w: where);
                      y: components (1|3); z: noise octaves; w: noise seed (bits) */
    vec4 value;    /* constant value; painted: the background */
    vec4 lo;       /* mapped kinds: output at t = 0 (per component) */
    vec4 hi;       /* output at t = 1 */
    vec4 from;     /* gradient: xyz start point; noise: w frequency (cells per world unit);
                      painted: w 1 / voxel size */
    vec4 axis;     /* gradient: (to - from) / |to - from|^2; w: a layered field's layer offset
                      in the field data (bits; spot_generate.h spotFieldLayer) */
    uvec4 data;    /* vertex: xyz offsets of the attribute columns in the field data array;
                      image: x offset, y width, z height, w repeat (1) or clamp (0);
                      painted: x hash table offset, y its size, z longest probe, w blocks'
                      offset (spot_generate.h) */
    vec4 clampLo;  /* vertex: bounds of the attribute values; image: bounds of the texels;
                      painted: bounds of the values */
    vec4 clampHi;
};

/* Everything the generator needs besides mesh and cells. Field slots: */
#define SPOT_FIELD_DENSITY 0
#define SPOT_FIELD_COMB 1
#define SPOT_FIELD_TILT 2
#define SPOT_FIELD_SPIN 3
#define SPOT_FIELD_BEND 4
#define SPOT_FIELD_SCALE 5
#define SPOT_FIELD_COLOR 6
#define SPOT_FIELD_WEIGHT 7
#define SPOT_FIELD_CLUMP 8      /* clump strength in [0, 1] (spot_clump.h) */
#define SPOT_FIELD_CLUMP_SIZE 9 /* relative clump size in [0.5, 2] */
#define SPOT_FIELD_MASK 10      /* the groom's mask in [0, 1]: what masked fields are limited to */
#define SPOT_FIELD_COUNT 11

struct SpotGenParams {
    vec4 distribution; /* x: density_max (1 / world unit^2); y: jitter; z: height offset; w: height jitter */
    vec4 variation0;   /* x: tilt (deg); y: spin (deg); z: bend (deg per kernel unit); w: scale (relative) */
    vec4 variation1;   /* x: colour (relative); y: weight (relative); z: cell size h; w: lattice spacing */
    uvec4 flags;       /* x: seed; y: 0 poisson, 1 jittered; z: 1 if a comb field is set;
                          w: bit 0 mesh has uv, bit 1 mesh has tangents */
    vec4 lod;          /* level of detail for the current view: xyz eye (world); w: focal length in
                          pixels / LOD size in pixels (0 = off). A cell seen smaller than the LOD
                          size keeps each impulse with probability (size / LOD size)^2 and divides
                          the kept ones' weight by it (stochastic simplification). The CPU
                          generator leaves it off; the GPU's comes per generation in
                          SpotGenPush.lod (spot_generate_layout.h). */
    vec4 clump;        /* clumps (spot_clump.h): x: cell edge G = clump.size (world units);
                          y: size variation (the seeds' weight spread); z: shape (0 a lean,
                          1 a bend); w: the kernel's tip height (kernel units) */
    vec4 clump2;       /* x: secondary clumps' cell edge (0: none); y: their strength
                          (relative to the clump field); z: per-impulse strength variation;
                          w: unused */
    uvec4 clumpFlags;  /* x: the clumps' seed; y: bit 0 clumping on, bit 1 secondary clumps,
                          bit 2 the mask overlay (the editor's view); z, w: unused */
    SpotField fields[SPOT_FIELD_COUNT];
};
