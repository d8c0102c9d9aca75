#version 450
// Ray march, step 2 (paper eq. 7-9): one invocation per march pixel (the output image
// supersampled n x n: march pixel (x, y) is the ray through the centre of sub-pixel (x mod n,
// y mod n) of output pixel (x / n, y / n)). The ray is marched through the shell up to the base
// mesh (raymarch_shared.glsl), steps push.range.x to push.range.y of it in this dispatch,
// continuing from the state the previous dispatch left (state[], radiance and transmittance).
// When counting (kMarchCount), each invocation's loop count goes to loops[1 + pixel] (the largest
// over the dispatches) and the maximum over all to loops[0] (integer atomicMax), so tests can hold
// the host's bound against what the shader really ran; otherwise the count is compiled out (its
// writes and atomics cost about 5% of a frame).
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"
#include "raymarch_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push { SpotMarchPush push; };

layout(constant_id = kMarchSpecLobes) const uint kMarchLobes = 1u;
layout(constant_id = kMarchSpecLambert) const bool kMarchLambert = false;
layout(constant_id = kMarchSpecCull) const bool kMarchCull = true;
layout(constant_id = kMarchSpecCount) const bool kMarchCount = false;
layout(constant_id = kMarchSpecWalkBits) const bool kMarchWalkBits = false;

layout(std430, binding = kMarchBindParams) readonly buffer Params { SpotMarchParams params; };
layout(std430, binding = kMarchBindTable) readonly buffer Table { ivec4 table[]; };
layout(std430, binding = kMarchBindCells) readonly buffer Cells { SpotMarchCell cells[]; };
layout(std430, binding = kMarchBindStarts) readonly buffer Starts { uint starts[]; };
layout(std430, binding = kMarchBindList) readonly buffer List { uint entries[]; };
layout(std430, binding = kMarchBindWorldLobes) readonly buffer Lobes { SpotWorldLobe lobes[]; };
layout(std430, binding = kMarchBindBoxes) readonly buffer Boxes { SpotMarchBox boxes[]; };
layout(binding = kMarchBindMeshDistance, r32f) uniform readonly image2D meshDistance;
layout(std430, binding = kMarchBindState) buffer State { vec4 state[]; };
layout(std430, binding = kMarchBindLoops) buffer Loops { uint loopCounts[]; };
layout(std430, binding = kMarchBindWalkBits) readonly buffer WalkBits { uvec2 walkBits[]; };

SpotMarchParams marchParams() { return params; }
ivec4 marchSlot(uint i) { return table[i]; }
SpotMarchCell marchCell(uint record) { return cells[record]; }
uint marchStart(uint slot) { return starts[slot]; }
uint marchEntry(uint i) { return entries[i]; }
mat3 marchLobeMatrix(uint i) { return mat3(lobes[i].a0.xyz, lobes[i].a1.xyz, lobes[i].a2.xyz); }
vec3 marchLobeCentre(uint i) { return vec3(lobes[i].a0.w, lobes[i].a1.w, lobes[i].a2.w); }
vec4 marchLobeColor(uint i) { return lobes[i].color; }
vec4 marchLobeSlope(uint i) { return lobes[i].a0; }
vec4 marchLobeAxis(uint i) { return lobes[i].a1; }
SpotMarchBox marchBox(uint impulse) { return boxes[impulse]; }
vec4 marchLight() { return push.light; }
uvec2 marchWalkBrick(ivec3 b) {
    ivec3 n = (params.hi.xyz - params.lo.xyz + ivec3(kMarchWalkBrick)) / kMarchWalkBrick;
    return walkBits[uint((b.x * n.y + b.y) * n.z + b.z)];
}

#include "raymarch_shared.glsl"

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    uint width = uint(push.size.x);
    if (p.x >= width || p.y >= uint(push.size.y))
        return;
    vec3 o;
    vec3 d;
    marchPixelRay(push, float(p.x) + 0.5, float(p.y) + 0.5, o, d);
    uint index = p.y * width + p.x;
    vec4 before = push.range.x == 0u ? vec4(0.0, 0.0, 0.0, 1.0) : state[index];
    uint loops = 0u;
    state[index] = marchRay(o, d, imageLoad(meshDistance, ivec2(p)).r, push.range.x, push.range.y,
                            push.range.z, before, loops);
    if (kMarchCount) {
        loopCounts[1u + index] = max(loopCounts[1u + index], loops);
        atomicMax(loopCounts[0], loops);
    }
}
