#version 450
// Radix sort, pass 2 of 5 per digit (spot_sort.h): one invocation per block of kSortScanBlock
// histogram entries sums its block. Loop iterations: kSortScanBlock = 1,024.
#extension GL_GOOGLE_include_directive : require
#include "spot_sort.h"

layout(local_size_x = kSortGroup) in;
layout(push_constant) uniform Push { SpotSortPush sortPush; };

layout(std430, binding = kSortBindHistogram) readonly buffer Histogram { uint hist[]; };
layout(std430, binding = kSortBindBlockSums) writeonly buffer BlockSums { uint blockSums[]; };

void main() {
    uint b = gl_GlobalInvocationID.x;
    uint entries = sortPush.scan.x;
    if (b >= sortPush.scan.y)
        return;
    uint begin = b * kSortScanBlock;
    uint end = min(begin + kSortScanBlock, entries);
    uint sum = 0u;
    for (uint i = begin; i < end; ++i)
        sum += hist[i];
    blockSums[b] = sum;
}
