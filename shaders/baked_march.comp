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
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

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
            vec4 s = sampleLevel(x, leafOrigin, leafDims, inverseSize, unit);
            if (s.w > 0.0) {
                float alpha = 1.0 - exp(-s.w * dt);
                radiance += transmittance * alpha * (s.rgb / s.w);
                transmittance *= 1.0 - alpha;
            }
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
            if (atMesh || samples >= kBakedMaxLayerSamples)
                break;
            if (!spotTetNext(neighbours[tet][exitFace], tet, entryFace))
                break; // left the shell
            inTet = false;
        }
    }
    compositeLayer(pixel, acc, under, radiance, transmittance, tEnd, tMesh, entryDepth, sampledTo);
}
