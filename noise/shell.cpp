#include "noise/shell.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "noise/error.h"
#include "noise/mesh.h"

namespace spot::noise {

std::array<ShellTetrahedron, 3> prismTetrahedra(glm::uvec3 tri, std::uint32_t t,
                                                std::uint32_t baseCount) {
    std::array<std::uint32_t, 3> v = {tri.x, tri.y, tri.z};
    std::sort(v.begin(), v.end());
    const std::uint32_t b0 = v[0], b1 = v[1], b2 = v[2];
    const std::uint32_t t0 = v[0] + baseCount, t1 = v[1] + baseCount, t2 = v[2] + baseCount;
    std::array<ShellTetrahedron, 3> out{};
    out[0] = {{b0, b1, b2, t2}, t};
    out[1] = {{b0, b1, t2, t1}, t};
    out[2] = {{b0, t0, t1, t2}, t};
    // Sorting may have reversed the triangle's winding: then swap two corners of each, so every
    // tetrahedron keeps the orientation of the triangle's counter-clockwise normal.
    const bool reversed = !((tri.x == v[0] && tri.y == v[1]) || (tri.y == v[0] && tri.z == v[1]) ||
                            (tri.z == v[0] && tri.x == v[1]));
    if (reversed)
        for (ShellTetrahedron& tet : out)
            std::swap(tet.vertices[0], tet.vertices[1]);
    return out;
}

bool raySegmentInTetrahedron(const ShellMesh& shell, const ShellTetrahedron& tet, glm::dvec3 origin,
                             glm::dvec3 dir, double& tEnter, double& tExit) {
    glm::dvec3 p[4];
    for (int i = 0; i < 4; ++i)
        p[i] = glm::dvec3(shell.positions[tet.vertices[std::size_t(i)]]);
    tEnter = 0.0;
    tExit = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 4; ++i) {
        // The face opposite vertex i, its normal turned towards vertex i (inwards).
        const glm::dvec3 a = p[(i + 1) % 4], b = p[(i + 2) % 4], c = p[(i + 3) % 4];
        glm::dvec3 n = glm::cross(b - a, c - a);
        const double side = glm::dot(n, p[i] - a);
        if (!(side != 0.0))
            return false;
        if (side < 0.0)
            n = -n;
        const double num = glm::dot(n, origin - a), den = glm::dot(n, dir);
        if (den == 0.0) {
            if (num < 0.0)
                return false;
            continue;
        }
        const double t = -num / den;
        if (den > 0.0)
            tEnter = std::max(tEnter, t);
        else
            tExit = std::min(tExit, t);
    }
    return tEnter < tExit;
}

ShellMesh buildShell(const Mesh& mesh, float thickness) {
    if (!(std::isfinite(thickness) && thickness > 0.0f))
        throw InputError(
            cat("shell of ", mesh.name, ": thickness ", thickness, " must be finite and > 0"));
    SPOT_CHECK_EQ(mesh.normals.size(), mesh.positions.size());
    ShellMesh shell;
    shell.thickness = thickness;
    shell.baseCount = std::uint32_t(mesh.positions.size());
    shell.positions.reserve(2 * mesh.positions.size());
    shell.positions = mesh.positions;
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
        shell.positions.push_back(mesh.positions[i] + thickness * mesh.normals[i]);
    shell.tetrahedra.reserve(3 * mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (const ShellTetrahedron& tet :
             prismTetrahedra(mesh.triangles[t], std::uint32_t(t), shell.baseCount))
            shell.tetrahedra.push_back(tet);
    return shell;
}

} // namespace spot::noise
