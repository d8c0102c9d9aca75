#version 450
// Baked renderer, one layer's march (docs/design.md section 5): per pixel of the layer's list
// (the peel's: those with an entry; dispatched indirectly), a walk through the
// shell's tetrahedra from the layer's entry, front to back, across the face where the ray leaves
// each into the neighbour there (the host's noise::shellNeighbours), so one layer covers the
// ray's whole contiguous passage through the shell. Per tetrahedron: the exit is the nearest of
// its face planes the ray leaves through (the entry face excluded, the previous exit the entry;
// backward through a fold's inverted tetrahedra, spot_tet_walk.h),
// and the samples of the layer's fixed spacing that fall in [entry, exit) are taken in rest-pose
// (texture) coordinates by the tetrahedron's affine map, through the baked grid at the mip level
// of the pixel's footprint at the layer's entry; composited under what the earlier layers left.
// The walk ends at the shell's boundary (no neighbour), at the mesh, when the transmittance
// falls below kBakedOpaque, or at kBakedMaxLayerTets tetrahedra or kBakedMaxLayerSamples samples.
// The next layer's peel takes entries behind this layer's entry (0 when nothing behind can show:
// the pixel became opaque, or the walk reached the mesh), not behind its exit: where parts of the
// shell overlap (a fold, a part thinner than the shell), the ray can enter another part before it
// leaves this one, and that part goes on behind this walk's exit. Each layer samples only behind
// the farthest point the earlier ones walked (written with the depth), so nothing is sampled twice.
// Each layer also writes its pixels' composite over the mesh colour into the frame's result (the
// base image: the mesh's colour elsewhere), from the mesh colour the first layer kept (every pixel
// a later layer walks, the first walked: a pixel with no entry face before the mesh has none in any
// layer), and clears the pixel's entry for the next peel.
//
// A layer starts at the entry face the peel kept (the layer's entries); but the first layer
// (kFirstLayer), when the eye is inside the shell, starts every pixel at t = 0 in the
// tetrahedron holding the eye (found by baked_shell.comp), over every pixel (the shell raises
// the first list's dispatch to cover them), and the next peel continues behind.
//
// Loop bound per invocation (the host checks it against kBakedLoopBudget before recording):
//   M (1 + 4) + S
// with M = kBakedMaxLayerTets (the walk, at most 4 planes each: the 3 after the entry face, and
// face 0 too from the eye) and S = kBakedMaxLayerSamples (each a
// trilinear sample of 8 voxels, unrolled; its leaf is one read of the leaf table, no loop):
// the walk's one loop takes a sample or enters a tetrahedron per iteration (M + S, the last
// one's break included, since the walk ends at S samples on the next step).
//
// Lit scenes (the modules compiled with BAKED_LIT, shaders/CMakeLists.txt, which alone declare
// the bindings the lit march reads; docs/design.md section 5): each sample that adds at least
// kBakedLitMinWeight to the pixel is shaded by spot_light.h's models for every light and
// kBakedSkyDirections sky directions instead of emitting its colour: the axis (the shading
// bricks' extinction-weighted tangent or normal, normalized) through the kernel's axis model,
// the rest of the sample (where the kernel mixes models) through lambert with the normal of the
// trilinear gradient. Each light's transmittance comes from a shadow march through the bake at
// the samples' own level, each sky direction's through its coarsest level (shadowTransmittance),
// both stopped by the mesh's solid. The walk that reaches the mesh shades it diffuse by the same
// lights and sky with the same shadow marches. A shadow march is an inner loop of at most
// kBakedShadowSteps iterations.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"
#ifdef BAKED_LIT
#include "spot_light.h"
#endif

layout(local_size_x = kBakedMarchGroupSize) in;

layout(constant_id = kBakedSpecCount) const bool kCountLoops = false;
layout(constant_id = kBakedSpecFirstLayer) const bool kFirstLayer = false;
// The storage buffers the density bricks span (1 to kBakedBrickBuffers): one module per count
// (shaders/CMakeLists.txt), each declaring only the buffers it reads.
#ifndef BAKED_BRICK_BUFFERS
#define BAKED_BRICK_BUFFERS 1
#endif

