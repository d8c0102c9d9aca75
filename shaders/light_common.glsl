// light_common.glsl: the light-space structure's GLSL side (spot_shadow.h): the lit frame's
// parameters, the light-space coordinates of a view, the lookup of the transmittance from a point
// towards a light, and a lobe's or the mesh's lit colour. Included after spot_shared.h,
// spot_layout.h and spot_light.h.
#include "spot_shadow.h"

layout(std430, binding = kShadowBindParams) readonly buffer LitParamsBuffer {
    SpotLitParams lit;
    float ownShadow[]; // spot_shadow.h's table of spotOwnShadow
};
layout(std430, binding = kShadowBindExtents) buffer ShadowExtents { SpotShadowExtent extents[]; };
#ifdef SHADOW_LAYERS_WRITE
layout(std430, binding = kShadowBindLayers) buffer ShadowLayers { uint layers[]; };
layout(std430, binding = kShadowBindFirst) buffer ShadowFirst { uint firstDepth[]; };
#else
layout(std430, binding = kShadowBindLayers) readonly buffer ShadowLayers { uint layers[]; };
layout(std430, binding = kShadowBindFirst) readonly buffer ShadowFirst { uint firstDepth[]; };
#endif

// The texel square of view v: lower corner (x, y) and texel size (z), in light-space units.
vec3 shadowSquare(uint v) {
    SpotShadowExtent e = extents[v];
    vec2 lo = vec2(uintBitsToFloat(spotOrderedToBits(e.lo.x)), uintBitsToFloat(spotOrderedToBits(e.lo.y)));
    vec2 hi = vec2(uintBitsToFloat(spotOrderedToBits(e.hi.x)), uintBitsToFloat(spotOrderedToBits(e.hi.y)));
    return spotShadowSquare(lo, hi, lit.views[v].axisU.w);
}

// Light-space (x, y, s) of world point p in view v; `ok` false behind a perspective view's eye.
vec3 shadowCoords(uint v, vec3 p, out bool ok) {
    SpotShadowView view = lit.views[v];
    ok = true;
    if (view.origin.w < 0.5)
        return vec3(dot(p, view.axisU.xyz), dot(p, view.axisW.xyz), dot(p, view.axisD.xyz));
    vec3 q = p - view.origin.xyz;
    float z = dot(q, view.axisD.xyz);
    ok = z > 1e-6 * length(q);
    float iz = ok ? 1.0 / z : 0.0;
    return vec3(dot(q, view.axisU.xyz) * iz, dot(q, view.axisW.xyz) * iz, length(q));
}

// The ray of texel (i, j) of view v (square from shadowSquare): origin and unit direction, s
// along it being the light-space s of its points.
void shadowTexelRay(uint v, vec3 square, uint i, uint j, out vec3 o, out vec3 d) {
    SpotShadowView view = lit.views[v];
    vec2 xy = square.xy + (vec2(float(i), float(j)) + 0.5) * square.z;
    if (view.origin.w < 0.5) {
        o = xy.x * view.axisU.xyz + xy.y * view.axisW.xyz;
        d = view.axisD.xyz;
    } else {
        o = view.origin.xyz;
        d = normalize(view.axisD.xyz + xy.x * view.axisU.xyz + xy.y * view.axisW.xyz);
    }
}

// The tile of texel (x, y) in a view of r texels a side.
uint shadowTileOf(uint x, uint y, uint r) {
    uint tiles = (r + kShadowTile - 1u) / kShadowTile;
    return (y / kShadowTile) * tiles + x / kShadowTile;
}

#ifndef SHADOW_LAYERS_WRITE
// Optical depth from the light to s along texel (x, y) = t of view v: the layers cumulative
// below s's layer, and within it the layer's own part as a uniform step over its box (the
// moments the deposit kept), so a point in front of an opaque lobe in the same layer is not
// shadowed by it.
float shadowTexelDepth(SpotShadowView view, uint x, uint y, uint t, float s) {
    uint tile = shadowTileOf(x, y, view.offsets.w);
    float first = uintBitsToFloat(spotOrderedToBits(firstDepth[view.offsets.y + tile]));
    if (!(s > first))
        return 0.0;
    uint layerCount = uint(view.axisW.w);
    float f = (s - first) / view.axisD.w;
    uint base = view.offsets.x + t * layerCount * 3u;
    if (f >= float(layerCount))
        return uintBitsToFloat(layers[base + 3u * (layerCount - 1u)]);
    uint k = uint(f);
    float below = k == 0u ? 0.0 : uintBitsToFloat(layers[base + 3u * (k - 1u)]);
    float above = uintBitsToFloat(layers[base + 3u * k]);
    vec2 box = unpackUnorm2x16(layers[base + 3u * k + 1u]);
    float u = f - float(k);
    float step = box.y > box.x ? clamp((u - box.x) / (box.y - box.x), 0.0, 1.0) : (u >= box.x ? 1.0 : 0.0);
    return mix(below, above, step);
}

