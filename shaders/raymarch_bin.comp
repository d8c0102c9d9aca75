#version 450
// Ray march, step 1 (run when the impulses change): which impulses each shell cell holds. One
// invocation per impulse: its cell's record (the shared hash lookup), then first index, end index
// and count per record with integer atomics (order independent, so deterministic). The host reads
// them back, checks the impulses are in cell order (each cell's impulses contiguous, cells in the
// shell's sorted order) and builds every sub-cell's impulse list. Also each lobe's box and each
// impulse's (their union) (SpotMarchBox), from its world lobes, which the host reads for the
// lists.
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"
#include "raymarch_layout.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = kMarchBindParams) readonly buffer Params { SpotMarchParams params; };
layout(std430, binding = kMarchBindTable) readonly buffer Table { ivec4 table[]; };
layout(std430, binding = kMarchBindImpulses) readonly buffer Impulses { SpotImpulse impulses[]; };
layout(std430, binding = kMarchBindCount) readonly buffer Count { uint impulseCount; };
// [0, n): first impulse (0xffffffff: none); [n, 2n): one past the last; [2n, 3n): count;
// [3n]: impulses whose cell is not in the shell; [3n + 1]: the impulse count (n = records).
layout(std430, binding = kMarchBindBins) buffer Bins { uint bins[]; };
layout(std430, binding = kMarchBindWorldLobes) readonly buffer Lobes { SpotWorldLobe lobes[]; };
layout(std430, binding = kMarchBindBoxes) writeonly buffer Boxes { SpotMarchBox boxes[]; };
layout(std430, binding = kMarchBindLobeBoxes) writeonly buffer LobeBoxes { SpotMarchBox lobeBoxes[]; };

layout(push_constant) uniform Push {
    uint records; // shell cells
} pc;

SpotMarchParams marchParams() { return params; }
ivec4 marchSlot(uint i) { return table[i]; }

#define RAYMARCH_LOOKUP_ONLY
#include "raymarch_shared.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i == 0u)
        bins[3u * pc.records + 1u] = impulseCount;
    if (i >= impulseCount)
        return;
    uint lobeCount = params.counts.y;
    float k = params.grid.z;
    vec3 lo = vec3(kMarchFar);
    vec3 hi = vec3(-kMarchFar);
    for (uint l = 0u; l < lobeCount; ++l) {
        SpotWorldLobe w = lobes[i * lobeCount + l];
        lobeBoxes[i * lobeCount + l] = SpotMarchBox(vec4(kMarchFar), vec4(-kMarchFar)); // empty
        if (!(w.color.w > 0.0))
            continue; // no density anywhere
        mat3 inv = inverse(mat3(w.a0.xyz, w.a1.xyz, w.a2.xyz));
        vec3 c = vec3(w.a0.w, w.a1.w, w.a2.w);
        vec3 e = k * vec3(length(vec3(inv[0][0], inv[1][0], inv[2][0])),
                          length(vec3(inv[0][1], inv[1][1], inv[2][1])),
                          length(vec3(inv[0][2], inv[1][2], inv[2][2])));
        e = 1.01 * e + 1e-5 * (abs(c) + 1.0);
        if (!(max(e.x, max(e.y, e.z)) < kMarchFar)) { // not finite: never cull
            lo = vec3(-kMarchFar);
            hi = vec3(kMarchFar);
            lobeBoxes[i * lobeCount + l] = SpotMarchBox(vec4(-kMarchFar), vec4(kMarchFar));
        } else {
            lo = min(lo, c - e);
            hi = max(hi, c + e);
            lobeBoxes[i * lobeCount + l] = SpotMarchBox(vec4(c - e, 0.0), vec4(c + e, 0.0));
        }
    }
    boxes[i] = SpotMarchBox(vec4(lo, 0.0), vec4(hi, 0.0));

    uint loops = 0u;
    int record = marchFind(impulses[i].cell.xyz, loops);
    if (record < 0) {
        atomicAdd(bins[3u * pc.records], 1u);
        return;
    }
    uint r = uint(record);
    atomicMin(bins[r], i);
    atomicMax(bins[pc.records + r], i + 1u);
    atomicAdd(bins[2u * pc.records + r], 1u);
}