layout(std430, binding = kBakedBindParams) readonly buffer Params { SpotBakedParams params; };
layout(std430, binding = kBakedBindTets) readonly buffer Tets { SpotBakedTet tets[]; };
layout(std430, binding = kBakedBindNeighbours) readonly buffer Neighbours { ivec4 neighbours[]; };
layout(std430, binding = kBakedBindEyeTet) readonly buffer EyeTet { uint eyeTet; };
layout(std430, binding = kBakedBindTable) readonly buffer Table { int table[]; };
layout(std430, binding = kBakedBindBricks) readonly buffer Bricks0 { uvec2 bricks0[]; };
#if BAKED_BRICK_BUFFERS > 1
layout(std430, binding = kBakedBindBricks1) readonly buffer Bricks1 { uvec2 bricks1[]; };
#endif
#if BAKED_BRICK_BUFFERS > 2
layout(std430, binding = kBakedBindBricks2) readonly buffer Bricks2 { uvec2 bricks2[]; };
#endif
#if BAKED_BRICK_BUFFERS > 3
layout(std430, binding = kBakedBindBricks3) readonly buffer Bricks3 { uvec2 bricks3[]; };
#endif
layout(std430, binding = kBakedBindLayerEntry) buffer LayerEntry { uvec2 layerEntry[]; };
layout(binding = kBakedBindMeshDistance, r32f) uniform readonly image2D meshDistance;
layout(binding = kBakedBindAccum, rgba32f) uniform image2D accum;
layout(binding = kBakedBindBase, rgba32f) uniform image2D baseColor;
layout(binding = kBakedBindBaseKept, rgba32f) uniform image2D baseKept;
layout(binding = kBakedBindExitDepth, rgba32f) uniform image2D exitDepth;
layout(std430, binding = kBakedBindLoops) buffer Loops { uint maxLoops; };
layout(std430, binding = kBakedBindList) readonly buffer List { SpotBakedList list; };
#ifdef BAKED_LIT
// The mesh now (its normal where a walk reaches it), its inside (the solid) and the shading
// bricks, split over the buffers the density bricks are.
layout(std430, binding = kBakedBindVertices) readonly buffer Vertices {
    SpotMeshVertex vertices[];
};
layout(std430, binding = kBakedBindIndices) readonly buffer Indices { uint indices[]; };
layout(std430, binding = kBakedBindSolid) readonly buffer Solid { uint solid[]; };
layout(std430, binding = kBakedBindShading) readonly buffer Shading0 { uvec2 shading0[]; };
#if BAKED_BRICK_BUFFERS > 1
layout(std430, binding = kBakedBindShading1) readonly buffer Shading1 { uvec2 shading1[]; };
#endif
#if BAKED_BRICK_BUFFERS > 2
layout(std430, binding = kBakedBindShading2) readonly buffer Shading2 { uvec2 shading2[]; };
#endif
#if BAKED_BRICK_BUFFERS > 3
layout(std430, binding = kBakedBindShading3) readonly buffer Shading3 { uvec2 shading3[]; };
#endif
#endif
layout(std430, binding = kBakedBindListPixels) readonly buffer ListPixels { uint listPixels[]; };

vec4 spotWalkPlane(uint tet, uint f) { return tets[tet].plane[f]; }
#include "spot_tet_walk.h"

uint loops = 0u;

// The brick of the leaf holding voxel `ijk`, or -1, from a section's leaf table (origin, dims:
// its SpotBakedParams leafOrigin and leafDims; baked_layout.glsl).
int findBrickIn(ivec3 ijk, ivec4 origin, ivec3 dims) {
    ivec3 r = (ijk >> int(kBakedLeafBits)) - origin.xyz;
    if (any(lessThan(r, ivec3(0))) || any(greaterThanEqual(r, dims)))
        return -1;
    return table[origin.w + (r.z * dims.y + r.y) * dims.x + r.x];
}

// Where voxel ijk of a leaf lies in the leaf's brick (baked_layout.glsl: the apron layout).
uint voxelOffset(ivec3 ijk) {
    ivec3 l = ijk & 7;
    return uint((l.x * int(kBakedBrickSide) + l.y) * int(kBakedBrickSide) + l.z);
}

vec4 unpackVoxel(uvec2 v) { return vec4(unpackHalf2x16(v.x), unpackHalf2x16(v.y)); }

