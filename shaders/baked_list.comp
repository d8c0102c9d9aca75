#version 450
// Baked renderer, per layer between the peel and the march: the pixels the march has to walk,
// compacted into a list, and the march's indirect dispatch (64 list entries per workgroup).
// lavapipe runs a shader's straight-line code and every loop body at least once per SIMD batch
// even where all its lanes have returned, so a march over every pixel costs the whole march's
// code per 8 pixels also where nothing is drawn; over the list it runs only where a layer
// starts. A pixel walks when the peel kept an entry face and it is not opaque yet, or, in the
// first layer, for every pixel when the eye is inside the shell (baked_shell.comp). The others'
// exit depth is written here (0: nothing behind shows). The list's order depends on the atomics'
// order, but every entry is one pixel marched on its own, so the image does not.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = kBakedSpecFirstLayer) const bool kFirstLayer = false;

layout(std430, binding = kBakedBindEyeTet) readonly buffer EyeTet { uint eyeTet; };
layout(std430, binding = kBakedBindLayerEntry) readonly buffer LayerEntry { uvec2 layerEntry[]; };
layout(binding = kBakedBindAccum, rgba32f) uniform readonly image2D accum;
layout(binding = kBakedBindExitDepth, r32f) uniform writeonly image2D exitDepth;
layout(std430, binding = kBakedBindList) buffer List { SpotBakedList list; uint listPixels[]; };

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x >= int(frame.size.x) || pixel.y >= int(frame.size.y))
        return;
    bool walk = (kFirstLayer && eyeTet != kBakedNoTet) ||
                (layerEntry[splatPixelIndex(pixel)].x != 0u &&
                 imageLoad(accum, pixel).a < 1.0);
    if (!walk) {
        imageStore(exitDepth, pixel, vec4(0.0));
        return;
    }
    uint i = atomicAdd(list.count, 1u);
    listPixels[i] = uint(pixel.x) | uint(pixel.y) << 16u;
    atomicMax(list.groups.x, i / 64u + 1u);
}
