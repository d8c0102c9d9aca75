/// @file layout.h
/// @brief C++ side of shaders/spot_layout.h (structs shared with GLSL), with the size checks
/// that keep the two in step, and conversions from the CPU model.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "noise/cells.h"
#include "noise/impulses.h"
#include "noise/kernel.h"

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
static_assert(sizeof(SpotKernelBound) == 32);
static_assert(alignof(SpotImpulse) <= 16);

/// The model's impulse in the GPU layout, and back (exact: floats are copied bit for bit).
SpotImpulse toGpu(const noise::Impulse& impulse);
noise::Impulse fromGpu(const SpotImpulse& impulse);
std::vector<SpotImpulse> toGpu(const std::vector<noise::Impulse>& impulses);
/// Kernel lobes in the GPU layout (at most 8).
std::vector<SpotLobe> toGpu(const noise::Kernel& kernel);

} // namespace spot::gpu
