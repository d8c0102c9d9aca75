#version 450
// Per impulse: its kernel's lobes placed in the world (spotPlaceLobe), optionally EWA-widened by
// the pixel footprint at the lobe's depth, keeping what each lobe covers (spotWidenLobeCoverage). With kScreen (the splatting methods),
// also each lobe's screen form (SpotScreenLobe, what the fragment shaders evaluate) and the
// kernel's screen bound (SpotKernelBound): each lobe's k-sigma ellipsoid projects to an ellipse
// (the conic |w(p)|^2 = k^2 |v(p)|^2 in pixel coordinates, exact), and the kernel's quad is the
// rectangle around their union along the union's principal axis, so a thin tilted strand is not
// shaded over its axis-aligned box. A lobe whose support reaches the eye plane projects to no
// ellipse: its conic clipped to the image gives an axis-aligned box instead (clippedConicBox), and
// the kernel's quad is the union of its lobes' boxes (a whole-image quad, as before, cost a grazing
// view of grass 3.7 times the fragments it needed). An empty quad culls the kernel (off screen,
// behind the camera, zero weight or no lobe with extinction).
// Two dispatches: that clipped box is long code, and lavapipe runs every branch for every SIMD
// batch, taken or not, so the first dispatch only lists the kernels that need it (kClipped false)
// and a second, indirect, over that list (kClipped true) computes their bounds again in full.
// World lobes are stored only where something reads them (kWorldLobes: Lambert shading, N
// samples, the ray-march): they are 4 of a lobe's 8 stored vectors.
// With SPLAT_PREPARE_LIT (a lit frame), each world lobe's colour is its lit colour instead
// (litLobeColor: every light and the sky through the lobe's model at its centre, shadowed by the
// light-space structure), which every lit method reads in place of the unlit one, and how that
// colour changes along the lobe's shading axis, in the world lobes' second half (spot_layout.h's
// SpotWorldLobe), which the splatting's pixels and the ray-march's samples read.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#ifdef SPLAT_PREPARE_LIT
#include "spot_light.h"
#include "light_common.glsl"
#endif

layout(local_size_x = 64) in;

layout(std430, binding = kSplatBindImpulses) readonly buffer Impulses { SpotImpulse impulses[]; };
layout(std430, binding = kSplatBindLobes) readonly buffer Lobes { SpotLobe lobes[]; };
layout(std430, binding = kSplatBindWorldLobes) writeonly buffer WorldLobes { SpotWorldLobe worldLobes[]; };
layout(std430, binding = kSplatBindScreenLobes) writeonly buffer ScreenLobes { SpotScreenLobe screenLobes[]; };
layout(std430, binding = kSplatBindBounds) writeonly buffer Bounds { SpotKernelBound bounds[]; };
layout(std430, binding = kSplatBindCount) readonly buffer Count { uint impulseCount; };
layout(std430, binding = kSplatBindClipList) buffer ClipList { SpotSplatList clipList; uint clipped[]; };

layout(constant_id = kSplatSpecWorldLobes) const bool kWorldLobes = true;
layout(constant_id = kSplatSpecClipped) const bool kClipped = false;

bool finite3(vec3 v) { return !any(isnan(v)) && !any(isinf(v)); }

// The lobe's ray line in pixel terms, for the bounds: with delta = p - ref,
// w(p) = K0 + delta.x KX + delta.y KY = o'(p) x v(p) and v(p) = V0 + delta.x VX + delta.y VY
// (spot_splat.h's o' and v), both affine in the pixel (for perspective o' is one point, for
// orthographic v), so the pixels whose ray line meets the k-sigma support,
// |w|^2 < k^2 |v|^2, are a conic's region (supportConic) with nothing cancelling.
struct ScreenForm {
    vec4 k0; // xyz: K0; w: ref.x (pixels)
    vec4 kx; // xyz: KX; w: ref.y
    vec4 ky; // xyz: KY
    vec4 v0; // xyz: V0
    vec4 vx; // xyz: VX
    vec4 vy; // xyz: VY
};

