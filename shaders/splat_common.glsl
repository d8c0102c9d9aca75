// splat_common.glsl: what every splatting shader shares: the frame's push constants, the
// specialization constants, the pixel's ray, and (when SPLAT_READS_LOBES is defined before
// inclusion) one kernel's colour and alpha along a pixel's ray. All the math comes from
// spot_shared.h; this file only loops.
//
// A kernel's lobes are worldLobes[kernel * kLobes + l] (SpotWorldLobe) and
// screenLobes[kernel * kLobes + l] (SpotScreenLobe), both written by splat_prepare.comp.
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"
#include "spot_splat.h"

layout(push_constant) uniform Push { SpotSplatFrame frame; };

// Each pipeline is compiled for one setting (splat/passes/splatting_vk.cpp sets these); the defaults
// below are never used as such.
layout(constant_id = kSplatSpecLobes) const uint kLobes = 1u;
layout(constant_id = kSplatSpecSamples) const uint kSamples = 0u;
layout(constant_id = kSplatSpecLambert) const bool kLambert = false;
layout(constant_id = kSplatSpecOrthographic) const bool kOrthographic = false;
layout(constant_id = kSplatSpecEwa) const bool kEwa = true;
layout(constant_id = kSplatSpecWeight) const uint kWeight = kSpotWeightMcGuireBavoil;
layout(constant_id = kSplatSpecCount) const bool kCount = false;
layout(constant_id = kSplatSpecScreen) const bool kScreen = true;
layout(constant_id = kSplatSpecSmallPixels) const uint kSmallPixels = 0u;
layout(constant_id = kSplatSpecResolveList) const bool kResolveList = false;
layout(constant_id = kSplatSpecLit) const bool kLit = false;
// Lambert's gradient terms as varyings (splatShadeLobes; spot_splat.h
// kSplatMaxShadeVaryingLobes), and the size of their arrays (1 when unused).
const bool kShadeVaryings = kLambert && kLobes <= kSplatMaxShadeVaryingLobes;
const uint kShadeLobes = kShadeVaryings ? kLobes : 1u;

// Pixel `pixel`'s index in a row-major per-pixel buffer of the frame's size.
uint splatPixelIndex(ivec2 pixel) {
    return uint(pixel.y) * uint(frame.size.x) + uint(pixel.x);
}

// The ray through continuous pixel position p (pixels, (0,0) top-left), as noise::CameraRays:
// world origin and unit direction. (The projection is also read from the frame: the ray-march's
// shaders are not specialized for it.)
void splatPixelRay(vec2 p, out vec3 origin, out vec3 dir) {
    spotPixelRay(frame.eye.xyz, frame.forward.xyz, frame.right.xyz * frame.right.w,
                 frame.up.xyz * frame.up.w, kOrthographic || frame.eye.w > 0.5, frame.size.xy, p,
                 origin, dir);
}

// World length of the pixel's ray direction scaled to unit view depth (1 for orthographic): a
// view depth t along the ray is the world distance t x splatRayScale(p).
// With forward, right and up orthonormal and square pixels of footprint f per unit depth,
// |e|^2 = 1 + ((p.x - W/2) f)^2 + ((p.y - H/2) f)^2.
float splatRayScale(vec2 p) {
    if (kOrthographic)
        return 1.0;
    vec2 q = (p - 0.5 * frame.size.xy) * frame.size.z;
    return sqrt(1.0 + dot(q, q));
}

// View depth (world units along the view direction) of a world point.
float splatViewDepth(vec3 x) { return dot(x - frame.eye.xyz, frame.forward.xyz); }

// The pixels whose centres lie in the axis-aligned box of a kernel's quad, clamped to the image:
// [lo, hi] inclusive (empty where hi < lo); returns how many (the compute path's loop length).
uint splatQuadPixelBox(SpotKernelBound b, out ivec2 lo, out ivec2 hi) {
    vec2 u = abs(b.axis.xy);
    vec2 reach = vec2(u.x * b.quad.z + u.y * b.quad.w, u.y * b.quad.z + u.x * b.quad.w);
    // Pixel x's centre is x + 0.5; clamp in float first (a huge quad must not overflow an int).
    vec2 first = clamp(ceil(b.quad.xy - reach - 0.5), vec2(0.0), frame.size.xy);
    vec2 last = clamp(floor(b.quad.xy + reach - 0.5), vec2(-1.0), frame.size.xy - 1.0);
    lo = ivec2(first);
    hi = ivec2(last);
    ivec2 n = max(hi - lo + 1, ivec2(0));
    return uint(n.x) * uint(n.y);
}

