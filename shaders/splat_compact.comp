#version 450
// Deterministic stream compaction of the kernels prepare.comp kept (non-empty quad): their
// indices in increasing order, and the indirect draw of one 4-vertex strip per kept kernel. With
// the compute path (kSmallPixels > 0), the small kernels go to a second list, in increasing
// order within each of four size classes, with the indirect dispatch of splat_small.comp; and
// when every kernel left to draw would fit the compute path's loop (a pixel box of at most
// kSplatMaxSmallPixels centres), they all take it and nothing is drawn: on lavapipe a frame that
// draws any kernel pays a fixed cost that grows with the kernel count (docs/design.md section 4),
// more than the compute path's lanes lose on kernels of up to a few hundred pixels. One
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

// Per chunk: x, the kernels drawn; y, those of them whose pixel box holds more than
// kSplatMaxSmallPixels centres (none in the whole list: none is drawn).
shared uvec2 sums[kSplatCompactThreads];
shared uvec4 smallSums[kSplatCompactThreads]; // the small kernels per size class
shared uvec4 drawnSums[kSplatCompactThreads]; // the drawn ones per size class, should none be drawn

// The compute path's size class of a pixel box of `pixels` centres.
uint sizeClass(uint pixels) {
    return pixels <= 2u ? 0u : pixels <= 6u ? 1u : pixels <= 16u ? 2u : 3u;
}

// 0: culled (an empty quad, or one whose pixel box holds no pixel centre); 1 + c: drawn, or with
// every drawn kernel fitting the compute path, small in class c (the compute path's
// kSmallPixels > 0 only); 5 + c: too large for the compute path (always drawn); 10 + c: small
// (kSmallPixels > 0: the compute path, splat_small.comp), c its size class.
uint kind(uint i) {
    SpotKernelBound b = bounds[i];
    if (!(b.quad.z > 0.0))
        return 0u;
    if (kSmallPixels == 0u)
        return 5u;
    ivec2 lo;
    ivec2 hi;
    uint pixels = splatQuadPixelBox(b, lo, hi);
    if (pixels == 0u)
        return 0u;
    if (pixels > kSplatMaxSmallPixels)
        return 5u;
    return (pixels > kSmallPixels ? 1u : 10u) + sizeClass(pixels);
}

// One-hot of size class c from kind `k` = base + c (zero for other kinds).
uvec4 classOf(uint k, uint base) {
    return uvec4(equal(uvec4(k), uvec4(base) + uvec4(0u, 1u, 2u, 3u)));
}

void main() {
    uint n = min(impulseCount, frame.counts.x);
    uint t = gl_LocalInvocationID.x;
    uint chunk = (n + kSplatCompactThreads - 1u) / kSplatCompactThreads;
    uint begin = min(t * chunk, n);
    uint end = min(begin + chunk, n);
    uvec2 count = uvec2(0u); // drawn; drawn and too large for the compute path
    uvec4 smallCount = uvec4(0u);
    uvec4 drawnCount = uvec4(0u);
    for (uint i = begin; i < end; ++i) {
        uint k = kind(i);
        count += uvec2(k >= 1u && k < 10u ? 1u : 0u, k >= 5u && k < 10u ? 1u : 0u);
        smallCount += classOf(k, 10u);
        drawnCount += classOf(k, 1u);
    }
    sums[t] = count;
    smallSums[t] = smallCount;
    drawnSums[t] = drawnCount;
    barrier();
    // Inclusive Hillis-Steele scans over the 256 chunk counts.
    for (uint offset = 1u; offset < kSplatCompactThreads; offset <<= 1u) {
        uvec2 add = t >= offset ? sums[t - offset] : uvec2(0u);
        uvec4 addSmall = t >= offset ? smallSums[t - offset] : uvec4(0u);
        uvec4 addDrawn = t >= offset ? drawnSums[t - offset] : uvec4(0u);
        barrier();
        sums[t] += add;
        smallSums[t] += addSmall;
        drawnSums[t] += addDrawn;
        barrier();
    }
    // Nothing drawn when every kernel left to draw fits the compute path (none of kind 5 + c).
    bool noneDrawn = kSmallPixels > 0u && sums[kSplatCompactThreads - 1u].y == 0u;
    uint out_ = sums[t].x - count.x;
    // The small list holds the size classes one after the other (each in impulse order), so the
    // compute path's neighbouring invocations, which share a SIMD vector, loop about as long.
    uvec4 smallBefore = smallSums[t] - smallCount;
    uvec4 total = smallSums[kSplatCompactThreads - 1u];
    if (noneDrawn) {
        smallBefore += drawnSums[t] - drawnCount;
        total += drawnSums[kSplatCompactThreads - 1u];
    }
    uvec4 outSmall = uvec4(0u, total.x, total.x + total.y, total.x + total.y + total.z) + smallBefore;
    for (uint i = begin; i < end; ++i) {
        uint k = kind(i);
        if (noneDrawn && k >= 1u && k < 5u)
            k += 9u; // small after all
        if (k >= 1u && k < 10u) {
            visible[out_++] = i;
        } else if (k >= 10u) {
            uint c = k - 10u;
            small[outSmall[c]] = i;
            outSmall[c] += 1u;
        }
    }
    if (t == kSplatCompactThreads - 1u) {
        draw[0] = 4u;
        draw[1] = noneDrawn ? 0u : sums[t].x;
        draw[2] = 0u;
        draw[3] = 0u;
        uint smallTotal = total.x + total.y + total.z + total.w;
        draw[4] = (smallTotal + kSplatSmallThreads - 1u) / kSplatSmallThreads;
        draw[5] = 1u;
        draw[6] = 1u;
        draw[7] = smallTotal;
    }
}
