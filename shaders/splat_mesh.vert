#version 450
// The opaque base mesh, vertices pulled from a storage buffer. Depth is reversed (near / z, see
// spotReversedDepth): perspective clip z = near, w = z; orthographic depth comes from the fragment.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#ifdef SPLAT_MESH_LIT
// Lit (a variant): the sky's shadowed diffuse per vertex, for both faces (light_common.glsl).
#include "spot_light.h"
#include "light_common.glsl"
layout(location = 2) out vec2 vSky;
#endif

layout(std430, binding = kSplatBindVertices) readonly buffer Vertices { SpotMeshVertex vertices[]; };

layout(location = 0) out vec3 vWorld;
layout(location = 1) out vec3 vNormal;

void main() {
    SpotMeshVertex v = vertices[gl_VertexIndex];
    vWorld = v.position.xyz;
    vNormal = v.normal.xyz;
#ifdef SPLAT_MESH_LIT
    {
        float len = length(v.normal.xyz);
        vSky = litSurfaceSky(v.position.xyz, len > 0.0 ? v.normal.xyz / len : vec3(0.0));
    }
#endif
    vec3 rel = v.position.xyz - frame.eye.xyz;
    float x = dot(rel, frame.right.xyz) / frame.right.w;
    float y = -dot(rel, frame.up.xyz) / frame.up.w; // image rows grow downwards (Vulkan NDC)
    float z = dot(rel, frame.forward.xyz);
    if (frame.eye.w > 0.5) // orthographic (a run-time flag: one mesh pipeline for every view)
        gl_Position = vec4(x, y, 0.5, 1.0);
    else
        gl_Position = vec4(x, y, frame.forward.w, z); // clipped where z < near
}
