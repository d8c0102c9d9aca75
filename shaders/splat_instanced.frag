#version 450
// Instanced opaque kernels (paper fig. 4 left): a kernel covers a pixel, opaque with its mean
// colour, where one of its lobes' optical depth there reaches that lobe's cover threshold (so its
// opaque footprint covers as much as the lobe does: spotCoverThreshold) and its depth is nearer
// than the mesh's (splatInstancedCovers), and the nearest covering kernel wins. The nearest is found as
// the hybrid finds its closest kernel: a 64-bit atomicMin of (depth bits << 32 | kernel index)
// into a storage buffer (the index breaks ties as a depth test does, the first drawn kernel
// winning); the resolve paints the winner's colour over the mesh. No depth is written, so the
// test against the mesh (the quad at its kernel's nearest depth) runs before shading.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#define SPLAT_READS_LOBES
#define SPLAT_FRAGMENT
#define SPLAT_COUNTS
#define SPLAT_INSTANCED_COVER
#include "splat_common.glsl"

layout(early_fragment_tests) in;

layout(binding = kSplatBindMeshDistance, r32f) uniform readonly image2D meshDistance;
layout(std430, binding = kSplatBindClosest) buffer Closest { uint64_t closest[]; };

layout(location = 0) flat in uint vKernel;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    splatCountFragment();
    if (!splatMeetsSupport())
        discard; // alpha 0 (splatMeetsSupport)
    float tMesh = imageLoad(meshDistance, pixel).r;
    SplatKernelSample s = splatKernel(vKernel, gl_FragCoord.xy, tMesh);
    splatCountCovered(s.alpha);
    if (splatInstancedCovers(s, gl_FragCoord.xy, tMesh)) {
        uint64_t key = (uint64_t(floatBitsToUint(max(s.depth, 0.0))) << 32) | uint64_t(vKernel);
        atomicMin(closest[splatPixelIndex(pixel)], key);
    }
}
