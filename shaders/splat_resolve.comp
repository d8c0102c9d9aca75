#version 450
// The final image, one thread per pixel, into a linear float RGBA buffer for readback.
// Instanced: the base colour image (mesh, background and opaque kernels).
// OIT (eq. 12, MB13): avg = accum.rgb / max(accum.a, 1e-5); avg (1 - revealage) + base revealage.
// Hybrid (eq. 13): the closest kernel f found in the OIT pass is re-evaluated here (C_f, alpha_f)
// and composited over the OIT of the others: C_f alpha_f + (1 - alpha_f) OIT_rest. The
// accumulators hold every kernel, f included, so f's own terms are taken out first (its weight
// and alpha recomputed by the same code): accum - w_f (C_f alpha_f, alpha_f), revealage / (1 -
// alpha_f). Taken literally, eq. 13 would count f twice: on one isolated kernel of alpha 0.5 it
// would give 0.75 of its colour instead of 0.5.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#define SPLAT_LOBES_BINDING 5
#include "splat_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0, rgba32f) uniform readonly image2D baseColor;
layout(binding = 1, rgba32f) uniform readonly image2D accumulation;
layout(binding = 2, r32f) uniform readonly image2D revealage;
layout(binding = 3, r32f) uniform readonly image2D meshDistance;
layout(std430, binding = 4) readonly buffer Closest { uint64_t closest[]; };
layout(std430, binding = 6) writeonly buffer Result { vec4 result[]; };

vec3 oitComposite(vec4 accum, float reveal, vec3 behind) {
    vec3 average = accum.rgb / max(accum.a, 1e-5);
    return average * (1.0 - reveal) + behind * reveal;
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    uint width = uint(frame.size.x);
    if (p.x >= width || p.y >= uint(frame.size.y))
        return;
    ivec2 pixel = ivec2(p);
    vec3 base = imageLoad(baseColor, pixel).rgb;
    vec3 color = base;
    if (!splatFlag(kSplatFlagInstanced)) {
        vec4 accum = imageLoad(accumulation, pixel);
        float reveal = imageLoad(revealage, pixel).r;
        uint64_t key = closest[p.y * width + p.x];
        if (splatFlag(kSplatFlagHybrid) && key != ~uint64_t(0)) {
            uint kernel = uint(key & 0xffffffffUL);
            vec3 o;
            vec3 d;
            splatPixelRay(vec2(p) + 0.5, o, d);
            SplatKernelSample f = splatKernel(kernel, o, d, imageLoad(meshDistance, pixel).r);
            float w = spotOitWeight(splatViewDepth(o + f.depth * d), f.alpha,
                                    splatFlag(kSplatFlagMcGuireBavoil) ? kSpotWeightMcGuireBavoil
                                                                        : kSpotWeightConstant);
            vec4 rest = max(accum - w * vec4(f.premul, f.alpha), vec4(0.0));
            float restReveal = f.alpha < 1.0 ? min(reveal / (1.0 - f.alpha), 1.0) : 1.0;
            color = f.premul + (1.0 - f.alpha) * oitComposite(rest, restReveal, base);
        } else {
            color = oitComposite(accum, reveal, base);
        }
    }
    result[p.y * width + p.x] = vec4(color, 1.0);
}