// The lobe's screen forms for the world-to-lobe map A and centre c: the one the bounds are found
// from (returned) and the one stored for the pixels (`stored`, spot_splat.h). ref: the pixel the
// affine forms are written around (the centre's projection when it has one).
ScreenForm screenLobe(mat3 A, vec3 c, float amplitude, out SpotScreenLobe stored, out vec2 ref) {
    vec3 R = frame.right.xyz * frame.right.w;
    vec3 U = frame.up.xyz * frame.up.w;
    vec3 F = frame.forward.xyz;
    // A pixel step moves the ray direction (perspective) or origin (orthographic) by ex, ey.
    vec3 ex = R * (2.0 / frame.size.x);
    vec3 ey = -U * (2.0 / frame.size.y);
    vec3 rel = c - frame.eye.xyz;
    float z = dot(rel, F);
    ref = 0.5 * frame.size.xy;
    if (kOrthographic) {
        ref = vec2(0.5 * (dot(rel, frame.right.xyz) / frame.right.w + 1.0) * frame.size.x,
                   0.5 * (1.0 - dot(rel, frame.up.xyz) / frame.up.w) * frame.size.y);
    } else if (z > 0.0) {
        ref = vec2(0.5 * (dot(rel, frame.right.xyz) / (z * frame.right.w) + 1.0) * frame.size.x,
                   0.5 * (1.0 - dot(rel, frame.up.xyz) / (z * frame.up.w)) * frame.size.y);
    }
    float sx = 2.0 * ref.x / frame.size.x - 1.0;
    float sy = 1.0 - 2.0 * ref.y / frame.size.y;
    vec3 v0;
    vec3 vx;
    vec3 vy;
    vec3 k0;
    vec3 kx;
    vec3 ky;
    if (kOrthographic) {
        vec3 o0 = A * (frame.eye.xyz + sx * R + sy * U - c);
        vec3 ox = A * ex;
        vec3 oy = A * ey;
        v0 = A * F;
        vx = vec3(0.0);
        vy = vec3(0.0);
        k0 = cross(o0, v0);
        kx = cross(ox, v0);
        ky = cross(oy, v0);
        stored.a0 = vec4(o0, ref.x);
        stored.ax = vec4(ox, ref.y);
        stored.ay = vec4(oy, amplitude);
        stored.b = vec4(v0, 0.0);
    } else {
        vec3 o = A * (frame.eye.xyz - c);
        v0 = A * (F + sx * R + sy * U);
        vx = A * ex;
        vy = A * ey;
        k0 = cross(o, v0);
        kx = cross(o, vx);
        ky = cross(o, vy);
        stored.a0 = vec4(v0, ref.x);
        stored.ax = vec4(vx, ref.y);
        stored.ay = vec4(vy, amplitude);
        stored.b = vec4(o, 0.0);
    }
    ScreenForm s;
    s.k0 = vec4(k0, ref.x);
    s.kx = vec4(kx, ref.y);
    s.ky = vec4(ky, 0.0);
    s.v0 = vec4(v0, 0.0);
    s.vx = vec4(vx, 0.0);
    s.vy = vec4(vy, 0.0);
    return s;
}

// The pixels p = ref + d whose ray line meets a lobe's k-sigma support: |w|^2 < k^2 |v|^2 with
// w and v affine in d (ScreenForm), the conic f(d) = d^T M d + 2 b.d + c < 0.
struct SupportConic {
    float m00, m01, m11; // M
    float b0, b1;        // b
    float c;
};

SupportConic supportConic(ScreenForm s, float k) {
    float k2 = k * k;
    vec3 k0 = s.k0.xyz;
    vec3 kx = s.kx.xyz;
    vec3 ky = s.ky.xyz;
    SupportConic q;
    q.m00 = dot(kx, kx) - k2 * dot(s.vx.xyz, s.vx.xyz);
    q.m01 = dot(kx, ky) - k2 * dot(s.vx.xyz, s.vy.xyz);
    q.m11 = dot(ky, ky) - k2 * dot(s.vy.xyz, s.vy.xyz);
    q.b0 = dot(k0, kx) - k2 * dot(s.v0.xyz, s.vx.xyz);
    q.b1 = dot(k0, ky) - k2 * dot(s.v0.xyz, s.vy.xyz);
    q.c = dot(k0, k0) - k2 * dot(s.v0.xyz, s.v0.xyz);
    return q;
}

