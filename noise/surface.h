/// @file surface.h
/// @brief Points on a mesh surface: interpolation of position, normal, tangent frame and uv.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "field.h"

namespace spot::noise {

struct Mesh;

/// Tangent used where a mesh has no uv: world -y (the way fur hangs) projected on the tangent
/// plane, or world +x where the normal is vertical. Continuous over smooth surfaces except where
/// the normal passes through +-y, unlike a generic orthonormal basis whose seam would show as a
/// sudden change of comb direction.
glm::vec3 defaultTangent(glm::vec3 normal);

/// The surface at barycentric (b0, b1, b2) of triangle `triangle`: interpolated position,
/// normal (unit; the face normal if the interpolation vanishes), tangent (unit, _|_ normal: the
/// interpolated +u tangent when the mesh has uv, else defaultTangent) and uv.
SurfacePoint surfacePoint(const Mesh& mesh, std::uint32_t triangle, glm::dvec3 barycentric);

/// Barycentric coordinates of the point of triangle (a, b, c) closest to p (Ericson, Real-Time
/// Collision Detection, 5.1.5).
glm::dvec3 closestPointBarycentric(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c);

} // namespace spot::noise
