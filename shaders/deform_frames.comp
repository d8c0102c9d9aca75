#version 450
// Deform pass 3 of 4 (spot_deform_layout.h): each triangle's rotation from rest to the pose
// (spotTriangleRotation); a triangle the pose collapses keeps the rotation it had.
#extension GL_GOOGLE_include_directive : require
#include "deform_common.glsl"
#include "spot_deform.h"

layout(std430, binding = kDeformBindPosed) readonly buffer Posed { SpotMeshVertex posed[]; };
layout(std430, binding = kDeformBindRest) readonly buffer Rest { SpotMeshVertex rest[]; };
layout(std430, binding = kDeformBindIndices) readonly buffer Indices { uint indices[]; };
layout(std430, binding = kDeformBindRotations) buffer Rotations { vec4 rotations[]; };

void main() {
    uint t = deformInvocation();
    if (t >= push.counts.y)
        return;
    uvec3 tri = uvec3(indices[3u * t], indices[3u * t + 1u], indices[3u * t + 2u]);
    mat3 R = mat3(rotations[3u * t].xyz, rotations[3u * t + 1u].xyz, rotations[3u * t + 2u].xyz);
    if (spotTriangleRotation(rest[tri.x].position.xyz, rest[tri.y].position.xyz,
                             rest[tri.z].position.xyz, posed[tri.x].position.xyz,
                             posed[tri.y].position.xyz, posed[tri.z].position.xyz, R)) {
        rotations[3u * t] = vec4(R[0], 0.0);
        rotations[3u * t + 1u] = vec4(R[1], 0.0);
        rotations[3u * t + 2u] = vec4(R[2], 0.0);
    }
}
