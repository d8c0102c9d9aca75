#version 450
// Sorted splatting: the kernels arrive back to front (splat_sorted_keys.comp and the radix sort)
// and each is blended over what lies behind it with premultiplied "over" (ONE,
// ONE_MINUS_SRC_ALPHA) onto the base mesh colour: C = C_k + (1 - alpha_k) C. Rasterized blending
// follows primitive order, so the result is the same on every run. The kernel's colour and alpha
// at this pixel come from the code every method shares (splatKernel: its lobes composited front to
// back, integrated up to the mesh).
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
    if (!(s.alpha > 0.0))
        discard;
    outColor = vec4(s.premul, s.alpha);
}
