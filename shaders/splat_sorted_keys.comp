#version 450
// Sorted method: the sort key of each kept kernel, ahead of the radix sort (splat/passes/radix_sort_vk.h).
// Kernels are composited back to front, so the key is the bitwise complement of the kernel's
// view depth's float bits: for depths >= 0 the float bits order as the floats do, their
// complement in reverse. The kernel's depth is the view depth of its centre of mass
// (SpotKernelBound.axis.z, from splat_prepare.comp: its lobe centres weighted by their masses
// a / |det A|, which EWA widening conserves): where a kernel's lobes sit along a strand, the
// centre of what it shows, not its root.
// Entries past the kept count (the compaction's draw) get the largest key and no kernel: the sort
// is stable, so they stay after every kept kernel, and the draw never reaches them.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindVisible) buffer Visible { uint visible[]; };
layout(std430, binding = kSplatBindDraw) readonly buffer Indirect { uint draw[kSplatDrawWords]; };
layout(std430, binding = kSplatBindKeys) writeonly buffer Keys { uint keys[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= frame.counts.x)
        return;
    if (i >= draw[0] / kSplatQuadIndices) { // the quads' index count
        keys[i] = 0xffffffffu;
        visible[i] = 0xffffffffu;
        return;
    }
    keys[i] = ~floatBitsToUint(bounds[visible[i]].axis.z);
}
