#version 450
// The compute path of the small kernels (docs/design.md section 4): `oit`, `hybrid` and
// `instanced` do not draw a kernel whose quad's pixel box holds at most kSmallPixels pixel
// centres (lavapipe's cost per primitive dwarfs the few fragments such a quad has); one
// invocation per such kernel (splat_compact.comp's second list, an indirect dispatch) loops over
// the pixel centres of its box that lie in its quad and are not behind the mesh (the raster
// path's depth test), evaluates the kernel there with the same code as the resolve
// (splatKernel on the screen lobes), and does what the method's fragment shader does:
//  - oit, hybrid: adds w x (premultiplied colour, alpha) and the optical depth to the pixel's
//    fixed-point sums (kSplatBindOitFixed, spot_splat.h: 64-bit integer atomicAdd, associative,
//    so the sums do not depend on the order the invocations run in); the resolve adds them to
//    the raster targets' values. Hybrid also competes for the closest kernel (atomicMin);
//  - instanced: the atomicMin where a lobe reaches its cover threshold (SPLAT_INSTANCED_COVER).
// One module per method (shaders/CMakeLists.txt), each declaring the buffers it writes:
// SPLAT_SMALL_OIT (the fixed-point sums), SPLAT_SMALL_CLOSEST (hybrid's atomicMin),
// SPLAT_SMALL_INSTANCED (instanced's).
// Each evaluation counts as a fragment shaded (splatCount). Loop iterations: kSmallPixels <=
// kSplatMaxSmallPixels pixels, each the analytic kernel's few hundred at most.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#define SPLAT_READS_LOBES
#define SPLAT_COUNTS
#define SPLAT_CACHED_LOBES
#ifdef SPLAT_SMALL_INSTANCED
#define SPLAT_INSTANCED_COVER
#endif
#include "splat_common.glsl"
#if !defined(SPLAT_SMALL_OIT) && !defined(SPLAT_SMALL_INSTANCED)
#error "define what this module writes (SPLAT_SMALL_OIT, ...)"
#endif

layout(local_size_x = kSplatSmallThreads) in;

layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindSmall) readonly buffer Small { uint small[]; };
layout(std430, binding = kSplatBindDraw) readonly buffer Indirect { uint draw[kSplatDrawWords]; };
layout(binding = kSplatBindMeshDistance, r32f) uniform readonly image2D meshDistance;
#if defined(SPLAT_SMALL_CLOSEST) || defined(SPLAT_SMALL_INSTANCED)
layout(std430, binding = kSplatBindClosest) buffer Closest { uint64_t closest[]; };
#endif
#ifdef SPLAT_SMALL_OIT
layout(std430, binding = kSplatBindOitFixed) buffer OitFixed { uint64_t oitFixed[]; };
layout(std430, binding = kSplatBindOitTiles) buffer OitTiles { uint oitTiles[]; };
#endif

// One contribution in fixed point (spot_splat.h: clamped to [0, kSplatFixedMax]; NaN adds 0).
uint64_t splatFixed(float value) {
    return value > 0.0 ? uint64_t(min(value, kSplatFixedMax) * kSplatFixedScale) : uint64_t(0);
}

#ifdef SPLAT_SMALL_OIT
void splatAdd(uint slot, float value) {
    uint64_t add = splatFixed(value);
    if (add != uint64_t(0))
        atomicAdd(oitFixed[slot], add);
}
#endif

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= draw[kSplatDrawSmallCount])
        return;
    uint kernel = small[i];
    SpotKernelBound b = bounds[kernel];
    ivec2 lo;
    ivec2 hi;
    splatQuadPixelBox(b, lo, hi); // at most kSmallPixels centres (splat_compact.comp)
    uint width = uint(frame.size.x);
    splatCachedColor = b.color.rgb;
    for (uint l = 0u; l < kLobes; ++l) {
        splatCachedLobes[l] = screenLobes[kernel * kLobes + l];
        if (kLambert || kSamples > 0u || kLit)
            splatCachedWorldLobes[l] = worldLobes[kernel * kLobes + l];
        if (kLit) { // the world lobes' second half (splatLitColor)
            uint change = frame.counts.x * kLobes + kernel * kLobes + l;
            splatCachedSlopes[l] = worldLobes[change].a0;
            splatCachedAxes[l] = worldLobes[change].a1;
        }
    }
    for (int y = lo.y; y <= hi.y; ++y) {
        int first;
        int last;
        splatQuadRow(b, y, lo, hi, first, last);
        for (int x = first; x <= last; ++x) {
            vec2 p = vec2(x, y) + 0.5;
            if (!splatInQuad(b, p))
                continue;
            ivec2 pixel = ivec2(x, y);
            float tMesh = imageLoad(meshDistance, pixel).r;
            // The raster path's depth test: the quad at the support's nearest view depth against
            // the mesh's (world distance along the ray / splatRayScale).
            if (!(tMesh > b.axis.w * splatRayScale(p)))
                continue;
            SplatKernelSample s = splatKernel(kernel, p, tMesh);
            splatCount(s.alpha);
            if (!(s.alpha > 0.0))
                continue;
            uint index = uint(y) * width + uint(x);
            uint64_t key = (uint64_t(floatBitsToUint(max(s.depth, 0.0))) << 32) | uint64_t(kernel);
#ifdef SPLAT_SMALL_INSTANCED
            if (splatInstancedCovers(s, p, tMesh))
                atomicMin(closest[index], key);
#endif
#ifdef SPLAT_SMALL_CLOSEST
            if (s.alpha > kSplatHybridMinAlpha)
                atomicMin(closest[index], key);
#endif
#ifdef SPLAT_SMALL_OIT
            vec4 accum = vec4(s.premul, s.alpha) * splatOitWeight(s);
            uint tilesX = (width + kSplatResolveTile - 1u) / kSplatResolveTile;
            atomicOr(oitTiles[uint(y) / kSplatResolveTile * tilesX + uint(x) / kSplatResolveTile], 1u);
            uint base = index * kSplatFixedChannels;
            splatAdd(base + 0u, accum.r);
            splatAdd(base + 1u, accum.g);
            splatAdd(base + 2u, accum.b);
            splatAdd(base + 3u, accum.a);
            splatAdd(base + 4u, s.tau);
#endif
        }
    }
}
