/* spot_deform_layout.h: the deform passes' structs, bindings and push constants (docs/design.md
 * section 6), shared by C++ (splat/deform_vk.cpp, noise/animated_mesh.cpp through
 * spot_deform.hpp) and GLSL (deform_*.comp). C++ and GLSL use these names, never the numbers.
 * Same rules as spot_layout.h: 16-byte members only.
 *
 * An animated mesh's frame runs four compute passes before the method's own (splat/deform_vk.h):
 *   pose       per vertex: its base plus its morph deltas weighted, moved by the blend of its
 *              joints' matrices (spotPoseVertex); written to the base mesh's vertex buffer;
 *   normals    per vertex: the area-weighted normal of the posed triangles around it (a gather
 *              over the vertex's triangles, the twin of noise::computeNormals);
 *   frames     per triangle: its rotation from rest to the pose (spotTriangleRotation); a
 *              triangle collapsed by the pose keeps the rotation it had;
 *   move       per impulse: carried from its rest anchor to the pose (spotMoveImpulse), then
 *              turned by the wind (spotWindRotation).
 * Loop iterations per invocation: pose, 2 x 4 joints + the morph targets; normals, the vertex's
 * triangles (the host refuses a vertex with more than kDeformMaxValence); none elsewhere.
 */
#ifndef SPOT_CONST
#define SPOT_CONST const
#endif

/* One vertex as the pose pass reads it (80 bytes). A piece without a skin has one joint: its
 * node's matrix, weight 1. */
struct SpotDeformVertex {
    vec4 base;     /* xyz: position as stored (its piece's space); w: uintBitsToFloat(piece) */
    uvec4 joints0; /* palette indices of JOINTS_0 */
    vec4 weights0; /* WEIGHTS_0 (normalised with WEIGHTS_1 by their sum) */
    uvec4 joints1;
    vec4 weights1;
};

/* One piece: a run of vertices with its morph targets (32 bytes). */
struct SpotDeformPiece {
    uvec4 info;  /* x: first vertex; y: vertex count; z: morph targets; w: first delta (target k
                    of vertex v is delta[w + k y + v - x]) */
    uvec4 morph; /* x: its first weight in the frame's morph weights; yzw unused */
};

/* Push constants of every deform pipeline (48 bytes). */
struct SpotDeformPush {
    uvec4 counts; /* x: vertices; y: triangles; z: impulse capacity; w: 1 with wind */
    vec4 wind;    /* xyz: unit direction (world); w: strength (radians) */
    vec4 gust;    /* x: gust frequency (Hz); y: variation per impulse [0, 1]; z: time (s); w: the
                     cell size h (a moved impulse's cell is its root's, floor(root / h)) */
};

SPOT_CONST uint kDeformGroup = 64u;
SPOT_CONST uint kDeformMaxValence = 1024u;
/* A vertex whose area-weighted normal sum is below this fraction of its largest triangle's
 * takes that triangle's normal (noise/mesh.cpp's kCancelledRel). */
SPOT_CONST float kDeformCancelled = 1e-6;

/* Descriptor bindings. */
SPOT_CONST uint kDeformBindVertices = 0u;  /* SpotDeformVertex[] (pose) */
SPOT_CONST uint kDeformBindPieces = 1u;    /* SpotDeformPiece[] (pose) */
SPOT_CONST uint kDeformBindDeltas = 2u;    /* vec4[]: morph deltas (pose) */
SPOT_CONST uint kDeformBindPalette = 3u;   /* mat4[]: the frame's joint matrices (pose) */
SPOT_CONST uint kDeformBindWeights = 4u;   /* float[]: the frame's morph weights (pose) */
SPOT_CONST uint kDeformBindPosed = 5u;     /* SpotMeshVertex[]: the posed mesh (all passes) */
SPOT_CONST uint kDeformBindRest = 6u;      /* SpotMeshVertex[]: the rest mesh (frames) */
SPOT_CONST uint kDeformBindIndices = 7u;   /* uint[3 x triangles] (normals, frames, move) */
SPOT_CONST uint kDeformBindAdjacency = 8u; /* uint[vertices + 1] offsets, then corners 3 t + k (normals) */
SPOT_CONST uint kDeformBindRotations = 9u; /* vec4[3 x triangles]: each one's rotation's columns
                                              (frames writes, move reads) */
SPOT_CONST uint kDeformBindImpulses = 10u; /* SpotImpulse[]: at rest (move) */
SPOT_CONST uint kDeformBindMoved = 11u;    /* SpotImpulse[]: posed (move) */
SPOT_CONST uint kDeformBindCount = 12u;    /* uint: the impulse count (move) */