// Transmittance at depth s along texel t of view v (r texels a side): 1 outside the map (nothing
// in front), 0 where the mesh lies nearer than s by more than `bias`, else the kernels'.
float shadowTexelTransmittance(SpotShadowView view, uint r, ivec2 t, float s, float bias) {
    if (t.x < 0 || t.y < 0 || t.x >= int(r) || t.y >= int(r))
        return 1.0;
    uint texel = uint(t.y) * r + uint(t.x);
    float mesh = uintBitsToFloat(spotOrderedToBits(firstDepth[view.offsets.z + texel]));
    if (s - bias > mesh)
        return 0.0; // the mesh lies between
    return exp(-shadowTexelDepth(view, uint(t.x), uint(t.y), texel, s));
}

// Transmittance from world point p towards view v's light: the kernels' optical depth and the
// mesh, bilinear over the four nearest texels, or from the nearest one alone (`nearest`: the sky's
// lookups for the lobes, whose light is soft and averaged over its directions: a quarter of the
// loads). The mesh hides p where its depth is nearer than p's by more than `biasTexels` texels (a
// texel's world size at p), which keeps a surface from shadowing itself.
float shadowTransmittanceAt(uint v, vec3 p, float biasTexels, bool nearest) {
    bool ok;
    vec3 c = shadowCoords(v, p, ok);
    if (!ok)
        return 1.0;
    SpotShadowView view = lit.views[v];
    vec3 square = shadowSquare(v);
    uint r = view.offsets.w;
    float bias = biasTexels * square.z * (view.origin.w < 0.5 ? 1.0 : c.z);
    vec2 f = (c.xy - square.xy) / square.z;
    if (nearest)
        return shadowTexelTransmittance(view, r, ivec2(floor(f)), c.z, bias);
    f -= 0.5;
    vec2 fl = floor(f);
    vec2 w = f - fl;
    float sum = 0.0;
    for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
            float weight = (dx == 0 ? 1.0 - w.x : w.x) * (dy == 0 ? 1.0 - w.y : w.y);
            sum += weight * shadowTexelTransmittance(view, r, ivec2(fl) + ivec2(dx, dy), c.z, bias);
        }
    }
    return sum;
}

float shadowTransmittance(uint v, vec3 p, float biasTexels) {
    return shadowTransmittanceAt(v, p, biasTexels, false);
}

// How much of a lobe's own light it lets the eye see (spot_shared.h's spotOwnShadow, three
// rings), from the table: its depth scales along the eye's rays and the light's in lobe space and
// the cosine between them. v: towards the eye; l: towards the light.
float litOwnShadow(mat3 A, float amp, vec3 v, vec3 l) {
    vec3 dv = -(A * v); // the view rays' direction in lobe space
    vec3 dl = A * l;
    float lv = length(dv);
    float ll = length(dl);
    if (!(lv > 0.0) || !(ll > 0.0) || !(amp > 0.0))
        return 1.0;
    vec3 w;
    uint base = spotOwnShadowCell(amp / lv, amp / ll, dot(dv, dl) / (lv * ll), w);
    uint up = kOwnShadowB * kOwnShadowA;
    vec4 near = vec4(ownShadow[base], ownShadow[base + 1u], ownShadow[base + kOwnShadowA],
                     ownShadow[base + kOwnShadowA + 1u]);
    vec4 far = vec4(ownShadow[base + up], ownShadow[base + up + 1u],
                    ownShadow[base + up + kOwnShadowA], ownShadow[base + up + kOwnShadowA + 1u]);
    vec4 c = mix(near, far, w.z);
    vec2 b = mix(c.xy, c.zw, w.y);
    return mix(b.x, b.y, w.x);
}

// What arrives at p from `light` before any shadow: its direction l (towards the light) and
// radiance (a point light's falls off as 1 / d^2).
vec3 litIncoming(SpotLitLight light, vec3 p, out vec3 l) {
    if (light.where.w < 0.5) {
        l = light.where.xyz;
        return light.radiance.rgb;
    }
    vec3 q = light.where.xyz - p;
    float d = length(q);
    l = d > 0.0 ? q / d : vec3(0.0, 1.0, 0.0);
    return light.radiance.rgb * spotPointFalloff(1.0, d);
}

