#version 450
// OIT splatting (paper eq. 10-12): the kernel's premultiplied colour and alpha at this pixel,
// weighted (McGuire and Bavoil 2013) into an additive accumulation target. MB13's revealage
// prod (1 - alpha) is kept as its logarithm, the sum of the kernels' optical depths
// (-ln(1 - alpha) = tau), with the same additive blend: the same value, one blend state for both
// targets (the context does not enable independentBlend), no precision lost for opaque kernels,
// and the hybrid's resolve can take one kernel out exactly. Hybrid (eq. 13; the module compiled
// with SPLAT_CLOSEST_ATOMIC, splat_oit_closest.frag, which alone declares the buffer): the kernel
// also competes for the pixel's closest kernel with a 64-bit atomicMin of
// (depth bits << 32 | kernel index); depth is >= 0, so its float bits order as the floats do,
// and the kernel index breaks ties the same way every run.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#define SPLAT_READS_LOBES
#define SPLAT_FRAGMENT
#define SPLAT_COUNTS
#include "splat_common.glsl"

// The depth test against the mesh (splat_quad.vert) runs before shading despite the side effects.
layout(early_fragment_tests) in;

layout(binding = kSplatBindMeshDistance, r32f) uniform readonly image2D meshDistance;
#ifdef SPLAT_CLOSEST_ATOMIC
layout(std430, binding = kSplatBindClosest) buffer Closest { uint64_t closest[]; };
#endif

layout(location = 0) flat in uint vKernel;

layout(location = 0) out vec4 outAccum;
layout(location = 1) out float outOpticalDepth;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    splatCountFragment();
    if (!splatMeetsSupport())
        discard; // alpha 0 (splatMeetsSupport)
    SplatKernelSample s = splatKernel(vKernel, gl_FragCoord.xy, imageLoad(meshDistance, pixel).r);
    splatCountCovered(s.alpha);
    if (!(s.alpha > 0.0))
        discard;
#ifdef SPLAT_CLOSEST_ATOMIC
    if (s.alpha > kSplatHybridMinAlpha) {
        uint64_t key = (uint64_t(floatBitsToUint(max(s.depth, 0.0))) << 32) | uint64_t(vKernel);
        atomicMin(closest[splatPixelIndex(pixel)], key);
    }
#endif
    outAccum = vec4(s.premul, s.alpha) * splatOitWeight(s);
    outOpticalDepth = s.tau;
}
