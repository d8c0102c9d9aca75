#version 450
// One oriented quad per kept kernel, from its screen bound (centre, half extents along u and v):
// vertex 4k + c is corner c of the compacted kernel list's entry k (the indexed draw of
// spot_splat.h's kSplatQuadIndices; c's bit 0 the +u side, bit 1 the +v side). Each corner also
// carries the kernel's lobes in screen form (splat_common.glsl: vLobeA, vLobeB): the ray direction
// in lobe space is affine in the pixel, so the rasterizer interpolates it exactly. The
// quad lies at the reversed depth of the kernel's nearest point: where the mesh is nearer, the
// depth test drops the pixel before any shading (exact: the ray meets the mesh first).
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindVisible) readonly buffer Visible { uint visible[]; };
layout(std430, binding = kSplatBindScreenLobes) readonly buffer ScreenLobes { SpotScreenLobe screenLobes[]; };
layout(std430, binding = kSplatBindWorldLobes) readonly buffer WorldLobes { SpotWorldLobe worldLobes[]; };

layout(location = 0) flat out uint vKernel;
layout(location = 1) noperspective out vec3 vLobeA[kLobes];
layout(location = 9) flat out vec4 vLobeB[kLobes];
layout(location = 17) flat out vec3 vColor;
layout(location = 18) flat out float vOffImage;
// Lambert (kShadeVaryings, splat_common.glsl): per lobe A^T applied to the lobe-space ray, the
// part affine in the pixel (vShadeA) and the constant one (vShadeB).
layout(location = 19) noperspective out vec3 vShadeA[kShadeLobes];
layout(location = 25) flat out vec3 vShadeB[kShadeLobes];

void main() {
    uint kernel = visible[uint(gl_VertexIndex) / 4u];
    SpotKernelBound b = bounds[kernel];
    vec2 u = b.axis.xy;
    vec2 v = vec2(-u.y, u.x);
    float su = (gl_VertexIndex & 1) != 0 ? 1.0 : -1.0;
    float sv = (gl_VertexIndex & 2) != 0 ? 1.0 : -1.0;
    vec2 corner = b.quad.xy + su * b.quad.z * u + sv * b.quad.w * v;
    // The depth of the support's nearest point, tested against the mesh (reversed depth).
    gl_Position = vec4(2.0 * corner / frame.size.xy - 1.0, spotReversedDepth(b.axis.w, frame.forward.w), 1.0);
    vKernel = kernel;
    // Whether the quad reaches past the image (splat_common.glsl: vOffImage).
    vec2 reach = abs(u) * b.quad.z + abs(v) * b.quad.w;
    vOffImage = any(lessThan(b.quad.xy - reach, vec2(0.0))) ||
                        any(greaterThan(b.quad.xy + reach, frame.size.xy))
                    ? 1.0
                    : 0.0;
    vColor = b.color.rgb;
    for (uint l = 0u; l < kLobes; ++l) {
        SpotScreenLobe s = screenLobes[kernel * kLobes + l];
        // o' rebuilt at this corner from the affine w and n (the stored one differs in
        // rounding where the form is ill-conditioned; the compute path takes w and n so too).
        vec3 v, stored;
        vec4 wo = splatScreenLobeAt(s, corner, v, stored);
        vec3 o = (cross(v, wo.xyz) + wo.w * v) / dot(v, v); // w = o' x v, n = o'.v
        vLobeA[l] = kOrthographic ? o : v;
        vLobeB[l] = vec4(kOrthographic ? v : o, s.ay.w);
        if (kShadeVaryings) {
            SpotWorldLobe wl = worldLobes[kernel * kLobes + l];
            mat3 At = transpose(mat3(wl.a0.xyz, wl.a1.xyz, wl.a2.xyz));
            vShadeA[l] = At * vLobeA[l];
            vShadeB[l] = At * vLobeB[l].xyz;
        }
    }
    if (!kShadeVaryings) {
        vShadeA[0] = vec3(0.0);
        vShadeB[0] = vec3(0.0);
    }
}