// The x range (inclusive pixel indices, within [lo, hi]) of the pixel centres in row y whose
// centres may lie in the kernel's oriented quad: the intersection of the two slabs
// |dot(p - centre, u)| <= half.x and |dot(p - centre, v)| <= half.y with the row's centre line
// (a slab parallel to the row is all or nothing). Padded by a hundredth of a pixel; the caller
// still tests splatInQuad, so only the loop's length depends on it.
void splatQuadRow(SpotKernelBound b, int y, ivec2 lo, ivec2 hi, out int first, out int last) {
    vec2 u = b.axis.xy;
    float dy = float(y) + 0.5 - b.quad.y;
    float xa = float(lo.x);
    float xb = float(hi.x) + 1.0;
    // Slab u: |u.x dx + u.y dy| <= half.x; slab v: |-u.y dx + u.x dy| <= half.y.
    vec2 slope = vec2(u.x, -u.y);
    vec2 offset = vec2(u.y * dy, u.x * dy);
    vec2 halfExtent = b.quad.zw;
    for (int i = 0; i < 2; ++i) {
        if (abs(slope[i]) > 1e-6) {
            float e0 = (-halfExtent[i] - offset[i]) / slope[i];
            float e1 = (halfExtent[i] - offset[i]) / slope[i];
            xa = max(xa, b.quad.x + min(e0, e1) - 0.01);
            xb = min(xb, b.quad.x + max(e0, e1) + 0.01);
        } else if (abs(offset[i]) > halfExtent[i]) {
            xb = xa - 1.0; // the row misses this slab
        }
    }
    first = max(int(ceil(xa - 0.5)), lo.x);
    last = min(int(floor(xb - 0.5)), hi.x);
}

// Whether pixel position p lies in the kernel's oriented quad (the compute path's coverage; the
// rasterizer's differs only on the quad's edges, where the kernel is all but zero).
bool splatInQuad(SpotKernelBound b, vec2 p) {
    vec2 d = p - b.quad.xy;
    vec2 u = b.axis.xy;
    return abs(dot(d, u)) <= b.quad.z && abs(d.x * -u.y + d.y * u.x) <= b.quad.w;
}

// A lobe's ray line through pixel position p from its screen form (spot_splat.h): its
// lobe-space direction v and origin o' (one of them affine in the pixel, the other constant),
// and returned, w = o' x v (xyz) and n = o'.v (w) taken as affine functions (their terms at the
// reference pixel and per pixel step, k0 = o' x v(ref), kx = o' x vx, ...) rather than as a
// product at p: near the lobe's centre line o' and v are nearly parallel, and the terms keep the
// compute paths and the vertex shader (which rebuilds o' from them) rounding alike.
vec4 splatScreenLobeAt(SpotScreenLobe s, vec2 p, out vec3 v, out vec3 o) {
    vec2 delta = p - vec2(s.a0.w, s.ax.w);
    vec3 a = s.a0.xyz + delta.x * s.ax.xyz + delta.y * s.ay.xyz;
    v = kOrthographic ? s.b.xyz : a;
    o = kOrthographic ? a : s.b.xyz;
    vec3 k0 = kOrthographic ? cross(s.a0.xyz, s.b.xyz) : cross(s.b.xyz, s.a0.xyz);
    vec3 kx = kOrthographic ? cross(s.ax.xyz, s.b.xyz) : cross(s.b.xyz, s.ax.xyz);
    vec3 ky = kOrthographic ? cross(s.ay.xyz, s.b.xyz) : cross(s.b.xyz, s.ay.xyz);
    return vec4(k0 + delta.x * kx + delta.y * ky,
                dot(s.a0.xyz, s.b.xyz) + delta.x * dot(s.ax.xyz, s.b.xyz) +
                    delta.y * dot(s.ay.xyz, s.b.xyz));
}

#ifdef SPLAT_READS_LOBES
layout(std430, binding = kSplatBindWorldLobes) readonly buffer WorldLobes { SpotWorldLobe worldLobes[]; };
layout(std430, binding = kSplatBindScreenLobes) readonly buffer ScreenLobes { SpotScreenLobe screenLobes[]; };

