#version 450
// Baked renderer, one depth-peeling layer (docs/design.md section 5): of the
// tetrahedron front faces strictly farther than the previous layer's (reversed depth: smaller),
// the depth test keeps the nearest; the mesh's depth, copied into the depth buffer first, culls
// those behind the mesh. Writes the tetrahedron (+1; 0 where none) and its depth for the next
// layer. The march (baked_march.comp) then shades the one tetrahedron kept per pixel.
#extension GL_GOOGLE_include_directive : require
#include "splat_common.glsl"
#include "baked_layout.glsl"

layout(binding = kBakedBindPrevDepth, r32f) uniform readonly image2D prevDepth;

layout(location = 0) flat in uint vTet;
layout(location = 0) out uint outTet;
layout(location = 1) out float outDepth;

void main() {
    if (gl_FragCoord.z >= imageLoad(prevDepth, ivec2(gl_FragCoord.xy)).r)
        discard; // peeled by an earlier layer
    outTet = vTet + 1u;
    outDepth = gl_FragCoord.z;
}