// What reaches a lobe from view v's light (direction l) past everything else: the structure's
// transmittance at the lobe's two light points along its shading axis, one sigma to the root
// side (x) and one to the tip side (y) (spot_light.h's spotLobeLightPoint).
vec2 litLobeLightEnds(uint v, mat3 A, vec3 c, float k, vec3 l, vec3 axis) {
    return vec2(shadowTransmittance(v, spotLobeLightPoint(A, c, axis, -1.0, l, k), 1.0),
                shadowTransmittance(v, spotLobeLightPoint(A, c, axis, 1.0, l, k), 1.0));
}

// A lobe's lit colour (docs/design.md, "Lighting on the GPU"): every light through its model
// and the sky's directions through its diffuse part, each shadowed by what lies between (the
// structure) and by the lobe itself as the eye sees it (litOwnShadow). Returns the colour at the
// lobe's centre; `slope`: its change per sigma along the shading axis, from the key lights'
// transmittance one sigma to either side (the sky's, one lookup at the centre from the nearest
// texel, is soft and has none). (A, c, amp: the lobe placed, unwidened; k: the support; v:
// towards the eye.)
vec3 litLobeColor(uint model, vec3 axis, mat3 A, vec3 c, float amp, float k, vec3 v, vec3 color,
                  vec3 primary, vec3 secondary, out vec3 slope) {
    vec3 sum = vec3(0.0);
    slope = vec3(0.0);
    for (uint i = 0u; i < lit.counts.x; ++i) {
        SpotLitLight light = lit.lights[i];
        vec3 l;
        vec3 shaded = litIncoming(light, c, l) *
                      spotLobeShade(model, axis, l, v, color, primary, secondary);
        uint view = uint(light.radiance.w);
        if (view == 0u) {
            sum += shaded;
            continue;
        }
        vec2 ends = litLobeLightEnds(view - 1u, A, c, k, l, axis);
        shaded *= litOwnShadow(A, amp, v, l);
        sum += (0.5 * (ends.x + ends.y)) * shaded;
        slope += (0.5 * (ends.y - ends.x)) * shaded;
    }
    for (uint j = 0u; j < lit.counts.y; ++j) {
        vec3 w = lit.skyDirs[j].xyz;
        uint view = uint(lit.skyDirs[j].w);
        vec3 p = spotLobeLightPoint(A, c, axis, 0.0, w, k);
        float t = shadowTransmittanceAt(view, p, 1.0, true) * litOwnShadow(A, amp, v, w);
        sum += (t * spotLobeDiffuse(model, axis, w, v)) * lit.sky.rgb * color;
    }
    return sum;
}

// What arrives at p from light i: its direction l (towards the light) and radiance, shadowed.
vec3 litArrival(uint i, vec3 p, float biasTexels, out vec3 l) {
    SpotLitLight light = lit.lights[i];
    vec3 radiance = litIncoming(light, p, l);
    uint view = uint(light.radiance.w);
    if (view > 0u)
        radiance *= shadowTransmittance(view - 1u, p, biasTexels);
    return radiance;
}

// The base mesh's lit diffuse from every light at p with unit normal n facing the eye, shadowed
// (the mesh's own depth biased by 2 texels), per pixel.
vec3 litSurfaceLights(vec3 p, vec3 n) {
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < lit.counts.x; ++i) {
        vec3 l;
        vec3 radiance = litArrival(i, p, 2.0, l);
        sum += radiance * max(0.0, dot(n, l));
    }
    return sum;
}

// The sky's diffuse share at p, shadowed, for the two faces: x with normal n, y with -n (the
// mesh pass evaluates it per vertex, where the face the eye sees is not known yet: the sky is
// soft, and its directions' lookups are three quarters of the mesh's).
vec2 litSurfaceSky(vec3 p, vec3 n) {
    vec2 sum = vec2(0.0);
    for (uint k = 0u; k < lit.counts.y; ++k) {
        vec3 w = lit.skyDirs[k].xyz;
        float c = dot(n, w);
        float t = shadowTransmittance(uint(lit.skyDirs[k].w), p, 2.0);
        sum += t * vec2(max(0.0, c), max(0.0, -c));
    }
    return sum;
}
#endif