// One kernel seen along one pixel's ray.
struct SplatKernelSample {
    vec3 premul;  // premultiplied colour
    float alpha;  // 1 - transmittance through the kernel
    float tau;    // optical depth through the kernel: alpha = 1 - exp(-tau)
    float depth;  // view depth of the kernel along this pixel's ray: the mean of the lobe peaks
                  // (or samples) weighted by what each contributes to alpha
    bool covers;  // SPLAT_INSTANCED_COVER (instanced): some lobe's optical depth reaches its
                  // coverage threshold (splatLobeCoverThreshold)
};

mat3 splatLobeMatrix(SpotWorldLobe w) { return mat3(w.a0.xyz, w.a1.xyz, w.a2.xyz); }
vec3 splatLobeCentre(SpotWorldLobe w) { return vec3(w.a0.w, w.a1.w, w.a2.w); }

// The kernel lobes' colours (kSplatSpecLobeColor).
layout(constant_id = 16) const float kLobeColor0r = 1.0;
layout(constant_id = 17) const float kLobeColor0g = 1.0;
layout(constant_id = 18) const float kLobeColor0b = 1.0;
layout(constant_id = 19) const float kLobeColor1r = 1.0;
layout(constant_id = 20) const float kLobeColor1g = 1.0;
layout(constant_id = 21) const float kLobeColor1b = 1.0;
layout(constant_id = 22) const float kLobeColor2r = 1.0;
layout(constant_id = 23) const float kLobeColor2g = 1.0;
layout(constant_id = 24) const float kLobeColor2b = 1.0;
layout(constant_id = 25) const float kLobeColor3r = 1.0;
layout(constant_id = 26) const float kLobeColor3g = 1.0;
layout(constant_id = 27) const float kLobeColor3b = 1.0;
layout(constant_id = 28) const float kLobeColor4r = 1.0;
layout(constant_id = 29) const float kLobeColor4g = 1.0;
layout(constant_id = 30) const float kLobeColor4b = 1.0;
layout(constant_id = 31) const float kLobeColor5r = 1.0;
layout(constant_id = 32) const float kLobeColor5g = 1.0;
layout(constant_id = 33) const float kLobeColor5b = 1.0;
layout(constant_id = 34) const float kLobeColor6r = 1.0;
layout(constant_id = 35) const float kLobeColor6g = 1.0;
layout(constant_id = 36) const float kLobeColor6b = 1.0;
layout(constant_id = 37) const float kLobeColor7r = 1.0;
layout(constant_id = 38) const float kLobeColor7g = 1.0;
layout(constant_id = 39) const float kLobeColor7b = 1.0;
// Lobe l's colour: l is a constant once the lobe loops unroll, so this folds to a constant.
vec3 splatLobeColor(uint l) {
    switch (l) {
    case 0u: return vec3(kLobeColor0r, kLobeColor0g, kLobeColor0b);
    case 1u: return vec3(kLobeColor1r, kLobeColor1g, kLobeColor1b);
    case 2u: return vec3(kLobeColor2r, kLobeColor2g, kLobeColor2b);
    case 3u: return vec3(kLobeColor3r, kLobeColor3g, kLobeColor3b);
    case 4u: return vec3(kLobeColor4r, kLobeColor4g, kLobeColor4b);
    case 5u: return vec3(kLobeColor5r, kLobeColor5g, kLobeColor5b);
    case 6u: return vec3(kLobeColor6r, kLobeColor6g, kLobeColor6b);
    default: return vec3(kLobeColor7r, kLobeColor7g, kLobeColor7b);
    }
}

#ifndef SPLAT_FRAGMENT
// The impulse's colour multiplier of a kernel (the compute paths; the fragment shaders get it as
// vColor).
#ifdef SPLAT_CACHED_LOBES
vec3 splatCachedColor; // loaded with the lobes
vec3 splatKernelColor(uint kernel) { return splatCachedColor; }
#else
layout(std430, binding = kSplatBindBounds) readonly buffer Bounds { SpotKernelBound bounds[]; };
vec3 splatKernelColor(uint kernel) { return bounds[kernel].color.rgb; }
#endif
#endif

#ifdef SPLAT_CACHED_LOBES
// The kernel's lobes, loaded once by a shader that evaluates one kernel at many pixels
// (splat_small.comp) and read instead of the buffers (constant indices once the lobe loops
// unroll, so they stay in registers): the screen lobes (analytic path), the world lobes (Lambert
// shading, N samples).
SpotScreenLobe splatCachedLobes[kLobes];
SpotWorldLobe splatCachedWorldLobes[kLobes];
vec4 splatCachedSlopes[kLobes]; // a lit frame's: the second half's a0 and a1 (SpotWorldLobe)
vec4 splatCachedAxes[kLobes];
SpotWorldLobe splatWorldLobe(uint first, uint l) { return splatCachedWorldLobes[l]; }
#else
SpotWorldLobe splatWorldLobe(uint first, uint l) { return worldLobes[first + l]; }
#endif

