#version 450
// Ray march, step 2 (paper eq. 7-9): one invocation per march pixel (the output image
// supersampled n x n: march pixel (x, y) is the ray through the centre of sub-pixel (x mod n,
// y mod n) of output pixel (x / n, y / n)). The ray is marched through the shell up to the base
// mesh (raymarch_shared.glsl), steps params.range.x to params.range.y of it in this dispatch,
// continuing from the state the previous dispatch left (state[], radiance and transmittance).
// Each invocation's loop count goes to loops[1 + pixel] (the largest over the dispatches) and the
// maximum over all to loops[0] (integer atomicMax), so tests can hold the host's bound against
// what the shader really ran.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "raymarch_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) readonly buffer Params { SpotMarchParams params; };
layout(std430, binding = 1) readonly buffer Table { ivec4 table[]; };
layout(std430, binding = 2) readonly buffer Cells { SpotMarchCell cells[]; };
layout(std430, binding = 3) readonly buffer Lobes { SpotWorldLobe lobes[]; };
layout(binding = 5, r32f) uniform readonly image2D meshDistance;
layout(std430, binding = 6) buffer State { vec4 state[]; };
layout(std430, binding = 7) buffer Loops { uint loopCounts[]; };
layout(std430, binding = 9) readonly buffer Boxes { SpotMarchBox boxes[]; };

SpotMarchParams marchParams() { return params; }
ivec4 marchSlot(uint i) { return table[i]; }
SpotMarchCell marchCell(uint record) { return cells[record]; }
SpotWorldLobe marchLobe(uint i) { return lobes[i]; }
SpotMarchBox marchBox(uint impulse) { return boxes[impulse]; }

#include "raymarch_shared.glsl"

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    uint width = uint(frame.size.x);
    if (p.x >= width || p.y >= uint(frame.size.y))
        return;
    vec3 o;
    vec3 d;
    splatPixelRay(vec2(p) + 0.5, o, d);
    uint index = p.y * width + p.x;
    vec4 before = params.range.x == 0u ? vec4(0.0, 0.0, 0.0, 1.0) : state[index];
    uint loops = 0u;
    state[index] = marchRay(o, d, imageLoad(meshDistance, ivec2(p)).r, params.range.x,
                            params.range.y, before, loops);
    loopCounts[1u + index] = max(loopCounts[1u + index], loops);
    atomicMax(loopCounts[0], loops);
}