// Voxel `offset` of density brick b (in stored units), from the brick buffer that holds it.
vec4 brickVoxel(uint b, uint offset) {
#if BAKED_BRICK_BUFFERS == 1
    return unpackVoxel(bricks0[b * kBakedBrickVoxels + offset]); // one buffer: no selection (it costs)
#else
    uint per = params.counts.w;
    uint which = b / per;
    uint i = (b - which * per) * kBakedBrickVoxels + offset;
    if (which == 0u)
        return unpackVoxel(bricks0[i]);
#if BAKED_BRICK_BUFFERS > 2
    if (which == 1u)
        return unpackVoxel(bricks1[i]);
#if BAKED_BRICK_BUFFERS > 3
    if (which == 2u)
        return unpackVoxel(bricks2[i]);
    return unpackVoxel(bricks3[i]);
#else
    return unpackVoxel(bricks2[i]);
#endif
#else
    return unpackVoxel(bricks1[i]);
#endif
#endif
}

// Trilinear between the voxel centres (ijk + 1/2) x voxel size of `level`: the 8 corners
// unrolled. They all lie in the brick of the lowest corner's leaf (its apron holds the rest;
// a leaf without a brick has no stored voxel in its apron either), so one leaf lookup serves
// the sample. Branchless: a sample without a brick reads brick 0 and weighs it 0.
// origin, dims: the level's leaf table (SpotBakedParams), read once a layer.
vec4 sampleLevel(vec3 x, ivec4 origin, ivec3 dims, float inverseSize, float unit) {
    vec3 g = x * inverseSize - 0.5;
    vec3 f = floor(g);
    vec3 w = g - f;
    ivec3 c = ivec3(f);
    int found = findBrickIn(c, origin, dims);
    uint b = uint(max(found, 0));
    uint o = voxelOffset(c);
    const uint dy = kBakedBrickSide; // a step in y, and one in x
    const uint dx = kBakedBrickSide * kBakedBrickSide;
    vec4 z0 = mix(brickVoxel(b, o), brickVoxel(b, o + 1u), w.z);
    vec4 z1 = mix(brickVoxel(b, o + dy), brickVoxel(b, o + dy + 1u), w.z);
    vec4 z2 = mix(brickVoxel(b, o + dx), brickVoxel(b, o + dx + 1u), w.z);
    vec4 z3 = mix(brickVoxel(b, o + dx + dy), brickVoxel(b, o + dx + dy + 1u), w.z);
    return (float(found >= 0) * unit) * mix(mix(z0, z1, w.y), mix(z2, z3, w.y), w.x);
}

#ifdef BAKED_LIT
// Voxel `offset` of shading brick b (density brick b's), as brickVoxel reads the density.
vec4 shadingVoxel(uint b, uint offset) {
#if BAKED_BRICK_BUFFERS == 1
    return unpackVoxel(shading0[b * kBakedBrickVoxels + offset]);
#else
    uint per = params.counts.w;
    uint which = b / per;
    uint i = (b - which * per) * kBakedBrickVoxels + offset;
    if (which == 0u)
        return unpackVoxel(shading0[i]);
#if BAKED_BRICK_BUFFERS > 2
    if (which == 1u)
        return unpackVoxel(shading1[i]);
#if BAKED_BRICK_BUFFERS > 3
    if (which == 2u)
        return unpackVoxel(shading2[i]);
    return unpackVoxel(shading3[i]);
#else
    return unpackVoxel(shading2[i]);
#endif
#else
    return unpackVoxel(shading1[i]);
#endif
#endif
}

