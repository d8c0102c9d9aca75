#version 450
// Deterministic stream compaction of the kernels prepare.comp kept (non-empty quad): their
// indices in increasing order, and the indirect indexed draw of one quad per kept kernel
// (kSplatQuadIndices indices each, spot_splat.h). With
// the compute path (kSmallPixels > 0), the small kernels go to a second list, in increasing
// order within each of four size classes, with the indirect dispatch of splat_small.comp: those
// whose pixel box holds at most kSmallPixels centres, and the thin ones (at most 3 pixels wide)
// whose box holds at most kSplatMaxSmallPixels. One workgroup: each thread counts a contiguous
// chunk, a shared-memory scan gives the chunk's output offset, then each thread writes its chunk
// in order. No atomics, so the draw order (and with it the blended result) is the same on every
// run. The compute path's list exists in the module compiled with SPLAT_SMALL_LIST alone
// (splat_compact_small.comp: the methods that have that path). Loop iterations per thread: 2 x chunk + 16, with chunk = ceil(count / 256) <= 3,641 for
// the most impulses a 128 MiB buffer holds.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(local_size_x = 256) in;

layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindVisible) writeonly buffer Visible { uint visible[]; };
layout(std430, binding = kSplatBindDraw) writeonly buffer Indirect { uint draw[kSplatDrawWords]; }; // kSplatBindDraw
layout(std430, binding = kSplatBindCount) readonly buffer Count { uint impulseCount; };
#ifdef SPLAT_SMALL_LIST
layout(std430, binding = kSplatBindSmall) writeonly buffer Small { uint small[]; };
#endif

shared uint sums[kSplatCompactThreads];
shared uvec4 smallSums[kSplatCompactThreads];

// 0: culled (an empty quad, or one whose pixel box holds no pixel centre); 1: drawn; 2 + c:
// small (kSmallPixels > 0: the compute path, splat_small.comp), c its size class. A thin quad
// (half width at most kSplatThinHalfWidth pixels) fills few lanes of the 4x4 blocks lavapipe
// shades it in, so it is cheaper walked pixel by pixel, as long as the walk stays within
// kSplatMaxSmallPixels (docs/design.md section 4).
uint kind(uint i) {
    SpotKernelBound b = bounds[i];
    if (!(b.quad.z > 0.0))
        return 0u;
    if (kSmallPixels == 0u)
        return 1u;
    ivec2 lo;
    ivec2 hi;
    uint pixels = splatQuadPixelBox(b, lo, hi);
    if (pixels == 0u)
        return 0u;
    bool thin = min(b.quad.z, b.quad.w) <= kSplatThinHalfWidth;
    if (pixels > kSmallPixels && !(thin && pixels <= kSplatMaxSmallPixels))
        return 1u;
    return 2u + (pixels <= 2u ? 0u : pixels <= 6u ? 1u : pixels <= 16u ? 2u : 3u);
}

// One-hot of a small kernel's size class (zero for the others).
uvec4 smallClass(uint k) {
    return uvec4(equal(uvec4(k), uvec4(2u, 3u, 4u, 5u)));
}

void main() {
    uint n = min(impulseCount, frame.counts.x);
    uint t = gl_LocalInvocationID.x;
    uint chunk = (n + kSplatCompactThreads - 1u) / kSplatCompactThreads;
    uint begin = min(t * chunk, n);
    uint end = min(begin + chunk, n);
    uint count = 0u;
    uvec4 smallCount = uvec4(0u);
    for (uint i = begin; i < end; ++i) {
        uint k = kind(i);
        count += k == 1u ? 1u : 0u;
        smallCount += smallClass(k);
    }
    sums[t] = count;
    smallSums[t] = smallCount;
    barrier();
    // Inclusive Hillis-Steele scans over the 256 chunk counts.
    for (uint offset = 1u; offset < kSplatCompactThreads; offset <<= 1u) {
        uint add = t >= offset ? sums[t - offset] : 0u;
        uvec4 addSmall = t >= offset ? smallSums[t - offset] : uvec4(0u);
        barrier();
        sums[t] += add;
        smallSums[t] += addSmall;
        barrier();
    }
    uint out_ = sums[t] - count;
    // The small list holds the size classes one after the other (each in impulse order), so the
    // compute path's neighbouring invocations, which share a SIMD vector, loop about as long.
    uvec4 total = smallSums[kSplatCompactThreads - 1u];
    uvec4 outSmall = uvec4(0u, total.x, total.x + total.y, total.x + total.y + total.z) +
                     smallSums[t] - smallCount;
    for (uint i = begin; i < end; ++i) {
        uint k = kind(i);
        if (k == 1u) {
            visible[out_++] = i;
        }
#ifdef SPLAT_SMALL_LIST
        else if (k >= 2u) {
            uint c = k - 2u;
            small[outSmall[c]] = i;
            outSmall[c] += 1u;
        }
#endif
    }
    if (t == kSplatCompactThreads - 1u) {
        draw[0] = kSplatQuadIndices * sums[t]; // VkDrawIndexedIndirectCommand
        draw[1] = 1u;
        draw[2] = 0u;
        draw[3] = 0u;
        draw[4] = 0u;
        uint smallTotal = total.x + total.y + total.z + total.w;
        draw[kSplatDrawDispatch] = (smallTotal + kSplatSmallThreads - 1u) / kSplatSmallThreads;
        draw[kSplatDrawDispatch + 1u] = 1u;
        draw[kSplatDrawDispatch + 2u] = 1u;
        draw[kSplatDrawSmallCount] = smallTotal;
    }
}