// Lobe l's lit colour at point u of its (widened) lobe space in a lit frame: its colour at the
// centre, plus its change along the shading axis to u's place there, held within one sigma
// (the points its light was looked up at), the world lobes' second half (spot_layout.h).
vec3 splatLitColor(uint first, uint l, vec3 u) {
#ifdef SPLAT_CACHED_LOBES
    vec4 slope = splatCachedSlopes[l];
    vec4 axis = splatCachedAxes[l];
#else
    uint change = frame.counts.x * kLobes + first + l;
    vec4 slope = worldLobes[change].a0;
    vec4 axis = worldLobes[change].a1;
#endif
    return splatWorldLobe(first, l).color.rgb + slope.rgb * clamp(dot(axis.xyz, u), -1.0, 1.0);
}

vec3 splatShade(vec3 color, vec3 normal) {
    if (!kLambert)
        return color;
    return color * spotLambertFactor(normal, frame.light.xyz, frame.light.w);
}

// Lambert shading of the analytic path (kLambert), per lobe: the mean of the Lambert factor at
// kSplatShadingSamples points that split what the lobe emits towards the camera into equal
// shares, the normal at each the normalized negative gradient of the kernel's density sum
// a g(x) (the reference's formula; -d where it vanishes). One point at the lobe's density peak
// would not do: the gradient there is perpendicular to the ray, whatever the lobe's orientation;
// the shares put the points on the lobe's front for an opaque lobe and across it for a thin one,
// like the reference's quadrature.
// Every lobe's ray is known in its own space from its screen form, u_m(t) = o'_m + t v_m (t the
// view depth; o' = (v x w + n v) / |v|^2), so along this pixel's ray a lobe's density is
// G_m(t) = exp(-(p_m + |v_m|^2 (t - t*_m)^2) / 2), p_m = |w_m|^2 / |v_m|^2, and its world gradient
// direction A_m^T u_m(t) = P_m + t Q_m with P_m = A_m^T o'_m and Q_m = A_m^T v_m: a point costs
// a few multiplies and one exp per lobe, A_m^T being loaded and applied once per pixel.
#ifdef SPLAT_FRAGMENT
void splatShadeTerms(uint m, out vec3 P, out vec3 Q, out float amplitude); // below
bool splatVaryingsTrusted();                                                 // below
#endif
void splatShadeLobes(uint first, vec3 origins[kLobes], vec3 dirs[kLobes], float peaks[kLobes],
                     float depths[kLobes], float tEnd, vec3 d, inout float shades[kLobes]) {
    float k = frame.size.w;
    vec3 P[kLobes];
    vec3 Q[kLobes];
    float perp2[kLobes];
    float vv[kLobes];
    float amps[kLobes];
    for (uint m = 0u; m < kLobes; ++m) {
#ifdef SPLAT_FRAGMENT
        if (kShadeVaryings && splatVaryingsTrusted()) // from splat_quad.vert: no per-pixel loads
            splatShadeTerms(m, P[m], Q[m], amps[m]);
        else
#endif
        {
            SpotWorldLobe w = splatWorldLobe(first, m);
            mat3 At = transpose(mat3(w.a0.xyz, w.a1.xyz, w.a2.xyz));
            P[m] = At * origins[m];
            Q[m] = At * dirs[m];
            amps[m] = w.color.w;
        }
        vv[m] = dot(dirs[m], dirs[m]);
        vec3 perp = origins[m] + peaks[m] * dirs[m];
        perp2[m] = dot(perp, perp);
    }
    for (uint l = 0u; l < kLobes; ++l) {
        if (!(depths[l] > 0.0))
            continue;
        // The lobe's chord along the ray in its arc length s = (t - t*) |v|, clipped to [0, tEnd].
        float len = sqrt(vv[l]);
        float tStar = peaks[l];
        float h = sqrt(max(k * k - perp2[l], 0.0));
        float ua = max(-h, -tStar * len);
        float ub = min(h, (tEnd - tStar) * len);
        float erfA = spotScaledErfHalfSqrt2(ua, 1.0);
        float erfB = spotScaledErfHalfSqrt2(ub, 1.0);
        float sum = 0.0;
        for (uint j = 0u; j < kSplatShadingSamples; ++j) {
            float q = (float(j) + 0.5) / float(kSplatShadingSamples);
            float f = spotEmissionQuantileFraction(depths[l], q);
            float sj = 1.4142135623730951 * spotErfinvApprox(erfA + f * (erfB - erfA));
            float t = tStar + clamp(sj, ua, ub) / len;
            vec3 g = vec3(0.0);
            for (uint m = 0u; m < kLobes; ++m) {
                float dt = t - peaks[m];
                float r2 = perp2[m] + vv[m] * dt * dt;
                if (r2 < k * k)
                    g += (amps[m] * exp(-0.5 * r2)) * (P[m] + t * Q[m]);
            }
            float gLen = length(g);
            vec3 normal = gLen > 0.0 && !isinf(gLen) ? g / gLen : -d;
            sum += spotLambertFactor(normal, frame.light.xyz, frame.light.w);
        }
        shades[l] = sum / float(kSplatShadingSamples);
    }
}

