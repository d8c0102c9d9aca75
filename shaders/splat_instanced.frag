#version 450
// Instanced opaque kernels (paper fig. 4 left): where the kernel's alpha at this pixel reaches
// kSplatInstancedMinAlpha it is drawn opaque with its mean colour at its depth, tested against
// the mesh and the other kernels; elsewhere the fragment is discarded.
#extension GL_GOOGLE_include_directive : require
#define SPLAT_READS_LOBES
#define SPLAT_FRAGMENT
#define SPLAT_COUNTS
#include "splat_common.glsl"

layout(binding = kSplatBindMeshDistance, r32f) uniform readonly image2D meshDistance;

layout(location = 0) flat in uint vKernel;

layout(location = 0) out vec4 outColor;

void main() {
    float tMesh = imageLoad(meshDistance, ivec2(gl_FragCoord.xy)).r;
    // The depth written below rules out the early depth test: where the mesh is nearer than the
    // kernel's nearest point (view depth), the ray meets the mesh first, and nothing shows.
    if (vNearDepth * splatRayScale(gl_FragCoord.xy) >= tMesh)
        discard;
    SplatKernelSample s = splatKernel(vKernel, gl_FragCoord.xy, tMesh);
    splatCount(s.alpha);
    if (!(s.alpha >= kSplatInstancedMinAlpha))
        discard;
    outColor = vec4(s.premul / s.alpha, 1.0);
    gl_FragDepth = spotReversedDepth(s.depth, frame.forward.w);
}
