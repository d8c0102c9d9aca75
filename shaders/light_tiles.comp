#version 450
// The light-space structure, pass 2 (spot_shadow.h): per lobe (or, with SHADOW_MESH, per mesh
// triangle) and view, the tiles of kShadowTile x kShadowTile texels it covers, appended to the
// work list that the texel passes run over; a lobe also lowers the start of its tiles' layers to
// the nearest point of its support (an indirect dispatch: one invocation a tile, so no
// invocation loops over more than a tile however large the lobe). The list's order varies from
// run to run; what the texel passes add (integer atomics) does not.
#extension GL_GOOGLE_include_directive : require
#include "light_build.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = kShadowBindItems) buffer Items { SpotShadowList list; uvec2 items[]; };
#ifdef SHADOW_MESH
layout(std430, binding = kShadowBindVertices) readonly buffer Vertices { SpotMeshVertex vertices[]; };
layout(std430, binding = kShadowBindIndices) readonly buffer Indices { uint indices[]; };
#else
layout(std430, binding = kShadowBindCount) readonly buffer Count { uint impulseCount; };
layout(std430, binding = kShadowBindPlaced) readonly buffer Placed { SpotWorldLobe placed[]; };
#endif

void append(uint source, uint v, ivec2 lo, ivec2 hi) {
    uvec2 t0 = uvec2(lo) / kShadowTile;
    uvec2 t1 = uvec2(hi) / kShadowTile;
    uint n = (t1.x - t0.x + 1u) * (t1.y - t0.y + 1u);
    uint at = atomicAdd(list.count, n);
    if (at + n > push.n.w)
        return; // over capacity: the host sees the count and grows the list
    atomicMax(list.groupsX, (at + n + kShadowGroup - 1u) / kShadowGroup);
    for (uint ty = t0.y; ty <= t1.y; ++ty)
        for (uint tx = t0.x; tx <= t1.x; ++tx)
            items[at++] = shadowPackItem(source, v, uvec2(tx, ty));
}

void main() {
    uint views = push.n.z;
#ifdef SHADOW_MESH
    uint t = shadowIndex();
    if (t >= push.n.x)
        return;
    vec3 p0 = vertices[indices[3u * t]].position.xyz;
    vec3 p1 = vertices[indices[3u * t + 1u]].position.xyz;
    vec3 p2 = vertices[indices[3u * t + 2u]].position.xyz;
    for (uint v = 0u; v < views; ++v) {
        bool ok0, ok1, ok2;
        vec3 c0 = shadowCoords(v, p0, ok0);
        vec3 c1 = shadowCoords(v, p1, ok1);
        vec3 c2 = shadowCoords(v, p2, ok2);
        if (!(ok0 && ok1 && ok2))
            continue; // crosses a point light's eye plane: it casts no shadow there
        vec3 square = shadowSquare(v);
        int r = int(lit.views[v].offsets.w);
        vec2 flo = floor((min(min(c0.xy, c1.xy), c2.xy) - square.xy) / square.z - 0.5);
        vec2 fhi = floor((max(max(c0.xy, c1.xy), c2.xy) - square.xy) / square.z - 0.5) + 1.0;
        if (any(isnan(flo)) || any(isnan(fhi)) || fhi.x < 0.0 || fhi.y < 0.0 ||
            flo.x > float(r - 1) || flo.y > float(r - 1))
            continue;
        append(t | kShadowTriangleBit, v, ivec2(clamp(flo, vec2(0.0), vec2(float(r - 1)))),
               ivec2(clamp(fhi, vec2(0.0), vec2(float(r - 1)))));
    }
#else
    uint i = shadowIndex();
    if (i >= push.n.x || i / push.n.y >= impulseCount)
        return;
    SpotWorldLobe w = placed[i];
    for (uint v = 0u; v < views; ++v) {
        vec3 square = shadowSquare(v);
        mat3 A;
        vec3 c;
        float amp;
        ivec2 lo, hi;
        float near;
        if (!shadowLobe(v, w, square, A, c, amp) || !shadowLobeRect(v, A, c, square, lo, hi, near))
            continue;
        append(i, v, lo, hi);
        // Where the layers of the tiles it touches may start.
        SpotShadowView view = lit.views[v];
        uint r = view.offsets.w;
        uint bits = spotOrderedBits(floatBitsToUint(near));
        for (uint ty = uint(lo.y) / kShadowTile; ty <= uint(hi.y) / kShadowTile; ++ty)
            for (uint tx = uint(lo.x) / kShadowTile; tx <= uint(hi.x) / kShadowTile; ++tx)
                atomicMin(firstDepth[view.offsets.y + shadowTileOf(tx * kShadowTile, ty * kShadowTile, r)], bits);
    }
#endif
}
