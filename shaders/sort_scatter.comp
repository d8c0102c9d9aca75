#version 450
// Radix sort, pass 5 of 5 per digit (spot_sort.h): one invocation per chunk walks its pairs in
// order and writes each to the next free position of its digit, read from and advanced in the
// chunk's own histogram column. Chunks' positions are ordered by chunk within each digit, pairs
// by position within the chunk: a stable scatter, no atomics. Loop iterations: chunk <= 2,048.
#extension GL_GOOGLE_include_directive : require
#include "spot_sort.h"

layout(local_size_x = kSortGroup) in;
layout(push_constant) uniform Push { SpotSortPush sortPush; };

layout(std430, binding = kSortBindKeys) readonly buffer KeysIn { uint keysIn[]; };
layout(std430, binding = kSortBindValues) readonly buffer ValuesIn { uint valuesIn[]; };
layout(std430, binding = kSortBindKeysOut) writeonly buffer KeysOut { uint keysOut[]; };
layout(std430, binding = kSortBindValuesOut) writeonly buffer ValuesOut { uint valuesOut[]; };
layout(std430, binding = kSortBindHistogram) buffer Histogram { uint hist[]; };

void main() {
    uint c = gl_GlobalInvocationID.x;
    uint n = sortPush.counts.x;
    uint chunk = sortPush.counts.y;
    uint chunks = sortPush.counts.z;
    uint shift = sortPush.counts.w;
    if (c >= chunks)
        return;
    uint begin = c * chunk;
    uint end = min(begin + chunk, n);
    for (uint i = begin; i < end; ++i) {
        uint key = keysIn[i];
        uint slot = ((key >> shift) & (kSortRadix - 1u)) * chunks + c;
        uint position = hist[slot];
        hist[slot] = position + 1u;
        keysOut[position] = key;
        valuesOut[position] = valuesIn[i];
    }
}