// The screen ellipse of a lobe (supportConic's region). Returns false when it is not a bounded
// ellipse (the support reaches the eye plane, or is degenerate); else `centre` (pixels) and
// `shape` S, the ellipse being (x - centre)^T S^-1 (x - centre) <= 1. `seen` is false when no
// pixel ray meets the support.
bool screenEllipse(ScreenForm s, float k, out vec2 centre, out mat2 shape, out bool seen) {
    SupportConic q = supportConic(s, k);
    float m00 = q.m00, m01 = q.m01, m11 = q.m11, b0 = q.b0, b1 = q.b1, c = q.c;
    float det = m00 * m11 - m01 * m01;
    centre = vec2(s.k0.w, s.kx.w);
    shape = mat2(0.0);
    seen = true;
    if (!(det > 0.0) || !(m00 > 0.0) || isinf(det))
        return false;
    mat2 inv = mat2(m11, -m01, -m01, m00) / det;
    vec2 m = -(inv * vec2(b0, b1));
    float r2 = -dot(vec2(b0, b1), m) - c;
    if (!(r2 > 0.0)) {
        seen = !(r2 <= 0.0); // NaN: unknown, so seen (unbounded)
        return false;
    }
    centre += m;
    shape = r2 * inv;
    return true;
}

// The real roots of a t^2 + 2 h t + c = 0 (a linear equation when a is 0); returns how many.
int quadraticRoots(float a, float h, float c, out float t0, out float t1) {
    t0 = 0.0;
    t1 = 0.0;
    if (a == 0.0) {
        if (h == 0.0)
            return 0;
        t0 = -c / (2.0 * h);
        return 1;
    }
    float disc = h * h - a * c;
    if (!(disc >= 0.0))
        return 0;
    // The root of larger magnitude first, the other from the product of the roots (no
    // cancellation).
    float q = -(h + (h < 0.0 ? -sqrt(disc) : sqrt(disc)));
    t0 = q / a;
    t1 = q != 0.0 ? c / q : t0;
    return 2;
}

// Grows [lo, hi] by point p when it lies in the image rectangle (offset coordinates: d = p - ref,
// so the rectangle is [-ref, size - ref]), padded by half a pixel for the rounding of the roots.
void growInRect(vec2 p, vec2 rectLo, vec2 rectHi, inout vec2 lo, inout vec2 hi) {
    if (all(greaterThanEqual(p, rectLo - 0.5)) && all(lessThanEqual(p, rectHi + 0.5)) &&
        !any(isnan(p)) && !any(isinf(p))) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
}

// Grows [lo, hi] by the points origin + t dir at the first n of the roots t0, t1.
void growAtRoots(int n, float t0, float t1, vec2 origin, vec2 dir, vec2 rectLo, vec2 rectHi,
                 inout vec2 lo, inout vec2 hi) {
    if (n > 0)
        growInRect(origin + t0 * dir, rectLo, rectHi, lo, hi);
    if (n > 1)
        growInRect(origin + t1 * dir, rectLo, rectHi, lo, hi);
}

