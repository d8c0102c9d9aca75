#version 450
// Base mesh colour (unlit, or Lambert with the interpolated vertex normal), the ray distance t to
// the surface (what kernels integrate up to) and the reversed depth.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#ifdef SPLAT_MESH_LIT
// Lit (a variant: it binds the lit frame's parameters and the light-space structure): diffuse,
// every light per pixel and the sky from the vertices (splat_mesh.vert), shadowed
// (light_common.glsl).
#include "spot_light.h"
#include "light_common.glsl"
layout(location = 2) in vec2 vSky;
#endif

layout(location = 0) in vec3 vWorld;
layout(location = 1) in vec3 vNormal;

layout(location = 0) out vec4 outColor;
layout(location = 1) out float outT;

void main() {
    vec3 rel = vWorld - frame.eye.xyz;
    float z = dot(rel, frame.forward.xyz);
    if (!(z > 0.0))
        discard; // behind the orthographic camera's plane: rays start at t = 0
    vec3 color = frame.base.rgb;
#ifdef SPLAT_MESH_LIT
    {
        float len = length(vNormal);
        vec3 n = len > 0.0 ? vNormal / len : -frame.forward.xyz;
        vec3 v = frame.eye.w > 0.5 ? -frame.forward.xyz : normalize(frame.eye.xyz - vWorld);
        bool back = dot(n, v) < 0.0;
        color *= litSurfaceLights(vWorld, back ? -n : n) + (back ? vSky.y : vSky.x) * lit.sky.rgb;
    }
#endif
    if ((frame.counts.w & kSplatFlagLambert) != 0u) {
        float len = length(vNormal);
        vec3 n = len > 0.0 ? vNormal / len : -frame.forward.xyz;
        color *= spotLambertFactor(n, frame.light.xyz, frame.light.w);
    }
    outColor = vec4(color, 1.0);
    outT = frame.eye.w > 0.5 ? z : length(rel);
    gl_FragDepth = spotReversedDepth(z, frame.forward.w);
}
