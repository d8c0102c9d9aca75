#version 450
// Hybrid, the closest kernel by a separate depth pass (docs/design.md section 4: "measure both
// ways"): the same quads as the OIT pass, each fragment the kernel's alpha and view depth along
// the pixel's ray (splatKernel, as splat_oit.frag); where alpha exceeds kSplatHybridMinAlpha,
// depth = view depth x kSplatClosestDepthScale (exact: a power of two) against a depth test LESS,
// and the kernel index into an R32_UINT target. Primitive order breaks ties (the first kernel
// wins), so the pixel's kernel is exactly the one the single-pass 64-bit atomicMin of
// (depth bits, index) finds.
#extension GL_GOOGLE_include_directive : require
#define SPLAT_READS_LOBES
#define SPLAT_FRAGMENT
#include "splat_common.glsl"

layout(binding = kSplatBindMeshDistance, r32f) uniform readonly image2D meshDistance;

layout(location = 0) flat in uint vKernel;

layout(location = 0) out uint outKernel;

void main() {
    if (!splatMeetsSupport())
        discard; // alpha 0 (splatMeetsSupport)
    SplatKernelSample s = splatKernel(vKernel, gl_FragCoord.xy, imageLoad(meshDistance, ivec2(gl_FragCoord.xy)).r);
    if (!(s.alpha > kSplatHybridMinAlpha))
        discard;
    gl_FragDepth = min(max(s.depth, 0.0) * kSplatClosestDepthScale, 1.0);
    outKernel = vKernel;
}