#ifdef SPLAT_FRAGMENT
// The kernel's lobes as this pixel sees them, from splat_quad.vert. Each lobe's ray in lobe space,
// u(t) = o' + t v: perspective, v = A e is affine in the pixel, so the rasterizer's noperspective
// interpolation gives it exactly (vLobeA), and o' = A (eye - c) is one point (vLobeB, flat);
// orthographic, the other way round. Then w = o' x v and n = o'.v (no per-pixel loads or matrix
// products). vLobeB.w: the lobe's amplitude (extinction x weight x EWA). A lobe's colour is the
// kernel lobe's (a specialization constant) times the impulse's (vColor). Every flat input costs llvmpipe
// work per triangle and per 4x4 block, so there are as few as the kernel needs.
layout(location = 1) noperspective in vec3 vLobeA[kLobes];
layout(location = 9) flat in vec4 vLobeB[kLobes];
layout(location = 17) flat in vec3 vColor;
// 1 when the kernel's quad reaches past the image, else 0. lavapipe clips such a quad's
// triangles, and the lobe varyings it interpolates there were measured wrong over part of the
// quad (an isolated lobe's alpha off by up to 0.5, in a region bounded by a clip line, with the
// corners' values right): such a kernel's fragments evaluate their lobes' screen forms from the
// buffer (splatScreenLobeAt, as the compute paths do) instead. A flat value, the same for every
// fragment of a triangle; kernels inside the image keep the cheaper varyings (reading the buffer
// in every fragment cost 60% more splat time on fur-bunny at 640x480).
layout(location = 18) flat in float vOffImage;
bool splatVaryingsTrusted() { return !(vOffImage > 0.0); }
// Lambert (kShadeVaryings): each lobe's gradient terms P = A^T o' and Q = A^T v (splatShadeLobes),
// the one affine in the pixel interpolated (vShadeA: Q in perspective, P in orthographic), the
// other constant (vShadeB). Locations 19 to 30 at most (6 lobes).
layout(location = 19) noperspective in vec3 vShadeA[kShadeLobes];
layout(location = 25) flat in vec3 vShadeB[kShadeLobes];

// Lobe m's gradient terms and amplitude from the varyings (kShadeVaryings).
void splatShadeTerms(uint m, out vec3 P, out vec3 Q, out float amplitude) {
    P = kOrthographic ? vShadeA[m] : vShadeB[m];
    Q = kOrthographic ? vShadeB[m] : vShadeA[m];
    amplitude = vLobeB[m].w;
}
// Whether this pixel's ray meets some lobe's support (|w|^2 < k^2 |v|^2, spotScreenLobeDepth's
// test) at all: a few multiplies per lobe from the varyings. A fragment where it does not has
// alpha 0 in every path (analytic or sampled), so it can be discarded before the kernel's math;
// and lavapipe, which runs every branch one of its lanes takes, does skip the rest of a fragment
// shader for a batch of lanes that are all discarded.
bool splatMeetsSupport() {
    if (!splatVaryingsTrusted())
        return true; // splatKernelAnalytic decides from the buffer
    float k2 = frame.size.w * frame.size.w;
    bool meets = false;
    for (uint l = 0u; l < kLobes; ++l) {
        vec3 v = kOrthographic ? vLobeB[l].xyz : vLobeA[l];
        vec3 o = kOrthographic ? vLobeA[l] : vLobeB[l].xyz;
        vec3 w = cross(o, v);
        meets = meets || dot(w, w) < k2 * dot(v, v);
    }
    return meets;
}

