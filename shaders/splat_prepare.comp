#version 450
// Per impulse: its kernel's lobes placed in the world (spotPlaceLobe), optionally EWA-widened by
// the pixel footprint at the lobe's depth (spotWidenLobe), and the kernel's screen rectangle and
// depth range (SpotKernelBound). An empty rectangle culls the kernel (off screen, behind the
// camera, zero weight or no lobe with extinction).
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Impulses { SpotImpulse impulses[]; };
layout(std430, binding = 1) readonly buffer Lobes { SpotLobe lobes[]; };
layout(std430, binding = 2) writeonly buffer WorldLobes { SpotWorldLobe worldLobes[]; };
layout(std430, binding = 3) writeonly buffer Bounds { SpotKernelBound bounds[]; };

bool finite3(vec3 v) { return !any(isnan(v)) && !any(isinf(v)); }

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= frame.counts.x)
        return;
    SpotImpulse imp = impulses[i];
    uint lobeCount = frame.counts.y;
    float k = frame.size.w;
    mat3 kernelFrame = mat3(imp.frameX.xyz, imp.frameY.xyz, imp.frameZ.xyz);
    bool perspective = !splatOrthographic();
    // Pixel bounds of the kernel, and the view depth range of its support.
    vec2 lo = vec2(1e30);
    vec2 hi = vec2(-1e30);
    float zMin = 1e30;
    float zMax = -1e30;
    uint live = 0u;
    for (uint l = 0u; l < lobeCount; ++l) {
        SpotLobe lobe = lobes[l];
        mat3 inv = mat3(lobe.inv0.xyz, lobe.inv1.xyz, lobe.inv2.xyz);
        vec3 kernelCentre = vec3(lobe.inv0.w, lobe.inv1.w, lobe.inv2.w);
        vec3 centre;
        mat3 A = spotPlaceLobe(inv, kernelCentre, kernelFrame, imp.scale.xyz, imp.normal.w,
                               imp.position.xyz, centre);
        float amplitude = lobe.color.w * imp.position.w;
        if (splatFlag(kSplatFlagEwa)) {
            // Box pixel filter of one footprint: variance footprint^2 / 12 per image axis.
            float z = max(splatViewDepth(centre), 0.0);
            float footprint = frame.size.z * (perspective ? z : 1.0);
            vec3 dir = perspective ? normalize(centre - frame.eye.xyz) : frame.forward.xyz;
            float scale;
            A = spotWidenLobe(A, dir, footprint * 0.28867513459481287, scale);
            amplitude *= scale;
        }
        mat3 M = inverse(A);
        bool ok = amplitude > 0.0 && !isinf(amplitude) && finite3(A[0]) && finite3(A[1]) &&
                  finite3(A[2]) && finite3(centre) && finite3(M[0]) && finite3(M[1]) && finite3(M[2]);
        SpotWorldLobe w;
        w.a0 = vec4(A[0], centre.x);
        w.a1 = vec4(A[1], centre.y);
        w.a2 = vec4(A[2], centre.z);
        w.color = vec4(lobe.color.rgb * imp.color.rgb, ok ? amplitude : 0.0);
        if (!ok) {
            w.a0 = vec4(0.0);
            w.a1 = vec4(0.0);
            w.a2 = vec4(0.0);
        }
        worldLobes[i * lobeCount + l] = w;
        if (!ok)
            continue;
        // The support's exact screen extent (tangent planes through the eye).
        vec3 rel = centre - frame.eye.xyz;
        float x0;
        float x1;
        float y0;
        float y1;
        float lobeZMin;
        float lobeZMax;
        bool bounded = spotEllipsoidRange(rel, M, k, frame.right.xyz, frame.forward.xyz, !perspective,
                                          x0, x1, lobeZMin, lobeZMax);
        spotEllipsoidRange(rel, M, k, frame.up.xyz, frame.forward.xyz, !perspective, y0, y1, lobeZMin,
                           lobeZMax);
        if (lobeZMax <= 0.0)
            continue; // wholly behind the camera: no ray (t >= 0) reaches it
        vec2 lobeLo = vec2(0.0);
        vec2 lobeHi = frame.size.xy; // reaches the eye plane: the projection is unbounded
        if (bounded && !isnan(x0 + x1 + y0 + y1)) {
            lobeLo = vec2(0.5 * (x0 / frame.right.w + 1.0) * frame.size.x,
                          0.5 * (1.0 - y1 / frame.up.w) * frame.size.y);
            lobeHi = vec2(0.5 * (x1 / frame.right.w + 1.0) * frame.size.x,
                          0.5 * (1.0 - y0 / frame.up.w) * frame.size.y);
        }
        lo = min(lo, lobeLo);
        hi = max(hi, lobeHi);
        zMin = min(zMin, lobeZMin);
        zMax = max(zMax, lobeZMax);
        ++live;
    }
    // Pixels whose centre lies in [lo, hi]: a pixel whose centre is outside cannot see the kernel.
    vec4 rect = vec4(0.0);
    if (live > 0u) {
        rect.xy = max(floor(lo), vec2(0.0));
        rect.zw = min(ceil(hi), frame.size.xy);
        if (!(rect.z > rect.x && rect.w > rect.y))
            rect = vec4(0.0);
    }
    SpotKernelBound b;
    b.rect = rect;
    b.depth = vec4(zMin, zMax, splatViewDepth(imp.position.xyz), float(lobeCount));
    bounds[i] = b;
}
