#version 450
// Deterministic stream compaction of the kernels prepare.comp kept (non-empty quad): their
// indices in increasing order, and the indirect draw of one 4-vertex strip per kept kernel. With
// the compute path (kSmallPixels > 0), the small kernels go to a second list, also in increasing
// order, with the indirect dispatch of splat_small.comp. One
// workgroup: each thread counts a contiguous chunk, a shared-memory scan gives the chunk's output
// offset, then each thread writes its chunk in order. No atomics, so the draw order (and with it
// the blended result) is the same on every run. Loop iterations per thread: 2 x chunk + 16, with
// chunk = ceil(count / 256) <= 3,641 for the most impulses a 128 MiB buffer holds.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(local_size_x = 256) in;

layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindVisible) writeonly buffer Visible { uint visible[]; };
layout(std430, binding = kSplatBindDraw) writeonly buffer Indirect { uint draw[8]; }; // kSplatBindDraw
layout(std430, binding = kSplatBindCount) readonly buffer Count { uint impulseCount; };
layout(std430, binding = kSplatBindSmall) writeonly buffer Small { uint small[]; };

shared uint sums[kSplatCompactThreads];
shared uint smallSums[kSplatCompactThreads];

// 0: culled (an empty quad, or one whose pixel box holds no pixel centre); 1: drawn; 2: small
// (kSmallPixels > 0: the compute path, splat_small.comp).
uint kind(uint i) {
    SpotKernelBound b = bounds[i];
    if (!(b.quad.z > 0.0))
        return 0u;
    if (kSmallPixels == 0u)
        return 1u;
    ivec2 lo;
    ivec2 hi;
    uint pixels = splatQuadPixelBox(b, lo, hi);
    return pixels == 0u ? 0u : pixels <= kSmallPixels ? 2u : 1u;
}

void main() {
    uint n = min(impulseCount, frame.counts.x);
    uint t = gl_LocalInvocationID.x;
    uint chunk = (n + kSplatCompactThreads - 1u) / kSplatCompactThreads;
    uint begin = min(t * chunk, n);
    uint end = min(begin + chunk, n);
    uint count = 0u;
    uint smallCount = 0u;
    for (uint i = begin; i < end; ++i) {
        uint k = kind(i);
        count += k == 1u ? 1u : 0u;
        smallCount += k == 2u ? 1u : 0u;
    }
    sums[t] = count;
    smallSums[t] = smallCount;
    barrier();
    // Inclusive Hillis-Steele scans over the 256 chunk counts.
    for (uint offset = 1u; offset < kSplatCompactThreads; offset <<= 1u) {
        uint add = t >= offset ? sums[t - offset] : 0u;
        uint addSmall = t >= offset ? smallSums[t - offset] : 0u;
        barrier();
        sums[t] += add;
        smallSums[t] += addSmall;
        barrier();
    }
    uint out_ = sums[t] - count;
    uint outSmall = smallSums[t] - smallCount;
    for (uint i = begin; i < end; ++i) {
        uint k = kind(i);
        if (k == 1u)
            visible[out_++] = i;
        else if (k == 2u)
            small[outSmall++] = i;
    }
    if (t == kSplatCompactThreads - 1u) {
        draw[0] = 4u;
        draw[1] = sums[t];
        draw[2] = 0u;
        draw[3] = 0u;
        uint smallTotal = smallSums[t];
        draw[4] = (smallTotal + kSplatSmallThreads - 1u) / kSplatSmallThreads;
        draw[5] = 1u;
        draw[6] = 1u;
        draw[7] = smallTotal;
    }
}
