/* spot_pose.h: an animated mesh's vertices at a pose (docs/design.md section 6), one source for
 * the GPU's pose pass (deform_pose.comp) and the CPU (noise/animated_mesh.cpp poses through
 * spot_deform.hpp's SharedPoser).
 *
 * Included after spot_deform_layout.h. The includer provides the accessors
 *   SpotDeformVertex spotDeformVertexAt(uint v); SpotDeformPiece spotDeformPieceAt(uint p);
 *   vec4 spotMorphDeltaAt(uint i); float spotMorphWeightAt(uint i); mat4 spotPaletteAt(uint j).
 * Single precision on both sides.
 */

/* A vertex posed: its base plus its morph deltas weighted, moved by the blend of its joints'
 * matrices (linear blend skinning), the weights normalised by their sum as glTF asks. A vertex
 * whose weights are all zero stays at its base (the loader refuses such a skin). */
SPOT_FN vec3 spotPoseVertex(uint v) {
    SpotDeformVertex d = spotDeformVertexAt(v);
    SpotDeformPiece p = spotDeformPieceAt(floatBitsToUint(d.base.w));
    vec3 x = vec3(d.base.x, d.base.y, d.base.z);
    uint local = v - p.info.x;
    for (uint k = 0u; k < p.info.z; ++k)
        x += spotMorphWeightAt(p.morph.x + k) *
             vec3(spotMorphDeltaAt(p.info.w + k * p.info.y + local));
    mat4 m = mat4(0.0f);
    float sum = 0.0f;
    for (uint c = 0u; c < 4u; ++c) {
        if (d.weights0[c] != 0.0f) {
            m += d.weights0[c] * spotPaletteAt(d.joints0[c]);
            sum += d.weights0[c];
        }
        if (d.weights1[c] != 0.0f) {
            m += d.weights1[c] * spotPaletteAt(d.joints1[c]);
            sum += d.weights1[c];
        }
    }
    return sum > 0.0f ? vec3(m * vec4(x, 1.0f)) / sum : x;
}
