#version 450
// Ray march, step 2 (paper eq. 7-9): one invocation per pixel. The pixel's ray (through its
// centre, as the splat renderers' and noise::CameraRays), marched through the shell up to the
// base mesh (raymarch_shared.glsl), composited over the mesh pass's colour. Each invocation's
// loop count goes to loops[1 + pixel] and its maximum to loops[0] (integer atomicMax), so tests
// can hold the host's bound against what the shader really ran.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "raymarch_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) readonly buffer Params { SpotMarchParams params; };
layout(std430, binding = 1) readonly buffer Table { ivec4 table[]; };
layout(std430, binding = 2) readonly buffer Cells { SpotMarchCell cells[]; };
layout(std430, binding = 3) readonly buffer Lobes { SpotWorldLobe lobes[]; };
layout(binding = 4, rgba32f) uniform readonly image2D baseColor;
layout(binding = 5, r32f) uniform readonly image2D meshDistance;
layout(std430, binding = 6) writeonly buffer Result { vec4 result[]; };
layout(std430, binding = 7) buffer Loops { uint loopCounts[]; };

SpotMarchParams marchParams() { return params; }
ivec4 marchSlot(uint i) { return table[i]; }
SpotMarchCell marchCell(uint record) { return cells[record]; }
SpotWorldLobe marchLobe(uint i) { return lobes[i]; }

#include "raymarch_shared.glsl"

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    uint width = uint(frame.size.x);
    if (p.x >= width || p.y >= uint(frame.size.y))
        return;
    ivec2 pixel = ivec2(p);
    vec3 o;
    vec3 d;
    splatPixelRay(vec2(p) + 0.5, o, d);
    uint loops = 0u;
    vec4 march = marchRay(o, d, imageLoad(meshDistance, pixel).r, loops);
    vec3 behind = imageLoad(baseColor, pixel).rgb;
    uint index = p.y * width + p.x;
    result[index] = vec4(march.rgb + march.a * behind, 1.0);
    loopCounts[1u + index] = loops;
    atomicMax(loopCounts[0], loops);
}
