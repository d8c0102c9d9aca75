#version 450
// Baked renderer, one layer's march: per pixel, the tetrahedron the peel pass kept, the view
// ray's segment inside it (clipped by its 4 face planes, and at the mesh), mapped to rest-pose
// (texture) coordinates by the tetrahedron's affine map, marched through the baked grid at the
// mip level of the pixel's footprint, and composited under what the earlier layers left
// (front to back). docs/design.md section 5.
//
// Loop bound per invocation (the host checks it against kBakedLoopBudget before recording):
//   4 (planes) + N (1 + (P_d + 1) + 8 (1 + P + 1))
// with N the most steps per segment, P_d the distance table's longest probe, P the longest probe
// of any level. Empty-space skipping only lowers the count.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = kBakedSpecCount) const bool kCountLoops = false;

layout(std430, binding = kBakedBindParams) readonly buffer Params { SpotBakedParams params; };
layout(std430, binding = kBakedBindTets) readonly buffer Tets { SpotBakedTet tets[]; };
layout(std430, binding = kBakedBindTable) readonly buffer Table { ivec4 table[]; };
layout(std430, binding = kBakedBindBricks) readonly buffer Bricks { vec4 bricks[]; };
layout(std430, binding = kBakedBindDistances) readonly buffer Distances { float distances[]; };
layout(binding = kBakedBindLayerTet, r32ui) uniform readonly uimage2D layerTet;
layout(binding = kBakedBindMeshDistance, r32f) uniform readonly image2D meshDistance;
layout(binding = kBakedBindAccum, rgba32f) uniform image2D accum;
layout(std430, binding = kBakedBindLoops) buffer Loops { uint maxLoops; };

uint loops = 0u;

uint sectionValue(uvec4 a[3], uint s) { return a[s >> 2u][s & 3u]; }

// The brick holding voxel `ijk` of section `s`, or -1.
int findBrick(ivec3 ijk, uint s) {
    ivec3 leaf = ijk >> int(kBakedLeafBits);
    uint offset = sectionValue(params.tableOffset, s);
    uint mask = sectionValue(params.tableMask, s);
    uint probe = sectionValue(params.probe, s);
    uint slot = bakedHash(leaf, s) & mask;
    for (uint i = 0u; i <= probe; ++i) {
        if (kCountLoops)
            ++loops;
        ivec4 e = table[offset + slot];
        if (e.w == kBakedEmptySlot)
            return -1;
        if (e.xyz == leaf)
            return e.w;
        slot = (slot + 1u) & mask;
    }
    return -1;
}

uint voxelOffset(ivec3 ijk) {
    ivec3 l = ijk & 7;
    return uint(l.x << 6 | l.y << 3 | l.z);
}

// (extinction x colour, extinction) of voxel ijk of `level`, 0 where not stored.
vec4 voxel(ivec3 ijk, uint level) {
    int b = findBrick(ijk, level);
    return b < 0 ? vec4(0.0) : bricks[uint(b) * kBakedLeafVoxels + voxelOffset(ijk)];
}

// Trilinear between the voxel centres (ijk + 1/2) x voxel size of `level`.
vec4 sampleLevel(vec3 x, uint level, float inverseSize) {
    vec3 g = x * inverseSize - 0.5;
    vec3 f = floor(g);
    vec3 w = g - f;
    ivec3 c = ivec3(f);
    vec4 sum = vec4(0.0);
    for (uint i = 0u; i < 8u; ++i) {
        if (kCountLoops)
            ++loops;
        ivec3 o = ivec3(int(i >> 2u) & 1, int(i >> 1u) & 1, int(i) & 1);
        vec3 wo = mix(1.0 - w, w, vec3(o));
        float weight = wo.x * wo.y * wo.z;
        if (weight > 0.0)
            sum += weight * voxel(c + o, level);
    }
    return sum;
}

// Level-0 voxels to the nearest non-empty one (bake.h), the cap where not stored.
float distanceAt(vec3 x) {
    ivec3 ijk = ivec3(floor(x * params.grid.y));
    int b = findBrick(ijk, kBakedDistanceSection);
    return b < 0 ? params.grid.z : distances[uint(b) * kBakedLeafVoxels + voxelOffset(ijk)];
}

