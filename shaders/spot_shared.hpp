/// @file spot_shared.hpp
/// @brief C++ side of shaders/spot_shared.h, the math shared with GLSL.
///
/// The body is instantiated twice: spot::shared::f32 uses float (the GPU's exact twin, used by
/// tests that compare CPU and GPU) and spot::shared::f64 uses double (the CPU reference). Both
/// are the same source text as the shaders compile.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

namespace spot::shared {

namespace f32 {
using uint = std::uint32_t;
using real = float;
using rvec2 = glm::vec2;
using rvec3 = glm::vec3;
using rvec4 = glm::vec4;
using rmat3 = glm::mat3;
using namespace glm;
using std::abs, std::cos, std::exp, std::sin, std::sqrt;
#define SPOT_OUT(T) T&
#define SPOT_INOUT(T) T&
#define SPOT_CONST inline constexpr
#define SPOT_FN inline
#include "spot_shared.h"
#undef SPOT_OUT
#undef SPOT_INOUT
#undef SPOT_CONST
#undef SPOT_FN
} // namespace f32

namespace f64 {
using uint = std::uint32_t;
using real = double;
using rvec2 = glm::dvec2;
using rvec3 = glm::dvec3;
using rvec4 = glm::dvec4;
using rmat3 = glm::dmat3;
using namespace glm;
using std::abs, std::cos, std::exp, std::sin, std::sqrt;
#define SPOT_OUT(T) T&
#define SPOT_INOUT(T) T&
#define SPOT_CONST inline constexpr
#define SPOT_FN inline
#include "spot_shared.h"
#undef SPOT_OUT
#undef SPOT_INOUT
#undef SPOT_CONST
#undef SPOT_FN
} // namespace f64

} // namespace spot::shared
