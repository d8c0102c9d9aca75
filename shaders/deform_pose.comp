#version 450
// Deform pass 1 of 4 (spot_deform_layout.h): each vertex posed (spot_pose.h) into the base
// mesh's vertex buffer; its normal is the next pass's.
#extension GL_GOOGLE_include_directive : require
#include "deform_common.glsl"

layout(std430, binding = kDeformBindVertices) readonly buffer Vertices { SpotDeformVertex vertices[]; };
layout(std430, binding = kDeformBindPieces) readonly buffer Pieces { SpotDeformPiece pieces[]; };
layout(std430, binding = kDeformBindDeltas) readonly buffer Deltas { vec4 deltas[]; };
layout(std430, binding = kDeformBindPalette) readonly buffer Palette { mat4 palette[]; };
layout(std430, binding = kDeformBindWeights) readonly buffer Weights { float weights[]; };
layout(std430, binding = kDeformBindPosed) writeonly buffer Posed { SpotMeshVertex posed[]; };

SpotDeformVertex spotDeformVertexAt(uint v) { return vertices[v]; }
SpotDeformPiece spotDeformPieceAt(uint p) { return pieces[p]; }
vec4 spotMorphDeltaAt(uint i) { return deltas[i]; }
float spotMorphWeightAt(uint i) { return weights[i]; }
mat4 spotPaletteAt(uint j) { return palette[j]; }
#include "spot_pose.h"

void main() {
    uint v = deformInvocation();
    if (v >= push.counts.x)
        return;
    posed[v].position = vec4(spotPoseVertex(v), 1.0);
}
