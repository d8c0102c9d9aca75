#version 450
// Baked renderer, one depth-peeling layer (docs/design.md section 5): of the shell's entry faces
// strictly farther than where the previous layer's walk left the shell (its exit depth; reversed
// depth: smaller is farther), the depth test keeps the nearest; the mesh's depth, copied into the
// depth buffer first, culls those behind the mesh. Writes the entry (4 tet + face, + 1; 0 where
// none). The march (baked_march.comp) then walks the shell from there.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(binding = kBakedBindPrevDepth, r32f) uniform readonly image2D prevDepth;

layout(location = 0) flat in uint vEntry;
layout(location = 0) out uint outEntry;

void main() {
    if (gl_FragCoord.z >= imageLoad(prevDepth, ivec2(gl_FragCoord.xy)).r)
        discard; // before the previous layer's exit: walked already
    outEntry = vEntry + 1u;
}
