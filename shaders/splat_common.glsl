// splat_common.glsl: what every splatting shader shares: the frame's push constants, the pixel's
// ray, and (when SPLAT_LOBES_BINDING is defined before inclusion) one kernel's colour and alpha
// along a ray from its world lobes. All the math comes from spot_shared.h; this file only loops.
//
// A kernel's world lobes are worldLobes[kernel * lobes + l] (SpotWorldLobe, prepare.comp).
#extension GL_GOOGLE_include_directive : require
#include "spot_shared.h"
#include "spot_layout.h"
#include "spot_splat.h"

layout(push_constant) uniform Push { SpotSplatFrame frame; };

bool splatOrthographic() { return frame.eye.w > 0.5; }
bool splatFlag(uint bit) { return (frame.counts.w & bit) != 0u; }

// The ray through continuous pixel position p (pixels, (0,0) top-left), as noise::CameraRays.
void splatPixelRay(vec2 p, out vec3 origin, out vec3 dir) {
    float sx = 2.0 * p.x / frame.size.x - 1.0;
    float sy = 1.0 - 2.0 * p.y / frame.size.y;
    spotCameraRay(frame.eye.xyz, frame.forward.xyz, frame.right.xyz * frame.right.w,
                  frame.up.xyz * frame.up.w, splatOrthographic(), sx, sy, origin, dir);
}

// View depth (world units along the view direction) of a world point.
float splatViewDepth(vec3 x) { return dot(x - frame.eye.xyz, frame.forward.xyz); }

#ifdef SPLAT_LOBES_BINDING
layout(std430, binding = SPLAT_LOBES_BINDING) readonly buffer WorldLobes { SpotWorldLobe worldLobes[]; };

// One kernel seen along one pixel's ray.
struct SplatKernelSample {
    vec3 premul;  // premultiplied colour
    float alpha;  // 1 - transmittance through the kernel
    float tau;    // optical depth through the kernel: alpha = 1 - exp(-tau)
    float depth;  // ray parameter t (world distance) of the kernel at this pixel: the mean of the
                  // lobe peaks (or samples) weighted by what each contributes to alpha
};

mat3 splatLobeMatrix(SpotWorldLobe w) { return mat3(w.a0.xyz, w.a1.xyz, w.a2.xyz); }
vec3 splatLobeCentre(SpotWorldLobe w) { return vec3(w.a0.w, w.a1.w, w.a2.w); }

vec3 splatShade(vec3 color, vec3 normal) {
    if (!splatFlag(kSplatFlagLambert))
        return color;
    return color * spotLambertFactor(normal, frame.light.xyz, frame.light.w);
}

// Shading normal at world point x: the normalized negative gradient of the kernel's density
// sum a g(x) (the reference's formula); -dir where the gradient vanishes.
vec3 splatKernelNormal(uint first, uint lobes, vec3 x, vec3 dir) {
    vec3 g = vec3(0.0);
    for (uint l = 0u; l < lobes; ++l) {
        SpotWorldLobe w = worldLobes[first + l];
        if (!(w.color.w > 0.0))
            continue;
        mat3 A = splatLobeMatrix(w);
        vec3 u = A * (x - splatLobeCentre(w));
        g += w.color.w * spotLobeDensity(u, frame.size.w) * (transpose(A) * u);
    }
    float len = length(g);
    return len > 0.0 && !isinf(len) ? g / len : -dir;
}

// Lambert factor of one lobe along the ray (optical depth tau over [0, tMesh]): the mean of the
// factor with the kernel's normal at kSplatShadingSamples points splitting what the lobe emits
// towards the camera into equal shares. One point at the lobe's density peak would not do: the
// gradient there is perpendicular to the ray, whatever the lobe's orientation; the shares put
// the points on the lobe's front for an opaque lobe and across it for a thin one, like the
// reference's quadrature.
float splatLobeShading(uint first, uint lobes, SpotWorldLobe w, vec3 o, vec3 d, float tMesh, float tau) {
    mat3 A = splatLobeMatrix(w);
    vec3 ol = A * (o - splatLobeCentre(w));
    vec3 dl = A * d;
    float sum = 0.0;
    for (uint j = 0u; j < kSplatShadingSamples; ++j) {
        float q = (float(j) + 0.5) / float(kSplatShadingSamples);
        float t = spotLobeDepthQuantile(ol, dl, 0.0, tMesh, frame.size.w, spotEmissionQuantileFraction(tau, q));
        vec3 normal = splatKernelNormal(first, lobes, o + t * d, d);
        sum += spotLambertFactor(normal, frame.light.xyz, frame.light.w);
    }
    return sum / float(kSplatShadingSamples);
}

