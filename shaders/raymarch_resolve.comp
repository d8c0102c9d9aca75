#version 450
// Ray march, step 3: each output pixel is the mean of its n x n march pixels (a box filter, the
// reference's), each the marched radiance over the mesh colour behind it:
// radiance + transmittance * base, and its coverage 1 - transmittance x (1 - the base's alpha: 1
// where the mesh is hit). Summed in row order, so the image is deterministic.
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"
#include "raymarch_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push { SpotMarchPush push; };

layout(binding = kMarchBindBase, rgba32f) uniform readonly image2D baseColor;
layout(std430, binding = kMarchBindState) readonly buffer State { vec4 state[]; };
layout(binding = kMarchBindResult, rgba32f) uniform writeonly image2D result;

void main() {
    uint n = push.range.w;
    uint marchWidth = uint(push.size.x);
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= marchWidth / n || p.y >= uint(push.size.y) / n)
        return;
    vec3 sum = vec3(0.0);
    float covered = 0.0;
    for (uint sy = 0u; sy < n; ++sy)
        for (uint sx = 0u; sx < n; ++sx) {
            uvec2 q = p * n + uvec2(sx, sy);
            vec4 s = state[q.y * marchWidth + q.x];
            vec4 base = imageLoad(baseColor, ivec2(q));
            sum += s.rgb + s.a * base.rgb;
            covered += 1.0 - s.a * (1.0 - base.a);
        }
    imageStore(result, ivec2(p), vec4(sum / float(n * n), covered / float(n * n)));
}
