#version 450
// Baked renderer, pass 1: the shell, rebuilt every frame from the mesh's vertices (so that an
// animated mesh's shell follows it). Per triangle, its prism (base vertices on the mesh, top
// vertices thickness along the unit vertex normals) split into 3 tetrahedra by noise/shell.h's
// rule: corners sorted by index v0 < v1 < v2, (b0, b1, b2, t2), (b0, b1, t2, t1),
// (b0, t0, t1, t2). Each corner carries its position now (world) and at rest (the texture
// coordinate into the bake).
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = kBakedBindParams) readonly buffer Params { SpotBakedParams params; };
layout(std430, binding = kBakedBindVertices) readonly buffer Vertices { SpotMeshVertex vertices[]; };
layout(std430, binding = kBakedBindRest) readonly buffer Rest { SpotMeshVertex rest[]; };
layout(std430, binding = kBakedBindIndices) readonly buffer Indices { uint indices[]; };
layout(std430, binding = kBakedBindTets) writeonly buffer Tets { SpotBakedTet tets[]; };

vec3 extrude(SpotMeshVertex v, bool top) {
    float len = length(v.normal.xyz);
    vec3 n = len > 0.0 ? v.normal.xyz / len : vec3(0.0);
    return v.position.xyz + (top ? params.grid.w : 0.0) * n;
}

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= params.counts.x)
        return;
    uint a = indices[3u * t], b = indices[3u * t + 1u], c = indices[3u * t + 2u];
    uint v0 = min(a, min(b, c)), v2 = max(a, max(b, c));
    uint v1 = a + b + c - v0 - v2;
    // Corners (vertex, top?) of the three tetrahedra, as in noise::prismTetrahedra.
    const uvec4 kCorner[3] = uvec4[3](uvec4(0u, 1u, 2u, 2u), uvec4(0u, 1u, 2u, 1u),
                                      uvec4(0u, 0u, 1u, 2u));
    const uvec4 kTop[3] = uvec4[3](uvec4(0u, 0u, 0u, 1u), uvec4(0u, 0u, 1u, 1u),
                                   uvec4(0u, 1u, 1u, 1u));
    uint sorted[3] = uint[3](v0, v1, v2);
    for (uint k = 0u; k < 3u; ++k) {
        SpotBakedTet tet;
        for (uint i = 0u; i < 4u; ++i) {
            uint v = sorted[kCorner[k][i]];
            bool top = kTop[k][i] != 0u;
            tet.world[i] = vec4(extrude(vertices[v], top), 1.0);
            tet.rest[i] = vec4(extrude(rest[v], top), 1.0);
        }
        tets[3u * t + k] = tet;
    }
}