#endif

#ifdef SPLAT_INSTANCED_COVER
// The optical depth above which lobe `l` of `kernel` covers a pixel opaque for instanced
// (SpotScreenLobe::b.w, written by the prepare pass: spotCoverThreshold of its peak), so that its
// opaque footprint covers as much of the image as the lobe does.
float splatLobeCoverThreshold(uint kernel, uint l) {
#ifdef SPLAT_CACHED_LOBES
    return splatCachedLobes[l].b.w;
#else
    return screenLobes[kernel * kLobes + l].b.w;
#endif
}
#endif

// Analytic: each lobe's exact optical depth up to the mesh (spotScreenLobeDepth on the lobe's
// screen form), lobes composited front to back in the order of their density peaks along the
// ray. kLobes is a specialization constant, so the loops unroll and the per-lobe arrays stay in
// registers (llvmpipe keeps dynamically indexed arrays in memory); the order is not sorted
// out but decided pair by pair (below).
// p: pixel position (its centre); o, d: its world ray (Lambert only); tMesh: world distance to the
// mesh; scale: splatRayScale(p).
SplatKernelSample splatKernelAnalytic(uint kernel, vec2 p, vec3 o, vec3 d, float tMesh, float scale) {
    uint first = kernel * kLobes;
    float k = frame.size.w;
    float tEnd = tMesh / scale;
    float peaks[kLobes];
    float depths[kLobes];
    vec3 colors[kLobes];
    float shades[kLobes];
    vec3 origins[kLobes]; // Lambert: each lobe's ray in its space, u(t) = origin + t dir
    vec3 dirs[kLobes];
    bool covers = false;
    for (uint l = 0u; l < kLobes; ++l) {
#ifdef SPLAT_FRAGMENT
        vec3 v, ol;
        vec4 wo;
        if (!splatVaryingsTrusted()) {
            wo = splatScreenLobeAt(screenLobes[first + l], p, v, ol);
        } else {
            v = kOrthographic ? vLobeB[l].xyz : vLobeA[l];
            ol = kOrthographic ? vLobeA[l] : vLobeB[l].xyz;
            wo = vec4(cross(ol, v), dot(ol, v));
        }
        vec4 c = vec4(kLit ? vec3(0.0) : splatLobeColor(l) * vColor, vLobeB[l].w);
#else
#ifdef SPLAT_CACHED_LOBES
        SpotScreenLobe s = splatCachedLobes[l];
#else
        SpotScreenLobe s = screenLobes[first + l];
#endif
        vec3 v, ol;
        vec4 wo = splatScreenLobeAt(s, p, v, ol);
        vec4 c = vec4(kLit ? vec3(0.0) : splatLobeColor(l) * splatKernelColor(kernel), s.ay.w);
#endif
        float tPeak;
        float tau = c.w * scale * spotScreenLobeDepth(wo.xyz, v, wo.w, tEnd, k, tPeak);
        if (kLit) // at the point of the lobe the ray meets densest (in front of the mesh)
            c.rgb = splatLitColor(first, l, ol + clamp(tPeak, 0.0, tEnd) * v);
        depths[l] = tau > 0.0 && !isinf(tau) ? tau : 0.0;
#ifdef SPLAT_INSTANCED_COVER
        covers = covers || (depths[l] > 0.0 && depths[l] >= splatLobeCoverThreshold(kernel, l));
#endif
        peaks[l] = tPeak;
        colors[l] = c.rgb;
        shades[l] = 1.0;
        origins[l] = ol;
        dirs[l] = v;
    }
    if (kLambert)
        splatShadeLobes(first, origins, dirs, peaks, depths, tEnd, d, shades);
    // Front to back in the order of the lobes' density peaks along the ray, without sorting them:
    // lobe i's light is dimmed by the lobes in front of it, those j with peaks[j] < peaks[i]
    // (on a tie the lower index in front, as a stable sort would order them), so its share is
    // a_i times the product of their (1 - a_j). Pairs of constant indices once the loops
    // unroll: a compare and a select per pair, where a sorting network moved every lobe's
    // peak, depth, colour and shade by selects at each of its (kLobes - 1)^2 steps.
    float alphas[kLobes];
    for (uint i = 0u; i < kLobes; ++i)
        alphas[i] = spotOneMinusExp(depths[i]);
    SplatKernelSample s;
    s.premul = vec3(0.0);
    s.tau = 0.0;
    float transmittance = 1.0;
    float depthSum = 0.0;
    float weightSum = 0.0;
    for (uint i = 0u; i < kLobes; ++i) {
        float front = 1.0;
        for (uint j = 0u; j < kLobes; ++j) {
            if (j == i)
                continue;
            bool inFront = j < i ? peaks[j] <= peaks[i] : peaks[j] < peaks[i];
            front *= inFront ? 1.0 - alphas[j] : 1.0;
        }
        float share = front * alphas[i];
        s.tau += depths[i];
        s.premul += share * shades[i] * colors[i];
        depthSum += share * clamp(peaks[i], 0.0, tEnd);
        weightSum += share;
        transmittance *= 1.0 - alphas[i];
    }
    // exp(-sum tau) is the product of the lobes' transmittances, already at hand (faint
    // kernels take the series, as spotOneMinusExp does, for relative precision).
    s.alpha = s.tau < 1e-3 ? s.tau * (1.0 - s.tau * (0.5 - s.tau * (1.0 / 6.0))) : 1.0 - transmittance;
    s.depth = weightSum > 0.0 ? depthSum / weightSum : 0.0;
    s.covers = covers;
    return s;
}

