#version 450
// The light-space structure, passes 3 (spot_shadow.h), one invocation per work item (a tile of
// a triangle's or a lobe's texels), indirect over the list pass 2 made.
//  SHADOW_MESH_RASTER: triangle items: per texel ray, the triangle's hit (atomicMin into the
//    mesh's depth map).
//  SHADOW_DEPOSIT: lobe items: per texel ray, the lobe's exact optical depth over each layer its
//    support's chord crosses (erf between the layer's boundaries), with its first and second
//    moments along the ray in the layer's coordinate, added in fixed point; the last layer takes
//    all that lies beyond.
// Each returns at once for the other kind's items (the list holds both).
#extension GL_GOOGLE_include_directive : require
#include "light_build.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = kShadowBindItems) readonly buffer Items { SpotShadowList list; uvec2 items[]; };
#ifdef SHADOW_MESH_RASTER
layout(std430, binding = kShadowBindVertices) readonly buffer Vertices { SpotMeshVertex vertices[]; };
layout(std430, binding = kShadowBindIndices) readonly buffer Indices { uint indices[]; };
#else
layout(std430, binding = kShadowBindPlaced) readonly buffer Placed { SpotWorldLobe placed[]; };
#endif

void main() {
    uint index = gl_GlobalInvocationID.x;
    if (index >= list.count || index >= push.n.w)
        return;
    ShadowItem it = shadowUnpackItem(items[index]);
    uint v = it.view;
    SpotShadowView view = lit.views[v];
    vec3 square = shadowSquare(v);
    uint r = view.offsets.w;
    bool ortho = view.origin.w < 0.5;
    ivec2 tileLo = ivec2(it.tile * kShadowTile);
    ivec2 tileHi = min(tileLo + int(kShadowTile) - 1, ivec2(int(r) - 1));
    // Texel (x, y)'s ray: orthographic rays are parallel, their origins affine in (x, y).
    vec3 o00 = square.x * view.axisU.xyz + square.y * view.axisW.xyz;
    vec3 ox = square.z * view.axisU.xyz;
    vec3 oy = square.z * view.axisW.xyz;
#ifdef SHADOW_MESH_RASTER
    if ((it.source & kShadowTriangleBit) == 0u)
        return;
    uint t = it.source & ~kShadowTriangleBit;
    vec3 p0 = vertices[indices[3u * t]].position.xyz;
    vec3 e1 = vertices[indices[3u * t + 1u]].position.xyz - p0;
    vec3 e2 = vertices[indices[3u * t + 2u]].position.xyz - p0;
    for (int y = tileLo.y; y <= tileHi.y; ++y) {
        for (int x = tileLo.x; x <= tileHi.x; ++x) {
            vec3 o, d;
            if (ortho) {
                o = o00 + (float(x) + 0.5) * ox + (float(y) + 0.5) * oy;
                d = view.axisD.xyz;
            } else {
                shadowTexelRay(v, square, uint(x), uint(y), o, d);
            }
            // Moller-Trumbore
            vec3 pv = cross(d, e2);
            float det = dot(e1, pv);
            float inv = 1.0 / det;
            vec3 tv = o - p0;
            float b1 = dot(tv, pv) * inv;
            vec3 qv = cross(tv, e1);
            float b2 = dot(d, qv) * inv;
            float s = dot(e2, qv) * inv;
            if (!(abs(det) > 1e-30) || b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0 || (!ortho && !(s > 0.0)))
                continue;
            uint texel = uint(y) * r + uint(x);
            atomicMin(firstDepth[view.offsets.z + texel], spotOrderedBits(floatBitsToUint(s)));
        }
    }
#else
    if ((it.source & kShadowTriangleBit) != 0u)
        return;
    mat3 A;
    vec3 c;
    float amp;
    if (!shadowLobe(v, placed[it.source], square, A, c, amp))
        return;
    ivec2 lo, hi;
    float near;
    if (!shadowLobeRect(v, A, c, square, lo, hi, near))
        return;
    lo = max(lo, tileLo);
    hi = min(hi, tileHi);
    float k = push.k.x;
    uint layerCount = uint(view.axisW.w);
    float thickness = view.axisD.w;
    float first = uintBitsToFloat(spotOrderedToBits(
        firstDepth[view.offsets.y + shadowTileOf(uint(tileLo.x), uint(tileLo.y), r)]));
    // The ray in lobe space: A (o - c) affine in (x, y) for orthographic views.
    vec3 ol00 = A * (o00 - c);
    vec3 olx = A * ox;
    vec3 oly = A * oy;
    vec3 dl0 = A * view.axisD.xyz;
    for (int y = lo.y; y <= hi.y; ++y) {
        for (int x = lo.x; x <= hi.x; ++x) {
            vec3 ol, dl;
            if (ortho) {
                ol = ol00 + (float(x) + 0.5) * olx + (float(y) + 0.5) * oly;
                dl = dl0;
            } else {
                vec3 o, d;
                shadowTexelRay(v, square, uint(x), uint(y), o, d);
                ol = A * (o - c);
                dl = A * d;
            }
            float tStar, perp2, halfChord;
            if (!spotLobeLine(ol, dl, k, tStar, perp2, halfChord))
                continue;
            float ta = tStar - halfChord;
            float tb = tStar + halfChord;
            if (!ortho)
                ta = max(ta, 0.0); // a point light's ray starts at the light
            if (!(tb > ta))
                continue;
            float len = length(dl);
            float scale = amp * kSqrtTwoPi / len * exp(-0.5 * perp2);
            int k0 = clamp(int(floor((ta - first) / thickness)), 0, int(layerCount) - 1);
            int k1 = clamp(int(floor((tb - first) / thickness)), 0, int(layerCount) - 1);
            uint base = view.offsets.x + (uint(y) * r + uint(x)) * layerCount * 3u;
            float sigma = 1.0 / len;
            for (int layer = k0; layer <= k1; ++layer) {
                float start = first + float(layer) * thickness;
                float a = layer == 0 ? ta : max(ta, start);
                float b = layer == int(layerCount) - 1 ? tb : min(tb, start + thickness);
                if (!(b > a))
                    continue;
                float alpha = (a - tStar) * len;
                float beta = (b - tStar) * len;
                float share = spotErfDifferenceHalf(alpha * kInvSqrtTwo, beta * kInvSqrtTwo);
                float tau = scale * share;
                if (!(tau > 0.0))
                    continue;
                // The part's mean and variance along the ray (a truncated Gaussian), in the
                // layer's own coordinate u = (s - start) / thickness: where in the layer its
                // optical depth lies (the lookup's step, shadowTexelDepth).
                float pa = exp(-0.5 * alpha * alpha) * 0.3989422804014327;
                float pb = exp(-0.5 * beta * beta) * 0.3989422804014327;
                float z = max(share, 1e-30);
                float shift = (pa - pb) / z;
                float mean = tStar + sigma * shift;
                float variance = sigma * sigma * max(1.0 + (alpha * pa - beta * pb) / z - shift * shift, 0.0);
                float u = clamp((mean - start) / thickness, 0.0, 1.0);
                float u2 = u * u + variance / (thickness * thickness);
                float weight = min(tau, kShadowMaxDeposit) * kShadowFixed;
                uint w = base + 3u * uint(layer);
                uint fixedTau = uint(weight + 0.5);
                if (fixedTau == 0u)
                    continue;
                atomicAdd(layers[w], fixedTau);
                atomicAdd(layers[w + 1u], uint(weight * u + 0.5));
                atomicAdd(layers[w + 2u], uint(weight * min(u2, 1.0) + 0.5));
            }
        }
    }
#endif
}
