#version 450
// Baked renderer, the peel passes' vertices: the shell's boundary faces that a ray can enter
// through (the top surface, one face per triangle, and the side faces of open mesh edges) that
// face the eye, as baked_shell.comp listed them this frame (4 tet + face; it lists nearly
// edge-on ones too), 3 vertices each pulled from the shell. Only faces that face the eye are
// drawn (a back face's three vertices collapse to one point, so it covers no pixel).
// Reversed depth near / z as the base mesh's (splat_mesh.vert); perspective cameras only.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(std430, binding = kBakedBindTets) readonly buffer Tets { SpotBakedTet tets[]; };
layout(std430, binding = kBakedBindPeelDraw) readonly buffer PeelDraw { uvec4 peelDraw; uint entryFaces[]; };

layout(location = 0) flat out uint vEntry;

void main() {
    uint entry = entryFaces[uint(gl_VertexIndex) / 3u];
    uint tet = entry >> 2u;
    uint face = entry & 3u; // the face opposite corner `face`
    uint corner = uint(gl_VertexIndex) % 3u;
    vec3 p[4];
    for (uint i = 0u; i < 4u; ++i)
        p[i] = tets[tet].world[i].xyz;
    uint i0 = (face + 1u) % 4u, i1 = (face + 2u) % 4u, i2 = (face + 3u) % 4u;
    vec3 n = cross(p[i1] - p[i0], p[i2] - p[i0]);
    if (dot(n, p[face] - p[i0]) > 0.0)
        n = -n; // outwards
    bool front = dot(n, p[i0] - frame.eye.xyz) < 0.0;
    vec3 x = front ? p[corner == 0u ? i0 : corner == 1u ? i1 : i2] : p[i0];
    vEntry = entry;
    vec3 rel = x - frame.eye.xyz;
    float sx = dot(rel, frame.right.xyz) / frame.right.w;
    float sy = -dot(rel, frame.up.xyz) / frame.up.w;
    float z = dot(rel, frame.forward.xyz);
    gl_Position = vec4(sx, sy, frame.forward.w, z);
}
