/// @file generator_shared.h
/// @brief shaders/spot_generate.h compiled for the CPU: the same candidate-by-candidate impulse
/// generation the GPU runs, with the data accessors reading the model's arrays.
///
/// The shared functions become member functions of SharedGenerator (a class body can hold them
/// unchanged), in namespace spot::shared::f32 so they see the float twin of spot_shared.h.
#pragma once

#include <bit>
#include <cstdint>
#include <vector>

#include "shaders/spot_layout.hpp"
#include "shaders/spot_shared.hpp"

namespace spot::shared::f32 {

using gpu::SpotCell;
using gpu::SpotField;
using gpu::SpotGenParams;
using gpu::SpotImpulse;
using gpu::SpotPiece;

/// What the generator reads: the CPU side of the GPU's storage buffers.
struct GeneratorArrays {
    const glm::uvec3* triangles = nullptr;
    const glm::vec3* positions = nullptr;
    const glm::vec3* normals = nullptr;
    const glm::vec3* tangents = nullptr; ///< null: the mesh has none
    const glm::vec2* uvs = nullptr;      ///< null: the mesh has none
    const SpotPiece* pieces = nullptr;   ///< cumulative areas (gpu::piecesToGpu)
    const float* fieldData = nullptr;
    const SpotGenParams* params = nullptr;
};

class SharedGenerator {
public:
    explicit SharedGenerator(const GeneratorArrays& arrays) : m_a(arrays) {}

private:
    GeneratorArrays m_a;
    glm::uvec3 spotMeshTriangle(uint t) const { return m_a.triangles[t]; }
    glm::vec3 spotMeshPosition(uint v) const { return m_a.positions[v]; }
    glm::vec3 spotMeshNormal(uint v) const { return m_a.normals[v]; }
    glm::vec3 spotMeshTangent(uint v) const { return m_a.tangents ? m_a.tangents[v] : glm::vec3(0.0f); }
    glm::vec2 spotMeshUv(uint v) const { return m_a.uvs ? m_a.uvs[v] : glm::vec2(0.0f); }
    SpotPiece spotCellPiece(uint i) const { return m_a.pieces[i]; }
    float spotFieldData(uint i) const { return m_a.fieldData[i]; }
    glm::vec4 spotParamDistribution() const { return m_a.params->distribution; }
    glm::vec4 spotParamVariation0() const { return m_a.params->variation0; }
    glm::vec4 spotParamVariation1() const { return m_a.params->variation1; }
    glm::uvec4 spotParamFlags() const { return m_a.params->flags; }
    glm::vec4 spotParamLod() const { return m_a.params->lod; }
    const SpotField& spotParamField(uint slot) const { return m_a.params->fields[slot]; }
    glm::ivec2 spotParamFieldKind(uint slot) const { return glm::ivec2(m_a.params->fields[slot].kind); }
    glm::vec4 spotParamClump() const { return m_a.params->clump; }
    glm::vec4 spotParamClump2() const { return m_a.params->clump2; }
    glm::uvec4 spotParamClumpFlags() const { return m_a.params->clumpFlags; }

public:
#define SPOT_FN
#define SPOT_CONST static constexpr
#define SPOT_OUT(T) T&
#define SPOT_INOUT(T) T&
#include "spot_generate.h"
#undef SPOT_FN
#undef SPOT_CONST
#undef SPOT_OUT
#undef SPOT_INOUT

    /// Host only, jittered distribution: the candidates of `cell` whose moved lattice site lies
    /// in its triangle and the cell, in candidate order, appended to `out`. Only the density
    /// test and the level of detail stand between them and impulses; the others are rejected
    /// whatever the fields say, so the GPU need not examine them. Walks the groups and their
    /// sites in spotJitteredCandidate's order (at most kMaxCandidatesPerCell candidates).
    void jitteredSitesInside(const SpotCell& cell, std::vector<std::uint16_t>& out) {
        static_assert(kMaxCandidatesPerCell <= 65536u, "candidate indices are 16-bit");
        const real spacing = spotParamVariation1().w;
        const real jitter = spotParamDistribution().y;
        const uint end = cell.info.x + uint(cell.ijk.w);
        uint m = 0;
        for (uint first = cell.info.x; first < end;) {
            const uint last = spotGroupEnd(first, end);
            const uint tri = floatBitsToUint(spotCellPiece(first).c2.w);
            const SpotLattice l = spotLatticeOf(first, last, tri, spacing, jitter);
            for (uint site = 0; site < l.sites && m < kMaxCandidatesPerCell; ++site, ++m) {
                uint key;
                rvec3 bary;
                if (spotLatticeSite(l, tri, site, glm::ivec3(cell.ijk), key, bary))
                    out.push_back(std::uint16_t(m));
            }
            first = last;
        }
    }
};

} // namespace spot::shared::f32
