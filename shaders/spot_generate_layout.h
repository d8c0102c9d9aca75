/* spot_generate_layout.h: the GPU impulse generator's descriptor bindings, specialization
 * constants, push constants and limits, shared by C++ (splat/generate_vk.cpp) and GLSL (the
 * generate_*.comp shaders). C++ and GLSL use these names, never the numbers.
 *
 * Same rules as spot_layout.h: 16-byte members only, so the push-constant layout equals the C++
 * layout; generate_vk.cpp includes this file inside a namespace with glm types and static_asserts
 * the size.
 *
 * One generation is three passes, recorded into the frame's command buffer with no host wait
 * (the host has already counted each cell's candidates with the CPU twin of spot_generate.h and
 * written their offsets into SpotCell.info.z; for a jittered lattice it examined the sites and
 * lists only those that land in their triangle and cell, the only ones that can pass):
 *   candidates  one invocation per candidate examined decides it (spotCandidate): the impulse
 *               into scratch[g], 1 into flags[g] when accepted, 0 otherwise;
 *   scan        one workgroup turns the flags into 1-based output indices in (cell, candidate)
 *               order (each thread a contiguous chunk, a shared-memory scan of the chunk totals,
 *               no atomics) and writes the impulse count;
 *   scatter     one invocation per candidate copies an accepted impulse to its index.
 * Loop iterations per invocation (lavapipe stops a shader silently after 65,535 in all):
 *   candidates  32 (cell search) + spot_generate.h's per-candidate loops (piece search; the
 *               jittered lattice walks the cell's pieces: at most a few hundred);
 *   scan        2 x ceil(examined / kGenScanThreads) + 8 <= 2 x 8,192 + 8 at kGenMaxCandidates;
 *   scatter     none.
 */
#ifndef SPOT_CONST
#define SPOT_CONST const
#endif

/* Push constants of every generator pipeline (32 bytes). */
struct SpotGenPush {
    uvec4 counts; /* x: cells; y: candidates examined; z: 1 when the candidates pass decides only
                     some cells' candidates again (the others' scratch and flags stand): its
                     cells' info.z are offsets among those candidates, kGenBindDirty gives each
                     one's offset in the whole generation; w: unused */
    vec4 lod;     /* SpotGenParams::lod of this generation (w = 0: off) */
};

/* Descriptor bindings. */
SPOT_CONST uint kGenBindParams = 0u;     /* SpotGenParams (candidates) */
SPOT_CONST uint kGenBindCells = 1u;      /* SpotCell[cells], offsets in info.z (candidates) */
SPOT_CONST uint kGenBindPieces = 2u;     /* SpotPiece[] (candidates) */
SPOT_CONST uint kGenBindTriangles = 3u;  /* uint[3 x triangles] (candidates) */
SPOT_CONST uint kGenBindPositions = 4u;  /* float[3 x vertices] (candidates) */
SPOT_CONST uint kGenBindNormals = 5u;    /* float[3 x vertices] (candidates) */
SPOT_CONST uint kGenBindTangents = 6u;   /* float[3 x vertices], read when kGenSpecTangents */
SPOT_CONST uint kGenBindUvs = 7u;        /* float[2 x vertices], read when kGenSpecUv */
SPOT_CONST uint kGenBindFieldData = 8u;  /* float[]: the fields' data (candidates) */
SPOT_CONST uint kGenBindScratch = 9u;    /* SpotImpulse[examined] (candidates, scatter) */
SPOT_CONST uint kGenBindFlags = 10u;     /* uint[examined] (candidates, scan, scatter) */
SPOT_CONST uint kGenBindImpulses = 11u;  /* SpotImpulse[]: the output (scatter) */
SPOT_CONST uint kGenBindCount = 12u;     /* uint: the impulse count (scan) */
SPOT_CONST uint kGenBindSites = 13u;     /* uint[examined]: each one's index in its cell
                                            (jittered candidates) */
SPOT_CONST uint kGenBindDirty = 14u;     /* uint[cells]: with counts.z, each cell's offset in the
                                            whole generation (candidates) */

/* Specialization constants of the candidates pass, compiled for one preset's generator: lavapipe
 * compiles a shader at its first use and pays for every path it carries, so only the field kinds
 * a preset uses are compiled. (The distribution picks the module itself, generate_poisson.comp or
 * generate_jittered.comp: a path made dead by a constant still costs pipeline creation.) */
SPOT_CONST uint kGenSpecComb = 0u;       /* bool: a comb field is set (else the surface tangent) */
SPOT_CONST uint kGenSpecUv = 1u;         /* bool: the mesh has uvs */
SPOT_CONST uint kGenSpecTangents = 2u;   /* bool: the mesh has tangents */
/* int: field slot s's kind (SpotField.kind.x) at id kGenSpecFieldKind + s, its component count
 * (1 or 3) at kGenSpecFieldComponents + s; s < SPOT_FIELD_COUNT. */
SPOT_CONST uint kGenSpecFieldKind = 3u;
SPOT_CONST uint kGenSpecFieldComponents = 14u;
/* uint: SpotGenParams.clumpFlags.y (clumps, secondary clumps, the mask overlay: spot_generate.h
 * kClump*), so that a preset without clumps compiles none of their code. */
SPOT_CONST uint kGenSpecClump = 25u;

SPOT_CONST uint kGenGroup = 64u;          /* workgroup size of the per-candidate passes */
SPOT_CONST uint kGenScanThreads = 256u;   /* the scan's one workgroup */
SPOT_CONST uint kGenMaxCandidates = 2097152u; /* per generation: the scan's loop budget above */
