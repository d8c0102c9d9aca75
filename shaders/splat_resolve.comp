#version 450
// The final image, one thread per pixel, into the linear float RGBA result image: the colour over
// the base (the mesh's colour, or the background) and the coverage alpha = 1 - the transmittance
// through the kernels and the mesh (the base's alpha: 1 where the mesh is hit, 0 elsewhere). OIT and hybrid
// first add the small kernels' fixed-point sums (splat_small.comp) to the raster targets'.
// Pixels with a closest kernel (hybrid, instanced) are listed, and a second dispatch over the list
// evaluates that kernel and writes them (kResolveList; see SpotSplatList for why).
// Sorted (kSplatResolveCopy): the base colour image (kernels were drawn onto it). Instanced: the
// nearest kernel whose alpha reaches 0.5 (splat_instanced.frag) re-evaluated, its mean colour
// premul / alpha over the base.
// OIT (eq. 12, MB13): avg = accum.rgb / max(accum.a, eps); avg (1 - revealage) + base revealage,
// revealage = exp(-sum of the kernels' optical depths) (see splat_oit.frag). MB13 floor accum.a
// at eps = 1e-5 for their 16-bit float targets; ours are 32-bit, and with w proportional to alpha
// (accum.a = sum alpha^2 c(z)) that floor darkens every faint fringe (4e-4 of the colour on one
// isolated lobe), so eps here only keeps 0 / 0 away.
// Hybrid (eq. 13): the closest kernel f found in the OIT pass is re-evaluated here (C_f, alpha_f)
// and composited over the OIT of the others: C_f alpha_f + (1 - alpha_f) OIT_rest. The
// accumulators hold every kernel, f included, so f's own terms are taken out first (its weight
// and alpha recomputed by the same code): accum - w_f (C_f alpha_f, alpha_f), optical depth -
// tau_f. Taken literally, eq. 13 would count f twice: on one isolated kernel of alpha 0.5 it
// would give 0.75 of its colour instead of 0.5.
//
// One module per resolve (shaders/CMakeLists.txt), each declaring exactly the targets it reads:
// SPLAT_RESOLVE_COPY (sorted), SPLAT_RESOLVE_OIT, SPLAT_RESOLVE_HYBRID (closest kernel by
// atomicMin), SPLAT_RESOLVE_HYBRID_PASS (by the depth pass), SPLAT_RESOLVE_INSTANCED; with
// SPLAT_RESOLVE_FIXED (oit, hybrid) it adds the small kernels' fixed-point sums.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#if defined(SPLAT_RESOLVE_COPY)
#elif defined(SPLAT_RESOLVE_OIT)
#define SPLAT_RESOLVE_ACCUM
#elif defined(SPLAT_RESOLVE_HYBRID)
#define SPLAT_RESOLVE_ACCUM
#define SPLAT_RESOLVE_LIST
#define SPLAT_RESOLVE_ATOMIC
#elif defined(SPLAT_RESOLVE_HYBRID_PASS)
#define SPLAT_RESOLVE_ACCUM
#define SPLAT_RESOLVE_LIST
#elif defined(SPLAT_RESOLVE_INSTANCED)
#define SPLAT_RESOLVE_LIST
#define SPLAT_RESOLVE_ATOMIC
#else
#error "define which resolve this module is (SPLAT_RESOLVE_COPY, ...)"
#endif
#ifdef SPLAT_RESOLVE_LIST // the listed pixels' closest kernel is evaluated again
#define SPLAT_READS_LOBES
#endif
#include "splat_common.glsl"

layout(local_size_x = kSplatResolveTile, local_size_y = kSplatResolveTile) in;

layout(binding = kSplatBindBase, rgba32f) uniform readonly image2D baseColor;
#ifdef SPLAT_RESOLVE_ACCUM
// The OIT sums; the first dispatch writes back those of listed pixels with the small kernels'
// sums added (the fixed-point sums are cleared as they are read).
layout(binding = kSplatBindAccum, rgba32f) uniform image2D accumulation;
layout(binding = kSplatBindOpticalDepth, r32f) uniform image2D opticalDepth;
#endif
#ifdef SPLAT_RESOLVE_LIST
layout(binding = kSplatBindMeshDistance, r32f) uniform readonly image2D meshDistance;
#endif
#ifdef SPLAT_RESOLVE_ATOMIC
layout(std430, binding = kSplatBindClosest) readonly buffer Closest { uint64_t closest[]; };
#endif
#ifdef SPLAT_RESOLVE_HYBRID_PASS
// The closest kernel from the depth pass.
layout(binding = kSplatBindClosestKernel, r32ui) uniform readonly uimage2D closestKernel;
#endif
layout(binding = kSplatBindResult, rgba32f) uniform writeonly image2D result;
#ifdef SPLAT_RESOLVE_FIXED
// The small kernels' OIT sums in fixed point (splat_small.comp; kSmallPixels > 0), added to the
// raster targets' and cleared for the next frame (only where set: most pixels have none).
layout(std430, binding = kSplatBindOitFixed) buffer OitFixed { uint64_t oitFixed[]; };
// Non-zero where a tile (this workgroup's pixels) has sums: most have none, and reading 40 bytes
// a pixel for nothing would cost more than the compute path saves at 640x480. (Cleared by a fill
// each frame: clearing them here would need a barrier, and llvmpipe runs a shader with a barrier
// as coroutines, much slower.)
layout(std430, binding = kSplatBindOitTiles) readonly buffer OitTiles { uint oitTiles[]; };
#endif
#ifdef SPLAT_RESOLVE_LIST
// The pixels with a closest kernel (spot_splat.h: SpotSplatList; hybrid, instanced), listed by the
// first dispatch, resolved by the second.
layout(std430, binding = kSplatBindClosestList) buffer ClosestList { SpotSplatList list; uint listPixels[]; };
#endif

