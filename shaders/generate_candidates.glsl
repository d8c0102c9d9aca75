// Impulse generation, pass 1 of 3 (spot_generate_layout.h): one invocation per candidate examined
// decides it with the shared code of spot_generate.h, specialized for one preset's generator.
// The impulse goes to scratch[g] and its accepted flag to flags[g], g = the cell's offset + the
// candidate's rank among the cell's examined ones: the CPU's (cell, candidate) order.
//
// Included by generate_poisson.comp and generate_jittered.comp, one module per distribution, each
// defining SPOT_GEN_JITTERED (0 or 1) first; the rest is specialization constants.
#extension GL_GOOGLE_include_directive : require
#if SPOT_GEN_JITTERED
#define SPOT_GEN_NO_POISSON
#else
#define SPOT_GEN_NO_JITTERED
#endif
// The groom modules (compiled with SPOT_GEN_GROOM) carry the clumps, the masks and the mask
// overlay; the others leave them out (spot_generate.h).
#ifndef SPOT_GEN_GROOM
#define SPOT_GEN_NO_GROOM
#endif
#include "spot_shared.h"
#include "spot_layout.h"
#include "spot_generate_layout.h"

layout(local_size_x = kGenGroup) in;

layout(push_constant) uniform Push { SpotGenPush push; };

layout(std430, binding = kGenBindParams) readonly buffer Params { SpotGenParams params; };
layout(std430, binding = kGenBindCells) readonly buffer Cells { SpotCell cells[]; };
layout(std430, binding = kGenBindPieces) readonly buffer Pieces { SpotPiece pieces[]; };
layout(std430, binding = kGenBindTriangles) readonly buffer Triangles { uint triangles[]; };
layout(std430, binding = kGenBindPositions) readonly buffer Positions { float positions[]; };
layout(std430, binding = kGenBindNormals) readonly buffer Normals { float normals[]; };
layout(std430, binding = kGenBindTangents) readonly buffer Tangents { float tangents[]; };
layout(std430, binding = kGenBindUvs) readonly buffer Uvs { float uvs[]; };
layout(std430, binding = kGenBindFieldData) readonly buffer FieldData { float fieldData[]; };
layout(std430, binding = kGenBindScratch) writeonly buffer Scratch { SpotImpulse scratch[]; };
layout(std430, binding = kGenBindFlags) writeonly buffer Flags { uint flags[]; };
#if SPOT_GEN_JITTERED
layout(std430, binding = kGenBindSites) readonly buffer Sites { uint sites[]; };
#endif
// A partial generation (the modules compiled with SPOT_GEN_PARTIAL) lists only the changed
// cells: each one's offset in the whole generation.
#ifdef SPOT_GEN_PARTIAL
layout(std430, binding = kGenBindDirty) readonly buffer Dirty { uint dirtyOffsets[]; };
#endif

const bool kJittered = SPOT_GEN_JITTERED != 0;
// Set by splat/generate_vk.cpp from the generator's parameters; the defaults are never used.
layout(constant_id = kGenSpecComb) const bool kComb = false;
layout(constant_id = kGenSpecUv) const bool kUv = false;
layout(constant_id = kGenSpecTangents) const bool kTangents = false;
layout(constant_id = kGenSpecFieldKind + 0u) const int kKind0 = 0;
layout(constant_id = kGenSpecFieldKind + 1u) const int kKind1 = 0;
layout(constant_id = kGenSpecFieldKind + 2u) const int kKind2 = 0;
layout(constant_id = kGenSpecFieldKind + 3u) const int kKind3 = 0;
layout(constant_id = kGenSpecFieldKind + 4u) const int kKind4 = 0;
layout(constant_id = kGenSpecFieldKind + 5u) const int kKind5 = 0;
layout(constant_id = kGenSpecFieldKind + 6u) const int kKind6 = 0;
layout(constant_id = kGenSpecFieldKind + 7u) const int kKind7 = 0;
layout(constant_id = kGenSpecFieldKind + 8u) const int kKind8 = 0;
layout(constant_id = kGenSpecFieldKind + 9u) const int kKind9 = 0;
layout(constant_id = kGenSpecFieldKind + 10u) const int kKind10 = 0;
layout(constant_id = kGenSpecFieldComponents + 0u) const int kComponents0 = 1;
layout(constant_id = kGenSpecFieldComponents + 1u) const int kComponents1 = 1;
layout(constant_id = kGenSpecFieldComponents + 2u) const int kComponents2 = 1;
layout(constant_id = kGenSpecFieldComponents + 3u) const int kComponents3 = 1;
layout(constant_id = kGenSpecFieldComponents + 4u) const int kComponents4 = 1;
layout(constant_id = kGenSpecFieldComponents + 5u) const int kComponents5 = 1;
layout(constant_id = kGenSpecFieldComponents + 6u) const int kComponents6 = 1;
layout(constant_id = kGenSpecFieldComponents + 7u) const int kComponents7 = 1;
layout(constant_id = kGenSpecFieldComponents + 8u) const int kComponents8 = 1;
layout(constant_id = kGenSpecFieldComponents + 9u) const int kComponents9 = 1;
layout(constant_id = kGenSpecFieldComponents + 10u) const int kComponents10 = 1;
layout(constant_id = kGenSpecClump) const uint kClumpBits = 0u;

