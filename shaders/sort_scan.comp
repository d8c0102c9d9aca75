#version 450
// Radix sort, pass 3 of 5 per digit (spot_sort.h): the exclusive prefix sum of the block sums,
// in place, by one workgroup: each thread sums a contiguous run of at most
// kSortMaxBlocksPerThread blocks, a shared-memory scan of the run totals gives each run's offset,
// then each thread writes its run's prefix sums. Loop iterations: 2 x 8 + 8 = 24 at most (the
// host checks blocks <= kSortScanThreads x kSortMaxBlocksPerThread).
#extension GL_GOOGLE_include_directive : require
#include "spot_sort.h"

layout(local_size_x = kSortScanThreads) in;
layout(push_constant) uniform Push { SpotSortPush sortPush; };

layout(std430, binding = kSortBindBlockSums) buffer BlockSums { uint blockSums[]; };

shared uint sums[kSortScanThreads];

void main() {
    uint blocks = sortPush.scan.y;
    uint t = gl_LocalInvocationID.x;
    uint per = (blocks + kSortScanThreads - 1u) / kSortScanThreads;
    uint begin = min(t * per, blocks);
    uint end = min(begin + per, blocks);
    uint total = 0u;
    for (uint i = begin; i < end; ++i)
        total += blockSums[i];
    sums[t] = total;
    barrier();
    // Inclusive Hillis-Steele scan over the run totals.
    for (uint offset = 1u; offset < kSortScanThreads; offset <<= 1u) {
        uint add = t >= offset ? sums[t - offset] : 0u;
        barrier();
        sums[t] += add;
        barrier();
    }
    uint running = sums[t] - total;
    for (uint i = begin; i < end; ++i) {
        uint v = blockSums[i];
        blockSums[i] = running;
        running += v;
    }
}
