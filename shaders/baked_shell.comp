#version 450
// Baked renderer, pass 1: the shell, rebuilt every frame from the mesh's vertices (so that an
// animated mesh's shell follows it). Per triangle, its prism (base vertices on the mesh, top
// vertices thickness along the unit vertex normals) split into 3 tetrahedra by noise/shell.h's
// rule: corners sorted by index v0 < v1 < v2, (b0, b1, b2, t2), (b0, b1, t2, t1),
// (b0, t0, t1, t2), with corners 0 and 1 swapped where sorting reversed the triangle's winding
// (so that tetrahedron 3t + k and its face i, opposite corner i, are noise::shellTetrahedra's,
// whose neighbours the host uploads). Each corner carries its position now (world) and at rest
// (the texture coordinate into the bake): its 4 face planes, normals inwards, and its affine map
// from world now to rest, for the march.
// The peel's faces: of its tetrahedra's entry faces (the host's mask, and every face but the base
// of a folded tetrahedron, which the geometry decides each frame), those that face the eye
// (the eye on the face's outer side, or within 1e-3 of its distance of the face's plane: the
// peel's vertex shader decides those) are appended to the peel's draw, all of an invocation's
// with one atomicAdd. The list's order depends on the atomics' order; the peel keeps the same
// entry in any order (baked_peel.frag).
// The eye test: each invocation also tests its 3 tetrahedra against the eye, and the lowest
// index of those whose 4 face planes hold it is kept (atomicMin on an integer: deterministic;
// the host fills kBakedNoTet first). The first layer's march (baked_march.comp) starts every
// pixel's walk there, at t = 0, when the camera is inside the shell: an invocation that finds the
// eye raises the first layer's dispatch to cover every pixel.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"
#define SPOT_TET_WALK_BUILD_ONLY
#include "spot_tet_walk.h"

layout(local_size_x = 64) in;

layout(std430, binding = kBakedBindParams) readonly buffer Params { SpotBakedParams params; };
layout(std430, binding = kBakedBindVertices) readonly buffer Vertices { SpotMeshVertex vertices[]; };
layout(std430, binding = kBakedBindRest) readonly buffer Rest { SpotMeshVertex rest[]; };
layout(std430, binding = kBakedBindIndices) readonly buffer Indices { uint indices[]; };
layout(std430, binding = kBakedBindTets) writeonly buffer Tets { SpotBakedTet tets[]; };
layout(std430, binding = kBakedBindEyeTet) buffer EyeTet { uint eyeTet; };
layout(std430, binding = kBakedBindEntryMasks) readonly buffer EntryMasks { uint entryMasks[]; };
layout(std430, binding = kBakedBindPeelDraw) buffer PeelDraw { uvec4 peelDraw; uint peelFaces[]; };
layout(std430, binding = kBakedBindList) buffer List { SpotBakedList firstList; };

vec3 unitNormal(SpotMeshVertex v) {
    float len = length(v.normal.xyz);
    return len > 0.0 ? v.normal.xyz / len : vec3(0.0);
}

