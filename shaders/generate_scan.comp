#version 450
// Impulse generation, pass 2 of 3 (spot_generate_layout.h): the accepted flags become 1-based
// output indices in candidate order (0 for a rejected candidate), and the impulse count is
// written. Any non-zero flag counts as accepted, so a generation that decides only some cells'
// candidates again (GpuGenerator::refreshFields(cells)) scans the others' indices as they stand.
// One workgroup: each thread counts a contiguous chunk, a shared-memory scan gives the
// chunk's first index, then each thread numbers its chunk in order. No atomics: the order is the
// candidates' order on every run. Loop iterations per thread: 2 x chunk + 8.
#extension GL_GOOGLE_include_directive : require
#include "spot_generate_layout.h"

layout(local_size_x = kGenScanThreads) in;

layout(push_constant) uniform Push { SpotGenPush push; };

layout(std430, binding = kGenBindFlags) buffer Flags { uint flags[]; };
layout(std430, binding = kGenBindCount) writeonly buffer Count { uint impulseCount; };

shared uint sums[kGenScanThreads];

void main() {
    uint n = push.counts.y;
    uint t = gl_LocalInvocationID.x;
    uint chunk = (n + kGenScanThreads - 1u) / kGenScanThreads;
    uint begin = min(t * chunk, n);
    uint end = min(begin + chunk, n);
    uint count = 0u;
    for (uint i = begin; i < end; ++i)
        count += flags[i] != 0u ? 1u : 0u;
    sums[t] = count;
    barrier();
    // Inclusive Hillis-Steele scan over the chunk totals.
    for (uint offset = 1u; offset < kGenScanThreads; offset <<= 1u) {
        uint add = t >= offset ? sums[t - offset] : 0u;
        barrier();
        sums[t] += add;
        barrier();
    }
    uint index = sums[t] - count;
    for (uint i = begin; i < end; ++i)
        flags[i] = flags[i] != 0u ? ++index : 0u;
    if (t == kGenScanThreads - 1u)
        impulseCount = sums[t];
}