// Paper eq. 10: N midpoint samples over the kernel's extent along the ray (the union of its lobe
// chords) clipped to [0, tMesh], each sample's opacity 1 - exp(-density x step), front to back,
// stopping once opaque. World lobes, world distances; the depth returned is a view depth.
// Each lobe's ray is taken into its own space once, u(t) = A (o - c) + t A d (as the chord and
// the analytic path's screen form take it), so a sample costs three multiply-adds a lobe where
// A (x - c) cost a matrix product and the lobe's loads; Lambert's gradient direction
// A^T u(t) = P + t Q likewise.
SplatKernelSample splatKernelMarch(uint kernel, vec3 o, vec3 d, float tMesh, float scale) {
    uint first = kernel * kLobes;
    float k = frame.size.w;
    float ta = kSplatNoMesh;
    float tb = -kSplatNoMesh;
    vec3 origins[kLobes];
    vec3 dirs[kLobes];
    vec3 colors[kLobes];
    float amps[kLobes]; // 0 for a lobe that emits nothing (or a NaN amplitude): skipped
    vec3 P[kLobes];
    vec3 Q[kLobes];
    vec3 slopes[kLobes]; // lit: the colour's change along the shading axis (splatLitColor)
    vec3 axes[kLobes];
    for (uint l = 0u; l < kLobes; ++l) {
        SpotWorldLobe w = splatWorldLobe(first, l);
        mat3 A = splatLobeMatrix(w);
        origins[l] = A * (o - splatLobeCentre(w));
        dirs[l] = A * d;
        colors[l] = w.color.rgb;
        slopes[l] = vec3(0.0);
        axes[l] = vec3(0.0);
        if (kLit) {
#ifdef SPLAT_CACHED_LOBES
            slopes[l] = splatCachedSlopes[l].rgb;
            axes[l] = splatCachedAxes[l].xyz;
#else
            uint change = frame.counts.x * kLobes + first + l;
            slopes[l] = worldLobes[change].a0.rgb;
            axes[l] = worldLobes[change].a1.xyz;
#endif
        }
        amps[l] = w.color.w > 0.0 ? w.color.w : 0.0;
        if (kLambert) {
            mat3 At = transpose(A);
            P[l] = At * origins[l];
            Q[l] = At * dirs[l];
        }
        float a;
        float b;
        if (amps[l] > 0.0 && spotLobeChord(origins[l], dirs[l], k, a, b)) {
            ta = min(ta, a);
            tb = max(tb, b);
        }
    }
    ta = max(ta, 0.0);
    tb = min(tb, tMesh);
    SplatKernelSample s;
    s.premul = vec3(0.0);
    s.alpha = 0.0;
    s.depth = 0.0;
    s.tau = 0.0;
    s.covers = false;
    if (!(tb > ta))
        return s;
    float dt = (tb - ta) / float(kSamples);
    float transmittance = 1.0;
    float depthSum = 0.0;
    float weightSum = 0.0;
    for (uint i = 0u; i < kSamples && transmittance > 1e-6; ++i) {
        float t = ta + (float(i) + 0.5) * dt;
        float sigma = 0.0;
        vec3 emitted = vec3(0.0);
        vec3 g = vec3(0.0);
        for (uint l = 0u; l < kLobes; ++l) {
            vec3 u = origins[l] + t * dirs[l];
            float density = amps[l] > 0.0 ? amps[l] * spotLobeDensity(u, k) : 0.0;
            sigma += density;
            emitted += density * (kLit ? colors[l] + slopes[l] * clamp(dot(axes[l], u), -1.0, 1.0)
                                       : colors[l]);
            if (kLambert)
                g += density * (P[l] + t * Q[l]);
        }
        if (!(sigma > 0.0) || isinf(sigma))
            continue;
        float gLen = length(g);
        vec3 normal = gLen > 0.0 && !isinf(gLen) ? g / gLen : -d;
        s.tau += sigma * dt;
        float a = spotOneMinusExp(sigma * dt);
        s.premul += transmittance * a * splatShade(emitted / sigma, normal);
        depthSum += transmittance * a * t;
        weightSum += transmittance * a;
        transmittance *= 1.0 - a;
    }
    // The composite's own alpha, the sum of the samples' shares (1 - transmittance, and
    // 1 - exp(-tau) up to rounding): the colour premul / alpha is then a mean of the samples'
    // colours to rounding, never above the brightest (instanced draws it opaque).
    s.alpha = weightSum;
    s.depth = (weightSum > 0.0 ? depthSum / weightSum : ta) / scale;
#ifdef SPLAT_INSTANCED_COVER
    // The samples do not keep each lobe's depth apart: the kernel's, against its lobes' lowest
    // threshold (a strand's lobes overlap along it, and each alone would reach its own).
    float threshold = kSplatNoMesh;
    for (uint l = 0u; l < kLobes; ++l)
        threshold = amps[l] > 0.0 ? min(threshold, splatLobeCoverThreshold(kernel, l)) : threshold;
    s.covers = s.tau > 0.0 && s.tau >= threshold;
#endif
    return s;
}