// Analytic: each lobe's exact optical depth over [0, tMesh] (spotLobeDepth), lobes composited
// front to back in the order of their density peaks along the ray.
SplatKernelSample splatKernelAnalytic(uint kernel, vec3 o, vec3 d, float tMesh) {
    uint lobes = frame.counts.y;
    uint first = kernel * lobes;
    float k = frame.size.w;
    float peaks[8];
    float depths[8];
    uint ids[8];
    uint n = 0u;
    for (uint l = 0u; l < lobes; ++l) {
        SpotWorldLobe w = worldLobes[first + l];
        if (!(w.color.w > 0.0))
            continue;
        mat3 A = splatLobeMatrix(w);
        float tPeak;
        float tau = w.color.w * spotLobeDepth(A * (o - splatLobeCentre(w)), A * d, 0.0, tMesh, k, tPeak);
        if (!(tau > 0.0) || isinf(tau))
            continue;
        // Insertion sort by peak (at most 8 lobes, in registers).
        uint j = n;
        while (j > 0u && peaks[j - 1u] > tPeak) {
            peaks[j] = peaks[j - 1u];
            depths[j] = depths[j - 1u];
            ids[j] = ids[j - 1u];
            --j;
        }
        peaks[j] = tPeak;
        depths[j] = tau;
        ids[j] = l;
        ++n;
    }
    SplatKernelSample s;
    s.premul = vec3(0.0);
    s.depth = 0.0;
    s.tau = 0.0;
    float transmittance = 1.0;
    float depthSum = 0.0;
    float weightSum = 0.0;
    bool lit = splatFlag(kSplatFlagLambert);
    for (uint i = 0u; i < n; ++i) {
        s.tau += depths[i];
        float a = spotOneMinusExp(depths[i]);
        float t = clamp(peaks[i], 0.0, tMesh);
        SpotWorldLobe w = worldLobes[first + ids[i]];
        float shade = lit ? splatLobeShading(first, lobes, w, o, d, tMesh, depths[i]) : 1.0;
        s.premul += transmittance * a * shade * w.color.rgb;
        depthSum += transmittance * a * t;
        weightSum += transmittance * a;
        transmittance *= 1.0 - a;
    }
    s.alpha = spotOneMinusExp(s.tau);
    s.depth = weightSum > 0.0 ? depthSum / weightSum : 0.0;
    return s;
}

// Paper eq. 10: N midpoint samples over the kernel's extent along the ray (the union of its lobe
// chords) clipped to [0, tMesh], each sample's opacity 1 - exp(-density x step), front to back,
// stopping once opaque.
SplatKernelSample splatKernelMarch(uint kernel, vec3 o, vec3 d, float tMesh, uint samples) {
    uint lobes = frame.counts.y;
    uint first = kernel * lobes;
    float k = frame.size.w;
    float ta = kSplatNoMesh;
    float tb = -kSplatNoMesh;
    for (uint l = 0u; l < lobes; ++l) {
        SpotWorldLobe w = worldLobes[first + l];
        if (!(w.color.w > 0.0))
            continue;
        mat3 A = splatLobeMatrix(w);
        float a;
        float b;
        if (spotLobeChord(A * (o - splatLobeCentre(w)), A * d, k, a, b)) {
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
    if (!(tb > ta))
        return s;
    float dt = (tb - ta) / float(samples);
    float transmittance = 1.0;
    float depthSum = 0.0;
    float weightSum = 0.0;
    bool lit = splatFlag(kSplatFlagLambert);
    for (uint i = 0u; i < samples && transmittance > 1e-6; ++i) {
        float t = ta + (float(i) + 0.5) * dt;
        vec3 x = o + t * d;
        float sigma = 0.0;
        vec3 emitted = vec3(0.0);
        vec3 g = vec3(0.0);
        for (uint l = 0u; l < lobes; ++l) {
            SpotWorldLobe w = worldLobes[first + l];
            if (!(w.color.w > 0.0))
                continue;
            mat3 A = splatLobeMatrix(w);
            vec3 u = A * (x - splatLobeCentre(w));
            float density = w.color.w * spotLobeDensity(u, k);
            sigma += density;
            emitted += density * w.color.rgb;
            g += density * (transpose(A) * u);
        }
        if (!(sigma > 0.0) || isinf(sigma))
            continue;
        float gLen = length(g);
        vec3 normal = lit && gLen > 0.0 && !isinf(gLen) ? g / gLen : -d;
        s.tau += sigma * dt;
        float a = spotOneMinusExp(sigma * dt);
        s.premul += transmittance * a * splatShade(emitted / sigma, normal);
        depthSum += transmittance * a * t;
        weightSum += transmittance * a;
        transmittance *= 1.0 - a;
    }
    s.alpha = spotOneMinusExp(s.tau);
    s.depth = weightSum > 0.0 ? depthSum / weightSum : ta;
    return s;
}

// The kernel at a pixel with the frame's setting (analytic, or N samples).
SplatKernelSample splatKernel(uint kernel, vec3 o, vec3 d, float tMesh) {
    uint samples = min(frame.counts.z, kSplatMaxKernelSamples);
    return samples == 0u ? splatKernelAnalytic(kernel, o, d, tMesh)
                         : splatKernelMarch(kernel, o, d, tMesh, samples);
}
#endif
