#version 450
// Deform pass 4 of 4 (spot_deform_layout.h): each impulse carried from its rest anchor to the
// pose (spotMoveAnchor: the posed point plus its height along the posed normal; its frame,
// normal and comb turned by its triangle's rotation), then by the wind about its root. Its cell
// becomes its root's at the pose (the ray march bins by it).
#extension GL_GOOGLE_include_directive : require
#include "deform_common.glsl"
#include "spot_deform.h"

layout(std430, binding = kDeformBindPosed) readonly buffer Posed { SpotMeshVertex posed[]; };
layout(std430, binding = kDeformBindIndices) readonly buffer Indices { uint indices[]; };
layout(std430, binding = kDeformBindRotations) readonly buffer Rotations { vec4 rotations[]; };
layout(std430, binding = kDeformBindImpulses) readonly buffer Impulses { SpotImpulse impulses[]; };
layout(std430, binding = kDeformBindMoved) writeonly buffer Moved { SpotImpulse moved[]; };
layout(std430, binding = kDeformBindCount) readonly buffer Count { uint count; };

void main() {
    uint i = deformInvocation();
    if (i >= min(count, push.counts.z))
        return;
    SpotImpulse imp = impulses[i];
    uint t = floatBitsToUint(imp.scale.w);
    float b1 = imp.color.w;
    float b2 = intBitsToFloat(imp.cell.w);
    vec3 b = vec3(1.0 - b1 - b2, b1, b2);
    uvec3 tri = uvec3(indices[3u * t], indices[3u * t + 1u], indices[3u * t + 2u]);
    mat3 R = mat3(rotations[3u * t].xyz, rotations[3u * t + 1u].xyz, rotations[3u * t + 2u].xyz);
    vec3 root;
    vec3 position;
    spotMoveAnchor(posed[tri.x].position.xyz, posed[tri.y].position.xyz,
                   posed[tri.z].position.xyz, posed[tri.x].normal.xyz, posed[tri.y].normal.xyz,
                   posed[tri.z].normal.xyz, b, imp.comb.w, R, imp.normal.xyz, root, position);
    mat3 turn = R;
    if (push.counts.w != 0u) {
        mat3 W = spotWindRotation(R * imp.normal.xyz, push.wind.xyz, push.wind.w, push.gust.x,
                                  push.gust.y, push.gust.z, spotAnchorKey(t, b1, b2));
        position = root + W * (position - root);
        turn = W * R;
    }
    imp.position.xyz = position;
    imp.cell.xyz = ivec3(floor(root / push.gust.w));
    imp.normal.xyz = turn * imp.normal.xyz;
    imp.comb.xyz = turn * imp.comb.xyz;
    imp.frameX.xyz = turn * imp.frameX.xyz;
    imp.frameY.xyz = turn * imp.frameY.xyz;
    imp.frameZ.xyz = turn * imp.frameZ.xyz;
    moved[i] = imp;
}
