#version 450
// One screen-aligned quad (a 4-vertex strip) per kept kernel, from its pixel rectangle; the
// instance is the compacted kernel list's entry.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"

layout(std430, binding = 0) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = 1) readonly buffer Visible { uint visible[]; };

layout(location = 0) flat out uint vKernel;

void main() {
    uint kernel = visible[gl_InstanceIndex];
    vec4 r = bounds[kernel].rect;
    vec2 corner = vec2((gl_VertexIndex & 1) != 0 ? r.z : r.x, (gl_VertexIndex & 2) != 0 ? r.w : r.y);
    gl_Position = vec4(2.0 * corner / frame.size.xy - 1.0, 0.0, 1.0);
    vKernel = kernel;
}