// The kernel at pixel position p (its centre) with the pipeline's setting (analytic, or N
// samples), up to the mesh at world distance tMesh.
SplatKernelSample splatKernel(uint kernel, vec2 p, float tMesh) {
    vec3 o = vec3(0.0);
    vec3 d = vec3(0.0);
    if (kLambert || kSamples > 0u)
        splatPixelRay(p, o, d);
    float scale = splatRayScale(p);
    if (kSamples > 0u)
        return splatKernelMarch(kernel, o, d, tMesh, scale);
    return splatKernelAnalytic(kernel, p, o, d, tMesh, scale);
}

// Instanced (paper fig. 4 left): whether the kernel's sample at pixel position p covers it as an
// opaque splat. One of its lobes' optical depth reaches that lobe's cover threshold
// (SPLAT_INSTANCED_COVER), and its depth is strictly nearer than the mesh at world distance
// tMesh. The splat is opaque at that depth, so the mesh hides it there, as a depth test would. A
// kernel whose lobes all peak at or behind the mesh has its depth clamped to the mesh, and stays
// hidden.
bool splatInstancedCovers(SplatKernelSample s, vec2 p, float tMesh) {
    return s.covers && s.depth * splatRayScale(p) < tMesh;
}

// The OIT weight of a kernel sample (view depth z), as the pipeline is specialized.
float splatOitWeight(SplatKernelSample s) { return spotOitWeight(s.depth, s.alpha, kWeight); }
#endif

#ifdef SPLAT_COUNTS
// Fragment efficiency (RenderSettings::countFragments): fragments shaded, and those where the
// kernel's alpha reaches kSplatHybridMinAlpha. 64-bit counts from two 32-bit atomics each.
layout(std430, binding = kSplatBindCounters) buffer Counters { SpotSplatCounters counters; };
// A fragment (or a compute path's pixel) that reached the shader, counted as shaded whether or
// not it is discarded before the kernel's math (splatMeetsSupport).
void splatCountFragment() {
    if (kCount && atomicAdd(counters.fragments.x, 1u) == 0xffffffffu)
        atomicAdd(counters.fragments.y, 1u);
}
// Whether the kernel covers it (alpha at least kSplatHybridMinAlpha).
void splatCountCovered(float alpha) {
    if (kCount && alpha >= kSplatHybridMinAlpha && atomicAdd(counters.fragments.z, 1u) == 0xffffffffu)
        atomicAdd(counters.fragments.w, 1u);
}
void splatCount(float alpha) {
    splatCountFragment();
    splatCountCovered(alpha);
}
#endif
