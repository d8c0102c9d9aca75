/// @file spot_light.hpp
/// @brief C++ side of shaders/spot_light.h, the lit shading model shared with GLSL: its
/// functions in spot::shared::f32 (float, the GPU's twin) and spot::shared::f64 (double, the CPU
/// reference), the same source text the shaders compile.
#pragma once

#include <cmath>

#include "spot_shared.hpp"

namespace spot::shared {

namespace f32 {
#define SPOT_OUT(T) T&
#define SPOT_CONST inline constexpr
#define SPOT_FN inline
#include "spot_light.h"
#undef SPOT_OUT
#undef SPOT_CONST
#undef SPOT_FN
} // namespace f32

namespace f64 {
#define SPOT_OUT(T) T&
#define SPOT_CONST inline constexpr
#define SPOT_FN inline
#include "spot_light.h"
#undef SPOT_OUT
#undef SPOT_CONST
#undef SPOT_FN
} // namespace f64

} // namespace spot::shared