// Lit: the trilinear sample of `sampleLevel` (returned), with the same sample of the shading
// bricks (`axis`: extinction x axis, stored units x unit) and the gradient of the extinction
// (per world unit of the bake) from the same 8 voxels.
vec4 sampleLit(vec3 x, ivec4 origin, ivec3 dims, float inverseSize, float unit, out vec4 axis,
               out vec3 gradient) {
    vec3 g = x * inverseSize - 0.5;
    vec3 f = floor(g);
    vec3 w = g - f;
    ivec3 c = ivec3(f);
    int found = findBrickIn(c, origin, dims);
    uint b = uint(max(found, 0));
    uint o = voxelOffset(c);
    const uint dy = kBakedBrickSide;
    const uint dx = kBakedBrickSide * kBakedBrickSide;
    vec4 v000 = brickVoxel(b, o), v001 = brickVoxel(b, o + 1u);
    vec4 v010 = brickVoxel(b, o + dy), v011 = brickVoxel(b, o + dy + 1u);
    vec4 v100 = brickVoxel(b, o + dx), v101 = brickVoxel(b, o + dx + 1u);
    vec4 v110 = brickVoxel(b, o + dx + dy), v111 = brickVoxel(b, o + dx + dy + 1u);
    vec4 z0 = mix(v000, v001, w.z), z1 = mix(v010, v011, w.z);
    vec4 z2 = mix(v100, v101, w.z), z3 = mix(v110, v111, w.z);
    float scale = float(found >= 0) * unit;
    gradient = scale * inverseSize *
               vec3(mix(z2.w, z3.w, w.y) - mix(z0.w, z1.w, w.y),
                    mix(z1.w - z0.w, z3.w - z2.w, w.x),
                    mix(mix(v001.w - v000.w, v011.w - v010.w, w.y),
                        mix(v101.w - v100.w, v111.w - v110.w, w.y), w.x));
    vec4 a0 = mix(shadingVoxel(b, o), shadingVoxel(b, o + 1u), w.z);
    vec4 a1 = mix(shadingVoxel(b, o + dy), shadingVoxel(b, o + dy + 1u), w.z);
    vec4 a2 = mix(shadingVoxel(b, o + dx), shadingVoxel(b, o + dx + 1u), w.z);
    vec4 a3 = mix(shadingVoxel(b, o + dx + dy), shadingVoxel(b, o + dx + dy + 1u), w.z);
    axis = scale * mix(mix(a0, a1, w.y), mix(a2, a3, w.y), w.x);
    return scale * mix(mix(z0, z1, w.y), mix(z2, z3, w.y), w.x);
}

// Whether rest point p lies in the mesh's solid (the host's voxelization of the mesh's inside at
// level params.shadow.x, a bit per voxel of that level's box of leaves; kBakedBindSolid).
bool inSolid(vec3 p) {
    uint level = params.shadow.x;
    ivec4 origin = params.leafOrigin[level];
    ivec3 n = params.leafDims[level].xyz * 8;
    ivec3 v = ivec3(floor(p * (params.grid.y / float(1u << level)))) - origin.xyz * 8;
    if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, n)))
        return false;
    uint bit = uint((v.z * n.y + v.y) * n.x + v.x);
    return (solid[bit >> 5u] & (1u << (bit & 31u))) != 0u;
}

// Lit: the transmittance from rest point x towards unit direction l over `distance` through the
// bake's `level`, one voxel a step from `start` voxels on (a light's from the sample itself at
// the samples' own level: a left sum, the sample's own extinction weighs a whole step; measured,
// docs/design.md section 5); a leaf without a brick is crossed in one step. 0 in the mesh's
// solid from one voxel on (the bake holds only the fur; the reference stops a shadow ray at the
// mesh; the first voxel is not tested, since a root's or the mesh's own voxel may have its centre
// inside). Stops at the box of the level's leaves, at kBakedShadowOpaqueDepth, or after
// kBakedShadowSteps steps (the rest taken as clear).
float shadowTransmittance(vec3 x, vec3 l, float distance, uint level, float start) {
    float size = params.grid.x * float(1u << level);
    float inverseSize = 1.0 / size;
    ivec4 origin = params.leafOrigin[level];
    ivec3 dims = params.leafDims[level].xyz;
    float unit = params.unit.x;
    // Where the ray leaves the box of the level's leaves (sample positions, in voxels of the
    // level: a sample's lowest corner lies in a leaf of the box).
    vec3 g0 = x * inverseSize - 0.5;
    vec3 inv = 1.0 / (l * inverseSize);
    vec3 lo = vec3(origin.xyz * 8), hi = vec3((origin.xyz + dims) * 8);
    vec3 ta = (lo - g0) * inv, tb = (hi - g0) * inv;
    float tEnd = min(distance, min(min(max(ta.x, tb.x), max(ta.y, tb.y)), max(ta.z, tb.z)));
    float tau = 0.0;
    float t = start * size;
    for (uint i = 0u; i < kBakedShadowSteps; ++i) {
        if (!(t < tEnd) || tau > kBakedShadowOpaqueDepth)
            break;
        vec3 p = x + t * l;
        if (t >= size && inSolid(p))
            return 0.0;
        ivec3 c = ivec3(floor(p * inverseSize - 0.5));
        if (findBrickIn(c, origin, dims) < 0) {
            // An empty leaf: on to where the ray leaves it.
            vec3 leafLo = vec3((c >> int(kBakedLeafBits)) * 8);
            vec3 la = (leafLo - g0) * inv, lb = (leafLo + 8.0 - g0) * inv;
            float leave = min(min(max(la.x, lb.x), max(la.y, lb.y)), max(la.z, lb.z));
            t = max(t + size, leave * 1.0001 + 1e-4 * size);
            continue;
        }
        tau += sampleLevel(p, origin, dims, inverseSize, unit).w * size;
        t += size;
    }
    return exp(-tau);
}

