#version 450
// Impulse generation, pass 3 of 3 (spot_generate_layout.h): each accepted candidate's impulse
// copied to its output index (1-based in flags, made by the scan). One invocation per candidate.
#extension GL_GOOGLE_include_directive : require
#include "spot_layout.h"
#include "spot_generate_layout.h"

layout(local_size_x = kGenGroup) in;

layout(push_constant) uniform Push { SpotGenPush push; };

layout(std430, binding = kGenBindScratch) readonly buffer Scratch { SpotImpulse scratch[]; };
layout(std430, binding = kGenBindFlags) readonly buffer Flags { uint flags[]; };
layout(std430, binding = kGenBindImpulses) writeonly buffer Impulses { SpotImpulse impulses[]; };

void main() {
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    uint id = group * kGenGroup + gl_LocalInvocationID.x;
    if (id >= push.counts.y)
        return;
    uint index = flags[id];
    if (index != 0u)
        impulses[index - 1u] = scratch[id];
}
