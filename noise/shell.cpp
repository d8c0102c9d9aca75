#include "noise/shell.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "noise/error.h"
#include "noise/mesh.h"
#include "shaders/spot_shared.hpp"

namespace spot::shared::f32 {
#include "noise/shell_walk_twin.h"
} // namespace spot::shared::f32
namespace spot::shared::f64 {
#include "noise/shell_walk_twin.h"
} // namespace spot::shared::f64

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
    // The welded triangles: prisms meet at one vertex (one extrusion, one diagonal rule) across
    // uv and normal seams, so neighbouring prisms share their side faces.
    shell.tetrahedra = shellTetrahedra(mesh.weldedTriangles(), shell.baseCount);
    return shell;
}

std::vector<glm::ivec4> shellWalkNeighbours(const std::vector<ShellTetrahedron>& tetrahedra) {
    const std::vector<std::array<std::int32_t, 4>> neighbours = shellNeighbours(tetrahedra);
    std::vector<glm::ivec4> packed(neighbours.size(), glm::ivec4(-1));
    for (std::size_t t = 0; t < neighbours.size(); ++t)
        for (std::uint32_t f = 0; f < 4; ++f) {
            // The neighbour and the face it shares, as that neighbour numbers it.
            const std::int32_t n = neighbours[t][f];
            std::int32_t back = 0;
            while (n >= 0 && back < 3 &&
                   neighbours[std::size_t(n)][std::size_t(back)] != std::int32_t(t))
                ++back;
            packed[t][int(f)] = n < 0 ? -1 : n * 4 + back;
        }
    return packed;
}

namespace {

/// The walk, in either precision: `Twin` the shared functions' class of that precision, `Real`
/// its scalar.
template <typename Twin, typename Real>
bool walkSegment(Twin twin, std::uint32_t tet, glm::dvec3 origin, glm::dvec3 dir, double& tEnter,
                 double& tExit) {
    using Vec3 = glm::vec<3, Real>;
    const Vec3 o(origin), d(dir);
    Real enter = Real(0);
    for (std::uint32_t f = 0; f < 4; ++f) {
        Real num, den;
        twin.spotTetCrossing(twin.plane(tet, f), o, d, num, den);
        if (den > Real(0))
            enter = std::max(enter, num / den);
        else if (den == Real(0) && num > Real(0))
            return false; // parallel to the face, outside it
    }
    Real exit;
    std::uint32_t loops = 0;
    bool backward = false;
    if (twin.spotTetExit(tet, Twin::kTetNoFace, o, d, false, exit, backward, loops) ==
        Twin::kTetNoFace)
        exit = std::numeric_limits<Real>::infinity(); // no plane left: unbounded (inside)
    tEnter = double(enter);
    tExit = double(exit);
    return enter < exit;
}

template <typename Twin, typename Real>
std::vector<WalkSegment> walkFrom(Twin twin, const std::vector<glm::ivec4>& neighbours,
                                  glm::dvec3 origin, glm::dvec3 dir, std::uint32_t tet,
                                  std::uint32_t entryFace, double tEnd, std::uint32_t maxTets) {
    using Vec3 = glm::vec<3, Real>;
    const Vec3 o(origin), d(dir);
    const Real tMesh = Real(tEnd);
    std::vector<WalkSegment> out;
    Real tIn = entryFace == Twin::kTetNoFace ? Real(0) : twin.spotTetEntry(tet, entryFace, o, d);
    std::uint32_t loops = 0;
    while (out.size() < maxTets) {
        Real tOut;
        bool backward = false;
        const std::uint32_t exitFace =
            twin.spotTetExit(tet, entryFace, o, d, false, tOut, backward, loops);
        if (exitFace == Twin::kTetNoFace)
            break; // flat or degenerate: the walk stops here
        tOut = backward ? std::min(tOut, tIn) : std::max(tOut, tIn);
        const bool atMesh = tOut >= tMesh;
        tOut = std::min(tOut, tMesh);
        out.push_back({tet, double(tIn), double(tOut), exitFace});
        tIn = tOut;
        if (atMesh || !twin.spotTetNext(neighbours[tet][int(exitFace)], tet, entryFace))
            break;
    }
    return out;
}

template <typename Twin, typename Real>
std::int64_t containingTet(Twin twin, std::size_t count, glm::dvec3 p) {
    using Vec3 = glm::vec<3, Real>;
    const Vec3 x(p);
    for (std::size_t t = 0; t < count; ++t) {
        bool holds = true;
        for (std::uint32_t f = 0; f < 4 && holds; ++f) {
            const auto plane = twin.plane(std::uint32_t(t), f);
            holds = glm::dot(Vec3(plane), x) + plane.w >= Real(0);
        }
        if (holds)
            return std::int64_t(t);
    }
    return -1;
}

/// The face planes of every tetrahedron of `shell`, by the shared spotTetFacePlane.
template <typename Twin, typename Vec4> std::vector<Vec4> facePlanes(const ShellMesh& shell) {
    using Vec3 = glm::vec<3, typename Vec4::value_type>;
    std::vector<Vec4> planes(4 * shell.tetrahedra.size());
    Twin twin(planes.data());
    for (std::size_t t = 0; t < shell.tetrahedra.size(); ++t) {
        Vec3 p[4];
        for (int i = 0; i < 4; ++i)
            p[i] = Vec3(shell.positions[shell.tetrahedra[t].vertices[std::size_t(i)]]);
        for (int f = 0; f < 4; ++f)
            planes[4 * t + std::size_t(f)] =
                twin.spotTetFacePlane(p[(f + 1) % 4], p[(f + 2) % 4], p[(f + 3) % 4], p[f]);
    }
    return planes;
}

} // namespace