// Lit: the sky's transmittance from rest point x towards direction w: the bake's coarsest level
// from half a voxel on (the sky is soft, and 4 directions at the samples' level cost 4 times a
// light's march; docs/design.md section 5).
float skyTransmittance(vec3 x, vec3 w) {
    return shadowTransmittance(x, w, 1e30, params.counts.y - 1u, 0.5);
}

// Lit: where a light sends its light from world point x: the unit direction towards it, its
// distance (infinite for a directional light) and what arrives (colour x intensity, a point
// light's over d^2).
void arrive(uint i, vec3 x, out vec3 l, out float distance, out vec3 radiance) {
    vec4 p = params.lights[i].position;
    radiance = params.lights[i].radiance.rgb;
    if (p.w < 0.5) {
        l = p.xyz;
        distance = 1e30;
        return;
    }
    vec3 to = p.xyz - x;
    distance = length(to);
    l = distance > 0.0 ? to / distance : vec3(0.0, 1.0, 0.0);
    radiance *= spotPointFalloff(1.0, distance);
}

// The sky's fixed directions (kBakedSkyDirections): alternately low and high (y = 1/4, 3/4),
// turning by a quarter (45, 135, 225, 315 degrees about +y).
vec3 skyDirection(uint k) {
    return spotSkyDirection((float(k & 1u) + 0.5) * 0.5,
                            (float(k) + 0.5) / float(kBakedSkyDirections));
}

// Lit: what a sample of colour c sends towards the eye (v), per unit of extinction: every
// light and the sky through its models (the file comment), shadowed from rest point xRest at
// `level`.
// `axis`: extinction x axis over extinction (the shading bricks); n: the gradient normal.
vec3 shadeSample(vec3 xRest, vec3 xWorld, vec3 v, vec3 c, vec3 axis, vec3 n, uint level) {
    uint model = params.lit.y;
    float len = length(axis);
    float share = model == kSpotShadeLambert || !(len > 1e-6)
                      ? 0.0
                      : (params.lit.z != 0u ? 1.0 : min(len, 1.0));
    vec3 a = len > 1e-6 ? axis / len : n;
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < params.lit.x; ++i) {
        vec3 l, radiance;
        float distance;
        arrive(i, xWorld, l, distance, radiance);
        float t = params.lights[i].radiance.w > 0.5
                      ? shadowTransmittance(xRest, l, distance, level, 0.0)
                      : 1.0;
        vec3 f = share * spotLobeShade(model, a, l, v, c, params.primary.xyz, params.secondary.xyz);
        if (share < 1.0)
            f += (1.0 - share) * spotLobeDiffuse(kSpotShadeLambert, n, l, v) * c;
        sum += (t * radiance) * f;
    }
    if (any(greaterThan(params.sky.rgb, vec3(0.0)))) {
        for (uint k = 0u; k < kBakedSkyDirections; ++k) {
            vec3 w = skyDirection(k);
            float d = share * spotLobeDiffuse(model, a, w, v) +
                      (1.0 - share) * spotLobeDiffuse(kSpotShadeLambert, n, w, v);
            if (d > 0.0)
                sum += (2.0 / float(kBakedSkyDirections)) * skyTransmittance(xRest, w) * d *
                       params.sky.rgb * c;
        }
    }
    return sum;
}

