#version 450
// Sorted method: the sort key of each kept kernel, ahead of the radix sort (splat/sort_vk.h).
// Kernels are composited back to front, so the key is the bitwise complement of the kernel's
// view depth's float bits: for depths >= 0 the float bits order as the floats do, their
// complement in reverse. The kernel's depth is the view depth of its centre of mass (its lobe
// centres weighted by their masses a / |det A|, which EWA widening conserves): where a kernel's
// lobes sit along a strand, the centre of what it shows, not its root. Negative depths (a kernel
// reaching behind a perspective eye) count as 0.
// Entries past the kept count (the compaction's draw) get the largest key and no kernel: the sort
// is stable, so they stay after every kept kernel, and the draw never reaches them.
#extension GL_GOOGLE_include_directive : require
#define SPLAT_LOBES_BINDING 3
#include "splat_common.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = 1) buffer Visible { uint visible[]; };
layout(std430, binding = 2) readonly buffer Indirect { uint draw[4]; }; // VkDrawIndirectCommand
layout(std430, binding = 4) writeonly buffer Keys { uint keys[]; };

float kernelDepth(uint kernel) {
    uint lobes = frame.counts.y;
    float massSum = 0.0;
    float depthSum = 0.0;
    for (uint l = 0u; l < lobes; ++l) {
        SpotWorldLobe w = worldLobes[kernel * lobes + l];
        if (!(w.color.w > 0.0))
            continue;
        float mass = w.color.w / abs(determinant(splatLobeMatrix(w)));
        if (!(mass > 0.0) || isinf(mass))
            continue;
        massSum += mass;
        depthSum += mass * splatViewDepth(splatLobeCentre(w));
    }
    float z = massSum > 0.0 && !isinf(massSum) ? depthSum / massSum : bounds[kernel].depth.z;
    return z > 0.0 ? z : 0.0; // also maps NaN and -0 to +0
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= frame.counts.x)
        return;
    if (i >= draw[1]) {
        keys[i] = 0xffffffffu;
        visible[i] = 0xffffffffu;
        return;
    }
    keys[i] = ~floatBitsToUint(kernelDepth(visible[i]));
}