// The axis-aligned box (pixels) of the image pixels whose ray line meets the lobe's k-sigma
// support, for a lobe whose projection is not a bounded ellipse (the support reaches the eye
// plane): supportConic's region clipped to the image. The region's extremes lie at the image
// corners inside it, where the conic crosses the image's edges, or where the conic's tangent is
// vertical (x extremes) or horizontal (y extremes), so the box of those points is exact (a line
// meeting the support behind the eye counts too: conservative). Returns false when the region
// misses the image; a box of the whole image when the conic's numbers are not finite.
bool clippedConicBox(ScreenForm s, float k, out vec2 lo, out vec2 hi) {
    SupportConic q = supportConic(s, k);
    float m00 = q.m00, m01 = q.m01, m11 = q.m11, b0 = q.b0, b1 = q.b1, c = q.c;
    vec2 ref = vec2(s.k0.w, s.kx.w);
    vec2 rectLo = -ref;
    vec2 rectHi = frame.size.xy - ref;
    lo = vec2(3e38);
    hi = vec2(-3e38);
    float coeffs[6] = float[6](m00, m01, m11, b0, b1, c);
    float largest = 0.0;
    for (int j = 0; j < 6; ++j) {
        if (isnan(coeffs[j]) || isinf(coeffs[j])) {
            lo = vec2(0.0);
            hi = frame.size.xy;
            return true;
        }
        largest = max(largest, abs(coeffs[j]));
    }
    if (!(largest > 0.0))
        return false;
    // A positive scale leaves the region f < 0 as it is; scaled to at most 1, the products below
    // (squares of coefficients times squared pixel offsets) cannot overflow.
    m00 /= largest;
    m01 /= largest;
    m11 /= largest;
    b0 /= largest;
    b1 /= largest;
    c /= largest;
    // Corners inside the region.
    for (int j = 0; j < 4; ++j) {
        vec2 d = vec2((j & 1) != 0 ? rectHi.x : rectLo.x, (j & 2) != 0 ? rectHi.y : rectLo.y);
        if (dot(d, mat2(m00, m01, m01, m11) * d) + 2.0 * dot(vec2(b0, b1), d) + c < 0.0)
            growInRect(d, rectLo, rectHi, lo, hi);
    }
    float t0;
    float t1;
    // The conic on the vertical edges x = e: m11 y^2 + 2 (m01 e + b1) y + (m00 e^2 + 2 b0 e + c).
    for (int j = 0; j < 2; ++j) {
        float e = j == 0 ? rectLo.x : rectHi.x;
        int n = quadraticRoots(m11, m01 * e + b1, (m00 * e + 2.0 * b0) * e + c, t0, t1);
        growAtRoots(n, t0, t1, vec2(e, 0.0), vec2(0.0, 1.0), rectLo, rectHi, lo, hi);
    }
    // The horizontal edges y = e.
    for (int j = 0; j < 2; ++j) {
        float e = j == 0 ? rectLo.y : rectHi.y;
        int n = quadraticRoots(m00, m01 * e + b0, (m11 * e + 2.0 * b1) * e + c, t0, t1);
        growAtRoots(n, t0, t1, vec2(0.0, e), vec2(1.0, 0.0), rectLo, rectHi, lo, hi);
    }
    // Vertical tangents (df/dy = 0: the line y = -(m01 x + b1) / m11) and horizontal ones
    // (x = -(m01 y + b0) / m00), each met with the conic.
    float det = m00 * m11 - m01 * m01;
    if (m11 != 0.0) {
        int n = quadraticRoots(det / m11, b0 - m01 * b1 / m11, c - b1 * b1 / m11, t0, t1);
        growAtRoots(n, t0, t1, vec2(0.0, -b1 / m11), vec2(1.0, -m01 / m11), rectLo, rectHi, lo, hi);
    }
    if (m00 != 0.0) {
        int n = quadraticRoots(det / m00, b1 - m01 * b0 / m00, c - b0 * b0 / m00, t0, t1);
        growAtRoots(n, t0, t1, vec2(-b0 / m00, 0.0), vec2(-m01 / m00, 1.0), rectLo, rectHi, lo, hi);
    }
    if (!(hi.x >= lo.x) || !(hi.y >= lo.y))
        return false;
    // Back to pixels, padded by a pixel (float rounding of large coefficients), clamped to the
    // image.
    lo = clamp(lo + ref - 1.0, vec2(0.0), frame.size.xy);
    hi = clamp(hi + ref + 1.0, vec2(0.0), frame.size.xy);
    return true;
}