// Lit: the base mesh where the walk in `tet` (a tetrahedron of triangle tet / 3) reaches it at
// world point x: diffuse, its interpolated vertex normal turned to the eye, by every light and the
// sky, shadowed by the bake from rest point xRest at `level`.
vec3 shadeMesh(uint tet, vec3 x, vec3 xRest, vec3 v, uint level) {
    uint tri = tet / 3u;
    vec3 p0 = vertices[indices[3u * tri]].position.xyz;
    vec3 p1 = vertices[indices[3u * tri + 1u]].position.xyz;
    vec3 p2 = vertices[indices[3u * tri + 2u]].position.xyz;
    vec3 e1 = p1 - p0, e2 = p2 - p0, q = x - p0;
    float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    float det = d11 * d22 - d12 * d12;
    float b1 = det != 0.0 ? (d22 * dot(q, e1) - d12 * dot(q, e2)) / det : 0.0;
    float b2 = det != 0.0 ? (d11 * dot(q, e2) - d12 * dot(q, e1)) / det : 0.0;
    vec3 n = (1.0 - b1 - b2) * vertices[indices[3u * tri]].normal.xyz +
             b1 * vertices[indices[3u * tri + 1u]].normal.xyz +
             b2 * vertices[indices[3u * tri + 2u]].normal.xyz;
    float len = length(n);
    n = spotTwoSided(len > 0.0 ? n / len : normalize(cross(e1, e2)), v);
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < params.lit.x; ++i) {
        vec3 l, radiance;
        float distance;
        arrive(i, x, l, distance, radiance);
        float cosine = max(0.0, dot(n, l));
        if (!(cosine > 0.0))
            continue;
        float t = params.lights[i].radiance.w > 0.5
                      ? shadowTransmittance(xRest, l, distance, level, 0.0)
                      : 1.0;
        sum += (cosine * t) * radiance;
    }
    for (uint k = 0u; k < kBakedSkyDirections; ++k) {
        vec3 w = skyDirection(k);
        float cosine = max(0.0, dot(n, w));
        if (cosine > 0.0 && any(greaterThan(params.sky.rgb, vec3(0.0))))
            sum += (2.0 / float(kBakedSkyDirections)) * cosine * skyTransmittance(xRest, w) *
                   params.sky.rgb;
    }
    return sum * frame.base.rgb;
}
#endif

// The rest-pose position of world point x in `tet`.
vec3 toRest(uint tet, vec3 x) {
    return spotTetToRest(tets[tet].toRest[0], tets[tet].toRest[1], tets[tet].toRest[2], x);
}

// Whether tetrahedron t is folded (spot_tet_walk.h).
bool folded(uint t) {
    return spotTetFolded(tets[t].world[0].xyz, tets[t].world[1].xyz, tets[t].world[2].xyz,
                         tets[t].world[3].xyz);
}

// The layer ends: the depth the next peel's entries must lie behind (reversed: near / view depth;
// 0: no later layer) and the ray parameter the layers have sampled to.
void finish(ivec2 pixel, float depth, float sampledTo) {
    imageStore(exitDepth, pixel, vec4(depth, sampledTo, 0.0, 0.0));
    if (kCountLoops)
        atomicMax(maxLoops, loops);
}

// This invocation's pixel, and where its walk starts: the eye's tetrahedron (first layer, eye in
// the shell: every pixel) or the entry the peel kept (the layer's list), whose record it clears
// for the next peel, and the depth the next peel's entries must lie behind (the entry's, as the
// peel kept it; from the eye, every entry face). False when the invocation has no pixel.
bool layerPixel(out ivec2 pixel, inout uint tet, inout uint entryFace, out float entryDepth) {
    bool fromEye = tet != kBakedNoTet;
    uint item = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kBakedMarchGroupSize +
                gl_LocalInvocationID.x; // rows of workgroups (SpotBakedList)
    uint width = uint(frame.size.x);
    if (fromEye) {
        if (item >= width * uint(frame.size.y))
            return false;
        pixel = ivec2(item % width, item / width);
    } else {
        if (item >= list.count)
            return false;
        uint packedPixel = listPixels[item];
        pixel = ivec2(packedPixel & 0xffffu, packedPixel >> 16u);
    }
    uint index = splatPixelIndex(pixel);
    entryDepth = 2.0; // reversed depth is at most 1
    if (!fromEye) {
        // Not 0: the list holds pixels with an entry.
        uvec2 entry = layerEntry[index];
        tet = (entry.x - 1u) >> 2u;
        entryFace = (entry.x - 1u) & 3u;
        entryDepth = uintBitsToFloat(entry.y);
    }
    layerEntry[index] = uvec2(0u); // the next peel starts with no entry
    return true;
}

