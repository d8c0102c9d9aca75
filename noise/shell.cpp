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

std::vector<ShellTetrahedron> shellTetrahedra(const std::vector<glm::uvec3>& triangles,
                                              std::uint32_t baseCount) {
    std::vector<ShellTetrahedron> out;
    out.reserve(3 * triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
        for (const ShellTetrahedron& tet :
             prismTetrahedra(triangles[t], std::uint32_t(t), baseCount))
            out.push_back(tet);
    return out;
}

std::vector<std::array<std::int32_t, 4>> shellNeighbours(
    const std::vector<ShellTetrahedron>& tetrahedra) {
    // Every face as (sorted vertex triple, tetrahedron x 4 + face), sorted: a face's holders
    // end up next to each other (deterministic, no hashing).
    struct Entry {
        std::array<std::uint32_t, 3> key;
        std::uint32_t id;
        bool operator<(const Entry& o) const { return key != o.key ? key < o.key : id < o.id; }
    };
    SPOT_CHECK_LE(tetrahedra.size(), std::size_t(1) << 29);
    std::vector<Entry> faces;
    faces.reserve(4 * tetrahedra.size());
    for (std::size_t t = 0; t < tetrahedra.size(); ++t)
        for (std::uint32_t f = 0; f < 4; ++f) {
            const auto& v = tetrahedra[t].vertices;
            std::array<std::uint32_t, 3> key = {v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]};
            std::sort(key.begin(), key.end());
            faces.push_back({key, std::uint32_t(t) * 4 + f});
        }
    std::sort(faces.begin(), faces.end());
    std::vector<std::array<std::int32_t, 4>> out(tetrahedra.size(), {-1, -1, -1, -1});
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t j = i + 1;
        while (j < faces.size() && faces[j].key == faces[i].key)
            ++j;
        if (j - i == 2) {
            const std::uint32_t a = faces[i].id, b = faces[i + 1].id;
            out[a >> 2][a & 3] = std::int32_t(b >> 2);
            out[b >> 2][b & 3] = std::int32_t(a >> 2);
        }
        i = j;
    }
    return out;
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
    shell.tetrahedra = shellTetrahedra(mesh.triangles, shell.baseCount);
    return shell;
}

} // namespace spot::noise