// The accessors spot_generate.h reads: buffers, with what the specialization fixes as constants
// (the slot is a constant at every call, so each field folds to its one kind).
uvec3 spotMeshTriangle(uint t) {
    return uvec3(triangles[3u * t], triangles[3u * t + 1u], triangles[3u * t + 2u]);
}
vec3 spotMeshPosition(uint v) {
    return vec3(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}
vec3 spotMeshNormal(uint v) {
    return vec3(normals[3u * v], normals[3u * v + 1u], normals[3u * v + 2u]);
}
vec3 spotMeshTangent(uint v) {
    if (!kTangents)
        return vec3(0.0);
    return vec3(tangents[3u * v], tangents[3u * v + 1u], tangents[3u * v + 2u]);
}
vec2 spotMeshUv(uint v) { return kUv ? vec2(uvs[2u * v], uvs[2u * v + 1u]) : vec2(0.0); }
SpotPiece spotCellPiece(uint i) { return pieces[i]; }
float spotFieldData(uint i) { return fieldData[i]; }
vec4 spotParamDistribution() { return params.distribution; }
vec4 spotParamVariation0() { return params.variation0; }
vec4 spotParamVariation1() { return params.variation1; }
uvec4 spotParamFlags() {
    uint mesh = (kUv ? 1u : 0u) | (kTangents ? 2u : 0u);
    return uvec4(params.flags.x, kJittered ? 1u : 0u, kComb ? 1u : 0u, mesh);
}
vec4 spotParamLod() { return push.lod; } // w = 0: off (a uniform branch: not worth a variant)
SpotField spotParamField(uint slot) { return params.fields[slot]; }
ivec2 spotParamFieldKind(uint slot) {
    switch (slot) {
    case 0u: return ivec2(kKind0, kComponents0);
    case 1u: return ivec2(kKind1, kComponents1);
    case 2u: return ivec2(kKind2, kComponents2);
    case 3u: return ivec2(kKind3, kComponents3);
    case 4u: return ivec2(kKind4, kComponents4);
    case 5u: return ivec2(kKind5, kComponents5);
    case 6u: return ivec2(kKind6, kComponents6);
    case 7u: return ivec2(kKind7, kComponents7);
    case 8u: return ivec2(kKind8, kComponents8);
    case 9u: return ivec2(kKind9, kComponents9);
    default: return ivec2(kKind10, kComponents10);
    }
}
vec4 spotParamClump() { return params.clump; }
vec4 spotParamClump2() { return params.clump2; }
uvec4 spotParamClumpFlags() { return uvec4(params.clumpFlags.x, kClumpBits, 0u, 0u); }

#include "spot_generate.h"

void main() {
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    uint id = group * kGenGroup + gl_LocalInvocationID.x;
    if (id >= push.counts.y)
        return;
    // The cell holding candidate id: the last cell whose offset is <= id (binary search).
    uint lo = 0u;
    uint hi = push.counts.x - 1u;
    for (int step = 0; step < 32 && lo < hi; ++step) {
        uint mid = (lo + hi + 1u) / 2u;
        if (cells[mid].info.z <= id)
            lo = mid;
        else
            hi = mid - 1u;
    }
    SpotCell cell = cells[lo];
    SpotImpulse imp;
    // The candidate's place in the whole generation (a partial one lists only some cells).
    uint rank = id - cell.info.z;
#ifdef SPOT_GEN_PARTIAL
    uint g = dirtyOffsets[lo] + rank;
#else
    uint g = id;
#endif
    // Poisson: every candidate is examined; jittered: those the host listed.
#if SPOT_GEN_JITTERED
    uint m = sites[g];
#else
    uint m = rank;
#endif
    bool accepted = spotCandidate(cell, m, imp);
    if (accepted)
        scratch[g] = imp;
    flags[g] = accepted ? 1u : 0u;
}