ShellWalk::ShellWalk(const ShellMesh& shell, Precision precision)
    : m_precision(precision), m_neighbours(shellWalkNeighbours(shell.tetrahedra)) {
    if (precision == Precision::Float)
        m_planesF = facePlanes<shared::f32::TetWalkTwin, glm::vec4>(shell);
    else
        m_planesD = facePlanes<shared::f64::TetWalkTwin, glm::dvec4>(shell);
}

bool ShellWalk::segment(std::uint32_t tet, glm::dvec3 origin, glm::dvec3 dir, double& tEnter,
                        double& tExit) const {
    SPOT_CHECK_LT(std::size_t(tet), m_neighbours.size());
    if (m_precision == Precision::Float)
        return walkSegment<shared::f32::TetWalkTwin, float>(
            shared::f32::TetWalkTwin(m_planesF.data()), tet, origin, dir, tEnter, tExit);
    return walkSegment<shared::f64::TetWalkTwin, double>(shared::f64::TetWalkTwin(m_planesD.data()),
                                                         tet, origin, dir, tEnter, tExit);
}

std::vector<WalkSegment> ShellWalk::walk(glm::dvec3 origin, glm::dvec3 dir, std::uint32_t tet,
                                         std::uint32_t entryFace, double tEnd,
                                         std::uint32_t maxTets) const {
    SPOT_CHECK_LT(std::size_t(tet), m_neighbours.size());
    SPOT_CHECK_LE(entryFace, 4u);
    if (m_precision == Precision::Float)
        return walkFrom<shared::f32::TetWalkTwin, float>(shared::f32::TetWalkTwin(m_planesF.data()),
                                                         m_neighbours, origin, dir, tet, entryFace,
                                                         tEnd, maxTets);
    return walkFrom<shared::f64::TetWalkTwin, double>(shared::f64::TetWalkTwin(m_planesD.data()),
                                                      m_neighbours, origin, dir, tet, entryFace,
                                                      tEnd, maxTets);
}

std::int64_t ShellWalk::containing(glm::dvec3 p) const {
    if (m_precision == Precision::Float)
        return containingTet<shared::f32::TetWalkTwin, float>(
            shared::f32::TetWalkTwin(m_planesF.data()), m_neighbours.size(), p);
    return containingTet<shared::f64::TetWalkTwin, double>(
        shared::f64::TetWalkTwin(m_planesD.data()), m_neighbours.size(), p);
}

} // namespace spot::noise
