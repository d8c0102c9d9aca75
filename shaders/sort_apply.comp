#version 450
// Radix sort, pass 4 of 5 per digit (spot_sort.h): one invocation per block of kSortScanBlock
// histogram entries replaces them by their exclusive prefix sums over the whole histogram (the
// block's offset from sort_scan.comp plus the sums within the block). In digit-major order,
// entry (digit d, chunk c) is then where chunk c's first pair with digit d goes.
// Loop iterations: kSortScanBlock = 1,024.
#extension GL_GOOGLE_include_directive : require
#include "spot_sort.h"

layout(local_size_x = kSortGroup) in;
layout(push_constant) uniform Push { SpotSortPush sortPush; };

layout(std430, binding = kSortBindHistogram) buffer Histogram { uint hist[]; };
layout(std430, binding = kSortBindBlockSums) readonly buffer BlockSums { uint blockSums[]; };

void main() {
    uint b = gl_GlobalInvocationID.x;
    uint entries = sortPush.scan.x;
    if (b >= sortPush.scan.y)
        return;
    uint begin = b * kSortScanBlock;
    uint end = min(begin + kSortScanBlock, entries);
    uint running = blockSums[b];
    for (uint i = begin; i < end; ++i) {
        uint v = hist[i];
        hist[i] = running;
        running += v;
    }
}
