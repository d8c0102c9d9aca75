#version 450
// Sorted splatting: the kernels arrive back to front (splat_sorted_keys.comp and the radix sort)
// and each is blended over what lies behind it with premultiplied "over" (ONE,
// ONE_MINUS_SRC_ALPHA) onto the base mesh colour: C = C_k + (1 - alpha_k) C. Rasterized blending
// follows primitive order, so the result is the same on every run. The kernel's colour and alpha
// at this pixel come from the code every method shares (splatKernel: its lobes composited front to
// back, integrated up to the mesh).
#extension GL_GOOGLE_include_directive : require
#define SPLAT_READS_LOBES
#define SPLAT_FRAGMENT
#define SPLAT_COUNTS
#include "splat_common.glsl"

// The depth test against the mesh (splat_quad.vert) runs before shading despite the side effects.
layout(early_fragment_tests) in;

layout(binding = kSplatBindMeshDistance, r32f) uniform readonly image2D meshDistance;

layout(location = 0) flat in uint vKernel;

layout(location = 0) out vec4 outColor;

void main() {
    splatCountFragment();
    if (!splatMeetsSupport())
        discard; // alpha 0 (splatMeetsSupport)
    SplatKernelSample s = splatKernel(vKernel, gl_FragCoord.xy, imageLoad(meshDistance, ivec2(gl_FragCoord.xy)).r);
    splatCountCovered(s.alpha);
    if (!(s.alpha > 0.0))
        discard;
    outColor = vec4(s.premul, s.alpha);
}
