// light_build.glsl: what the passes that build the light-space structure share (spot_shadow.h):
// the bindings they read, each lobe as a view sees it (widened by the view's texel, its mass
// kept), and a work item's texels.
#extension GL_GOOGLE_include_directive : require
#define SHADOW_LAYERS_WRITE
#include "spot_shared.h"
#include "spot_layout.h"
#include "spot_splat.h"
#include "light_common.glsl"

layout(push_constant) uniform Push { SpotShadowPush push; };

// This invocation's index in a dispatch laid out along x, then y (more than 65,535 groups).
uint shadowIndex() {
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * kShadowGroup;
}

// A work item: its source (a lobe, or a triangle with kShadowTriangleBit), view and tile.
struct ShadowItem {
    uint source;
    uint view;
    uvec2 tile;
};

uvec2 shadowPackItem(uint source, uint view, uvec2 tile) {
    return uvec2(source, (view << (2u * kShadowTileBits)) | (tile.y << kShadowTileBits) | tile.x);
}

ShadowItem shadowUnpackItem(uvec2 packed) {
    ShadowItem it;
    it.source = packed.x;
    it.view = packed.y >> (2u * kShadowTileBits);
    uint mask = (1u << kShadowTileBits) - 1u;
    it.tile = uvec2(packed.y & mask, (packed.y >> kShadowTileBits) & mask);
    return it;
}

// The texel world size at a point s along view v's rays (texel size z of the square).
float shadowTexelWorld(uint v, vec3 square, float s) {
    return lit.views[v].origin.w < 0.5 ? square.z : square.z * s;
}

// Lobe `w` (placed) as view v sees it: widened across the view's rays by the texel (a box
// filter's variance, mass conserved), so a strand thinner than a texel still shadows in
// proportion. Returns false for a lobe with no extinction. A: world -> lobe; amp: its peak.
bool shadowLobe(uint v, SpotWorldLobe w, vec3 square, out mat3 A, out vec3 c, out float amp) {
    A = mat3(w.a0.xyz, w.a1.xyz, w.a2.xyz);
    c = vec3(w.a0.w, w.a1.w, w.a2.w);
    amp = w.color.w;
    if (!(amp > 0.0))
        return false;
    SpotShadowView view = lit.views[v];
    vec3 dir = view.axisD.xyz;
    float s = 1.0;
    if (view.origin.w > 0.5) {
        dir = c - view.origin.xyz;
        s = length(dir);
        dir = s > 0.0 ? dir / s : view.axisD.xyz;
    }
    float scale;
    A = spotWidenLobe(A, dir, shadowTexelWorld(v, square, s) * 0.28867513459481287, scale);
    amp *= scale;
    return amp > 0.0 && !isinf(amp) && !isnan(amp);
}

// The texel rectangle [lo, hi] (inclusive) that lobe (A, c) covers in view v, and the nearest s
// of its support (`near`, a lower bound for a point light's view); false when it covers none.
bool shadowLobeRect(uint v, mat3 A, vec3 c, vec3 square, out ivec2 lo, out ivec2 hi, out float near) {
    SpotShadowView view = lit.views[v];
    mat3 M = inverse(A);
    float k = push.k.x;
    vec2 xlo, xhi;
    if (view.origin.w < 0.5)
        near = dot(c, view.axisD.xyz) - k * length(transpose(M) * view.axisD.xyz);
    else
        near = length(c - view.origin.xyz) - k * sqrt(dot(M[0], M[0]) + dot(M[1], M[1]) + dot(M[2], M[2]));
    if (view.origin.w < 0.5) {
        vec2 centre = vec2(dot(c, view.axisU.xyz), dot(c, view.axisW.xyz));
        vec2 e = k * vec2(length(transpose(M) * view.axisU.xyz), length(transpose(M) * view.axisW.xyz));
        xlo = centre - e;
        xhi = centre + e;
    } else {
        float zlo, zhi;
        vec3 rel = c - view.origin.xyz;
        if (!spotEllipsoidRange(rel, M, k, view.axisU.xyz, view.axisD.xyz, false, xlo.x, xhi.x, zlo, zhi))
            return false;
        if (!spotEllipsoidRange(rel, M, k, view.axisW.xyz, view.axisD.xyz, false, xlo.y, xhi.y, zlo, zhi))
            return false;
    }
    if (any(isnan(xlo)) || any(isnan(xhi)) || any(isinf(xlo)) || any(isinf(xhi)))
        return false;
    int r = int(view.offsets.w);
    vec2 flo = floor((xlo - square.xy) / square.z - 0.5);
    vec2 fhi = floor((xhi - square.xy) / square.z - 0.5) + 1.0;
    lo = ivec2(clamp(flo, vec2(0.0), vec2(float(r - 1))));
    hi = ivec2(clamp(fhi, vec2(0.0), vec2(float(r - 1))));
    return fhi.x >= 0.0 && fhi.y >= 0.0 && flo.x <= float(r - 1) && flo.y <= float(r - 1);
}
