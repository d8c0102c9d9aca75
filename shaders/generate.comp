#version 450
// Impulse generation on the GPU: the shared code of spot_generate.h over storage buffers.
// Three modes, so every invocation does a bounded amount of work and the output order is the
// CPU's (cell, candidate) order:
//   0 count:      one invocation per cell, candidate count into cells[i].info.w
//   1 candidates: one invocation per candidate (offsets in cells[i].info.z, prefix sums made on the
//                 host), the impulse into scratch[g], accepted flag into flags[g]
//   2 compact:    one invocation per candidate, accepted ones copied to impulses[flags[g] - 1]
//                 (flags replaced by 1-based compact indices on the host)
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Params { SpotGenParams params; };
layout(std430, binding = 1) buffer Cells { SpotCell cells[]; };
layout(std430, binding = 2) readonly buffer Pieces { SpotPiece pieces[]; };
layout(std430, binding = 3) readonly buffer Triangles { uint triangles[]; };
layout(std430, binding = 4) readonly buffer Positions { float positions[]; };
layout(std430, binding = 5) readonly buffer Normals { float normals[]; };
layout(std430, binding = 6) readonly buffer Tangents { float tangents[]; };
layout(std430, binding = 7) readonly buffer Uvs { float uvs[]; };
layout(std430, binding = 8) readonly buffer FieldData { float fieldData[]; };
layout(std430, binding = 9) buffer Scratch { SpotImpulse scratch[]; };
layout(std430, binding = 10) buffer Flags { uint flags[]; };
layout(std430, binding = 11) writeonly buffer Impulses { SpotImpulse impulses[]; };

layout(push_constant) uniform Push {
    uint mode;
    uint cellCount;
    uint candidateCount;
} pc;

uvec3 spotMeshTriangle(uint t) { return uvec3(triangles[3u * t], triangles[3u * t + 1u], triangles[3u * t + 2u]); }
vec3 spotMeshPosition(uint v) { return vec3(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]); }
vec3 spotMeshNormal(uint v) { return vec3(normals[3u * v], normals[3u * v + 1u], normals[3u * v + 2u]); }
vec3 spotMeshTangent(uint v) {
    return (params.flags.w & 2u) != 0u ? vec3(tangents[3u * v], tangents[3u * v + 1u], tangents[3u * v + 2u])
                                       : vec3(0.0);
}
vec2 spotMeshUv(uint v) { return (params.flags.w & 1u) != 0u ? vec2(uvs[2u * v], uvs[2u * v + 1u]) : vec2(0.0); }
SpotPiece spotCellPiece(uint i) { return pieces[i]; }
float spotFieldData(uint i) { return fieldData[i]; }
vec4 spotParamDistribution() { return params.distribution; }
vec4 spotParamVariation0() { return params.variation0; }
vec4 spotParamVariation1() { return params.variation1; }
uvec4 spotParamFlags() { return params.flags; }
vec4 spotParamLod() { return params.lod; }
SpotField spotParamField(uint slot) { return params.fields[slot]; }

#include "spot_generate.h"

void main() {
    uint id = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationID.x;
    if (pc.mode == 0u) {
        if (id < pc.cellCount)
            cells[id].info.w = spotCellCandidates(cells[id]);
        return;
    }
    if (id >= pc.candidateCount)
        return;
    if (pc.mode == 1u) {
        // The cell holding candidate id: the last cell whose offset is <= id (binary search).
        uint lo = 0u;
        uint hi = pc.cellCount - 1u;
        for (int step = 0; step < 32 && lo < hi; ++step) {
            uint mid = (lo + hi + 1u) / 2u;
            if (cells[mid].info.z <= id)
                lo = mid;
            else
                hi = mid - 1u;
        }
        SpotCell cell = cells[lo];
        SpotImpulse imp;
        bool accepted = spotCandidate(cell, id - cell.info.z, imp);
        if (accepted)
            scratch[id] = imp;
        flags[id] = accepted ? 1u : 0u;
        return;
    }
    if (flags[id] != 0u)
        impulses[flags[id] - 1u] = scratch[id];
}
