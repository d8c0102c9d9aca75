#version 450
// One oriented quad (a 4-vertex strip) per kept kernel, from its screen bound (centre, half
// extents along u and v); the instance is the compacted kernel list's entry.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindVisible) readonly buffer Visible { uint visible[]; };

layout(location = 0) flat out uint vKernel;

void main() {
    uint kernel = visible[gl_InstanceIndex];
    SpotKernelBound b = bounds[kernel];
    vec2 u = b.axis.xy;
    vec2 v = vec2(-u.y, u.x);
    float su = (gl_VertexIndex & 1) != 0 ? 1.0 : -1.0;
    float sv = (gl_VertexIndex & 2) != 0 ? 1.0 : -1.0;
    vec2 corner = b.quad.xy + su * b.quad.z * u + sv * b.quad.w * v;
    gl_Position = vec4(2.0 * corner / frame.size.xy - 1.0, 0.0, 1.0);
    vKernel = kernel;
}
