/// @file spot_shadow.hpp
/// @brief C++ side of shaders/spot_shadow.h: the light-space structure's and the lit frame's
/// structs and constants in spot::gpu, the same text the shaders compile, with their sizes
/// checked (std430: every member a 16-byte vector).
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

namespace spot::gpu {
namespace shadow_detail {
using uint = std::uint32_t;
using real = float;
using rvec2 = glm::vec2;
using rvec3 = glm::vec3;
using glm::clamp;
using glm::max;
using glm::min;
using std::exp;
using std::log;
#define SPOT_OUT(T) T&
using glm::uvec4;
using glm::vec4;
#define SPOT_CONST inline constexpr
#define SPOT_FN inline
#include "spot_shadow.h"
#undef SPOT_OUT
#undef SPOT_CONST
#undef SPOT_FN
} // namespace shadow_detail
using namespace shadow_detail;

static_assert(sizeof(SpotLitLight) == 32);
static_assert(sizeof(SpotLitLobe) == 64);
static_assert(sizeof(SpotShadowView) == 80);
static_assert(sizeof(SpotLitParams) == 32 + 16 * kShadowMaxSky + 8 * 32 + 8 * 64 + 80 * kShadowMaxViews);
static_assert(sizeof(SpotShadowExtent) == 32);
static_assert(sizeof(SpotShadowList) == 16);
static_assert(sizeof(SpotShadowPush) == 32);
} // namespace spot::gpu
