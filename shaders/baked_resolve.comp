#version 450
// Baked renderer, last pass: the layers' front-to-back accumulation over the mesh colour:
// premultiplied colour + (1 - alpha) x base.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = kBakedBindAccum, rgba32f) uniform readonly image2D accum;
layout(binding = kBakedBindBase, rgba32f) uniform readonly image2D baseColor;
layout(binding = kBakedBindResult, rgba32f) uniform writeonly image2D result;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(frame.size.x) || p.y >= int(frame.size.y))
        return;
    vec4 a = imageLoad(accum, p);
    imageStore(result, p, vec4(a.rgb + (1.0 - a.a) * imageLoad(baseColor, p).rgb, 1.0));
}