// The layer's radiance and transmittance composited under what the earlier layers left (acc),
// its composite over the mesh colour (under) into the frame's result, and where the next layer
// starts: behind this layer's entry (entryDepth), sampling behind sampledTo.
void compositeLayer(ivec2 pixel, vec4 acc, vec4 under, vec3 radiance, float transmittance,
                    float tEnd, float tMesh, float entryDepth, float sampledTo) {
    acc.rgb += (1.0 - acc.a) * radiance;
    acc.a += (1.0 - acc.a) * (1.0 - transmittance);
    if (transmittance < kBakedOpaque)
        acc.a = 1.0;
    imageStore(accum, pixel, acc);
    // The colour over the mesh's (or the background), and the coverage: 1 - the layers'
    // transmittance x the mesh's (its alpha: 1 where hit).
    imageStore(baseColor, pixel,
               vec4(acc.rgb + (1.0 - acc.a) * under.rgb, 1.0 - (1.0 - acc.a) * (1.0 - under.a)));
    // Opaque (alpha 1: this layer's transmittance fell below kBakedOpaque, or the layers' alpha
    // rounded to 1) or at the mesh: no later layer.
    finish(pixel, acc.a >= 1.0 || tEnd >= tMesh ? 0.0 : entryDepth, max(sampledTo, tEnd));
}

