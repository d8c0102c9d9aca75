#version 450
// Deterministic stream compaction of the kernels prepare.comp kept (non-empty quad): their
// indices in increasing order, and the indirect draw of one 4-vertex strip per kept kernel. One
// workgroup: each thread counts a contiguous chunk, a shared-memory scan gives the chunk's output
// offset, then each thread writes its chunk in order. No atomics, so the draw order (and with it
// the blended result) is the same on every run. Loop iterations per thread: 2 x chunk + 16, with
// chunk = ceil(count / 256) <= 3,641 for the most impulses a 128 MiB buffer holds.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(local_size_x = 256) in;

layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindVisible) writeonly buffer Visible { uint visible[]; };
layout(std430, binding = kSplatBindDraw) writeonly buffer Indirect { uint draw[4]; }; // VkDrawIndirectCommand
layout(std430, binding = kSplatBindCount) readonly buffer Count { uint impulseCount; };

shared uint sums[kSplatCompactThreads];

bool kept(uint i) { return bounds[i].quad.z > 0.0; }

void main() {
    uint n = min(impulseCount, frame.counts.x);
    uint t = gl_LocalInvocationID.x;
    uint chunk = (n + kSplatCompactThreads - 1u) / kSplatCompactThreads;
    uint begin = min(t * chunk, n);
    uint end = min(begin + chunk, n);
    uint count = 0u;
    for (uint i = begin; i < end; ++i)
        count += kept(i) ? 1u : 0u;
    sums[t] = count;
    barrier();
    // Inclusive Hillis-Steele scan over the 256 chunk counts.
    for (uint offset = 1u; offset < kSplatCompactThreads; offset <<= 1u) {
        uint add = t >= offset ? sums[t - offset] : 0u;
        barrier();
        sums[t] += add;
        barrier();
    }
    uint out_ = sums[t] - count;
    for (uint i = begin; i < end; ++i)
        if (kept(i))
            visible[out_++] = i;
    if (t == kSplatCompactThreads - 1u) {
        draw[0] = 4u;
        draw[1] = sums[t];
        draw[2] = 0u;
        draw[3] = 0u;
    }
}
