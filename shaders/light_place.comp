#version 450
// The light-space structure, pass 1 (spot_shadow.h): per impulse, its kernel's lobes placed in
// the world as the reference places them (no widening).
#extension GL_GOOGLE_include_directive : require
#include "light_build.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = kShadowBindImpulses) readonly buffer Impulses { SpotImpulse impulses[]; };
layout(std430, binding = kShadowBindLobes) readonly buffer Lobes { SpotLobe lobes[]; };
layout(std430, binding = kShadowBindCount) readonly buffer Count { uint impulseCount; };
layout(std430, binding = kShadowBindPlaced) writeonly buffer Placed { SpotWorldLobe placed[]; };

void main() {
    uint i = shadowIndex();
    if (i >= impulseCount || i >= push.n.x)
        return;
    SpotImpulse imp = impulses[i];
    mat3 kernelFrame = mat3(imp.frameX.xyz, imp.frameY.xyz, imp.frameZ.xyz);
    uint lobeCount = push.n.y;
    for (uint l = 0u; l < lobeCount; ++l) {
        SpotLobe lobe = lobes[l];
        mat3 inv = mat3(lobe.inv0.xyz, lobe.inv1.xyz, lobe.inv2.xyz);
        vec3 kernelCentre = vec3(lobe.inv0.w, lobe.inv1.w, lobe.inv2.w);
        vec3 centre;
        mat3 A = spotPlaceLobe(inv, kernelCentre, kernelFrame, imp.scale.xyz, imp.normal.w,
                               imp.position.xyz, centre);
        float amplitude = lobe.color.w * imp.position.w;
        bool ok = amplitude > 0.0 && !isinf(amplitude) && !any(isnan(A[0] + A[1] + A[2])) &&
                  !any(isinf(A[0] + A[1] + A[2])) && !any(isnan(centre)) && !any(isinf(centre));
        SpotWorldLobe w;
        w.a0 = vec4(A[0], centre.x);
        w.a1 = vec4(A[1], centre.y);
        w.a2 = vec4(A[2], centre.z);
        w.color = vec4(0.0, 0.0, 0.0, ok ? amplitude : 0.0);
        placed[i * lobeCount + l] = w;
    }
}