void main() {
    uint tet = kFirstLayer ? eyeTet : kBakedNoTet, entryFace = kTetNoFace; // from the eye
    bool fromEye = tet != kBakedNoTet;
    ivec2 pixel;
    float entryDepth;
    if (!layerPixel(pixel, tet, entryFace, entryDepth))
        return;
    // The earlier layers sampled the ray up to here (a layer may start inside what an earlier
    // one walked, where parts of the shell overlap): this one samples behind it only.
    float sampledTo = kFirstLayer ? 0.0 : imageLoad(exitDepth, pixel).y;
    // An entry through a face of a folded tetrahedron with a neighbour there (the peel draws
    // them: the ray can enter the shell across a fold, baked_shell.comp): both lie behind the
    // face, and the walk follows the fold from the neighbour's side when it is not folded itself
    // (into the folded one it soon meets the top surface, the fold's other side).
    if (!fromEye && folded(tet)) {
        int across = neighbours[tet][entryFace];
        if (across >= 0 && !folded(uint(across) >> 2u)) {
            tet = uint(across) >> 2u;
            entryFace = uint(across) & 3u;
        }
    }
    vec4 acc = kFirstLayer ? vec4(0.0) : imageLoad(accum, pixel);
    vec4 under;
    if (kFirstLayer) {
        under = imageLoad(baseColor, pixel);
        imageStore(baseKept, pixel, under);
    } else {
        under = imageLoad(baseKept, pixel);
    }
    vec3 origin, dir;
    splatPixelRay(vec2(pixel) + 0.5, origin, dir);
    float tMesh = imageLoad(meshDistance, pixel).r;
    float viewCos = dot(dir, frame.forward.xyz);

    float tIn = fromEye ? 0.0 : spotTetEntry(tet, entryFace, origin, dir);

    // The samples: t_k = tStart + (k + 1/2) dt for the whole layer, at the mip level of the
    // pixel's footprint at the entry (the coarsest whose voxel is no larger).
    float voxel0 = params.grid.x;
    float footprint = frame.size.z * tIn * viewCos;
    uint levels = params.counts.y;
    uint level = uint(clamp(floor(log2(max(footprint / voxel0, 1.0))), 0.0, float(levels - 1u)));
    float size = voxel0 * float(1u << level);
    float inverseSize = 1.0 / size;
    ivec4 leafOrigin = params.leafOrigin[level];
    ivec3 leafDims = params.leafDims[level].xyz;
    float unit = params.unit.x;
    float dt = kBakedStepFraction * size;
    float tStart = max(tIn, sampledTo);
    // No empty-space skipping: the distance grid (capped at 4 voxels) could skip at most 2 steps
    // at level 0 and none above, and its lookup cost more than it saved (docs/design.md 5).
    uint k = 0u;       // the next sample
    uint samples = 0u; // taken
    vec3 radiance = vec3(0.0);
    float transmittance = 1.0;
    float tEnd = tIn;
    // One flat loop: each iteration takes a sample and, where the tetrahedron then has none left,
    // steps into the next one (whose exit the next iteration computes first). So a SIMD batch runs
    // to its longest lane's samples plus sampleless tetrahedra, not per tetrahedron to its lanes'
    // most samples.
    uint walked = 0u;
    bool inTet = false;
    float tOut = tIn;
    bool atMesh = false;
    uint exitFace = 4u;
    vec3 ra = vec3(0.0), rb = vec3(0.0);
    float inverseLength = 0.0;
    for (uint step = 0u; step <= kBakedMaxLayerTets + kBakedMaxLayerSamples; ++step) {
        if (kCountLoops)
            ++loops;
        if (!inTet) {
            if (walked == kBakedMaxLayerTets)
                break;
            ++walked;
            // The exit: the nearest plane the ray leaves through, the entry face excluded (or,
            // backward through a fold's inverted tetrahedron, the farthest it enters through
            // before the entry: no sample there, it was taken before the fold).
            bool backward;
            exitFace = spotTetExit(tet, entryFace, origin, dir, kCountLoops, tOut, backward, loops);
            if (exitFace == kTetNoFace)
                break; // flat or degenerate: the walk stops here
            tOut = backward ? min(tOut, tIn) : max(tOut, tIn);
            atMesh = tOut >= tMesh;
            tOut = min(tOut, tMesh);
            inTet = true;
            if (tStart + (float(k) + 0.5) * dt < tOut) {
                // The segment's ends at rest (a sample follows, so tOut > tIn).
                ra = toRest(tet, origin + tIn * dir);
                rb = toRest(tet, origin + tOut * dir);
                inverseLength = 1.0 / (tOut - tIn);
            }
        }
        float t = tStart + (float(k) + 0.5) * dt;
        if (t < tOut && samples < kBakedMaxLayerSamples) {
            vec3 x = mix(ra, rb, (t - tIn) * inverseLength);
#ifdef BAKED_LIT
            {
                vec4 axis;
                vec3 gradient;
                vec4 s = sampleLit(x, leafOrigin, leafDims, inverseSize, unit, axis, gradient);
                if (s.w > 0.0) {
                    float alpha = 1.0 - exp(-s.w * dt);
                    if (transmittance * alpha >= kBakedLitMinWeight) {
                        vec3 view = -dir;
                        vec3 n = spotGradientNormal(-gradient, view, 1e30);
                        radiance += transmittance * alpha *
                                    shadeSample(x, origin + t * dir, view, s.rgb / s.w,
                                                axis.xyz / s.w, n, level);
                    }
                    transmittance *= 1.0 - alpha;
                }
            }
#else
            vec4 s = sampleLevel(x, leafOrigin, leafDims, inverseSize, unit);
            if (s.w > 0.0) {
                float alpha = 1.0 - exp(-s.w * dt);
                radiance += transmittance * alpha * (s.rgb / s.w);
                transmittance *= 1.0 - alpha;
            }
#endif
            ++k;
            ++samples;
            if (transmittance < kBakedOpaque) {
                tEnd = max(tEnd, tOut);
                break;
            }
            t = tStart + (float(k) + 0.5) * dt;
        }
        // No sample left in this tetrahedron: on to the next one, in the same iteration as its
        // last sample (a step in an iteration of its own made a tetrahedron of n samples take
        // n + 1).
        if (!(t < tOut && samples < kBakedMaxLayerSamples)) {
            tEnd = max(tEnd, tOut); // the farthest the walk reached
            tIn = tOut;
#ifdef BAKED_LIT
            // The mesh behind this layer, lit (the mesh pass drew its colour unlit): where the
            // walk reaches it, or leaves the shell within half a step of it (through the base
            // face, which the mesh pass's distance may lie just behind).
            bool nearMesh = !atMesh && neighbours[tet][exitFace] < 0 && tMesh - tOut < 0.5 * dt;
            if ((atMesh || nearMesh) && transmittance >= kBakedOpaque) {
                vec3 x = origin + tMesh * dir;
                under = vec4(shadeMesh(tet, x, toRest(tet, x), -dir, level), 1.0);
            }
#endif
            if (atMesh || samples >= kBakedMaxLayerSamples)
                break;
            if (!spotTetNext(neighbours[tet][exitFace], tet, entryFace))
                break; // left the shell
            inTet = false;
        }
    }
    compositeLayer(pixel, acc, under, radiance, transmittance, tEnd, tMesh, entryDepth, sampledTo);
}
