#include "surface.h"

#include <cmath>

#include "mesh.h"
#include "shaders/spot_shared.hpp"

namespace spot::shared::f64 {
namespace {

/// shaders/spot_surface.h over a noise::Mesh, in double: the generator's surface formulas (its
/// float twin: noise/generator_shared.h) at the CPU's precision.
class MeshSurface {
public:
    explicit MeshSurface(const noise::Mesh& mesh) : m_mesh(mesh) {}

private:
    const noise::Mesh& m_mesh;
    glm::uvec3 spotMeshTriangle(uint t) const { return m_mesh.triangles[t]; }
    rvec3 spotMeshPosition(uint v) const { return rvec3(m_mesh.positions[v]); }
    rvec3 spotMeshNormal(uint v) const { return rvec3(m_mesh.normals[v]); }
    rvec3 spotMeshTangent(uint v) const {
        return m_mesh.tangents.empty() ? rvec3(0.0) : rvec3(m_mesh.tangents[v]);
    }
    rvec2 spotMeshUv(uint v) const { return m_mesh.hasUv() ? rvec2(m_mesh.uvs[v]) : rvec2(0.0); }

public:
#define SPOT_FN
#include "shaders/spot_surface.h"
#undef SPOT_FN
};

} // namespace
} // namespace spot::shared::f64

namespace spot::noise {

SurfacePoint surfacePoint(const Mesh& mesh, std::uint32_t triangle, glm::dvec3 b) {
    shared::f64::MeshSurface surface(mesh);
    const auto s = surface.spotSurfaceAt(triangle, b);
    SurfacePoint sp;
    sp.triangle = triangle;
    sp.barycentric = glm::vec3(b);
    sp.position = glm::vec3(s.position);
    sp.normal = glm::vec3(s.normal);
    sp.tangent = glm::vec3(s.tangent);
    sp.uv = glm::vec2(s.uv);
    return sp;
}

glm::dvec3 closestPointBarycentric(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0)
        return {1.0, 0.0, 0.0};
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3)
        return {0.0, 1.0, 0.0};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double v = d1 / (d1 - d3);
        return {1.0 - v, v, 0.0};
    }
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6)
        return {0.0, 0.0, 1.0};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double w = d2 / (d2 - d6);
        return {1.0 - w, 0.0, w};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0.0, 1.0 - w, w};
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    return {1.0 - v - w, v, w};
}

} // namespace spot::noise