vec3 oitAverage(vec4 accum) { return accum.rgb / max(accum.a, 1e-30); }

vec3 oitComposite(vec3 average, float tau, vec3 behind) {
    float reveal = exp(-tau);
    return average * (1.0 - reveal) + behind * reveal;
}

#ifdef SPLAT_RESOLVE_LIST
// The closest kernel's key at pixel p, or ~0 where none.
uint64_t closestKey(uvec2 p, uint width) {
#ifdef SPLAT_RESOLVE_ATOMIC
    return closest[p.y * width + p.x];
#else
    uint id = imageLoad(closestKernel, ivec2(p)).r;
    return id == 0xffffffffu ? ~uint64_t(0) : uint64_t(id);
#endif
}

// The second dispatch (kResolveList): one listed pixel per invocation, its closest kernel f
// evaluated and composited.
void resolveListed() {
    uint i = gl_WorkGroupID.x * (kSplatResolveTile * kSplatResolveTile) + gl_LocalInvocationIndex;
    if (i >= list.count)
        return;
    uint packedPixel = listPixels[i];
    uvec2 p = uvec2(packedPixel & 0xffffu, packedPixel >> 16u);
    ivec2 pixel = ivec2(p);
    uint64_t key = closestKey(p, uint(frame.size.x));
    SplatKernelSample f = splatKernel(uint(key & 0xffffffffUL), vec2(p) + 0.5,
                                      imageLoad(meshDistance, pixel).r);
#ifdef SPLAT_RESOLVE_INSTANCED
    vec3 color = f.premul / f.alpha;
    float alpha = 1.0; // an opaque kernel
#else
    // The first dispatch stored the sums with the small kernels' added.
    vec4 accum = imageLoad(accumulation, pixel);
    float tau = imageLoad(opticalDepth, pixel).r;
    vec4 rest = accum - splatOitWeight(f) * vec4(f.premul, f.alpha);
    // Below about 1e-6 of accum.a the difference is float noise and the others' mean
    // colour cannot be told: take the mean of all (f's, mostly) there.
    vec3 average = rest.a > 1e-5 * accum.a ? max(rest.rgb, vec3(0.0)) / rest.a : oitAverage(accum);
    vec4 base = imageLoad(baseColor, pixel);
    float others = max(tau - f.tau, 0.0);
    vec3 color = f.premul + (1.0 - f.alpha) * oitComposite(average, others, base.rgb);
    float alpha = 1.0 - (1.0 - f.alpha) * exp(-others) * (1.0 - base.a);
#endif
    imageStore(result, pixel, vec4(color, alpha));
}
#endif

void main() {
#ifdef SPLAT_RESOLVE_LIST
    if (kResolveList) {
        resolveListed();
        return;
    }
#endif
#ifdef SPLAT_RESOLVE_FIXED
    bool fixedSums = oitTiles[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x] != 0u;
#endif
    uvec2 p = gl_GlobalInvocationID.xy;
    uint width = uint(frame.size.x);
    if (p.x >= width || p.y >= uint(frame.size.y))
        return;
    ivec2 pixel = ivec2(p);
    vec4 baseSample = imageLoad(baseColor, pixel);
    vec3 base = baseSample.rgb;
    vec3 color = base;
    float alpha = baseSample.a; // sorted: the coverage its blend left there
#ifdef SPLAT_RESOLVE_LIST
    uint64_t key = closestKey(p, width);
    bool listed = key != ~uint64_t(0);
#endif
#ifdef SPLAT_RESOLVE_ACCUM
    vec4 accum = imageLoad(accumulation, pixel);
    float tau = imageLoad(opticalDepth, pixel).r;
#ifdef SPLAT_RESOLVE_FIXED
    if (fixedSums) {
        uint base = (p.y * width + p.x) * kSplatFixedChannels;
        uint64_t r = oitFixed[base + 0u];
        uint64_t g = oitFixed[base + 1u];
        uint64_t b = oitFixed[base + 2u];
        uint64_t a = oitFixed[base + 3u];
        uint64_t t = oitFixed[base + 4u];
        if ((r | g | b | a | t) != uint64_t(0)) {
            const float unit = 1.0 / kSplatFixedScale;
            accum += vec4(float(r), float(g), float(b), float(a)) * unit;
            tau += float(t) * unit;
            for (uint c = 0u; c < kSplatFixedChannels; ++c)
                oitFixed[base + c] = uint64_t(0);
#ifdef SPLAT_RESOLVE_LIST
            if (listed) { // for the second dispatch
                imageStore(accumulation, pixel, accum);
                imageStore(opticalDepth, pixel, vec4(tau));
            }
#endif
        }
    }
#endif
    color = oitComposite(oitAverage(accum), tau, base);
    alpha = 1.0 - exp(-tau) * (1.0 - baseSample.a);
#endif
#ifdef SPLAT_RESOLVE_LIST
    if (listed) {
        uint i = atomicAdd(list.count, 1u);
        listPixels[i] = p.x | p.y << 16u;
        atomicMax(list.groupsX, i / (kSplatResolveTile * kSplatResolveTile) + 1u);
        return; // the second dispatch writes the result
    }
#endif
    imageStore(result, pixel, vec4(color, alpha));
}
