/// @file spot_layout.hpp
/// @brief C++ side of shaders/spot_layout.h: the structs shared with GLSL, in namespace spot::gpu,
/// with the size checks that keep both sides in step (std430: all members are 16-byte vectors).
/// Every field's offset, of these and of the other shared structs, is asserted in
/// tests/shaders/layout_test.cpp, against offsetof and against the shaders' compiled SPIR-V.
#pragma once

#include <glm/glm.hpp>

namespace spot::gpu {
using glm::ivec4;
using glm::uvec4;
using glm::vec4;
#include "spot_layout.h"

static_assert(sizeof(SpotCell) == 32);
static_assert(sizeof(SpotPiece) == 32);
static_assert(sizeof(SpotImpulse) == 144);
static_assert(sizeof(SpotLobe) == 64);
static_assert(sizeof(SpotWorldLobe) == 64);
static_assert(sizeof(SpotField) == 144);
static_assert(sizeof(SpotGenParams) == 128 + SPOT_FIELD_COUNT * 144);
static_assert(alignof(SpotImpulse) <= 16);
} // namespace spot::gpu
