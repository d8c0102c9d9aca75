#version 450
// Tests (tests/splat/light_space_test.cpp): the light-space structure's transmittance at given
// points, as prepare and the mesh pass look it up (light_common.glsl's shadowTransmittance).
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"
#include "spot_light.h"
#include "light_common.glsl"

layout(local_size_x = 64) in;
layout(push_constant) uniform Push { uvec4 n; /* x: points; y: bias in texels (float bits) */ } push;
layout(std430, binding = kShadowBindProbe) buffer Probe { vec4 points[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.n.x)
        return;
    vec4 p = points[i];
    points[i].w = shadowTransmittance(uint(p.w), p.xyz, uintBitsToFloat(push.n.y));
}
