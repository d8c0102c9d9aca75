#version 450
// Instanced opaque kernels (paper fig. 4 left): where the kernel's alpha at this pixel reaches
// kSplatInstancedMinAlpha it is drawn opaque with its mean colour at its depth, tested against
// the mesh and the other kernels; elsewhere the fragment is discarded.
#extension GL_GOOGLE_include_directive : require
#define SPLAT_LOBES_BINDING 2
#include "splat_common.glsl"

layout(binding = 3, r32f) uniform readonly image2D meshDistance;

layout(location = 0) flat in uint vKernel;

layout(location = 0) out vec4 outColor;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    float tMesh = imageLoad(meshDistance, pixel).r;
    vec3 o;
    vec3 d;
    splatPixelRay(gl_FragCoord.xy, o, d);
    SplatKernelSample s = splatKernel(vKernel, o, d, tMesh);
    if (!(s.alpha >= kSplatInstancedMinAlpha))
        discard;
    outColor = vec4(s.premul / s.alpha, 1.0);
    gl_FragDepth = spotReversedDepth(splatViewDepth(o + s.depth * d), frame.forward.w);
}