// One function for the whole kernel (about 170 lines), by choice: its per-lobe arrays (centres,
// shapes, boxes) stay in registers on lavapipe only while every index is a constant after
// unrolling, which arrays passed between functions do not guarantee (docs/design.md section 8).
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (kClipped) {
        if (i >= clipList.count)
            return;
        i = clipped[i];
    } else if (i >= impulseCount) {
        return;
    }
    SpotImpulse imp = impulses[i];
    float k = frame.size.w;
    mat3 kernelFrame = mat3(imp.frameX.xyz, imp.frameY.xyz, imp.frameZ.xyz);
    // Per lobe: its screen ellipse (when bounded), and the kernel's state.
    vec2 centres[kLobes];
    mat2 shapes[kLobes];
    bool live[kLobes];
    // Per lobe, an axis-aligned box in pixels; with one lobe unbounded, the kernel's quad is the
    // boxes' union.
    vec2 boxLo[kLobes];
    vec2 boxHi[kLobes];
    bool unbounded = false;
    bool clip = false; // a lobe projects to no ellipse: the second dispatch bounds the kernel
    float zNear = 3e38;
    float massSum = 0.0;
    float depthSum = 0.0;
    for (uint l = 0u; l < kLobes; ++l) {
        SpotLobe lobe = lobes[l];
        mat3 inv = mat3(lobe.inv0.xyz, lobe.inv1.xyz, lobe.inv2.xyz);
        vec3 kernelCentre = vec3(lobe.inv0.w, lobe.inv1.w, lobe.inv2.w);
        vec3 centre;
        mat3 A = spotPlaceLobe(inv, kernelCentre, kernelFrame, imp.scale.xyz, imp.normal.w,
                               imp.position.xyz, centre);
        float amplitude = lobe.color.w * imp.position.w;
        vec3 color = lobe.color.rgb * imp.color.rgb;
#ifdef SPLAT_PREPARE_LIT
        vec3 slope;       // the lit colour's change per sigma along the shading axis
        vec3 axisLobe;    // that axis in lobe space (unwidened), unit
        mat3 unwidened = A;
        {
            SpotLitLobe model = lit.lobes[l];
            vec3 axis = normalize(imp.normal.xyz); // lambert: the surface's normal on the GPU
            if (model.model.x == kSpotShadeStrand)
                axis = spotPlacedAxis(model.axis.xyz, kernelCentre, kernelFrame, imp.scale.xyz,
                                      imp.normal.w);
            else if (model.model.x == kSpotShadeFlake)
                axis = spotPlacedNormal(A, int(model.model.y));
            vec3 v = kOrthographic ? -frame.forward.xyz : normalize(frame.eye.xyz - centre);
            color = litLobeColor(model.model.x, axis, A, centre, amplitude, frame.size.w, v, color,
                                 model.primary.xyz, model.secondary.xyz, slope);
            axisLobe = A * axis;
            float axisLength = length(axisLobe);
            axisLobe = axisLength > 0.0 ? axisLobe / axisLength : vec3(0.0);
            if (any(isnan(color)) || any(isinf(color)) || any(isnan(slope)) || any(isinf(slope))) {
                color = vec3(0.0);
                slope = vec3(0.0);
            }
        }
#endif
        if (kEwa) {
            // Box pixel filter of one footprint: variance footprint^2 / 12 per image axis.
            float z = max(splatViewDepth(centre), 0.0);
            float footprint = frame.size.z * (kOrthographic ? 1.0 : z);
            vec3 dir = kOrthographic ? frame.forward.xyz : normalize(centre - frame.eye.xyz);
            A = spotWidenLobeCoverage(A, dir, footprint * 0.28867513459481287, amplitude);
        }
        mat3 M = inverse(A);
        bool ok = amplitude > 0.0 && !isinf(amplitude) && finite3(A[0]) && finite3(A[1]) &&
                  finite3(A[2]) && finite3(centre) && finite3(M[0]) && finite3(M[1]) && finite3(M[2]);
        SpotWorldLobe w;
        w.a0 = ok ? vec4(A[0], centre.x) : vec4(0.0);
        w.a1 = ok ? vec4(A[1], centre.y) : vec4(0.0);
        w.a2 = ok ? vec4(A[2], centre.z) : vec4(0.0);
        w.color = vec4(color, ok ? amplitude : 0.0);
        if (kWorldLobes) // (makePreparePipeline sets it without kScreen)
            worldLobes[i * kLobes + l] = w;
#ifdef SPLAT_PREPARE_LIT
        if (kWorldLobes) {
            // The axis in the widened lobe space the pixels evaluate: x = axisLobe . (A0 M u).
            vec3 along = transpose(M) * (transpose(unwidened) * axisLobe);
            SpotWorldLobe change;
            change.a0 = vec4(ok ? slope : vec3(0.0), 0.0);
            change.a1 = vec4(ok && finite3(along) ? along : vec3(0.0), 0.0);
            change.a2 = vec4(0.0);
            change.color = vec4(0.0);
            worldLobes[(frame.counts.x + i) * kLobes + l] = change;
        }
#endif
        live[l] = false;
        centres[l] = vec2(0.0);
        shapes[l] = mat2(0.0);
        boxLo[l] = vec2(0.0);
        boxHi[l] = vec2(0.0);
        if (!kScreen)
            continue;
        vec2 ref;
        SpotScreenLobe stored;
        ScreenForm s = screenLobe(A, centre, ok ? amplitude : 0.0, stored, ref);
        if (!ok) {
            stored.ay.w = 0.0;
            screenLobes[i * kLobes + l] = stored;
            continue;
        }
        // Instanced's opaque footprint: the optical depth from which it covers a pixel, from
        // the peak along the view through the centre (spotCoverThreshold).
        vec3 viewDir = kOrthographic ? frame.forward.xyz : normalize(centre - frame.eye.xyz);
        stored.b.w = spotCoverThreshold(amplitude * kSqrtTwoPi / length(A * viewDir));
        screenLobes[i * kLobes + l] = stored;
        // The depth range of the support (tangent planes along the view direction).
        vec3 rel = centre - frame.eye.xyz;
        float zc = dot(rel, frame.forward.xyz);
        float zHalf = k * length(transpose(M) * frame.forward.xyz);
        if (zc + zHalf <= 0.0)
            continue; // wholly behind the camera: no ray (t >= 0) reaches it
        float mass = amplitude / abs(determinant(A));
        if (mass > 0.0 && !isinf(mass)) {
            massSum += mass;
            depthSum += mass * zc;
        }
        bool seen;
        bool bounded = screenEllipse(s, k, centres[l], shapes[l], seen);
        if (!kOrthographic && zc - zHalf <= 0.0)
            bounded = false; // reaches the eye plane: the projection is unbounded
        if (!seen)
            continue;
        if (bounded && !any(isnan(centres[l])) && !any(isinf(centres[l]))) {
            vec2 e = sqrt(max(vec2(shapes[l][0][0], shapes[l][1][1]), vec2(0.0)));
            boxLo[l] = centres[l] - e;
            boxHi[l] = centres[l] + e;
        } else if (!kClipped) {
            clip = true;
            continue;
        } else {
            // Not an ellipse: the part of the conic in the image (none: the lobe is not seen).
            if (!clippedConicBox(s, k, boxLo[l], boxHi[l]))
                continue;
            unbounded = true;
        }
        zNear = min(zNear, zc - zHalf);
        live[l] = true;
    }
    if (!kScreen)
        return;
    if (clip) { // (never in the second dispatch)
        uint j = atomicAdd(clipList.count, 1u);
        clipped[j] = i;
        atomicMax(clipList.groupsX, j / 64u + 1u);
    }

    // The union's principal axis from its second moments (an ellipse of shape S has S / 4).
    uint n = 0u;
    vec2 mean = vec2(0.0);
    mat2 second = mat2(0.0);
    for (uint l = 0u; l < kLobes; ++l) {
        if (!live[l])
            continue;
        ++n;
        mean += centres[l];
        second += 0.25 * shapes[l] + outerProduct(centres[l], centres[l]);
    }
    SpotKernelBound b;
    b.quad = vec4(0.0);
    b.axis = vec4(1.0, 0.0, 0.0, 0.0);
    float z = massSum > 0.0 && !isinf(massSum) ? depthSum / massSum : splatViewDepth(imp.position.xyz);
    b.axis.z = z > 0.0 ? z : 0.0; // also maps NaN and -0 to +0
    b.axis.w = zNear;
    b.color = vec4(imp.color.rgb, 0.0);
    if (n > 0u && unbounded) {
        vec2 lo = vec2(3e38);
        vec2 hi = vec2(-3e38);
        for (uint l = 0u; l < kLobes; ++l) {
            if (live[l]) {
                lo = min(lo, boxLo[l]);
                hi = max(hi, boxHi[l]);
            }
        }
        lo = clamp(lo - kSplatBoundPadding, vec2(0.0), frame.size.xy);
        hi = clamp(hi + kSplatBoundPadding, vec2(0.0), frame.size.xy);
        if (all(greaterThan(hi, lo)))
            b.quad = vec4(0.5 * (lo + hi), 0.5 * (hi - lo));
    } else if (n > 0u) {
        mean /= float(n);
        mat2 cov = second / float(n) - outerProduct(mean, mean);
        float angle = 0.5 * atan(2.0 * cov[0][1], cov[0][0] - cov[1][1]);
        vec2 u = vec2(cos(angle), sin(angle));
        if (any(isnan(u)))
            u = vec2(1.0, 0.0);
        vec2 v = vec2(-u.y, u.x);
        vec2 lo = vec2(3e38);
        vec2 hi = vec2(-3e38);
        for (uint l = 0u; l < kLobes; ++l) {
            if (!live[l])
                continue;
            vec2 c = vec2(dot(centres[l], u), dot(centres[l], v));
            vec2 e = sqrt(max(vec2(dot(u, shapes[l] * u), dot(v, shapes[l] * v)), vec2(0.0)));
            lo = min(lo, c - e);
            hi = max(hi, c + e);
        }
        lo -= kSplatBoundPadding;
        hi += kSplatBoundPadding;
        vec2 mid = 0.5 * (lo + hi);
        vec2 half_ = 0.5 * (hi - lo);
        vec2 centre = mid.x * u + mid.y * v;
        // Cull quads wholly off screen (their axis-aligned box misses it).
        vec2 reach = abs(u) * half_.x + abs(v) * half_.y;
        bool onScreen = all(greaterThan(centre + reach, vec2(0.0))) && all(lessThan(centre - reach, frame.size.xy));
        if (onScreen && all(greaterThan(half_, vec2(0.0))) && !any(isinf(reach)))
            b.quad = vec4(centre, half_);
        b.axis.xy = u;
    }
    bounds[i] = b;
}
