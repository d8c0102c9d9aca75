#include "surface.h"

#include <cmath>

#include "mesh.h"

namespace spot::noise {

glm::vec3 defaultTangent(glm::vec3 normal) {
    glm::vec3 t = glm::vec3(0.0f, -1.0f, 0.0f) - normal * -normal.y;
    if (glm::dot(t, t) < 1e-8f)
        t = glm::vec3(1.0f, 0.0f, 0.0f) - normal * normal.x;
    return glm::normalize(t);
}

SurfacePoint surfacePoint(const Mesh& mesh, std::uint32_t triangle, glm::dvec3 b) {
    const glm::uvec3 tri = mesh.triangles[triangle];
    SurfacePoint sp;
    sp.triangle = triangle;
    sp.barycentric = glm::vec3(b);
    const glm::dvec3 p0(mesh.positions[tri.x]), p1(mesh.positions[tri.y]), p2(mesh.positions[tri.z]);
    sp.position = glm::vec3(b.x * p0 + b.y * p1 + b.z * p2);
    glm::vec3 n = float(b.x) * mesh.normals[tri.x] + float(b.y) * mesh.normals[tri.y] +
                  float(b.z) * mesh.normals[tri.z];
    if (!(glm::dot(n, n) > 1e-12f))
        n = glm::vec3(glm::cross(p1 - p0, p2 - p0));
    sp.normal = glm::normalize(n);
    if (mesh.hasUv()) {
        sp.uv = float(b.x) * mesh.uvs[tri.x] + float(b.y) * mesh.uvs[tri.y] +
                float(b.z) * mesh.uvs[tri.z];
    }
    glm::vec3 t(0.0f);
    if (!mesh.tangents.empty())
        t = float(b.x) * mesh.tangents[tri.x] + float(b.y) * mesh.tangents[tri.y] +
            float(b.z) * mesh.tangents[tri.z];
    t -= sp.normal * glm::dot(t, sp.normal);
    sp.tangent = glm::dot(t, t) > 1e-12f ? glm::normalize(t) : defaultTangent(sp.normal);
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
