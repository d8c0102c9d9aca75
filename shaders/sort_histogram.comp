#version 450
// Radix sort, pass 1 of 5 per digit (spot_sort.h): one invocation per chunk of consecutive pairs
// counts the digit of each of its keys, then writes the counts to its own histogram column
// (hist[digit * chunks + chunk]): no atomics. Loop iterations: 2 x kSortRadix + chunk <= 2,560.
#extension GL_GOOGLE_include_directive : require
#include "spot_sort.h"

layout(local_size_x = kSortGroup) in;
layout(push_constant) uniform Push { SpotSortPush sortPush; };

layout(std430, binding = kSortBindKeys) readonly buffer Keys { uint keys[]; };
layout(std430, binding = kSortBindHistogram) writeonly buffer Histogram { uint hist[]; };

void main() {
    uint c = gl_GlobalInvocationID.x;
    uint n = sortPush.counts.x;
    uint chunk = sortPush.counts.y;
    uint chunks = sortPush.counts.z;
    uint shift = sortPush.counts.w;
    if (c >= chunks)
        return;
    uint counts[kSortRadix];
    for (uint d = 0u; d < kSortRadix; ++d)
        counts[d] = 0u;
    uint begin = c * chunk;
    uint end = min(begin + chunk, n);
    for (uint i = begin; i < end; ++i)
        counts[(keys[i] >> shift) & (kSortRadix - 1u)] += 1u;
    for (uint d = 0u; d < kSortRadix; ++d)
        hist[d * chunks + c] = counts[d];
}
