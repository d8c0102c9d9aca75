#version 450
// Deform pass 2 of 4 (spot_deform_layout.h): each posed vertex's unit normal, area-weighted over
// the posed triangles around it (a gather: the twin of noise::computeNormals' scatter), the
// largest of them where the sum cancels (below kDeformCancelled of it), +y where the vertex has
// no area at all: noise::computeNormals' rules.
#extension GL_GOOGLE_include_directive : require
#include "deform_common.glsl"

layout(std430, binding = kDeformBindPosed) buffer Posed { SpotMeshVertex posed[]; };
layout(std430, binding = kDeformBindIndices) readonly buffer Indices { uint indices[]; };
layout(std430, binding = kDeformBindAdjacency) readonly buffer Adjacency { uint adjacency[]; };

void main() {
    uint v = deformInvocation();
    if (v >= push.counts.x)
        return;
    uint first = adjacency[v];
    uint last = adjacency[v + 1u];
    vec3 sum = vec3(0.0);
    vec3 largest = vec3(0.0);
    float largestLength = 0.0;
    for (uint i = first; i < last; ++i) {
        uint t = adjacency[push.counts.x + 1u + i];
        vec3 p0 = posed[indices[3u * t]].position.xyz;
        vec3 c = cross(posed[indices[3u * t + 1u]].position.xyz - p0,
                       posed[indices[3u * t + 2u]].position.xyz - p0);
        float length = sqrt(dot(c, c));
        sum += c;
        if (length > largestLength) {
            largestLength = length;
            largest = c;
        }
    }
    float length = sqrt(dot(sum, sum));
    vec3 n = vec3(0.0, 1.0, 0.0);
    if (length > kDeformCancelled * largestLength && length > 0.0)
        n = sum / length;
    else if (largestLength > 0.0)
        n = largest / largestLength;
    posed[v].normal = vec4(n, 0.0);
}
