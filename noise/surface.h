/// @file surface.h
/// @brief Points on a mesh surface: interpolation of position, normal, tangent frame and uv.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "field.h"

namespace spot::noise {

struct Mesh;

/// The surface at barycentric (b0, b1, b2) of triangle `triangle`: interpolated position,
/// normal (unit; the face normal if the interpolation vanishes), tangent (unit, _|_ normal: the
/// interpolated +u tangent when the mesh has uv, else spotDefaultTangent: world -y projected on
/// the tangent plane) and uv. The GPU generator's formulas (shaders/spot_surface.h), evaluated
/// in double and rounded to float.
SurfacePoint surfacePoint(const Mesh& mesh, std::uint32_t triangle, glm::dvec3 barycentric);

/// Barycentric coordinates of the point of triangle (a, b, c) closest to p (Ericson, Real-Time
/// Collision Detection, 5.1.5).
glm::dvec3 closestPointBarycentric(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c);

} // namespace spot::noise