// Barycentric coordinates of x in the tetrahedron with corners p (weights of p1, p2, p3).
vec3 barycentric(vec3 p[4], vec3 x) {
    mat3 m = mat3(p[1] - p[0], p[2] - p[0], p[3] - p[0]);
    return inverse(m) * (x - p[0]);
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x >= int(frame.size.x) || pixel.y >= int(frame.size.y))
        return;
    uint id = imageLoad(layerTet, pixel).r;
    vec4 acc = imageLoad(accum, pixel);
    if (id == 0u || acc.a >= 1.0)
        return;
    SpotBakedTet tet = tets[id - 1u];
    vec3 origin, dir;
    splatPixelRay(vec2(pixel) + 0.5, origin, dir);

    // The segment: the ray clipped by the 4 face planes (noise::raySegmentInTetrahedron).
    vec3 p[4], r[4];
    for (uint i = 0u; i < 4u; ++i) {
        p[i] = tet.world[i].xyz;
        r[i] = tet.rest[i].xyz;
    }
    float tEnter = 0.0, tExit = imageLoad(meshDistance, pixel).r;
    for (uint f = 0u; f < 4u; ++f) {
        if (kCountLoops)
            ++loops;
        vec3 a = p[(f + 1u) % 4u], b = p[(f + 2u) % 4u], c = p[(f + 3u) % 4u];
        vec3 n = cross(b - a, c - a);
        if (dot(n, p[f] - a) < 0.0)
            n = -n; // inwards
        float num = dot(n, a - origin); // inside where dot(n, x - a) >= 0
        float den = dot(n, dir);
        if (den > 0.0)
            tEnter = max(tEnter, num / den);
        else if (den < 0.0)
            tExit = min(tExit, num / den);
        else if (num > 0.0)
            tExit = -1.0; // parallel and outside
    }
    if (!(tExit > tEnter)) {
        if (kCountLoops)
            atomicMax(maxLoops, loops);
        return;
    }
    vec3 ra = vec3(0.0), rb = vec3(0.0);
    {
        vec3 ba = barycentric(p, origin + tEnter * dir), bb = barycentric(p, origin + tExit * dir);
        mat3 rm = mat3(r[1] - r[0], r[2] - r[0], r[3] - r[0]);
        ra = r[0] + rm * ba;
        rb = r[0] + rm * bb;
    }

    // The mip level: the coarsest whose voxel is no larger than the pixel's footprint there.
    float voxel0 = params.grid.x;
    float footprint = frame.size.z * dot(origin + 0.5 * (tEnter + tExit) * dir - frame.eye.xyz,
                                         frame.forward.xyz);
    uint levels = params.counts.y;
    uint level = uint(clamp(floor(log2(max(footprint / voxel0, 1.0))), 0.0, float(levels - 1u)));
    float size = voxel0 * float(1u << level);
    float restLength = length(rb - ra);
    uint steps = uint(clamp(ceil(restLength / (kBakedStepFraction * size)), 1.0,
                            float(params.counts.z)));
    float dtWorld = (tExit - tEnter) / float(steps);
    float dtRest = restLength / float(steps);
    // A sample at level L reads voxels whose level-0 children lie within 1.5 x size of it
    // (Chebyshev): with the distance d there, the next (d - 1) voxel0 - 1.5 size along the ray
    // (in rest units) read only empty voxels, so those samples are skipped (they add nothing).
    float reach = 1.5 * size;

    vec3 radiance = vec3(0.0);
    float transmittance = 1.0;
    float inverseSize = 1.0 / size;
    for (uint i = 0u; i < steps; ++i) {
        if (kCountLoops)
            ++loops;
        vec3 x = mix(ra, rb, (float(i) + 0.5) / float(steps));
        float skip = (distanceAt(x) - 1.0) * voxel0 - reach;
        if (skip >= 0.0) {
            i += uint(floor(skip / max(dtRest, 1e-30)));
            continue;
        }
        vec4 s = sampleLevel(x, level, inverseSize);
        if (s.w > 0.0) {
            float alpha = 1.0 - exp(-s.w * dtWorld);
            radiance += transmittance * alpha * (s.rgb / s.w);
            transmittance *= 1.0 - alpha;
        }
    }
    acc.rgb += (1.0 - acc.a) * radiance;
    acc.a += (1.0 - acc.a) * (1.0 - transmittance);
    imageStore(accum, pixel, acc);
    if (kCountLoops)
        atomicMax(maxLoops, loops);
}
