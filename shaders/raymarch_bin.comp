#version 450
// Ray march, step 1: which impulses each shell cell holds. One invocation per impulse: its cell's
// record (the shared hash lookup), then first index, end index and count per record with integer
// atomics (order independent, so deterministic). The host reads them back, checks the impulses
// are in cell order (each cell's impulses contiguous, cells in the shell's sorted order) and
// builds every record's 27-neighbour ranges.
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"
#include "raymarch_layout.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Params { SpotMarchParams params; };
layout(std430, binding = 1) readonly buffer Table { ivec4 table[]; };
layout(std430, binding = 2) readonly buffer Impulses { SpotImpulse impulses[]; };
// [0, n): first impulse (0xffffffff: none); [n, 2n): one past the last; [2n, 3n): count;
// [3n]: impulses whose cell is not in the shell (n = records).
layout(std430, binding = 3) buffer Bins { uint bins[]; };

layout(push_constant) uniform Push {
    uint count;   // impulses
    uint records; // shell cells
} pc;

SpotMarchParams marchParams() { return params; }
ivec4 marchSlot(uint i) { return table[i]; }

#define RAYMARCH_LOOKUP_ONLY
#include "raymarch_shared.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    uint loops = 0u;
    int record = marchFind(impulses[i].cell.xyz, loops);
    if (record < 0) {
        atomicAdd(bins[3u * pc.records], 1u);
        return;
    }
    uint r = uint(record);
    atomicMin(bins[r], i);
    atomicMax(bins[pc.records + r], i + 1u);
    atomicAdd(bins[2u * pc.records + r], 1u);
}
