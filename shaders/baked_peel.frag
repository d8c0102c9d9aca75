#version 450
// Baked renderer, one depth-peeling layer (docs/design.md section 5): of the shell's entry faces
// strictly farther than the previous layer's entry (reversed depth: smaller is farther; not its
// exit: where prisms overlap, at a fold or a thin part, the ray may enter another part of the shell
// before leaving the one it walks, and that part goes on behind the walk's exit; the march samples
// only behind what the earlier layers sampled), the nearest is kept; the mesh's depth (the depth
// attachment, tested before the shader runs, not written) culls those behind the mesh. The nearest
// is kept by a 64-bit atomicMax of (depth bits << 32 | 4 tet + face + 1) per pixel (depth >= 0, so
// its bits order as the floats do): the same entry whatever order the faces are drawn in, the
// larger entry on a tie (the faces that face the eye are listed by baked_shell.comp's atomics). The
// march (baked_march.comp) then walks the shell from there.
// The layer's list of pixels to march: the fragment whose atomicMax found the pixel without an
// entry (the march clears each entry it takes, so a layer starts with none) appends the pixel.
// The list's order depends on the atomics' order; every pixel is marched on its own, so the image
// does not.
// The first layer has no previous entry. A pixel without an entry there has no entry face before
// the mesh at all, so it has none in any later layer either: the peel depth of pixels that are
// never walked is never written, nor needed.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(early_fragment_tests) in;

layout(constant_id = kBakedSpecFirstLayer) const bool kFirstLayer = false;

layout(binding = kBakedBindPrevDepth, rgba32f) uniform readonly image2D prevDepth;
layout(std430, binding = kBakedBindLayerEntry) buffer LayerEntry { uint64_t layerEntry[]; };
layout(std430, binding = kBakedBindList) buffer List { SpotBakedList list; };
layout(std430, binding = kBakedBindListPixels) writeonly buffer ListPixels { uint listPixels[]; };

layout(location = 0) flat in uint vEntry;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    if (!kFirstLayer && gl_FragCoord.z >= imageLoad(prevDepth, pixel).x)
        return; // not behind the previous layer's entry: walked already
    uint64_t key = (uint64_t(floatBitsToUint(gl_FragCoord.z)) << 32) | uint64_t(vEntry + 1u);
    if (atomicMax(layerEntry[splatPixelIndex(pixel)], key) == uint64_t(0)) {
        uint i = atomicAdd(list.count, 1u);
        listPixels[i] = uint(pixel.x) | uint(pixel.y) << 16u;
        uvec2 groups = spotBakedMarchGroups(i + 1u);
        atomicMax(list.groups.x, groups.x);
        if (groups.y > 1u) // past the first row: rarely, so the second atomic is rarely paid
            atomicMax(list.groups.y, groups.y);
    }
}