// The prism's 6 corners: base (slot c) and top (slot 3 + c) of sorted corner c.
void prismCorners(uint v0, uint v1, uint v2, out vec3 world[6], out vec3 atRest[6]) {
    uint sorted[3] = uint[3](v0, v1, v2);
    for (uint c = 0u; c < 3u; ++c) {
        SpotMeshVertex w = vertices[sorted[c]];
        SpotMeshVertex r = rest[sorted[c]];
        world[c] = w.position.xyz;
        atRest[c] = r.position.xyz;
        world[3u + c] = w.position.xyz + params.grid.w * unitNormal(w);
        atRest[3u + c] = r.position.xyz + params.grid.w * unitNormal(r);
    }
}

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= params.counts.x)
        return;
    uint a = indices[3u * t], b = indices[3u * t + 1u], c = indices[3u * t + 2u];
    uint v0 = min(a, min(b, c)), v2 = max(a, max(b, c));
    uint v1 = a + b + c - v0 - v2;
    // Each corner's slot among the prism's 6 (sorted corner + 3 for the top) in the three
    // tetrahedra, as in noise::prismTetrahedra; constants once the loops unroll, so the corners
    // stay in registers (a corner picked by a runtime index would be read from memory).
    const uvec4 kSlot[3] = uvec4[3](uvec4(0u, 1u, 2u, 5u), uvec4(0u, 1u, 5u, 4u),
                                    uvec4(0u, 3u, 4u, 5u));
    vec3 world[6], atRest[6];
    prismCorners(v0, v1, v2, world, atRest);
    bool reversed = !((a == v0 && b == v1) || (b == v0 && c == v1) || (c == v0 && a == v1));
    uint mask = entryMasks[t];
    uint front = 0u; // the entry faces that face the eye, bit 4 k + f
    // The faces of folded (inverted) tetrahedra are entries too: where the shell folds, the ray
    // can enter it across the fold, through a face inside the shell that both its tetrahedra lie
    // behind, with no boundary face before it (the walk, spot_tet_walk.h, follows the fold from
    // there). Not the base (face 3 of the prism's first tetrahedron: the mesh).
    uint folded = 0u;
    for (uint k = 0u; k < 3u; ++k) {
        SpotBakedTet tet;
        vec3 p[4], r[4];
        for (uint i = 0u; i < 4u; ++i) {
            p[i] = world[kSlot[k][i]];
            r[i] = atRest[kSlot[k][i]];
        }
        // Corners 0 and 1 swapped where sorting reversed the triangle's winding.
        vec3 p0 = p[0], r0 = r[0];
        p[0] = reversed ? p[1] : p[0];
        r[0] = reversed ? r[1] : r[0];
        p[1] = reversed ? p0 : p[1];
        r[1] = reversed ? r0 : r[1];
        for (uint i = 0u; i < 4u; ++i)
            tet.world[i] = vec4(p[i], 1.0);
        bool holdsEye = true;
        for (uint f = 0u; f < 4u; ++f) {
            vec3 a = p[(f + 1u) % 4u];
            tet.plane[f] = spotTetFacePlane(a, p[(f + 2u) % 4u], p[(f + 3u) % 4u], p[f]);
            float eyeSide = dot(tet.plane[f].xyz, frame.eye.xyz) + tet.plane[f].w;
            holdsEye = holdsEye && eyeSide >= 0.0;
            // Faces the eye (or nearly: the peel's vertex shader decides), so the peel draws it.
            if (eyeSide <= 1e-3 * length(tet.plane[f].xyz) * length(frame.eye.xyz - a))
                front |= 1u << (4u * k + f);
        }
        if (spotTetFolded(p[0], p[1], p[2], p[3]))
            folded |= (k == 0u ? 0x7u : 0xfu) << (4u * k);
        spotTetRestMap(p[0], p[1], p[2], p[3], r[0], r[1], r[2], r[3], tet.toRest[0],
                       tet.toRest[1], tet.toRest[2]);
        tets[3u * t + k] = tet;
        if (holdsEye) {
            atomicMin(eyeTet, 3u * t + k);
            uvec2 groups = spotBakedMarchGroups(uint(frame.size.x) * uint(frame.size.y));
            atomicMax(firstList.groups.x, groups.x);
            atomicMax(firstList.groups.y, groups.y);
        }
    }
    front &= mask | folded;
    if (front != 0u) {
        uint n = bitCount(front);
        uint slot = atomicAdd(peelDraw.x, 3u * n) / 3u;
        for (uint bit = 0u; bit < 12u; ++bit)
            if ((front & (1u << bit)) != 0u)
                peelFaces[slot++] = 4u * (3u * t + bit / 4u) + bit % 4u;
    }
}
