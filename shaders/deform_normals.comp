#version 450
// Deform pass 2 of 4 (spot_deform_layout.h): each posed vertex's unit normal, angle-weighted over
// the posed triangles around its welded vertex (each adds its unit normal times its angle at the
// corner; the adjacency lists the corners, 3 t + k: a gather, the twin of noise::computeNormals'
// scatter), the face of the largest angle where the sum cancels (below kDeformCancelled of it),
// +y where the vertex has no area at all: noise::computeNormals' rules.
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
    float largestWeight = 0.0;
    for (uint i = first; i < last; ++i) {
        uint corner = adjacency[push.counts.x + 1u + i];
        uint t = corner / 3u, k = corner - 3u * t;
        vec3 p0 = posed[indices[3u * t + k]].position.xyz;
        vec3 p1 = posed[indices[3u * t + (k + 1u) % 3u]].position.xyz;
        vec3 p2 = posed[indices[3u * t + (k + 2u) % 3u]].position.xyz;
        vec3 a = p1 - p0, b = p2 - p0;
        vec3 c = cross(a, b);
        float area = sqrt(dot(c, c));
        if (!(area > 0.0))
            continue;
        float angle = atan(area, dot(a, b));
        vec3 unit = c / area;
        sum += angle * unit;
        if (angle > largestWeight) {
            largestWeight = angle;
            largest = unit;
        }
    }
    float length = sqrt(dot(sum, sum));
    vec3 n = vec3(0.0, 1.0, 0.0);
    if (length > kDeformCancelled * largestWeight && length > 0.0)
        n = sum / length;
    else if (largestWeight > 0.0)
        n = largest;
    posed[v].normal = vec4(n, 0.0);
}
