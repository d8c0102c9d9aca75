/// @file spot_deform.hpp
/// @brief C++ side of shaders/spot_deform_layout.h, spot_deform.h and spot_pose.h: the deform
/// passes' structs (spot::gpu) and the float twin of their formulas (spot::shared::f32), the same
/// source text the shaders compile.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "spot_shared.hpp"

namespace spot::gpu {
using glm::ivec4;
using glm::uvec4;
using glm::vec4;
#define SPOT_CONST inline constexpr
#include "spot_deform_layout.h"
#undef SPOT_CONST

static_assert(sizeof(SpotDeformVertex) == 80);
static_assert(sizeof(SpotDeformPiece) == 32);
static_assert(sizeof(SpotDeformPush) == 48);
} // namespace spot::gpu

namespace spot::shared::f32 {
using gpu::SpotDeformPiece;
using gpu::SpotDeformVertex;
#define SPOT_OUT(T) T&
#define SPOT_INOUT(T) T&
#define SPOT_FN inline
#include "spot_deform.h"
#undef SPOT_FN

/// What the pose reads: the CPU side of the pose pass's storage buffers.
struct PoseArrays {
    const gpu::SpotDeformVertex* vertices = nullptr;
    const gpu::SpotDeformPiece* pieces = nullptr;
    const glm::vec4* deltas = nullptr;
    const float* weights = nullptr;
    const glm::mat4* palette = nullptr;
};

/// spot_pose.h over host arrays.
class SharedPoser {
public:
    explicit SharedPoser(const PoseArrays& arrays) : m_a(arrays) {}

private:
    PoseArrays m_a;
    gpu::SpotDeformVertex spotDeformVertexAt(uint v) const { return m_a.vertices[v]; }
    gpu::SpotDeformPiece spotDeformPieceAt(uint p) const { return m_a.pieces[p]; }
    glm::vec4 spotMorphDeltaAt(uint i) const { return m_a.deltas[i]; }
    float spotMorphWeightAt(uint i) const { return m_a.weights[i]; }
    glm::mat4 spotPaletteAt(uint j) const { return m_a.palette[j]; }

public:
#define SPOT_FN
#include "spot_pose.h"
#undef SPOT_FN
};
#undef SPOT_OUT
#undef SPOT_INOUT
} // namespace spot::shared::f32
